"""The embedded maps are regenerated bit for bit by scripts/make_maps.py from their sources."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from curiosity_cli.config import CONFIG_DIR, load_dataset_config
from curiosity_cli.data import dataset_names

#: The repository this test checks.
PROJECT_ROOT = Path(__file__).resolve().parents[1]


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
    embedded = [n for n in dataset_names() if load_dataset_config(CONFIG_DIR / "datasets" / f"{n}.yaml").fetch is None]
    assert len(embedded) == 3
    for name in embedded:
        assert f"{name}: identical" in result.stdout
