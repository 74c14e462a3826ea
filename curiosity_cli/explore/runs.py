"""One run's folder on disk: written whole or not at all, and read back.

A run's folder (:meth:`~curiosity_cli.experiment.layout.ExperimentFolder.run`) holds:

- ``path.csv``: one row per step: ``step, row, col, cell, first_visit, words_sampled,
  log_likelihood, fallback, boxed_in``;
- ``candidates.csv``: one row per scored neighbour (none for a planned walker): ``step,
  row, col, cell, coverage, word_perplexity, topic_perplexity, weight, chosen``;
- ``checkpoints.npz`` (compressed): the path's cells and, for every checkpoint length
  ``L``, the non-zero word-topic counts Φ_p as ``L/words``, ``L/topics``, ``L/counts``;
- ``run.json``: what the run was (dataset, weight function, restart, start cell, seed,
  word store, vocabulary hashes, model parameters), its ``recipe``
  (:mod:`curiosity_cli.experiment.recipes`), the size and SHA-256 of each of the three
  files above (``files``, :mod:`curiosity_cli.experiment.wholeness`) and what it cost
  (seconds, and ``bytes``: the size of the whole folder).

The folder is built under a hidden temporary name and renamed into place, so a folder
under its real name was complete when written; a killed writer leaves only a hidden
``.restart-NNN.tmp-*`` folder, which the next grid run removes. What happens to it
afterwards (a full disk, a copy, an edit) is caught by the recorded sizes and digests:
a run whose files are not those it wrote is not finished, and is redone.
"""

from __future__ import annotations

import json
import os
import shutil
import uuid
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.errors import RERUN, CuriosityError
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.experiment.wholeness import FILES_KEY, changed, records
from curiosity_cli.explore.walker import Exploration, SparseCounts
from curiosity_cli.files import CorruptFileError, display_path, naming_os_errors, note, open_npz

RUN_FORMAT = 1
#: What readers of a run take from its ``run.json``: a file without one of them is corrupt.
_RUN_KEYS = (
    "format", "dataset", "weight_function", "restart", "seed", "store", "vocabulary_hashes", "vocabulary_size",
    "n_topics", "checkpoints",
)
_TMP_MARK = ".tmp-"
#: ``candidates.csv``'s columns that its readers take (:meth:`Run.candidates`).
CANDIDATE_COLUMNS = ("step", "cell", "coverage", "weight", "topic_perplexity", "word_perplexity")
#: The files of a run besides ``run.json``, which records their sizes and digests.
_RUN_FILES = [ExperimentFolder.RUN_PATH, ExperimentFolder.RUN_CANDIDATES, ExperimentFolder.RUN_CHECKPOINTS]


class RunError(CuriosityError):
    """A run folder that is missing, incomplete or corrupt."""


def remove_partial_runs(root: Path) -> int:
    """Delete the temporary folders killed writers left under ``root/runs``; returns how many."""
    removed = 0
    for tmp in ExperimentFolder(root).runs.glob(f"*/*/.restart-*{_TMP_MARK}*"):
        shutil.rmtree(tmp, ignore_errors=True)
        removed += 1
    return removed


def write_run(folder: Path, exploration: Exploration, meta: dict, grid: SquareGrid) -> int:
    """Write a run's folder atomically (replacing an old one, whose files the tool did not write are kept);
    returns its size in bytes, run.json included.

    Parameters
    ----------
    folder : Path
        From :meth:`~curiosity_cli.experiment.layout.ExperimentFolder.run`.
    exploration : Exploration
    meta : dict
        JSON-ready facts about the run; ``format``, ``checkpoints`` and ``bytes`` are added.
    grid : SquareGrid
        The map's cells, to write their rows and columns.
    """
    folder = Path(folder)
    tmp = folder.parent / f".{folder.name}{_TMP_MARK}{uuid.uuid4().hex[:8]}"
    tmp.mkdir(parents=True)
    try:
        with naming_os_errors(folder):  # a full disk names the run, not "no space left" alone
            size = _write_files(tmp, exploration, meta, grid)
        if folder.exists():
            written = {item.name for item in tmp.iterdir()}
            for item in folder.iterdir():
                if item.name not in written:  # a user's file: --force replaces only what the tool wrote
                    os.replace(item, tmp / item.name)
            shutil.rmtree(folder)
        os.rename(tmp, folder)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return size


def _write_files(tmp: Path, exploration: Exploration, meta: dict, grid: SquareGrid) -> int:
    """The files of a run folder (module docstring), written into ``tmp``; returns their size in bytes."""
    import pandas as pd

    e = exploration
    rows, cols = grid.row_col(e.path)
    pd.DataFrame(
        {
            "step": np.arange(e.path.size), "row": rows, "col": cols, "cell": e.path,
            "first_visit": e.first_visit, "words_sampled": e.words_sampled,
            "log_likelihood": e.log_likelihood, "fallback": e.fallback, "boxed_in": e.boxed_in,
        }
    ).to_csv(tmp / ExperimentFolder.RUN_PATH, index=False)
    c_rows, c_cols = grid.row_col(e.candidate_cell)
    pd.DataFrame(
        {
            "step": e.candidate_step, "row": c_rows, "col": c_cols, "cell": e.candidate_cell,
            "coverage": e.coverage, "word_perplexity": e.word_perplexity,
            "topic_perplexity": e.topic_perplexity, "weight": e.weight, "chosen": e.chosen,
        }
    ).to_csv(tmp / ExperimentFolder.RUN_CANDIDATES, index=False)
    arrays = {"path": e.path.astype(np.int32), "lengths": np.array(sorted(e.checkpoints), np.int32)}
    for length, counts in e.checkpoints.items():
        arrays.update({f"{length}/words": counts.words, f"{length}/topics": counts.topics, f"{length}/counts": counts.counts})
    np.savez_compressed(tmp / ExperimentFolder.RUN_CHECKPOINTS, **arrays)
    files = records(tmp, _RUN_FILES)
    size = sum(f["size"] for f in files.values())
    meta = {"format": RUN_FORMAT, **meta, "checkpoints": sorted(e.checkpoints), "bytes": size, FILES_KEY: files}
    (tmp / ExperimentFolder.RUN_META).write_text(json.dumps(meta, indent=2) + "\n")
    size += (tmp / ExperimentFolder.RUN_META).stat().st_size
    return size


@dataclass(frozen=True)
class Run:
    """A finished run read back from its folder.

    Attributes
    ----------
    folder : Path
    meta : dict
        ``run.json``.
    path : (L,) int64 ndarray
        Row-major cell of each step.
    """

    folder: Path
    meta: dict
    path: np.ndarray

    def phi(self, length: int) -> np.ndarray:
        """(V, K) int32 ndarray: the word-topic counts Φ_p after ``length`` steps.

        Raises
        ------
        ParameterError
            ``length`` is not an int.
        RunError
            The run has no checkpoint at ``length``, naming those it has.
        """
        from curiosity_cli.checks import check_int

        length = check_int("length", length, 0)
        if length not in self.meta["checkpoints"]:
            raise RunError(
                f"{display_path(self.folder)}: no checkpoint at path length {length}; "
                f"it has {', '.join(map(str, self.meta['checkpoints']))}"
            )
        words, topics, counts = _load_arrays(
            self.folder / ExperimentFolder.RUN_CHECKPOINTS, [f"{length}/words", f"{length}/topics", f"{length}/counts"]
        )
        return SparseCounts(words, topics, counts, (self.meta["vocabulary_size"], self.meta["n_topics"])).dense()

    def boxed_in(self) -> np.ndarray:
        """(L,) bool ndarray: ``path.csv``'s ``boxed_in``, the steps whose neighbours were all visited.

        Raises
        ------
        RunError
            ``path.csv`` missing, unreadable, or not one ``boxed_in`` value per step.
        """
        import pandas as pd

        csv = self.folder / ExperimentFolder.RUN_PATH
        try:
            column = pd.read_csv(csv, usecols=["boxed_in"])["boxed_in"]
        except FileNotFoundError:
            raise RunError(f"{display_path(csv)}: not found; the run folder is incomplete") from None
        except (ValueError, OSError) as exc:
            raise RunError(f"{display_path(csv)}: corrupt ({exc})") from None
        if column.dtype != bool or column.size != self.path.size:
            raise RunError(
                f"{display_path(csv)}: boxed_in: expected {self.path.size} values true or false, one per step"
            )
        return column.to_numpy()

    def candidates(self):
        """``candidates.csv``'s ``step``, ``cell``, ``coverage``, ``weight``, ``topic_perplexity`` and
        ``word_perplexity``: a row per scored neighbour (none for a plan), as steering and the mechanism read them.

        Returns
        -------
        pandas.DataFrame

        Raises
        ------
        RunError
            ``candidates.csv`` missing, unreadable, without those columns, with a step
            outside the path's moves or a cell that is not one.
        """
        import pandas as pd

        csv = self.folder / ExperimentFolder.RUN_CANDIDATES
        try:
            table = pd.read_csv(csv, usecols=list(CANDIDATE_COLUMNS))
        except FileNotFoundError:
            raise RunError(f"{display_path(csv)}: not found; the run folder is incomplete") from None
        except (ValueError, OSError) as exc:
            raise RunError(f"{display_path(csv)}: corrupt ({exc})") from None
        if len(table):
            steps, cells = table["step"], table["cell"]
            if steps.dtype.kind not in "iu" or steps.min() < 0 or steps.max() >= self.path.size - 1:
                raise RunError(
                    f"{display_path(csv)}: step: expected whole numbers 0 .. {self.path.size - 2}, the moves of the path"
                )
            if cells.dtype.kind not in "iu" or cells.min() < 0:
                raise RunError(f"{display_path(csv)}: cell: expected whole numbers >= 0, the cells of the map")
        return table


def finished_meta(folder: Path) -> dict | None:
    """The ``run.json`` of a run folder that exists under its real name (so it was written whole) and reads back.

    ``None`` for a folder not there; also for one with a corrupt ``run.json`` or
    ``checkpoints.npz``, or a file that is not as it was written, with a note on stderr,
    so that the grid redoes just that run.
    """
    if not (Path(folder) / ExperimentFolder.RUN_META).is_file():
        return None
    try:
        return _read(Path(folder)).meta
    except RunError as exc:
        note(f"{exc}; redoing the run")
        return None


def read_run(folder: Path) -> Run:
    """Read a run folder.

    Raises
    ------
    RunError
        A missing or corrupt ``run.json`` or ``checkpoints.npz``, a ``path.csv``
        without a row per step, or a file whose size or digest is not what ``run.json``
        records, naming the file; explore redoes such a run.
    """
    try:
        return _read(Path(folder))
    except RunError as exc:
        raise RunError(f"{exc}; {RERUN} redoes the run", rerun="explore", force=False) from None


def _read(folder: Path) -> Run:
    """:func:`read_run` without the advice: the error names the file and what is wrong with it."""
    meta = _read_meta(folder / ExperimentFolder.RUN_META)
    (path,) = _load_arrays(folder / ExperimentFolder.RUN_CHECKPOINTS, ["path"])
    _check_steps(folder / ExperimentFolder.RUN_PATH, path.size)
    # runs written before their files were recorded have no FILES_KEY; their checks end above
    if (change := changed(folder, meta.get(FILES_KEY, {}))) is not None:
        raise RunError(f"{display_path(change[0])}: {change[1]}")
    return Run(folder, meta, path.astype(np.int64))


def _check_steps(csv: Path, steps: int) -> None:
    """Refuse a ``path.csv`` without a whole line per step (cut short, or missing)."""
    try:
        data = csv.read_bytes()
    except FileNotFoundError:
        raise RunError(f"{display_path(csv)}: not found; the run folder is incomplete") from None
    lines = data.count(b"\n")
    if lines != steps + 1 or not data.endswith(b"\n"):
        raise RunError(f"{display_path(csv)}: {max(lines - 1, 0)} whole rows, expected a header and {steps} steps")


def _read_meta(path: Path) -> dict:
    """A run's ``run.json``, checked to be a mapping of this format with every key a reader needs."""
    try:
        meta = json.loads(path.read_text())
    except FileNotFoundError:
        raise RunError(f"{display_path(path)}: not found; the run is not finished") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise RunError(f"{display_path(path)}: corrupt ({exc})") from None
    if not isinstance(meta, dict):
        raise RunError(f"{display_path(path)}: a JSON {type(meta).__name__}, expected an object of the run's facts")
    missing = [key for key in _RUN_KEYS if key not in meta]
    if missing:
        raise RunError(f"{display_path(path)}: no key {missing[0]!r}; expected a finished run's facts")
    if meta["format"] != RUN_FORMAT:
        raise RunError(f"{display_path(path)}: format {meta['format']!r}, expected {RUN_FORMAT}")
    return meta


def _load_arrays(path: Path, names: list[str]) -> list[np.ndarray]:
    try:
        with open_npz(path) as npz:
            return [npz[name] for name in names]
    except FileNotFoundError:
        raise RunError(f"{display_path(path)}: not found; the run folder is incomplete") from None
    except CorruptFileError as exc:
        raise RunError(str(exc)) from None
