"""The wire protocol between the host (``curiosity drive``) and a robot, version 1.

Pure functions and a byte-stream parser, no I/O: :mod:`~curiosity_cli.drive.link` speaks
it for the host, :mod:`~curiosity_cli.drive.simrobot` for the simulated robot. The
normative description, written for firmware authors, is ``PROTOCOL.md`` beside this
file; the names below follow it.

A frame is one ASCII line ``$TYPE,SEQ,FIELD,...*CS\\n`` (``\\r\\n`` accepted), at most
:data:`MAX_LINE` bytes with its line ending; ``CS`` is two upper-case hex digits, the XOR
of every byte between ``$`` and ``*``. Decoding is strict: anything that is not exactly
a frame of a known shape is refused with a reason, and never raises.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

PROTOCOL_VERSION = 1
MAX_LINE = 128
SEQ_MODULUS = 65536

# The payload alphabet: printable ASCII except the three framing characters. Text
# fields (NAME, REASON) also exclude ',' since it separates fields.
_TEXT = re.compile(rb"[\x20-\x7e]+")
_FORBIDDEN_IN_TEXT = frozenset(b"$*,")
_SEQ = re.compile(rb"(0|[1-9][0-9]{0,4})")
# Decimal with '.' as separator: no exponent, no leading '+', no 'nan' or 'inf', so a
# number on the wire is finite by construction.
_NUMBER = re.compile(rb"-?[0-9]{1,9}(\.[0-9]{1,9})?")
_TYPE = re.compile(rb"[A-Z]{2,8}")
_CHECKSUM = re.compile(rb"[0-9A-F]{2}")

# Decimal places when encoding numbers: 1 mm, 1 mrad, 1 ms resolution is plenty for a
# vehicle, and keeps a STATE frame well under MAX_LINE.
_PLACES = 4


# --------------------------------------------------------------------------- frames


@dataclass(frozen=True)
class Hello:
    """``HELLO,seq,version`` from the host; ``HELLO,seq,version,NAME`` from the robot.

    The robot's reply carries the SEQ of the host HELLO it answers.
    """

    seq: int
    version: int
    name: str | None = None


@dataclass(frozen=True)
class Vel:
    """``VEL,seq,surge,yaw_rate,pitch_rate`` (m/s, rad/s, rad/s; body frame, see PROTOCOL.md)."""

    seq: int
    surge: float
    yaw_rate: float
    pitch_rate: float


@dataclass(frozen=True)
class Stop:
    """``STOP,seq``: all velocities to zero until the next VEL."""

    seq: int


@dataclass(frozen=True)
class Ping:
    """``PING,seq``: keeps the robot's watchdog fed when there is nothing new to command."""

    seq: int


@dataclass(frozen=True)
class Ack:
    """``ACK,seq``: the robot accepted the host frame with this SEQ."""

    seq: int


@dataclass(frozen=True)
class Nak:
    """``NAK,seq,REASON``: the robot refused the host frame with this SEQ."""

    seq: int
    reason: str


@dataclass(frozen=True)
class State:
    """``STATE,seq,t,x,y,heading,depth`` telemetry (s, m, m, rad, m)."""

    seq: int
    t: float
    x: float
    y: float
    heading: float
    depth: float


@dataclass(frozen=True)
class Estop:
    """``ESTOP,seq,REASON``: the robot stopped itself; the host must stop commanding."""

    seq: int
    reason: str


#: Frames each side sends: what a host accepts and what a robot accepts.
HOST_TO_ROBOT = ("HELLO", "VEL", "STOP", "PING")
ROBOT_TO_HOST = ("HELLO", "ACK", "NAK", "STATE", "ESTOP")


#: Why a line is refused; the last two concern well-formed frames (a robot NAKs them).
REFUSALS = (
    "TOO_LONG",        # more than MAX_LINE bytes with the line ending
    "NO_DOLLAR",       # the first byte is not '$'
    "NO_CHECKSUM",     # does not end in '*' and two upper-case hex digits
    "BAD_CHARACTERS",  # a byte outside printable ASCII, or '$' or '*' inside
    "BAD_CHECKSUM",    # the XOR does not match
    "BAD_HEADER",      # not TYPE,SEQ with TYPE 2-8 upper-case letters and SEQ 0..65535
    "UNKNOWN_TYPE",    # a TYPE this side does not accept
    "BAD_FIELDS",      # the fields do not match the TYPE
)


@dataclass(frozen=True)
class Refused:
    """A line that is not a frame the receiver accepts.

    Attributes
    ----------
    reason : str
        Why, as one of :data:`REFUSALS` (a robot's NAK carries it as REASON).
    seq : int or None
        The SEQ when the line was a well-formed frame with a valid checksum whose type or
        fields the receiver does not accept: a robot answers it with NAK. None for a
        line that is not a frame at all (bad checksum, bad shape): it is ignored.
    line : bytes
        The line as received (line ending removed), for the log.
    """

    reason: str
    seq: int | None
    line: bytes


# --------------------------------------------------------------------------- encoding


def checksum(payload: bytes) -> int:
    """XOR of every byte of ``payload`` (the bytes between ``$`` and ``*``), 0..255."""
    value = 0
    for byte in payload:
        value ^= byte
    return value


def next_seq(seq: int) -> int:
    """The SEQ after ``seq``: counts 0..65535 and wraps to 0."""
    return (seq + 1) % SEQ_MODULUS


def encode(frame) -> bytes:
    """One frame as its wire line, ``$...*CS\\n``.

    Raises
    ------
    ValueError
        A SEQ outside 0..65535, a non-finite number, a text field that is empty or holds
        ``$ * ,`` or non-printable characters, or a line longer than :data:`MAX_LINE`.
    """
    fields = [_frame_type(frame), _encode_seq(frame.seq)]
    if isinstance(frame, Hello):
        fields.append(str(int(frame.version)))
        if frame.name is not None:
            fields.append(_encode_text(frame.name, "name"))
    elif isinstance(frame, Vel):
        fields += [_encode_number(v) for v in (frame.surge, frame.yaw_rate, frame.pitch_rate)]
    elif isinstance(frame, State):
        fields += [_encode_number(v) for v in (frame.t, frame.x, frame.y, frame.heading, frame.depth)]
    elif isinstance(frame, (Nak, Estop)):
        fields.append(_encode_text(frame.reason, "reason"))
    payload = ",".join(fields).encode("ascii")
    line = b"$" + payload + b"*" + f"{checksum(payload):02X}".encode("ascii") + b"\n"
    if len(line) > MAX_LINE:
        raise ValueError(f"frame: {len(line)} bytes on the wire, expected at most {MAX_LINE}")
    return line


def _frame_type(frame) -> str:
    for name, cls in _CLASSES.items():
        if type(frame) is cls:
            return name
    raise ValueError(f"frame: got {type(frame).__name__}, expected a protocol frame")


def _encode_seq(seq) -> str:
    if isinstance(seq, bool) or not isinstance(seq, int) or not 0 <= seq < SEQ_MODULUS:
        raise ValueError(f"seq: got {seq!r}, expected an integer 0..{SEQ_MODULUS - 1}")
    return str(seq)


def _encode_number(value) -> str:
    value = float(value)
    if not math.isfinite(value) or abs(value) >= 1e9:
        raise ValueError(f"number: got {value!r}, expected a finite number below 1e9 in size")
    text = f"{value:.{_PLACES}f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def _encode_text(text, what: str) -> str:
    raw = text.encode("utf-8") if isinstance(text, str) else b""
    if not raw or not _TEXT.fullmatch(raw) or _FORBIDDEN_IN_TEXT & set(raw):
        raise ValueError(f"{what}: got {text!r}, expected printable ASCII without '$', '*' or ','")
    return raw.decode("ascii")


# --------------------------------------------------------------------------- decoding


def decode(line: bytes, receiver: str):
    """Decode one line (without its ``\\n``; a trailing ``\\r`` is allowed).

    Parameters
    ----------
    line : bytes
    receiver : {"host", "robot"}
        Who reads the line: a host accepts :data:`ROBOT_TO_HOST` frames, a robot
        :data:`HOST_TO_ROBOT` ones (HELLO carries a NAME only from the robot).

    Returns
    -------
    frame or Refused
        A frame dataclass, or :class:`Refused` saying why not. Never raises.
    """
    if len(line) + 1 > MAX_LINE:  # + 1 for the '\\n' already cut off
        return Refused("TOO_LONG", None, line)
    if line.endswith(b"\r"):
        line = line[:-1]
    if not line.startswith(b"$"):
        return Refused("NO_DOLLAR", None, line)
    star = line.rfind(b"*")
    if star < 0 or len(line) - star != 3 or not _CHECKSUM.fullmatch(line[star + 1 :]):
        return Refused("NO_CHECKSUM", None, line)
    payload = line[1:star]
    if not _TEXT.fullmatch(payload) or b"$" in payload or b"*" in payload:
        return Refused("BAD_CHARACTERS", None, line)
    if checksum(payload) != int(line[star + 1 :], 16):
        return Refused("BAD_CHECKSUM", None, line)
    fields = payload.split(b",")
    if not _TYPE.fullmatch(fields[0]) or len(fields) < 2 or not _SEQ.fullmatch(fields[1]):
        return Refused("BAD_HEADER", None, line)
    seq = int(fields[1])
    if seq >= SEQ_MODULUS:
        return Refused("BAD_HEADER", None, line)
    kind = fields[0].decode("ascii")
    if kind not in _ACCEPTED[receiver]:
        return Refused("UNKNOWN_TYPE", seq, line)
    frame = _decode_fields(kind, seq, fields[2:], robot_hello=receiver == "host")
    if frame is None:
        return Refused("BAD_FIELDS", seq, line)
    return frame


def _decode_fields(kind: str, seq: int, fields: list[bytes], robot_hello: bool):
    """The frame of a checked TYPE and SEQ from its remaining fields, or None."""
    if kind == "HELLO":
        if len(fields) != (2 if robot_hello else 1) or not re.fullmatch(rb"[0-9]{1,5}", fields[0]):
            return None
        name = _decode_text(fields[1]) if robot_hello else None
        if robot_hello and name is None:
            return None
        return Hello(seq, int(fields[0]), name)
    if kind in ("STOP", "PING", "ACK"):
        return _CLASSES[kind](seq) if not fields else None
    if kind in ("NAK", "ESTOP"):
        reason = _decode_text(fields[0]) if len(fields) == 1 else None
        return None if reason is None else _CLASSES[kind](seq, reason)
    numbers = [float(f) for f in fields if _NUMBER.fullmatch(f)]
    if len(numbers) != len(fields) or len(fields) != (3 if kind == "VEL" else 5):
        return None
    return _CLASSES[kind](seq, *numbers)


def _decode_text(field: bytes) -> str | None:
    return field.decode("ascii") if _TEXT.fullmatch(field) and not _FORBIDDEN_IN_TEXT & set(field) else None


_ACCEPTED = {"host": ROBOT_TO_HOST, "robot": HOST_TO_ROBOT}
_CLASSES = {
    "HELLO": Hello,
    "VEL": Vel,
    "STOP": Stop,
    "PING": Ping,
    "ACK": Ack,
    "NAK": Nak,
    "STATE": State,
    "ESTOP": Estop,
}


class LineParser:
    """Cuts a byte stream into lines and decodes them; keeps the count of refused lines.

    Bytes arrive in chunks of any size (a serial read returns what is there); a line is
    complete at ``\\n``. A line that grows past :data:`MAX_LINE` without one is dropped
    up to the next ``\\n`` (one refused line), so garbage cannot grow memory.

    Parameters
    ----------
    receiver : {"host", "robot"}
        As for :func:`decode`.
    """

    def __init__(self, receiver: str):
        if receiver not in _ACCEPTED:
            raise ValueError(f"receiver: got {receiver!r}, expected 'host' or 'robot'")
        self._receiver = receiver
        self._buffer = bytearray()
        self._overlong = False
        self.refused = 0

    def feed(self, data: bytes) -> list:
        """Frames and :class:`Refused` lines completed by ``data``, in order."""
        out = []
        self._buffer += data
        while True:
            end = self._buffer.find(b"\n")
            if end < 0:
                if len(self._buffer) >= MAX_LINE:
                    if not self._overlong:
                        out.append(Refused("TOO_LONG", None, bytes(self._buffer[:MAX_LINE])))
                        self.refused += 1
                    self._overlong = True
                    self._buffer.clear()
                return out
            line = bytes(self._buffer[:end])
            del self._buffer[: end + 1]
            if self._overlong:
                # the tail of a line already refused
                self._overlong = False
                continue
            result = decode(line, self._receiver)
            if isinstance(result, Refused):
                self.refused += 1
            out.append(result)
