"""Whether an experiment's files are still the ones that were written: their sizes and digests.

A recipe (:mod:`~curiosity_cli.experiment.recipes`) says what a file was made from; it
cannot say whether the bytes on disk are still those: a ``path.csv`` cut short by a full
disk, a checkpoint file with a flipped byte, an example label map copied from another
run. So whoever writes a set of files records each one's size and SHA-256
(:func:`records`), and every reader checks them (:func:`changed`) before trusting any.
"""

from __future__ import annotations

from pathlib import Path

from curiosity_cli.files import file_sha256

#: Where a file's meta (``run.json``, a label file's ``meta``) records the files that go with it.
FILES_KEY = "files"


def record(path: Path) -> dict:
    """``{"size": bytes, "sha256": hex}`` of a file as it is now."""
    return {"size": Path(path).stat().st_size, "sha256": file_sha256(path)}


def records(folder: Path, names: list[str]) -> dict[str, dict]:
    """:func:`record` of each file ``folder/name``, by name (a name may hold ``/``)."""
    return {name: record(Path(folder) / name) for name in names}


def changed(folder: Path, recorded: dict[str, dict]) -> tuple[Path, str] | None:
    """``None`` when every file of ``recorded`` (:func:`records`) is as written; else the
    first that is not and what is wrong with it, in words.

    Sizes are compared first, so a cut-short file is named without being read.
    """
    for name, expected in sorted(recorded.items()):
        path = Path(folder) / name
        if not path.is_file():
            return path, "missing"
        size = path.stat().st_size
        if size != expected.get("size"):
            return path, f"{size} bytes, but {expected.get('size')} were written"
        if record(path)["sha256"] != expected.get("sha256"):
            return path, "its contents changed since it was written"
    return None
