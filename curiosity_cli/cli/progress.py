"""Progress on stderr for commands with stages: a bar per stage that has units of work."""

from __future__ import annotations

import sys

import typer


class StagedProgress:
    """A context manager: :meth:`stage` starts a stage, :meth:`advance` marks one unit of it done.

    A stage without units (``units == 0``) is announced by its description on a line.
    """

    def __init__(self) -> None:
        self._bar = None

    def __enter__(self) -> StagedProgress:
        return self

    def __exit__(self, *exc) -> None:
        self._close()

    def stage(self, description: str, units: int) -> None:
        self._close()
        if units:
            self._bar = typer.progressbar(length=units, label=description, file=sys.stderr)
            self._bar.__enter__()
        else:
            typer.echo(description, err=True)

    def advance(self, *_) -> None:
        """One unit done (extra arguments, as callbacks pass them, are ignored)."""
        if self._bar is not None:
            self._bar.update(1)

    def _close(self) -> None:
        if self._bar is not None:
            self._bar.__exit__(None, None, None)
            self._bar = None
