"""The wire protocol: encoding, strict decoding, the stream parser; fuzzed with hypothesis."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from curiosity_cli.drive import protocol
from curiosity_cli.drive.protocol import (
    MAX_LINE,
    Ack,
    Estop,
    Hello,
    LineParser,
    Nak,
    Ping,
    Refused,
    State,
    Stop,
    Vel,
    checksum,
    decode,
    encode,
)

#: The repository this test checks.
PROJECT_ROOT = Path(__file__).resolve().parents[2]

FUZZ = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def test_checksum_is_the_xor_of_the_payload():
    assert checksum(b"ACK,1") == 0x41 ^ 0x43 ^ 0x4B ^ 0x2C ^ 0x31 == 0x54
    assert encode(Ack(1)) == b"$ACK,1*54\n"


@pytest.mark.parametrize(
    "frame, receiver",
    [
        (Hello(0, 1), "robot"),
        (Hello(7, 1, "aqua-2"), "host"),
        (Vel(1, 0.3, -0.25, 0.0), "robot"),
        (Stop(65535), "robot"),
        (Ping(2), "robot"),
        (Ack(3), "host"),
        (Nak(4, "NO_HELLO"), "host"),
        (State(5, 12.5, 6.0, -17.25, 3.1416, 2.5), "host"),
        (Estop(6, "LEAK"), "host"),
    ],
)
def test_every_frame_type_round_trips(frame, receiver):
    assert decode(encode(frame)[:-1], receiver) == frame


def test_crlf_is_accepted_and_numbers_are_plain_decimals():
    assert decode(b"$ACK,1*54\r", "host") == Ack(1)
    assert encode(Vel(9, 1e-5, -0.0, 100.0)) == b"$VEL,9,0,0,100*" + f"{checksum(b'VEL,9,0,0,100'):02X}".encode() + b"\n"


def line(payload: bytes) -> bytes:
    """A line with a correct checksum around any payload."""
    return b"$" + payload + b"*" + f"{checksum(payload):02X}".encode()


@pytest.mark.parametrize(
    "raw, receiver, reason, seq",
    [
        (b"ACK,1*54", "host", "NO_DOLLAR", None),
        (b"x$ACK,1*54", "host", "NO_DOLLAR", None),
        (b"$ACK,1*55", "host", "BAD_CHECKSUM", None),
        (b"$ACK,1*54 ", "host", "NO_CHECKSUM", None),
        (b"$ACK,1*5", "host", "NO_CHECKSUM", None),
        (b"$ACK,1*5a", "host", "NO_CHECKSUM", None),
        (b"$ACK,1", "host", "NO_CHECKSUM", None),
        (line(b"ACK,\x01"), "host", "BAD_CHARACTERS", None),
        (line(b"ACK,65536"), "host", "BAD_HEADER", None),
        (line(b"ACK,007"), "host", "BAD_HEADER", None),
        (line(b"ACK,-1"), "host", "BAD_HEADER", None),
        (line(b"ACK"), "host", "BAD_HEADER", None),
        (line(b"ack,1"), "host", "BAD_HEADER", None),
        (line(b"$" * 130), "host", "TOO_LONG", None),
        (line(b"VEL,1,0,0,0"), "host", "UNKNOWN_TYPE", 1),
        (line(b"STATE,2,0,0,0,0,0"), "robot", "UNKNOWN_TYPE", 2),
        (line(b"FLY,3"), "robot", "UNKNOWN_TYPE", 3),
        (line(b"VEL,4,0,0"), "robot", "BAD_FIELDS", 4),
        (line(b"VEL,5,0,0,nan"), "robot", "BAD_FIELDS", 5),
        (line(b"VEL,6,1e3,0,0"), "robot", "BAD_FIELDS", 6),
        (line(b"VEL,7,+1,0,0"), "robot", "BAD_FIELDS", 7),
        (line(b"VEL,8,1.,0,0"), "robot", "BAD_FIELDS", 8),
        (line(b"VEL,9, 1,0,0"), "robot", "BAD_FIELDS", 9),
        (line(b"PING,10,1"), "robot", "BAD_FIELDS", 10),
        (line(b"HELLO,11,1,NAME"), "robot", "BAD_FIELDS", 11),
        (line(b"HELLO,12,1"), "host", "BAD_FIELDS", 12),
        (line(b"NAK,13"), "host", "BAD_FIELDS", 13),
    ],
)
def test_anything_but_a_well_formed_frame_is_refused_with_a_reason(raw, receiver, reason, seq):
    result = decode(raw, receiver)
    assert isinstance(result, Refused) and (result.reason, result.seq) == (reason, seq)
    assert result.reason in protocol.REFUSALS


def test_a_line_of_exactly_128_bytes_is_accepted_and_129_refused():
    name = "n" * (MAX_LINE - len(b"$HELLO,1,1,*00\n"))
    assert len(encode(Hello(1, 1, name))) == MAX_LINE
    assert decode(encode(Hello(1, 1, name))[:-1], "host") == Hello(1, 1, name)
    with pytest.raises(ValueError, match="at most 128"):
        encode(Hello(1, 1, name + "n"))
    assert decode(line(b"HELLO,1,1," + name.encode() + b"n"), "host").reason == "TOO_LONG"
    # with "\r\n" the same frame is one byte too long
    assert decode(encode(Hello(1, 1, name))[:-1] + b"\r", "host").reason == "TOO_LONG"


@pytest.mark.parametrize(
    "frame, message",
    [
        (Ack(65536), "seq"),
        (Vel(1, float("nan"), 0, 0), "number"),
        (Vel(1, 2e9, 0, 0), "number"),
        (Nak(1, "A,B"), "reason"),
        (Estop(1, ""), "reason"),
        (Hello(1, 1, "été"), "name"),
    ],
)
def test_encode_refuses_what_the_wire_cannot_carry(frame, message):
    with pytest.raises(ValueError, match=message):
        encode(frame)


def test_the_parser_cuts_lines_across_chunks_and_drops_overlong_ones():
    parser = LineParser("host")
    data = encode(Ack(1)) + b"junk\n" + b"z" * 300 + b"\n" + encode(State(2, 1, 2, 3, 0, 0))
    out = []
    for i in range(0, len(data), 7):
        out += parser.feed(data[i : i + 7])
    assert out[0] == Ack(1) and out[-1] == State(2, 1.0, 2.0, 3.0, 0.0, 0.0)
    assert [r.reason for r in out[1:-1]] == ["NO_DOLLAR", "TOO_LONG"]
    assert parser.refused == 2


def test_every_example_line_in_protocol_md_is_a_valid_frame():
    text = (PROJECT_ROOT / "curiosity_cli" / "drive" / "PROTOCOL.md").read_text()
    examples = re.findall(r"([<>]) (\$[^\s`]+)", text)
    assert len(examples) >= 12
    for direction, raw in examples:
        receiver = "robot" if direction == ">" else "host"
        assert not isinstance(decode(raw.encode(), receiver), Refused), raw


# --------------------------------------------------------------------------- fuzzing

_TEXT = st.text(st.characters(min_codepoint=0x20, max_codepoint=0x7E, exclude_characters="$*,"), min_size=1, max_size=12)
_NUMBER = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)
_SEQ = st.integers(0, 65535)
_HOST_FRAMES = st.one_of(
    st.builds(Hello, _SEQ, st.integers(0, 99)),
    st.builds(Vel, _SEQ, _NUMBER, _NUMBER, _NUMBER),
    st.builds(Stop, _SEQ),
    st.builds(Ping, _SEQ),
)
_ROBOT_FRAMES = st.one_of(
    st.builds(Hello, _SEQ, st.integers(0, 99), _TEXT),
    st.builds(Ack, _SEQ),
    st.builds(Nak, _SEQ, _TEXT),
    st.builds(State, _SEQ, _NUMBER, _NUMBER, _NUMBER, _NUMBER, _NUMBER),
    st.builds(Estop, _SEQ, _TEXT),
)
_FRAMES = st.one_of(_HOST_FRAMES.map(lambda f: (f, "robot")), _ROBOT_FRAMES.map(lambda f: (f, "host")))


@FUZZ
@given(st.binary(max_size=200), st.sampled_from(["host", "robot"]))
def test_arbitrary_bytes_never_raise_and_an_accepted_line_is_canonical(raw, receiver):
    result = decode(raw, receiver)
    if not isinstance(result, Refused):
        # accepted: a correct checksum, and the frame reads back the same after re-encoding
        body = raw[:-1] if raw.endswith(b"\r") else raw
        star = body.rindex(b"*")
        assert int(body[star + 1 :], 16) == checksum(body[1:star])
        assert decode(encode(result)[:-1], receiver) == result


@FUZZ
@given(
    st.one_of(
        st.binary(max_size=130),
        # payloads from the protocol's own alphabet reach the field checks more often
        st.text("ACEHKLNOPSTVIG0123456789.,-", max_size=60).map(str.encode),
    ),
    st.sampled_from(["host", "robot"]),
)
def test_lines_with_a_correct_checksum_never_raise_and_an_accepted_one_is_canonical(payload, receiver):
    result = decode(line(payload), receiver)
    if not isinstance(result, Refused):
        assert decode(encode(result)[:-1], receiver) == result


@pytest.mark.slow
@FUZZ
@given(_FRAMES)
def test_encoded_frames_decode_to_themselves_up_to_rounding(pair):
    frame, receiver = pair
    decoded = decode(encode(frame)[:-1], receiver)
    assert type(decoded) is type(frame) and decoded.seq == frame.seq
    for name, value in vars(frame).items():
        if isinstance(value, float):
            # half a unit of the 4th decimal, plus the float error of forming the difference
            assert abs(getattr(decoded, name) - value) <= 0.5e-4 * (1 + 1e-9)
        else:
            assert getattr(decoded, name) == value


@pytest.mark.slow
@FUZZ
@given(_FRAMES, st.data())
def test_every_single_byte_corruption_of_a_frame_is_refused(pair, data):
    frame, receiver = pair
    raw = bytearray(encode(frame)[:-1])
    position = data.draw(st.integers(0, len(raw) - 1))
    new = data.draw(st.integers(0, 255).filter(lambda b: b != raw[position]))
    raw[position] = new
    result = decode(bytes(raw), receiver)
    assert isinstance(result, Refused), (bytes(raw), result)


@pytest.mark.slow
@FUZZ
@given(st.lists(st.one_of(_ROBOT_FRAMES.map(encode), st.binary(max_size=40)), max_size=12), st.data())
def test_the_stream_parser_never_raises_and_chunking_does_not_matter(pieces, data):
    stream = b"".join(pieces)
    whole = LineParser("host").feed(stream)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=8)))
    parser, chunked = LineParser("host"), []
    for start, end in zip([0, *cuts], [*cuts, len(stream)]):
        chunked += parser.feed(stream[start:end])
    assert chunked == whole
    for item in whole:
        assert isinstance(item, Refused) or isinstance(item, (Hello, Ack, Nak, State, Estop))
