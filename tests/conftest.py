"""Shared fixtures: a small bring-your-own dataset written as real files; the hooks that stop the run on Ctrl-C and
SIGTERM (interrupts.py)."""

from __future__ import annotations

from pathlib import Path

import pytest
from interrupts import pytest_runtest_protocol, pytest_sessionfinish, pytest_sessionstart  # noqa: F401 (hooks)
from small_maps import write_own_map


@pytest.fixture
def own_map(tmp_path: Path) -> Path:
    """A 96 x 128 px map with two classes, as a user would lay it out; returns its YAML."""
    return write_own_map(tmp_path)
