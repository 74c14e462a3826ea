"""The simulated robot through a real pseudo-terminal, with pyserial as the host."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import serial
from pty_robot import PATIENCE

from curiosity_cli.drive import protocol
from curiosity_cli.drive.protocol import Ack, Estop, Hello, Nak, Ping, Refused, State, Stop, Vel
from curiosity_cli.drive.sim import Body, Pose
from curiosity_cli.drive.simrobot import DECOY_POSITION, Noise, SimRobot, open_pty
from curiosity_cli.errors import CuriosityError

CURIOSITY = str(Path(sys.executable).parent / "curiosity")


class Host:
    """The test's side of the line: pyserial on the pty's slave, and a parser."""

    def __init__(self, port: str):
        self.port = serial.serial_for_url(port, baudrate=115200, timeout=0.02)
        self.parser = protocol.LineParser("host")
        self.seq = 0
        self.received = []

    def send(self, frame) -> None:
        self.port.write(protocol.encode(frame))

    def next_seq(self) -> int:
        self.seq += 1
        return self.seq

    def collect(self, seconds: float) -> list:
        deadline = time.monotonic() + seconds
        got = []
        while time.monotonic() < deadline:
            got += self.parser.feed(self.port.read(4096))
        self.received += got
        return got

    def until(self, condition, timeout: float = PATIENCE) -> list:
        deadline = time.monotonic() + timeout
        got = []
        while time.monotonic() < deadline:
            got += self.parser.feed(self.port.read(4096))
            if condition(got):
                break
        self.received += got
        return got


@pytest.fixture
def sim():
    """A SimRobot serving a pty in a thread: yields (robot, host, events)."""
    master, slave, path = open_pty()
    stop = threading.Event()
    events = []
    made = {}

    def start(**options):
        body = Body((1000, 1000), 0.01, Pose(5.0, 5.0, 0.0))
        robot = SimRobot(body, state_rate=10.0, watchdog=1.0, log=lambda e, **f: events.append((e, f)), **options)
        thread = threading.Thread(target=robot.serve, args=(master, stop.is_set), daemon=True)
        thread.start()
        made.update(thread=thread, host=Host(path))
        return robot, made["host"], events

    yield start
    stop.set()
    if made:
        made["thread"].join()
        made["host"].port.close()
    os.close(master)
    os.close(slave)


def test_hello_is_answered_and_every_valid_frame_acked(sim):
    robot, host, _ = sim()
    host.send(Hello(0, 1))
    got = host.until(lambda g: any(isinstance(f, Hello) for f in g))
    assert Ack(0) in got and Hello(0, 1, "curiosity-sim") in got
    for frame in (Vel(1, 0.2, 0.1, 0.3), Ping(2), Stop(3)):
        host.send(frame)
        assert Ack(frame.seq) in host.until(lambda g, s=frame.seq: Ack(s) in g)


def test_vel_before_hello_and_unknown_frames_get_a_nak(sim):
    robot, host, _ = sim()
    host.send(Vel(5, 0.2, 0.0, 0.0))
    assert Nak(5, "NO_HELLO") in host.until(lambda g: any(isinstance(f, Nak) for f in g))
    host.port.write(b"$FLY,6*" + f"{protocol.checksum(b'FLY,6'):02X}".encode() + b"\n")
    assert Nak(6, "UNKNOWN_TYPE") in host.until(lambda g: Nak(6, "UNKNOWN_TYPE") in g)
    host.port.write(b"$STOP,7*00\n")  # bad checksum: ignored, not answered
    host.send(Stop(8))
    got = host.until(lambda g: Ack(8) in g)
    assert Ack(7) not in got and Nak(7, "BAD_CHECKSUM") not in got


def test_state_reports_the_commanded_motion(sim):
    robot, host, _ = sim()
    host.send(Hello(0, 1))
    host.send(Vel(1, 0.5, 0.0, 0.0))
    host.until(lambda g: Ack(1) in g)
    first = host.until(lambda g: any(isinstance(f, State) for f in g))[-1]
    # keep the watchdog fed while the robot drives east
    for seq in range(2, 6):
        host.send(Ping(seq))
        host.collect(0.1)
    later = [f for f in host.received if isinstance(f, State)][-1]
    assert later.x > first.x and later.y == first.y == 5.0 and later.t > first.t


@pytest.mark.slow
def test_noise_corrupts_the_line_but_every_frame_that_decodes_is_genuine(sim):
    robot, host, events = sim(noise=Noise(garbage=0.3, checksum=0.3, truncate=0.1), seed=4)
    host.send(Hello(0, 1))
    got = host.collect(1.5)  # about 15 STATE frames, with noise around them
    kinds = {f["kind"] for e, f in events if e == "noise"}
    assert {"garbage", "checksum"} <= kinds
    assert any(isinstance(f, Refused) for f in got)
    states = [f for f in got if isinstance(f, State)]
    assert states and all(s.x != DECOY_POSITION for s in states)
    assert not any(isinstance(f, Estop) for f in got)


def test_dropped_acks_are_dropped(sim):
    robot, host, events = sim(noise=Noise(drop_ack=1.0))
    host.send(Hello(0, 1))
    got = host.until(lambda g: any(isinstance(f, Hello) for f in g))
    assert Ack(0) not in got and ("noise", {"kind": "drop-ack", "seq": 0}) in events


def test_estop_after_the_first_vel_refuses_later_vel(sim):
    robot, host, events = sim(estop_after=0.2)
    host.send(Hello(0, 1))
    host.send(Vel(1, 0.3, 0.0, 0.0))
    got = host.until(lambda g: any(isinstance(f, Estop) for f in g))
    assert [f.reason for f in got if isinstance(f, Estop)] == ["SIMULATED"]
    host.send(Vel(2, 0.3, 0.0, 0.0))
    assert Nak(2, "ESTOPPED") in host.until(lambda g: Nak(2, "ESTOPPED") in g)


@pytest.mark.parametrize(
    "text, message",
    [
        ("garbage=2", "^noise 'garbage=2': expected a rate between 0 and 1"),
        ("static=0.1", "expected KIND=RATE with KIND one of garbage, checksum, truncate, drop-ack"),
        ("checksum", "expected KIND=RATE"),
        ("truncate=x", "expected a rate between 0 and 1"),
    ],
)
def test_bad_noise_specs_are_refused(text, message):
    with pytest.raises(CuriosityError, match=message):
        Noise.parse(text)
    assert Noise.parse("drop-ack=0.5, garbage=0.1") == Noise(garbage=0.1, drop_ack=0.5)


@pytest.mark.slow
def test_the_watchdog_stops_the_simulated_robot_when_the_host_goes_silent(tmp_path):
    """`curiosity simrobot` as its own process; the test is the host, then falls silent."""
    log = tmp_path / "sim.jsonl"
    process = subprocess.Popen(
        [CURIOSITY, "simrobot", "--map", "reef-mosaic", "--log", str(log)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        port = process.stdout.readline().strip()
        assert port.startswith("/dev/"), process.stderr.read()
        host = Host(port)
        host.send(Hello(0, 1))
        host.send(Vel(1, 0.4, 0.2, 0.0))
        host.until(lambda g: Ack(1) in g)
        moving = [f for f in host.collect(0.5) if isinstance(f, State)]  # 0.5 s < the 1 s watchdog
        assert moving[-1].x != moving[0].x
        host.collect(2.5)  # silent: the watchdog fires after 1 s
        stopped = [f for f in host.collect(1.0) if isinstance(f, State)]
        assert len(stopped) >= 3 and len({(s.x, s.y, s.heading) for s in stopped}) == 1
        host.port.close()
    finally:
        process.terminate()
        _, stderr = process.communicate(timeout=PATIENCE * 3)
    assert process.returncode == 143, stderr  # 128 + SIGTERM, as a stopped process
    assert "simrobot: stopped by SIGTERM" in stderr
    events = [json.loads(line) for line in log.read_text().splitlines()]
    watchdog = [e for e in events if e["event"] == "watchdog"]
    # it fires once silence exceeds 1 s; the log rounds to ms, so 1.0004 s reads 1.0
    assert len(watchdog) == 1 and watchdog[0]["silent"] >= 1.0
