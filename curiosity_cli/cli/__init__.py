"""The ``curiosity`` command line: thin commands over :mod:`curiosity_cli.api`.

Every command module registers itself on :data:`~curiosity_cli.cli.app.app`; a command parses its options, calls
the API function of the same name and reports what it returns. A library
:class:`CuriosityError` becomes ``Error: …`` on stderr and exit code 1; usage mistakes
exit 2 (click's own, and a :class:`UsageError` of the API, :func:`~curiosity_cli.cli.app.usage_errors`).
Heavy libraries are imported inside commands so ``curiosity --help`` stays instant.
"""

from __future__ import annotations

import typer

from curiosity_cli.cli.app import app

# Registration order is the order `--help` lists the commands: the pipeline's order.
from curiosity_cli.cli import datasets, vocab, extract, explore, label, evaluate, plot, reproduce, drive, config_cmd  # noqa: E402,F401


def main() -> None:
    """Entry point of the ``curiosity`` console script.

    Ctrl-C (SIGINT) and SIGTERM stop any command the same way: KeyboardInterrupt unwinds
    it, so worker processes and clusters are shut down on the way out, then one line on
    stderr and exit code 130 or 143 (the shell's 128 + the signal's number). ``drive``
    and ``simrobot`` handle both signals themselves while they run (STOP goes first).
    """
    import os
    import signal
    import sys

    from curiosity_cli.errors import unwinding_interrupt

    # OpenCV and its FFmpeg print their own lines for a camera they cannot open, before
    # our one Error line says the same; a user who wants them sets the variables
    os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
    received = []

    def interrupt(signum, frame):
        received.append(signum)
        raise KeyboardInterrupt

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, interrupt)
    try:
        app()
    except BaseException as error:  # typer turns KeyboardInterrupt into exit code 130
        if not received or not (isinstance(error, SystemExit) or unwinding_interrupt(error)):
            raise
        typer.echo("Interrupted; finished work is kept, run the same command again to resume.", err=True)
        sys.exit(128 + received[0])
