"""The embedded maps are regenerated bit for bit by scripts/make_maps.py from their sources."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from curiosity_cli.config import CONFIG_DIR
from curiosity_cli.maps.datasets import load_dataset_config
from curiosity_cli.maps.map_data import dataset_names

#: The repository this test checks.
PROJECT_ROOT = Path(__file__).resolve().parents[2]


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
    configs = {n: load_dataset_config(CONFIG_DIR / "datasets" / f"{n}.yaml") for n in dataset_names()}
    # the generated maps have no files: their words are drawn when a store is made (tests/maps/test_generated.py)
    embedded = [n for n, c in configs.items() if c.fetch is None and c.generate is None]
    # geonrw-essen is made by scripts/make_geonrw_map.py from a repository CI cannot reach (see below)
    made_here = [n for n in embedded if n != "geonrw-essen"]
    assert made_here == ["aerial-mosaic", "rare-patches", "reef-mosaic", "sentinel-coast"]
    for name in made_here:
        assert f"{name}: identical" in result.stdout


def test_geonrw_essen_legend_is_the_one_its_script_writes():
    # Its source tile is on GitHub, which CI cannot reach, so only what needs no source is checked
    # here: the committed legend is the recipe's, and the size is the recipe's crop.
    sys.path.insert(0, str(PROJECT_ROOT / "scripts"))
    try:
        from embedded_maps.geonrw_essen import CROP_SHAPE, GEONRW_CLASSES, NAME
        from embedded_maps.legend import legend_entries, legend_yaml
    finally:
        sys.path.remove(str(PROJECT_ROOT / "scripts"))
    committed = (PROJECT_ROOT / "data" / "maps" / NAME / "legend.yaml").read_text(encoding="utf-8")
    assert committed == legend_yaml(NAME, legend_entries(list(GEONRW_CLASSES.values())), "scripts/make_geonrw_map.py")
    assert tuple(load_dataset_config(CONFIG_DIR / "datasets" / f"{NAME}.yaml").size) == CROP_SHAPE
