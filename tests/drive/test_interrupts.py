"""Ctrl-C and SIGTERM stop a test run inside a drive (tests/interrupts.py), and a drive puts the handlers back."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from drive_processes import RUN_SECONDS, wait_for_frames
from typer.testing import CliRunner

from curiosity_cli.cli import app

TESTS = Path(__file__).resolve().parents[1]
#: A test that drives in its own process until something stops it, as the CLI tests of `drive` do.
ENDLESS_DRIVE = '''
from typer.testing import CliRunner

from curiosity_cli.cli import app


def test_drives_until_stopped():
    result = CliRunner().invoke(app, [
        "drive", "--dry-run", "--camera", "sim", "--sim-map", "reef-mosaic", "--start", "1800,600",
        "--max-frames", "100000", "--out", {out!r},
    ])
    assert result.exit_code == 0, result.output


def test_never_reached():
    pass
'''


@pytest.mark.slow
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_during_a_drive_stops_the_test_run(tmp_path, warm_kernels, signum):
    out = tmp_path / "run"
    probe = tmp_path / "test_probe.py"
    probe.write_text(ENDLESS_DRIVE.format(out=str(out)))
    process = subprocess.Popen(
        [sys.executable, "-m", "pytest", "-p", "interrupts", "-p", "no:cacheprovider", "-v", str(probe)],
        cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(TESTS)}, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        wait_for_frames(out, 2, process)
        process.send_signal(signum)
        output, _ = process.communicate(timeout=RUN_SECONDS)
    finally:
        process.kill()
    assert process.returncode == pytest.ExitCode.INTERRUPTED, output
    assert f"{signum.name} during test_probe.py::test_drives_until_stopped; the run stops" in output
    assert "test_never_reached" not in output


def test_a_drive_in_this_process_puts_the_signal_handlers_back(tmp_path, warm_kernels):
    before = [signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)]
    result = CliRunner().invoke(app, [
        "drive", "--dry-run", "--camera", "sim", "--sim-map", "reef-mosaic", "--start", "1800,600", "--max-frames", "1",
        "--out", str(tmp_path / "run"),
    ])
    assert result.exit_code == 0, result.output
    assert [signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)] == before
