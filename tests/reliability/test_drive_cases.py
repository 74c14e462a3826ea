"""Reliability of `drive` and `simrobot` (issue 16): non-finite options, valid log lines, SEQs without gaps."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from cli_cases import assert_clean_error, run_cli

sys.path.insert(0, str(Path(__file__).parents[1] / "drive"))  # the scripted pty robot of the drive tests

from pty_robot import PtyRobot, polite  # noqa: E402

from curiosity_cli.drive.jsonlines import JsonLines  # noqa: E402
from curiosity_cli.drive.link import LinkTiming, RobotLink  # noqa: E402
from curiosity_cli.drive.protocol import Ack, Stop, Vel  # noqa: E402

SIM = ["--camera", "sim", "--sim-map", "reef-mosaic"]
RELAXED = LinkTiming(hello_timeout=10.0, ack_timeout=0.5, resends=3, keepalive=0.15)


@pytest.mark.parametrize(
    ("args", "option"),
    [
        (["drive", "--dry-run", *SIM, "--heading-deg", "nan"], "--heading-deg"),
        (["drive", "--dry-run", *SIM, "--heading-deg", "inf"], "--heading-deg"),
        (["simrobot", "--map", "reef-mosaic", "--heading-deg", "nan"], "--heading-deg"),
        (["simrobot", "--map", "reef-mosaic", "--heading-deg", "-inf"], "--heading-deg"),
        (["simrobot", "--map", "reef-mosaic", "--estop-after", "inf"], "--estop-after"),
    ],
)
def test_a_non_finite_number_is_refused_at_the_edge_naming_the_option(tmp_path, args, option):
    outcome = run_cli([*args, "--out", str(tmp_path / "run")] if args[0] == "drive" else args, cwd=tmp_path, timeout=120)
    assert_clean_error(outcome, option, "expected a finite number", code=2)
    assert not (tmp_path / "run").exists()


def test_a_log_file_that_exists_is_refused_not_emptied(tmp_path):
    """Hostile-user F2: ``simrobot --log FILE`` emptied a file of the user's, then served the robot.

    In a process of its own, with a time limit: a simrobot that took the file would serve until stopped.
    """
    (tmp_path / "precious.txt").write_text("precious data\n")
    outcome = run_cli(["simrobot", "--map", "reef-mosaic", "--log", "precious.txt"], cwd=tmp_path, timeout=120)
    assert_clean_error(outcome, "--log: precious.txt exists; expected a new file name")
    assert (tmp_path / "precious.txt").read_text() == "precious data\n"


def test_a_record_that_is_not_finite_is_refused_not_written(tmp_path):
    log = JsonLines(tmp_path / "log.jsonl")
    log.write("start", heading=0.5)
    with pytest.raises(ValueError):
        log.write("frame", heading=float("nan"))
    log.close()
    assert (tmp_path / "log.jsonl").read_text().count("\n") == 1


def _strict_json(line: str) -> dict:
    """``json.loads`` refusing NaN and Infinity, which Python's parser accepts by default."""
    return json.loads(line, parse_constant=lambda name: pytest.fail(f"{name} in {line}"))


@pytest.mark.slow
def test_every_line_a_dry_run_writes_is_strict_json(tmp_path):
    outcome = run_cli(["drive", "--dry-run", *SIM, "--heading-deg", "30", "--max-frames", "3", "--out", "run"], cwd=tmp_path)
    assert outcome.code == 0, outcome.output
    rows = [_strict_json(line) for line in (tmp_path / "run" / "log.jsonl").read_text().splitlines()]
    assert [row["event"] for row in rows] == ["start", "frame", "frame", "frame", "end"]


@pytest.fixture
def robot():
    robots = []

    def start(respond):
        robots.append(PtyRobot(respond))
        return robots[-1]

    yield start
    for started in robots:
        started.close()


def _first_velocity_unanswered(frame) -> list:
    """Polite, but the first VEL gets no ACK: it stays in flight and later commands wait."""
    return [] if isinstance(frame, Vel) and frame.seq == 1 else polite(frame)


def _new_seqs(frames) -> list[int]:
    """The SEQ of every frame put on the line, resends left out, in order."""
    seen = []
    for frame in frames:
        if frame.seq not in seen:
            seen.append(frame.seq)
    return seen


def test_a_command_replaced_while_it_waited_takes_no_seq(robot):
    robot = robot(_first_velocity_unanswered)
    link = RobotLink.open(robot.port, 115200, RELAXED)
    assert link.command(0.1, 0.0, 0.0) == 1  # in flight, unanswered
    assert link.command(0.2, 0.0, 0.0) == 2  # waits
    assert link.command(0.3, 0.0, 0.0) == 2  # replaces it: the same, still unsent, SEQ
    robot.send(Ack(1))
    assert robot.wait_for(lambda: link.ack_latency(2) is not None)
    assert link.close() is True
    sent = robot.frames()
    assert Vel(2, 0.3, 0.0, 0.0) in sent and Vel(2, 0.2, 0.0, 0.0) not in sent
    assert _new_seqs(sent) == list(range(len(_new_seqs(sent))))


def test_a_waiting_command_dropped_by_stop_gives_its_seq_to_the_stop(robot):
    robot = robot(_first_velocity_unanswered)
    link = RobotLink.open(robot.port, 115200, RELAXED)
    link.command(0.1, 0.0, 0.0)
    link.command(0.2, 0.0, 0.0)  # waits behind the unanswered VEL 1, then STOP drops it
    assert link.close() is True
    sent = robot.frames()
    assert sent[-1] == Stop(2) and not any(isinstance(f, Vel) and f.seq == 2 for f in sent)
    assert _new_seqs(sent) == [0, 1, 2]


@pytest.mark.parametrize("camera", ["7", "tcp://127.0.0.1:9"])
def test_a_camera_that_cannot_be_opened_is_the_only_line_on_stderr(tmp_path, camera):
    # OpenCV's and FFmpeg's own warnings ("[ WARN:0@0.02] ...", "[tcp @ 0x...] Connection refused") stay quiet
    outcome = run_cli(["drive", "--dry-run", "--camera", camera, "--out", "run"], cwd=tmp_path, timeout=60)
    assert_clean_error(outcome, f"camera '{camera}': OpenCV cannot open it")
    assert outcome.stderr.splitlines() == [line for line in outcome.stderr.splitlines() if line.startswith("Error: ")]
    assert not (tmp_path / "run").exists()
