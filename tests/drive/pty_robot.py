"""A scripted robot on a real pseudo-terminal, for testing the host's link (no mocks of pyserial).

The host under test opens the pty's slave end with pyserial as it would a USB serial
adapter; this thread reads the master end, records every line, and answers as the
``respond`` function says.
"""

from __future__ import annotations

import os
import select
import threading
import time
import tty

from curiosity_cli.drive import protocol
from curiosity_cli.drive.protocol import Ack, Hello

#: How long tests wait for something that should take milliseconds (a loaded CI machine).
PATIENCE = 10.0


def polite(frame) -> list:
    """A well-behaved robot's answers: ACK everything, answer HELLO with version 1."""
    if isinstance(frame, Hello):
        return [Ack(frame.seq), Hello(frame.seq, 1, "pty-robot")]
    return [Ack(frame.seq)]


class PtyRobot(threading.Thread):
    """Serves the master end of a fresh pty pair; :attr:`port` is the slave's path.

    Parameters
    ----------
    respond : callable
        ``respond(frame) -> list`` of frames (or raw ``bytes`` lines) to send back for
        each decoded host frame.
    """

    def __init__(self, respond=polite):
        super().__init__(daemon=True)
        self.master, self._slave = os.openpty()
        tty.setraw(self._slave)
        self.port = os.ttyname(self._slave)
        self._respond = respond
        self._halt = threading.Event()
        self._lock = threading.Lock()
        self.received = []  # (monotonic time, frame or Refused)
        self.start()

    def frames(self, kind=None) -> list:
        with self._lock:
            return [f for _, f in self.received if kind is None or isinstance(f, kind)]

    def times(self, kind) -> list[float]:
        with self._lock:
            return [t for t, f in self.received if isinstance(f, kind)]

    def send(self, *items) -> None:
        for item in items:
            os.write(self.master, item if isinstance(item, bytes) else protocol.encode(item))

    def wait_for(self, condition, timeout: float = PATIENCE) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if condition():
                return True
            time.sleep(0.01)
        return condition()

    def run(self) -> None:
        parser = protocol.LineParser("robot")
        while not self._halt.is_set():
            ready, _, _ = select.select([self.master], [], [], 0.02)
            if not ready:
                continue
            try:
                data = os.read(self.master, 4096)
            except OSError:
                continue
            for item in parser.feed(data):
                with self._lock:
                    self.received.append((time.monotonic(), item))
                if not isinstance(item, protocol.Refused):
                    self.send(*self._respond(item))

    def close(self) -> None:
        """Hang up: stop serving and close both ends (again: nothing)."""
        if self._halt.is_set():
            return
        self._halt.set()
        self.join()
        os.close(self.master)
        os.close(self._slave)
