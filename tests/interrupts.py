"""A pytest plugin: Ctrl-C and SIGTERM stop the test run, even inside code that handles them itself.

Python raises KeyboardInterrupt on SIGINT and pytest stops on it (exit code 2), but code under
test may take the signal first: ``drive`` and ``simrobot`` route SIGINT and SIGTERM to their
own handler while they run (they stop between frames, and the test goes on), and typer turns
a KeyboardInterrupt inside a ``CliRunner`` into exit code 130 (a failed test, and the run goes
on). So this plugin

- makes SIGTERM raise KeyboardInterrupt, as SIGINT does, so that a cancelled CI job or
  ``timeout`` ends the run with pytest's summary rather than killing it silently;
- has Python write every signal it receives to a pipe (:func:`signal.set_wakeup_fd`, which
  sees a signal whatever handler takes it), and after each test stops the run with exit
  code 2 when SIGINT or SIGTERM arrived during it;
- puts back the SIGINT and SIGTERM handlers a test left changed;
- in a run of several worker processes (pytest-xdist's ``-n``), passes a SIGTERM the controlling
  process receives on to its workers, so that each stops its test as a run of one process
  does (a command a test started is stopped with it) rather than being killed when the
  controller gives up waiting on it. Ctrl-C reaches every process of the terminal's group
  already.

``tests/conftest.py`` takes its hooks; a pytest of its own loads it with ``-p interrupts``
(``tests/drive/test_interrupts.py``).
"""

from __future__ import annotations

import os
import signal

import pytest

STOPPING = (signal.SIGINT, signal.SIGTERM)
#: The pipe's ends while a session runs, and what the session found: SIGTERM's handler and the wakeup file.
_pipe: tuple[int, int] | None = None
_before: tuple = ()


def pytest_sessionstart(session: pytest.Session) -> None:
    global _pipe, _before
    _pipe = os.pipe()
    for end in _pipe:
        os.set_blocking(end, False)
    controller = session.config.pluginmanager.has_plugin("dsession")  # xdist's, in the process that runs no test
    _before = (signal.signal(signal.SIGTERM, _to_workers_too if controller else signal.default_int_handler), _arm())


def pytest_sessionfinish(session: pytest.Session) -> None:
    global _pipe
    handler, wakeup = _before
    signal.signal(signal.SIGTERM, handler)
    signal.set_wakeup_fd(wakeup)
    for end in _pipe:
        os.close(end)
    _pipe = None


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None):
    _arm()  # again for each test: an asyncio event loop that handled signals resets the wakeup file as it closes
    handlers = {signum: signal.getsignal(signum) for signum in STOPPING}
    try:
        reports = yield
    finally:  # a KeyboardInterrupt that reached pytest goes on from here as it came
        for signum, handler in handlers.items():
            if signal.getsignal(signum) is not handler:
                signal.signal(signum, handler)
    received = _received()
    if received is not None:
        pytest.exit(f"{received.name} during {item.nodeid}; the run stops", returncode=pytest.ExitCode.INTERRUPTED)
    return reports


def _to_workers_too(signum: int, frame) -> None:
    """SIGTERM in the controlling process of an xdist run: sent on to its workers, then KeyboardInterrupt here."""
    import psutil

    for worker in psutil.Process().children():
        try:
            worker.send_signal(signum)
        except psutil.Error:
            pass  # gone already
    raise KeyboardInterrupt


def _arm() -> int:
    """Have Python write each signal's number to the pipe; returns the file it wrote to before (-1: none)."""
    return signal.set_wakeup_fd(_pipe[1], warn_on_full_buffer=False)


def _received() -> signal.Signals | None:
    """SIGINT or SIGTERM if either reached this process since the last call (the pipe is emptied)."""
    numbers = b""
    while True:
        try:
            chunk = os.read(_pipe[0], 512)
        except BlockingIOError:
            break
        if not chunk:
            break
        numbers += chunk
    return next((signal.Signals(n) for n in numbers if n in STOPPING), None)
