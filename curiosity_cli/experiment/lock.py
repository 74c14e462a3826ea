"""One process at a time in an experiment folder.

Two commands working in one folder would undo each other: a stage's start-up clean-up
removes the temporary files a killed run of it left, which in a second process are the
first one's files being written. So each stage holds the folder's lock
(:attr:`~curiosity_cli.experiment.layout.ExperimentFolder.lock`) while it works: an
advisory ``flock`` on the file, which the operating system releases when the process
ends however it ends (``kill -9`` included), and whose text says who holds it, for the
second process's message. A process may take the lock of a folder it already holds
(``reproduce`` runs every stage). Where ``fcntl`` does not exist (Windows) there is no lock,
nor for a folder that does not exist yet (the lock would make it).
"""

from __future__ import annotations

import contextlib
import json
import os
import time
from pathlib import Path

from curiosity_cli.errors import CuriosityError
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.files import display_path

#: The folders this process holds, by resolved path: (open lock file, how many holders).
_HELD: dict[Path, list] = {}


class FolderInUseError(CuriosityError):
    """Another process works in the experiment folder."""


@contextlib.contextmanager
def working_in(folder: Path, stage: str):
    """Hold ``folder``'s lock while the block runs, as ``stage`` (``label``, ``explore``, ...).

    Raises
    ------
    FolderInUseError
        Another process holds it: which (its stage and process id) and since when.
    """
    try:
        import fcntl
    except ImportError:  # Windows
        yield
        return
    key = Path(folder).resolve()
    if key in _HELD:
        _HELD[key][1] += 1
        try:
            yield
        finally:
            _HELD[key][1] -= 1
        return
    if not Path(folder).is_dir():  # nothing to share yet, and no folder to make: the stage says it is missing
        yield
        return
    handle = open(ExperimentFolder(folder).lock, "a+")
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        handle.seek(0)
        holder = _holder(handle.read())
        handle.close()
        raise FolderInUseError(
            f"{display_path(Path(folder))}: another process works in this experiment ({holder}); wait for it to end, "
            "or stop it"
        ) from None
    handle.seek(0)
    handle.truncate()
    handle.write(json.dumps({"pid": os.getpid(), "stage": stage, "since": time.strftime("%Y-%m-%d %H:%M:%S")}))
    handle.flush()
    _HELD[key] = [handle, 1]
    try:
        yield
    finally:
        _HELD[key][1] -= 1
        if _HELD[key][1] == 0:
            del _HELD[key]
            handle.close()  # releases the lock; the text stays, telling nobody anything once no one holds it


def _holder(text: str) -> str:
    """Who holds a lock, in words, from its file's text."""
    try:
        holder = json.loads(text)
        return f"`curiosity {holder['stage']}`, process {holder['pid']}, since {holder['since']}"
    except (ValueError, KeyError, TypeError):
        return "a process that has not said which yet" if not text else f"its lock file says {text[:80]!r}"


