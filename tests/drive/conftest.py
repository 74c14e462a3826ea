"""Fixtures of the drive tests: kernels compiled once, and `curiosity simrobot` started and stopped."""

from __future__ import annotations

import pytest

from drive_processes import SimRobotProcess


@pytest.fixture(scope="session")
def warm_kernels():
    """Compile (or load) the numba kernels once, so no drive process pays a compilation."""
    from curiosity_cli.config import CONFIG_DIR, load_config
    from curiosity_cli.drive.pipeline import warm_up

    warm_up(load_config(CONFIG_DIR / "paper-grid.yaml"))


@pytest.fixture
def simrobot(tmp_path):
    started = []

    def start(*options: str) -> SimRobotProcess:
        robot = SimRobotProcess(tmp_path, *options)
        started.append(robot)
        return robot

    yield start
    for robot in started:
        robot.stop()
