"""The simulated robot: the robot side of the protocol on a pseudo-terminal.

:func:`open_pty` makes a pty pair whose slave end is the robot's "serial port" (pass its
path to ``curiosity drive --serial``); :class:`SimRobot` serves the master end: it
answers HELLO, ACKs every valid host frame, integrates the commanded velocities over
the map (:class:`~curiosity_cli.drive.sim.Body`), sends STATE at ``state_rate`` and stops
when no valid host frame arrives for ``watchdog`` seconds. Pitch rate is acknowledged
and ignored (the map is flat); depth is reported as 0.

:class:`Noise` makes the line worse on purpose, on what the robot sends: bursts of
garbage bytes, decoy frames with bad checksums (some of them a STATE far off the map or
an ESTOP, which a host must never act on), truncated lines and dropped ACKs.
"""

from __future__ import annotations

import os
import select
import time
from dataclasses import dataclass, fields
from typing import Callable

import numpy as np

from curiosity_cli.drive import protocol
from curiosity_cli.drive.protocol import Ack, Estop, Hello, Nak, Ping, Refused, State, Stop, Vel
from curiosity_cli.drive.sim import Body
from curiosity_cli.errors import CuriosityError

ROBOT_NAME = "curiosity-sim"
# Integration step bound: the loop wakes at least this often to move the body.
_TICK = 0.01
# Bytes waiting for a reader beyond which they are dropped (nobody has the port open).
_MAX_BACKLOG = 16384
# Where decoy STATE frames put the robot: far off any map, so acting on one shows.
DECOY_POSITION = 9999.0


@dataclass(frozen=True)
class Noise:
    """Rates (0..1) of the simulator's line noise, each per line it sends.

    Attributes
    ----------
    garbage : float
        A burst of 1-24 random bytes before the line (half the bursts end in a line end;
        the others corrupt the line they run into).
    checksum : float
        A decoy frame with a bad checksum before the line: the line with altered
        checksum digits, a STATE at (9999, 9999) m, or an ESTOP.
    truncate : float
        The line cut short (and ended) instead of sent whole: it is lost.
    drop_ack : float
        An ACK not sent at all (per ACK).
    """

    garbage: float = 0.0
    checksum: float = 0.0
    truncate: float = 0.0
    drop_ack: float = 0.0

    @classmethod
    def parse(cls, text: str) -> Noise:
        """``garbage=0.05,checksum=0.05,truncate=0.02,drop-ack=0.02`` (any subset; empty for none).

        Raises
        ------
        CuriosityError
            Naming the bad entry.
        """
        names = {f.name.replace("_", "-"): f.name for f in fields(cls)}
        rates = {}
        for entry in filter(None, (part.strip() for part in text.split(","))):
            key, sep, value = entry.partition("=")
            if not sep or key.strip() not in names:
                raise CuriosityError(
                    f"noise {entry!r}: expected KIND=RATE with KIND one of {', '.join(names)}", parameter="noise"
                )
            try:
                rate = float(value)
            except ValueError:
                rate = -1.0
            if not 0 <= rate <= 1:
                raise CuriosityError(f"noise {entry!r}: expected a rate between 0 and 1", parameter="noise")
            rates[names[key.strip()]] = rate
        return cls(**rates)


def open_pty() -> tuple[int, int, str]:
    """A pseudo-terminal pair in raw mode: ``(master_fd, slave_fd, slave_path)``.

    The caller keeps the slave open too, so a host closing and reopening the port does
    not hang up the master; the master is non-blocking.
    """
    import tty

    master, slave = os.openpty()
    tty.setraw(slave)  # no echo, no line editing, no '\n' -> '\r\n': bytes pass unchanged
    os.set_blocking(master, False)
    return master, slave, os.ttyname(slave)


class SimRobot:
    """The robot side of the protocol over a file descriptor.

    Parameters
    ----------
    body : Body
        Moved by the commanded velocities.
    state_rate : float
        STATE frames per second.
    watchdog : float
        Seconds without a valid host frame after which the robot stops.
    noise : Noise
    seed : int
        Seeds the noise.
    estop_after : float, optional
        Send ESTOP this many seconds after the first VEL (a stand-in for a robot's own
        emergency stop); afterwards VEL is refused with NAK ``ESTOPPED``.
    log : callable, optional
        ``log(event, **fields)``: frames received, NAKs, watchdog stops, ESTOP.
    """

    def __init__(
        self,
        body: Body,
        *,
        state_rate: float,
        watchdog: float,
        noise: Noise = Noise(),
        seed: int = 0,
        estop_after: float | None = None,
        log: Callable[..., None] = lambda event, **fields: None,
    ):
        self.body = body
        self._period = 1.0 / state_rate
        self._watchdog = watchdog
        self._noise = noise
        self._rng = np.random.default_rng(seed)
        self._estop_after = estop_after
        self._log = log
        self._parser = protocol.LineParser("robot")
        self._out = bytearray()
        self._seq = 0
        self._session = False
        self._surge = 0.0
        self._yaw_rate = 0.0
        self._last_valid: float | None = None
        self._first_vel: float | None = None
        self._estopped = False
        self._start = time.monotonic()

    # ------------------------------------------------------------------ serving

    def serve(self, fd: int, should_stop: Callable[[], bool]) -> None:
        """Run until ``should_stop()`` is true (checked at least every 10 ms)."""
        last = time.monotonic()
        next_state = last
        while not should_stop():
            now = time.monotonic()
            wait = max(0.0, min(next_state, last + _TICK) - now)
            readable, writable, _ = select.select([fd], [fd] if self._out else [], [], wait)
            if readable:
                self._read(fd)
            now = time.monotonic()
            self.body.step(self._surge, self._yaw_rate, now - last)
            last = now
            self._check_watchdog(now)
            self._check_estop(now)
            if now >= next_state:
                pose = self.body.pose
                self._send(State(self._take_seq(), now - self._start, pose.x, pose.y, pose.heading, 0.0))
                next_state = max(next_state + self._period, now)
            if self._out or writable:
                self._flush(fd)

    def _read(self, fd: int) -> None:
        try:
            data = os.read(fd, 4096)
        except BlockingIOError:
            return
        except OSError:
            # EIO: no process has the slave open (cannot happen while we hold it; kept
            # so a pty closed under us idles instead of spinning)
            time.sleep(_TICK)
            return
        for item in self._parser.feed(data):
            self._handle(item, time.monotonic())

    def _flush(self, fd: int) -> None:
        if len(self._out) > _MAX_BACKLOG:
            self._log("backlog-dropped", bytes=len(self._out))
            self._out.clear()
            return
        try:
            written = os.write(fd, self._out)
        except BlockingIOError:
            return
        del self._out[:written]

    # ------------------------------------------------------------------ the protocol

    def _take_seq(self) -> int:
        seq = self._seq
        self._seq = protocol.next_seq(seq)
        return seq

    def _handle(self, item, now: float) -> None:
        if isinstance(item, Refused):
            self._log("refused", reason=item.reason, line=item.line.decode("ascii", "replace"))
            if item.seq is not None:
                self._send(Nak(item.seq, item.reason))
            return
        self._last_valid = now
        self._log("rx", frame=type(item).__name__.upper(), seq=item.seq, **_fields_of(item))
        if isinstance(item, Hello):
            self._session = True
            self._send(Ack(item.seq), ack=True)
            self._send(Hello(item.seq, protocol.PROTOCOL_VERSION, ROBOT_NAME))
        elif isinstance(item, Vel):
            if not self._session:
                self._send(Nak(item.seq, "NO_HELLO"))
            elif self._estopped:
                self._send(Nak(item.seq, "ESTOPPED"))
            else:
                self._surge, self._yaw_rate = item.surge, item.yaw_rate
                if self._first_vel is None:
                    self._first_vel = now
                self._send(Ack(item.seq), ack=True)
        elif isinstance(item, Stop):
            self._surge = self._yaw_rate = 0.0
            self._send(Ack(item.seq), ack=True)
        elif isinstance(item, Ping):
            self._send(Ack(item.seq), ack=True)

    def _check_watchdog(self, now: float) -> None:
        moving = self._surge != 0.0 or self._yaw_rate != 0.0
        if moving and self._last_valid is not None and now - self._last_valid > self._watchdog:
            self._surge = self._yaw_rate = 0.0
            self._log("watchdog", silent=round(now - self._last_valid, 3))

    def _check_estop(self, now: float) -> None:
        if self._estop_after is None or self._estopped or self._first_vel is None:
            return
        if now - self._first_vel >= self._estop_after:
            self._estopped = True
            self._surge = self._yaw_rate = 0.0
            self._send(Estop(self._take_seq(), "SIMULATED"))
            self._log("estop", reason="SIMULATED")

    # ------------------------------------------------------------------ sending, with noise

    def _send(self, frame, ack: bool = False) -> None:
        noise, rng = self._noise, self._rng
        if ack and rng.random() < noise.drop_ack:
            self._log("noise", kind="drop-ack", seq=frame.seq)
            return
        line = protocol.encode(frame)
        if rng.random() < noise.garbage:
            burst = rng.integers(0, 256, int(rng.integers(1, 25)), dtype=np.uint8).tobytes()
            self._out += burst + (b"\n" if rng.random() < 0.5 else b"")
            self._log("noise", kind="garbage", bytes=len(burst))
        if rng.random() < noise.checksum:
            self._out += self._decoy(line)
            self._log("noise", kind="checksum")
        if rng.random() < noise.truncate:
            self._out += line[: int(rng.integers(1, len(line) - 1))] + b"\n"
            self._log("noise", kind="truncate", frame=type(frame).__name__.upper(), seq=frame.seq)
            return
        self._out += line

    def _decoy(self, line: bytes) -> bytes:
        """A frame with a wrong checksum: a copy of ``line``, a STATE off the map, or an ESTOP."""
        kind = int(self._rng.integers(3))
        if kind == 1:
            pose = self.body.pose
            line = protocol.encode(State(self._seq, 0.0, DECOY_POSITION, DECOY_POSITION, pose.heading, 0.0))
        elif kind == 2:
            line = protocol.encode(Estop(self._seq, "DECOY"))
        star = line.rindex(b"*")
        wrong = int(line[star + 1 : star + 3], 16) ^ int(self._rng.integers(1, 256))
        return line[: star + 1] + f"{wrong:02X}".encode("ascii") + b"\n"


def _fields_of(frame) -> dict:
    return {f.name: getattr(frame, f.name) for f in fields(frame) if f.name != "seq"}
