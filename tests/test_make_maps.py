"""The embedded maps are regenerated bit for bit by scripts/make_maps.py from their sources."""

from __future__ import annotations

import subprocess
import sys

import pytest

from curiosity_cli.config import PROJECT_ROOT
from curiosity_cli.data import dataset_names


@pytest.mark.slow
def test_make_maps_reproduces_the_committed_maps():
    # --check regenerates into a temporary folder and compares decoded pixels and legends
    result = subprocess.run(
        [sys.executable, str(PROJECT_ROOT / "scripts" / "make_maps.py"), "--check"],
        capture_output=True,
        text=True,
        check=False,
        timeout=1200,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    for name in dataset_names():
        assert f"{name}: identical" in result.stdout
