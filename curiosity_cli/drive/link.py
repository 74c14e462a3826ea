"""The host side of the wire protocol over a serial port (pyserial; URLs accepted).

One background thread owns the port after :meth:`RobotLink.open`: it reads and decodes
what the robot sends, resends an unacknowledged frame, sends PING when there is nothing
new to command, and declares the link lost when resends run out or the port fails. The
driver's thread only hands it the newest velocity command (:meth:`RobotLink.command`)
and reads the newest STATE. At most one host frame is in flight at a time; a newer
command waits for the in-flight one to be answered and replaces any command already
waiting, so a slow link never builds a queue of stale commands.

SEQs count the frames on the wire (PROTOCOL.md section 2): a waiting command holds the
next SEQ, a command that replaces it takes that SEQ over, and a waiting command dropped
by STOP, ESTOP or a lost link gives its SEQ back, so the robot sees no gap.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Callable

from curiosity_cli.drive import protocol
from curiosity_cli.drive.protocol import Ack, Estop, Hello, Nak, Ping, Refused, State, Stop, Vel
from curiosity_cli.errors import CuriosityError

# How long one read waits for bytes: bounds how late a resend or keepalive can be.
_POLL_SECONDS = 0.005
# ACK latencies kept for the driver's log rows, which ask for the newest ones only.
_KEPT_LATENCIES = 1024


class LinkError(CuriosityError):
    """The robot cannot be driven: port trouble, no handshake, or the link was lost."""


@dataclass(frozen=True)
class LinkTiming:
    """The protocol's timings (s), from the ``drive`` config.

    Attributes
    ----------
    hello_timeout : float
        The robot must answer HELLO with version 1 within this time.
    ack_timeout : float
        A host frame not ACKed within this time is resent.
    resends : int
        Resends of one frame before the link is declared lost.
    keepalive : float
        Most time between two host frames; PING fills the gaps.
    """

    hello_timeout: float
    ack_timeout: float
    resends: int
    keepalive: float


@dataclass
class LinkStats:
    """Counters since the link opened (read them from the driver's thread)."""

    sent: int = 0
    resent: int = 0
    acked: int = 0
    naks: int = 0
    refused_lines: int = 0
    states: int = 0
    ack_latencies: dict = field(default_factory=dict)  # seq of a recent VEL -> seconds to its ACK


@dataclass
class _InFlight:
    frame: object
    line: bytes
    first_sent: float
    last_sent: float
    transmissions: int
    acked: bool = False  # a HELLO's ACK came; it stays in flight until the robot's HELLO reply


class RobotLink:
    """A handshaken connection to a robot; use :meth:`open`.

    Parameters
    ----------
    port : serial.SerialBase
        An open pyserial port (or URL handler) with a short read timeout.
    timing : LinkTiming
    log : callable, optional
        ``log(event, **fields)`` for what happens on the link (resends, refused lines,
        NAK, ESTOP, STOP); called from the link's thread.
    """

    def __init__(self, port, timing: LinkTiming, log: Callable[..., None] = lambda event, **fields: None):
        self._port = port
        self._timing = timing
        self._log = log
        self._parser = protocol.LineParser("host")
        self._lock = threading.Lock()
        self._seq = 0
        self._inflight: _InFlight | None = None
        self._waiting: object | None = None
        self._last_tx = 0.0
        self._commanding = False  # after the handshake, until STOP or ESTOP: keepalives flow
        self._hello_seq: int | None = None
        self._hello_reply = threading.Event()
        self._robot_hello: Hello | None = None
        self._stop_done = threading.Event()
        self._stop_seq: int | None = None
        self._stop_acked = False
        self._state: State | None = None
        self._new_state = threading.Condition(self._lock)
        self._estop: Estop | None = None
        self._error: str | None = None
        self._closing = threading.Event()
        self.stats = LinkStats()
        self._thread = threading.Thread(target=self._run, name="robot-link", daemon=True)

    # ------------------------------------------------------------------ opening

    @classmethod
    def open(cls, url: str, baud: int, timing: LinkTiming, log: Callable[..., None] = lambda event, **fields: None):
        """Open ``url`` (a device such as ``/dev/ttyUSB0`` or a pyserial URL), 8N1, and handshake.

        Returns
        -------
        RobotLink
            Running, with :attr:`robot_name` set.

        Raises
        ------
        LinkError
            The port cannot be opened, or the robot does not answer HELLO with protocol
            version 1 within ``timing.hello_timeout``. The port is closed again.
        """
        import serial

        try:
            port = serial.serial_for_url(
                url,
                baudrate=baud,
                bytesize=serial.EIGHTBITS,
                parity=serial.PARITY_NONE,
                stopbits=serial.STOPBITS_ONE,
                timeout=_POLL_SECONDS,
                write_timeout=timing.ack_timeout,
            )
        except (serial.SerialException, ValueError, OSError) as exc:
            raise LinkError(f"serial port {url}: cannot open it ({_one_line(exc)})") from None
        link = cls(port, timing, log)
        try:
            link._handshake(url)
        except BaseException:
            link._shut()
            raise
        return link

    def _handshake(self, url: str) -> None:
        self._thread.start()
        with self._lock:
            self._hello_seq = self._seq
            self._transmit(Hello(self._take_seq(), protocol.PROTOCOL_VERSION))
        answered = self._hello_reply.wait(self._timing.hello_timeout)
        with self._lock:
            reply = self._robot_hello
            if self._error is None and not answered:
                self._fail(
                    f"the robot did not answer HELLO within {self._timing.hello_timeout:g} s (is a robot speaking "
                    f"protocol version {protocol.PROTOCOL_VERSION} on this port, at this baud rate?)"
                )
            elif self._error is None and reply.version != protocol.PROTOCOL_VERSION:
                self._fail(
                    f"the robot speaks protocol version {reply.version}; "
                    f"this host speaks version {protocol.PROTOCOL_VERSION}"
                )
            if self._error is not None:
                raise LinkError(f"serial port {url}: {self._error}")
            self._commanding = True

    # ------------------------------------------------------------------ the driver's side

    @property
    def robot_name(self) -> str:
        return self._robot_hello.name if self._robot_hello else ""

    @property
    def error(self) -> str | None:
        """Why the link was lost (the thread already attempted STOP), or None."""
        with self._lock:
            return self._error

    @property
    def estop(self) -> Estop | None:
        """The robot's ESTOP, once received; the link then sends nothing but the final STOP."""
        with self._lock:
            return self._estop

    def command(self, surge: float, yaw_rate: float, pitch_rate: float) -> int | None:
        """Send a velocity command as soon as no other frame is in flight.

        Returns
        -------
        int or None
            The SEQ the command is sent with (a command replaced while it waits shares
            its SEQ with the one that replaced it); None when the link no longer commands
            (after ESTOP, STOP or a failure).
        """
        with self._lock:
            if not self._commanding or self._error is not None:
                return None
            if self._inflight is None:
                frame = Vel(self._take_seq(), surge, yaw_rate, pitch_rate)
                self._transmit(frame)
            else:
                seq = self._take_seq() if self._waiting is None else self._waiting.seq
                frame = self._waiting = Vel(seq, surge, yaw_rate, pitch_rate)
            return frame.seq

    def state(self) -> State | None:
        """The newest STATE, or None before the first."""
        with self._lock:
            return self._state

    def wait_state(self, newer_than: State | None, timeout: float) -> State | None:
        """Block until a STATE other than ``newer_than`` arrives (or ``timeout`` s pass); return the newest."""
        deadline = time.monotonic() + timeout
        with self._new_state:
            while self._state is newer_than and self._error is None and self._estop is None:
                left = deadline - time.monotonic()
                if left <= 0:
                    break
                self._new_state.wait(left)
            return self._state

    def ack_latency(self, seq: int | None) -> float | None:
        """Seconds from the first transmission of VEL ``seq`` to its ACK, if it came."""
        with self._lock:
            return self.stats.ack_latencies.get(seq)

    def close(self) -> bool:
        """Send STOP (resent like any frame), wait for its answer, stop the thread, close the port.

        Safe to call more than once and after a failure (the thread then already
        attempted STOP).

        Returns
        -------
        bool
            True when the robot ACKed the STOP.
        """
        if self._thread.is_alive():
            with self._lock:
                if self._error is None and self._stop_seq is None:
                    self._commanding = False
                    self._drop_waiting()
                    self._inflight = None  # STOP goes out now, not after a stale command
                    self._stop_seq = self._seq
                    self._transmit(Stop(self._take_seq()))
                    self._log("stop", seq=self._stop_seq)
            patience = self._timing.ack_timeout * (self._timing.resends + 1) + 0.5
            self._stop_done.wait(patience)
        self._shut()
        return self._stop_acked

    def _shut(self) -> None:
        self._closing.set()
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join()
        try:
            self._port.close()
        except OSError:
            pass

    # ------------------------------------------------------------------ the link's thread

    def _take_seq(self) -> int:
        seq = self._seq
        self._seq = protocol.next_seq(seq)
        return seq

    def _drop_waiting(self) -> None:
        """Forget the waiting command (lock held) and give back its SEQ, the newest taken: it was never sent."""
        if self._waiting is not None:
            self._seq = self._waiting.seq
            self._waiting = None

    def _transmit(self, frame) -> None:
        """Send a new frame (lock held); it becomes the one in flight."""
        line = protocol.encode(frame)
        now = time.monotonic()
        self._inflight = _InFlight(frame, line, now, now, 1)
        self._write(line, now)
        self.stats.sent += 1

    def _write(self, line: bytes, now: float) -> None:
        # a write error surfaces in the thread's loop (the port is broken for reading too)
        try:
            self._port.write(line)
        except Exception as exc:  # noqa: BLE001 - any port failure ends the link the same way
            self._fail(f"writing to the robot failed ({_one_line(exc)})")
            return
        self._last_tx = now

    def _run(self) -> None:
        import serial

        while not self._closing.is_set():
            try:
                data = self._port.read(max(1, self._port.in_waiting))
            except (serial.SerialException, OSError) as exc:
                with self._lock:
                    if not self._closing.is_set():
                        self._fail(f"the robot disconnected ({_one_line(exc)})")
                return
            with self._lock:
                for item in self._parser.feed(data):
                    self._receive(item)
                self._tick(time.monotonic())
                if self._error is not None:
                    return

    def _receive(self, item) -> None:
        inflight = self._inflight
        if isinstance(item, Refused):
            self.stats.refused_lines += 1
            self._log("refused", reason=item.reason, line=item.line.decode("ascii", "replace"))
        elif isinstance(item, State):
            self._state = item
            self.stats.states += 1
            self._new_state.notify_all()
        elif isinstance(item, Ack):
            if inflight is None or item.seq != inflight.frame.seq:
                return  # the ACK of a frame already answered (its resend crossed the first ACK)
            if isinstance(inflight.frame, Hello):  # answered by the robot's reply; an ACK alone: the reply was lost
                self.stats.acked += not inflight.acked  # a resend's ACK again is not another frame ACKed
                inflight.acked = True
                return
            self.stats.acked += 1
            if isinstance(inflight.frame, Vel):
                latencies = self.stats.ack_latencies
                latencies[item.seq] = time.monotonic() - inflight.first_sent
                if len(latencies) > _KEPT_LATENCIES:
                    del latencies[next(iter(latencies))]  # the oldest: a run may last for hours
            self._answered(item.seq)
        elif isinstance(item, Nak):
            if inflight is None or item.seq != inflight.frame.seq:
                return
            self.stats.naks += 1
            self._log("nak", seq=item.seq, reason=item.reason, frame=type(inflight.frame).__name__.upper())
            self._answered(item.seq)
        elif isinstance(item, Hello):
            if item.seq == self._hello_seq and self._robot_hello is None:
                self._robot_hello = item
                self._hello_reply.set()
                if inflight is not None and isinstance(inflight.frame, Hello):
                    self._answered(item.seq)
        elif isinstance(item, Estop):
            if self._estop is None:
                self._estop = item
                self._commanding = False
                self._drop_waiting()
                self._log("estop", seq=item.seq, reason=item.reason)
                self._new_state.notify_all()

    def _answered(self, seq: int) -> None:
        self._inflight = None
        if seq == self._stop_seq:
            self._stop_acked = True
            self._stop_done.set()
        elif self._waiting is not None and self._commanding:
            frame, self._waiting = self._waiting, None
            self._transmit(frame)

    def _tick(self, now: float) -> None:
        inflight = self._inflight
        if inflight is not None and now - inflight.last_sent >= self._timing.ack_timeout:
            if inflight.transmissions <= self._timing.resends:
                inflight.transmissions += 1
                inflight.last_sent = now
                self.stats.resent += 1
                self._log("resend", seq=inflight.frame.seq, frame=type(inflight.frame).__name__.upper())
                self._write(inflight.line, now)
            elif isinstance(inflight.frame, Hello):
                self._inflight = None  # the handshake's own deadline decides
            elif isinstance(inflight.frame, Stop):
                self._inflight = None
                self._stop_done.set()
            else:
                name = type(inflight.frame).__name__.upper()
                self._fail(
                    f"no ACK for {name} {inflight.frame.seq} after {inflight.transmissions} transmissions "
                    f"{self._timing.ack_timeout * 1000:g} ms apart: link lost"
                )
        elif inflight is None and self._commanding and now - self._last_tx >= self._timing.keepalive:
            self._transmit(Ping(self._take_seq()))

    def _fail(self, reason: str) -> None:
        """Declare the link lost (lock held): attempt one STOP, stop commanding."""
        if self._error is not None:
            return
        self._error = reason
        self._commanding = False
        self._drop_waiting()
        self._inflight = None
        self._new_state.notify_all()
        stop = Stop(self._take_seq())
        try:
            self._port.write(protocol.encode(stop))
            outcome = "written"
        except Exception as exc:  # noqa: BLE001 - the port may be gone; the attempt is what counts
            outcome = f"failed: {_one_line(exc)}"
        self._log("link-lost", reason=reason, stop_seq=stop.seq, stop=outcome)
        self._stop_done.set()


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__
