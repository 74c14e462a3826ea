"""The label stage and ``curiosity reproduce`` ask the device table's fields (issue 47), never a device's name."""

from __future__ import annotations

import dataclasses
import json
import shutil

import pytest
from experiments import label_contents, small_experiment

from curiosity_cli.label.stage import label_experiment
from curiosity_cli.topics.devices import DEVICES
from curiosity_cli.workers import cores


def one_block_at_a_time(monkeypatch) -> None:
    """The CPU as a device that takes a map's chains in one block, one block at a time, and leaves the cores free."""
    monkeypatch.setitem(DEVICES, "cpu", dataclasses.replace(
        DEVICES["cpu"], block_chains=None, parallel_blocks=False, frees_cores=True, shown="one block", announced=True,
    ))


@pytest.mark.skipif(cores() < 2, reason="blocks side by side need two workers")
def test_a_device_taking_one_block_at_a_time_gets_every_chain_of_a_map_in_one_block_and_the_same_labels(
    own_map, tmp_path, monkeypatch,
):
    config, folder = small_experiment(own_map, tmp_path / "side", restarts=1, weight_functions=("random-walk", "lawnmower"))
    shutil.copytree(folder, tmp_path / "one" / "grid")
    stages = []
    label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=2, chains_per_block=1, reuse=False,
                     on_stage=lambda *s: stages.append(s))
    # a block per run: too many to go beside; the labelling counted in the chain sweeps its profile records
    blocks = json.loads((folder / "label_profile.json").read_text())["blocks"]
    assert stages == [("batch reference own", 8), ("labelling runs (chain sweeps)", sum(b["chain_sweeps"] for b in blocks))]
    assert len(json.loads((folder / "label_profile.json").read_text())["blocks"]) == 2

    one_block_at_a_time(monkeypatch)  # chains_per_block is the CPU's when its blocks run side by side only
    label_experiment(config, tmp_path / "one" / "grid", cache_dir=tmp_path / "cache", jobs=2, chains_per_block=1,
                     reuse=False, on_stage=lambda *s: stages.append(s))
    sweeps = sum(b["chain_sweeps"] for b in json.loads((tmp_path / "one" / "grid" / "label_profile.json").read_text())["blocks"])
    assert stages[2:] == [("labelling runs on one block beside the batch reference of own (chain sweeps)", sweeps + 8)]
    assert len(json.loads((tmp_path / "one" / "grid" / "label_profile.json").read_text())["blocks"]) == 1
    assert label_contents(folder) == label_contents(tmp_path / "one" / "grid")


@pytest.mark.slow
def test_reproduce_on_a_device_that_frees_the_cores_leaves_the_batch_references_to_the_label_stage(
    own_map, tmp_path, monkeypatch,
):
    from curiosity_cli.study.pipeline import reproduce

    config, _ = small_experiment(own_map, tmp_path / "explored", restarts=1, weight_functions=("random-walk",))
    one_block_at_a_time(monkeypatch)
    stages = []
    reproduce(config, results_dir=tmp_path / "reproduce", cache_dir=tmp_path / "cache", jobs=1, reuse=False,
              on_stage=lambda *stage: stages.append(stage[0]))
    # not beside the exploration, where the label stage would have found it current
    assert "batch reference own" in stages and "labelling runs on one block (chain sweeps)" in stages
