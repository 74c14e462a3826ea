"""Processes for the closed-loop tests: `curiosity simrobot` and `curiosity drive` on a real pty, and their logs
(the fixtures that start them are in this folder's conftest.py)."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

CURIOSITY = str(Path(sys.executable).parent / "curiosity")
#: Generous limits for a loaded 2-core CI machine: start-up imports OpenCV and numba.
START_SECONDS = 60
RUN_SECONDS = 90


class SimRobotProcess:
    """``curiosity simrobot`` in the background; :attr:`port` is its pseudo-terminal."""

    def __init__(self, tmp_path: Path, *options: str):
        self.log = tmp_path / "sim.jsonl"
        self.process = subprocess.Popen(
            [CURIOSITY, "simrobot", "--map", "reef-mosaic", "--log", str(self.log), *options],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )
        self.port = self.process.stdout.readline().strip()
        assert self.port.startswith("/dev/"), self.process.stderr.read()

    def events(self) -> list[dict]:
        return [json.loads(line) for line in self.log.read_text().splitlines()]

    def received(self) -> list[str]:
        return [e["frame"] for e in self.events() if e["event"] == "rx"]

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.terminate()
        self.process.communicate(timeout=START_SECONDS)


def drive_command(out: Path, *options: str) -> list[str]:
    return [CURIOSITY, "drive", "--out", str(out), *options]


def read_log(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "log.jsonl").read_text().splitlines()]


def frame_rows(out: Path) -> list[dict]:
    return [row for row in read_log(out) if row["event"] == "frame"]


def wait_for_frames(out: Path, count: int, process: subprocess.Popen) -> None:
    """Until the run's log holds ``count`` frame rows (or the process ended)."""
    deadline = time.monotonic() + RUN_SECONDS
    while time.monotonic() < deadline and process.poll() is None:
        if (out / "log.jsonl").is_file() and len(frame_rows(out)) >= count:
            return
        time.sleep(0.05)
    raise AssertionError(f"no {count} frames logged; exit code {process.poll()}")
