"""Shared fixtures: a small bring-your-own dataset written as real files."""

from __future__ import annotations

from pathlib import Path

import pytest
from small_maps import write_own_map


@pytest.fixture
def own_map(tmp_path: Path) -> Path:
    """A 96 x 128 px map with two classes, as a user would lay it out; returns its YAML."""
    return write_own_map(tmp_path)
