"""Progress of a command's stages, wherever its output goes: a terminal, a log file, a notebook.

:class:`Progress` takes the callbacks every long-running function of the API offers
(``on_stage(description, units)`` when a stage starts, ``on_done()`` after each unit).
It draws one line per stage that it rewrites in place where someone watches (a terminal,
a notebook cell), and where output goes to a file (``nohup``, CI, a pipe) it writes a line
when a stage starts, one every :data:`EVERY` seconds while it runs, with the units done,
the rate and the time left, and one when it ends, so a log shows a long stage is alive.

The time left is :class:`Eta`'s: the stage's own rate so far (units done over the time
since it started), which weighs each unit by the time it took. A rate over the last few
units, as a progress bar usually shows, swings with every lumpy unit: a label stage's
blocks finish many runs at once, costliest first, and such a rate said 11 min 45 s for a
stage that took 85 s.
"""

from __future__ import annotations

import shutil
import sys
import threading
import time

#: Seconds between the lines of a stage written to a file.
EVERY = 15.0
#: Seconds between redraws of a line watched in a terminal or notebook.
_REDRAW = 0.2
_BAR = 24


class Eta:
    """The time left in a stage of ``total`` units from its rate so far.

    Parameters
    ----------
    total : int
        Units of the stage, >= 0.
    started : float
        When it started (``time.monotonic()``).
    """

    def __init__(self, total: int, started: float):
        self.total = total
        self.started = started

    def remaining(self, done: int, now: float) -> float | None:
        """Seconds left after ``done`` units at ``now``; None before the first unit (no rate yet)."""
        if done <= 0:
            return None
        return max(0.0, (now - self.started) * (self.total - done) / done)


def duration(seconds: float) -> str:
    """``42 s``, ``3 min 5 s``, ``1 h 2 min``: a duration for a person."""
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60} s"
    return f"{seconds // 3600} h {seconds % 3600 // 60} min"


def in_notebook() -> bool:
    """Whether this runs in a Jupyter kernel (whose cells show a line rewritten in place)."""
    return "ipykernel" in sys.modules


class Progress:
    """A context manager that shows stages and their units: pass :meth:`stage` as ``on_stage`` and
    :meth:`advance` as ``on_done`` to any function of :mod:`curiosity_cli.api`.

    Parameters
    ----------
    stream : file, optional
        Where it writes; default standard error.
    watched : bool, optional
        Rewrite a stage's line in place (a terminal, a notebook) rather than write a line
        every ``every`` seconds (a file); default: whether ``stream`` is a terminal or this
        runs in a notebook.
    every : float
        Seconds between the lines of a stage written to a file.
    clock : callable
        ``time.monotonic`` (tests give their own).
    """

    def __init__(self, stream=None, *, watched: bool | None = None, every: float = EVERY, clock=time.monotonic):
        self._stream = stream if stream is not None else sys.stderr
        if watched is None:
            isatty = getattr(self._stream, "isatty", None)
            watched = bool(isatty and isatty()) or in_notebook()
        self.watched = watched
        self._every = every
        self._clock = clock
        self._lock = threading.Lock()
        self._description = None
        self._units = self._done = 0
        self._eta = None
        self._drawn = 0.0
        self._width = 0
        self._stop = threading.Event()
        self._ticker = None

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def stage(self, description: str, units: int) -> None:
        """A stage starts: ``units`` units of work (0: a stage announced by its line alone)."""
        self.close()
        with self._lock:
            now = self._clock()
            self._description, self._units, self._done = description, units, 0
            self._eta = Eta(units, now)
            self._stop = threading.Event()
            if not units:
                self._write(description + "\n")
                self._description = None
                return
            if self.watched:
                self._draw(now)
            else:
                self._write(f"{description}: 0/{units}\n")
                self._ticker = threading.Thread(target=self._tick, args=(self._stop,), daemon=True)
                self._ticker.start()

    def advance(self, *_) -> None:
        """One unit done (extra arguments, as callbacks pass them, are ignored)."""
        with self._lock:
            if self._description is None:
                return
            self._done += 1
            now = self._clock()
            if self.watched and (now - self._drawn >= _REDRAW or self._done == self._units):
                self._draw(now)

    def close(self) -> None:
        """End the stage being shown: its last line says how many units it did and in how long."""
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join()
            self._ticker = None
        with self._lock:
            if self._description is None:
                return
            took = duration(self._clock() - self._eta.started)
            if self.watched:
                self._draw(self._clock())
                self._write(f" in {took}\n")
                self._width = 0
            else:
                self._write(f"{self._description}: {self._done}/{self._units} in {took}\n")
            self._description = None

    def status(self, now: float) -> str:
        """The stage's units done, rate and time left at ``now``, in words."""
        elapsed = now - self._eta.started
        left = self._eta.remaining(self._done, now)
        share = f"{self._done}/{self._units} ({100 * self._done / self._units:.0f} %)"
        if left is None:
            return f"{share}, {duration(elapsed)} so far, no estimate before the first is done"
        rate = self._done / elapsed if elapsed > 0 else float("inf")
        shown = f"{rate:.2f}/s" if rate >= 0.1 else f"{60 * rate:.2f}/min"
        return f"{share}, {shown}, about {duration(left)} left"

    def _draw(self, now: float) -> None:
        filled = int(_BAR * self._done / self._units) if self._units else _BAR
        bar = "#" * filled + "-" * (_BAR - filled)
        line = f"{self._description} [{bar}] {self.status(now)}"
        # a line as wide as the terminal wraps, and each redraw then starts a new row: cut it one column short
        line = line[: max(1, shutil.get_terminal_size().columns - 1)]
        # spaces over what a longer line before left: a notebook shows no terminal's erase codes
        self._write(f"\r{line}{' ' * max(0, self._width - len(line))}")
        self._width = len(line)
        self._drawn = now

    def _tick(self, stop: threading.Event) -> None:
        while not stop.wait(self._every):
            with self._lock:
                if self._description is not None:
                    self._write(f"  {self._description}: {self.status(self._clock())}\n")

    def _write(self, text: str) -> None:
        self._stream.write(text)
        self._stream.flush()
