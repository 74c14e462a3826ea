"""The label stage's profile: its segments add up to the stage's wall time, and every block's work and seconds are there."""

from __future__ import annotations

import json

import pytest
from small_maps import grid_config

from curiosity_cli.explore.grid import run_grid
from curiosity_cli.label.stage import label_experiment
from curiosity_cli.words.store import load_store


@pytest.mark.slow
def test_the_segments_sum_to_the_stage_and_the_blocks_hold_every_run(own_map, tmp_path):
    config = grid_config(own_map)
    run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=2)
    folder = tmp_path / config.name
    done = label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=2, reuse=False)
    profile = json.loads((folder / "label_profile.json").read_text())
    stage = json.loads((folder / "stage_seconds.json").read_text())["label"]
    assert abs(sum(profile["segments"].values()) - profile["wall"]) < 1e-3
    assert abs(profile["wall"] - stage) <= 0.03 * stage, "the profile accounts for the stage's whole time"
    assert {"setup", "waiting for blocks", "handling results", "writing", "closing"} <= set(profile["segments"])
    assert profile["jobs"] == 2
    blocks = profile["blocks"]
    assert sum(b["runs"] for b in blocks) == done["labelled"] == 8
    # 8 runs, restart 0 of each walker checked twice: 12 chains, each 2 checkpoints of label.sweeps then warm_sweeps
    assert sum(b["chains"] for b in blocks) == 12
    label = config.label
    assert sum(b["chain_sweeps"] for b in blocks) == 12 * (label.sweeps + label.warm_sweeps)
    words = sum(load_store(next((tmp_path / "cache").glob("own-*.npz"))).count_by_type().values())
    assert all(b["words"] == words and b["work"] == b["chain_sweeps"] * words for b in blocks)
    assert all(b["kernel"] > 0 and b["tables"] > 0 and b["reading"] >= 0 for b in blocks)
    # each block began within the stage, after its setup; the batch reference went before them (three tasks on two
    # workers), so none is listed as beside them
    assert all(profile["segments"]["setup"] - 0.5 <= b["began"] <= profile["wall"] for b in blocks)
    assert profile["segments"]["batch references before the blocks"] > 0 and profile["batches"] == {}

    before = (folder / "label_profile.json").read_bytes()
    again = label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=2)
    assert again["labelled"] == 0 and (folder / "label_profile.json").read_bytes() == before, "nothing labelled: kept"
