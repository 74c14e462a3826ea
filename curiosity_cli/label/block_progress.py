"""How far the label stage's blocks are while they run, counted in chain sweeps.

A block of runs is one task in a worker process, and its labels arrive whole when it ends:
on 2 cores the quick job's labelling is two blocks that end together, so counting runs as
they arrive says nothing for its whole length. So each block's worker counts the sweeps
its chains make (:class:`SweepCounter`, called after every sweep) and writes the count to
a file of its own, whole, at most every :data:`EVERY` seconds; a thread of the stage
(:class:`BlockProgress`) reads those files and passes what is new on as units of the
stage's ``on_done``, and a block that ends is topped up to its planned sweeps. Workers
elsewhere (a Dask cluster) get no folder and write nothing: their blocks count when they
arrive. Only the display reads these files; no label depends on them.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import threading
import time
from pathlib import Path

#: Seconds between a worker's writes of its count, and between the stage's reads.
EVERY = 0.5


class SweepCounter:
    """In a worker: the chain sweeps a block has made, written to ``path`` (None: counted, not written).

    Call it after each sweep with the chains that swept.
    """

    def __init__(self, path: str | None):
        self.path = path
        self.done = 0
        self._written = 0.0

    def __call__(self, chains: int) -> None:
        self.done += chains
        now = time.monotonic()
        if self.path is not None and now - self._written >= EVERY:
            self._written = now
            tmp = f"{self.path}.{os.getpid()}.tmp"
            with open(tmp, "w") as handle:
                handle.write(str(self.done))
            os.replace(tmp, self.path)  # whole or not at all: the reader never sees half a number


#: The progress folders' names in the temporary folder: the prefix, then the labelling process's id.
_PREFIX = "curiosity-label-progress-"


def remove_orphans() -> int:
    """Remove the progress folders whose labelling process is gone (killed: it could not remove its own); returns how
    many. A folder named without a process id (written before names held one) is left alone."""
    removed = 0
    for folder in Path(tempfile.gettempdir()).glob(f"{_PREFIX}*"):
        pid = folder.name[len(_PREFIX):].split("-", 1)[0]
        if not pid.isdigit():
            continue
        try:
            os.kill(int(pid), 0)
        except ProcessLookupError:
            shutil.rmtree(folder, ignore_errors=True)
            removed += 1
        except (PermissionError, OverflowError):  # another user's live process, or no such id: not ours to remove
            continue
    return removed


class BlockProgress:
    """In the stage: passes the blocks' sweeps on to ``on_done`` as they are made.

    Parameters
    ----------
    planned : dict of str to int
        Each block's key and the chain sweeps it will make.
    on_done : callable or None
        Called once per chain sweep (from this object's thread as well as the caller's).
    local : bool
        Whether the workers share this machine's files (loky); else only ended blocks count.
    """

    def __init__(self, planned: dict[str, int], on_done, *, local: bool):
        self._planned = planned
        self._on_done = on_done
        self._counted = dict.fromkeys(planned, 0)
        self._ended: set[str] = set()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._folder = None
        if on_done is not None and local:
            remove_orphans()
            self._folder = tempfile.mkdtemp(prefix=f"{_PREFIX}{os.getpid()}-")
        self._thread = None

    def path(self, key: str) -> str | None:
        """Where block ``key``'s worker writes its count; None when nobody reads it."""
        if self._folder is None:
            return None
        return os.path.join(self._folder, key.replace("/", "_"))

    def __enter__(self) -> BlockProgress:
        if self._folder is not None:
            self._thread = threading.Thread(target=self._read, daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        if self._folder is not None:
            shutil.rmtree(self._folder, ignore_errors=True)

    def ended(self, key: str) -> None:
        """Block ``key`` has ended (labelled or failed): the rest of its planned sweeps count now."""
        with self._lock:
            self._ended.add(key)
            self._count(key, self._planned[key])

    def _read(self) -> None:
        while not self._stop.wait(EVERY):
            for key in self._planned:
                path = self.path(key)
                try:
                    done = int(Path(path).read_text())
                except (OSError, ValueError):  # not written yet
                    continue
                with self._lock:
                    if key not in self._ended:
                        self._count(key, min(done, self._planned[key]))

    def _count(self, key: str, done: int) -> None:
        """Pass ``done - counted`` sweeps of block ``key`` on (under the lock)."""
        new = done - self._counted[key]
        if new <= 0 or self._on_done is None:
            return
        self._counted[key] = done
        for _ in range(new):
            self._on_done()
