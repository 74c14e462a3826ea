"""A map's batch reference beside its label blocks: the labels it gives before them, and a block that waits for it."""

from __future__ import annotations

import json
import shutil
import threading

import numpy as np
import pytest
from experiments import label_contents, small_experiment

from curiosity_cli.label.batch_references import WrittenBatch, write_batch
from curiosity_cli.label.stage import label_experiment
from curiosity_cli.label.pixel_tables import PixelTables
from curiosity_cli.experiment.recipes import Recipe
from curiosity_cli.workers import cores


@pytest.mark.skipif(cores() < 2, reason="a batch reference beside a block needs two workers")
def test_a_batch_reference_beside_the_blocks_gives_the_labels_it_gives_before_them(own_map, tmp_path):
    # 2 runs (4 chains with the checked ones) are one block: with 2 workers it and the batch reference run side by side
    config, folder = small_experiment(own_map, tmp_path / "beside", restarts=1, weight_functions=("random-walk", "lawnmower"))
    shutil.copytree(folder, tmp_path / "before" / "grid")
    stages, done = [], []
    label_experiment(config, folder, cache_dir=tmp_path / "beside" / "cache", jobs=2, on_stage=lambda *s: stages.append(s),
                     on_done=lambda: done.append(1))
    # the block's chain sweeps (its profile's) and the batch reference's own sweeps, each counted once
    sweeps = sum(b["chain_sweeps"] for b in json.loads((folder / "label_profile.json").read_text())["blocks"])
    assert stages == [("labelling runs beside the batch reference of own (chain sweeps)", sweeps + config.label.batch_sweeps)]
    assert len(done) == sweeps + config.label.batch_sweeps
    profile = json.loads((folder / "label_profile.json").read_text())
    assert list(profile["batches"]) == ["own"] and 0 < profile["batches"]["own"]["written"] <= profile["wall"]
    label_experiment(config, tmp_path / "before" / "grid", cache_dir=tmp_path / "beside" / "cache", jobs=1,
                     on_stage=lambda *s: stages.append(s), reuse=False)
    assert stages[1:] == [("batch reference own", 8), ("labelling runs (chain sweeps)", sweeps)]
    assert label_contents(folder) == label_contents(tmp_path / "before" / "grid")


def test_a_block_waits_for_the_batch_file_made_from_its_recipe(tmp_path):
    pixel_words = np.arange(12).reshape(3, 4)
    path = tmp_path / "batch" / "own.npz"
    stale = Recipe({"sweeps": 1})
    current = Recipe({"sweeps": 2})
    batch = np.arange(12).reshape(3, 4) % 3
    write_batch(path, stale, batch * 0, None, np.zeros(1), 0.0)  # the one before: not used
    waiting = WrittenBatch(str(path), current.digest, pixel_words, 3)
    labels = np.arange(12)[:, None] % 3
    writer = threading.Timer(0.5, write_batch, (path, current, batch, None, np.zeros(1), 0.0))
    writer.start()
    got = waiting.tables(labels, 3)
    writer.join()
    np.testing.assert_array_equal(got, PixelTables(pixel_words, batch, 3).tables(labels, 3))


@pytest.mark.slow
def test_reproduce_computes_the_batch_reference_beside_the_exploration_and_it_is_the_label_stages(own_map, tmp_path):
    from curiosity_cli.study.pipeline import reproduce

    config, labelled = small_experiment(own_map, tmp_path / "label", restarts=1, weight_functions=("random-walk",))
    label_experiment(config, labelled, cache_dir=tmp_path / "label" / "cache", jobs=1, reuse=False)
    stages = []
    reproduce(config, results_dir=tmp_path / "reproduce", cache_dir=tmp_path / "cache", jobs=1,
              on_stage=lambda *stage: stages.append(stage[0]))
    folder = tmp_path / "reproduce" / config.name
    # the label stage found it current: computed neither before its blocks nor beside them
    assert "labelling runs (chain sweeps)" in stages and not any("batch reference" in stage for stage in stages)
    assert json.loads((folder / "label_profile.json").read_text())["batches"] == {}
    with np.load(labelled / "batch" / "own.npz") as want, np.load(folder / "batch" / "own.npz") as got:
        for name in ("labels", "word_labels", "log_likelihood"):
            np.testing.assert_array_equal(got[name], want[name])
        assert json.loads(str(got["meta"]))["recipe"] == json.loads(str(want["meta"]))["recipe"]
    # and kept for the next experiment, as the label stage keeps what it computes
    assert len(list((tmp_path / "cache" / "shared" / "batch").glob("*.npz"))) == 1
