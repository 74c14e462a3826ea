"""Labelling on a Dask cluster: a real local cluster on loopback, label files as with loky."""

from __future__ import annotations

import json
import shutil

import dask
import distributed
import pytest
from experiments import label_contents, small_experiment
from small_maps import grid_yaml
from typer.testing import CliRunner

from curiosity_cli.cli import app
from curiosity_cli.label.stage import LabelError, label_experiment
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.workers import dask_client

#: Every test labels on a Dask cluster.
pytestmark = pytest.mark.slow

runner = CliRunner()


@pytest.fixture(scope="module")
def scheduler():
    """The address of a local cluster of 2 one-thread worker processes."""
    with dask_client(None, 2) as (client, _):
        yield client.scheduler.address


def test_labels_on_a_cluster_equal_the_loky_labels_byte_for_byte(own_map, tmp_path, scheduler):
    config, folder = small_experiment(own_map, tmp_path / "loky")
    shutil.copytree(folder, tmp_path / "dask" / "grid")
    cache = tmp_path / "loky" / "cache"
    label_experiment(config, tmp_path / "loky" / config.name, cache_dir=cache, jobs=2)
    loky = label_contents(folder)
    assert len([key for key in loky if key.startswith("labels/own/") and "/examples/" not in key]) == 8

    stages, done = [], []
    summary = label_experiment(config, tmp_path / "dask" / config.name, cache_dir=cache, backend="dask", reuse=False,
                               scheduler=scheduler, on_stage=lambda *stage: stages.append(stage), on_done=lambda: done.append(1))
    assert (summary["labelled"], summary["skipped"], summary["batch_reused"]) == (8, 0, 0)
    # a cluster's blocks count their chain sweeps (those its profile records) as they arrive, none before
    sweeps = sum(b["chain_sweeps"] for b in json.loads((tmp_path / "dask" / config.name / "label_profile.json").read_text())["blocks"])
    assert stages == [("batch reference own", 8), ("labelling runs (chain sweeps)", sweeps)] and len(done) == 8 + sweeps
    assert label_contents(tmp_path / "dask" / "grid") == loky
    again = label_experiment(config, tmp_path / "dask" / config.name, cache_dir=cache, backend="dask", scheduler=scheduler)
    assert (again["labelled"], again["skipped"], again["batch_reused"]) == (0, 8, 1)


@pytest.mark.parametrize("backend", ["loky", "dask"])
def test_a_run_that_cannot_be_labelled_is_named_and_the_others_are_written(own_map, tmp_path, scheduler, backend):
    config, folder = small_experiment(own_map, tmp_path)
    meta_path = ExperimentFolder(folder).run("own", "random-walk", 1) / "run.json"
    meta = json.loads(meta_path.read_text())
    meta_path.write_text(json.dumps({**meta, "n_topics": 9}))  # its checkpoints do not fit the model
    where = {"jobs": 2} if backend == "loky" else {"backend": "dask", "scheduler": scheduler}
    with pytest.raises(LabelError, match=r"^1 of 8 runs could not be labelled \(the others are written\): "
                                         r".*random-walk/restart-001/checkpoints.npz: the counts at 5 steps are \(\d+, 9\), "
                                         r"expected \(V, K\) = \(\d+, 8\)"):
        label_experiment(config, tmp_path / config.name, cache_dir=tmp_path / "cache", **where)
    assert len(list((folder / "labels" / "own").glob("*/restart-*.npz"))) == 7
    assert not (folder / "labels" / "own" / "random-walk" / "restart-001.npz").exists()

    meta_path.write_text(json.dumps(meta))  # mended: running again labels only that run
    again = label_experiment(config, tmp_path / config.name, cache_dir=tmp_path / "cache", **where)
    assert (again["labelled"], again["skipped"], again["batch_reused"]) == (1, 7, 1)


def test_reproduce_on_dask_explores_and_labels_on_one_local_cluster_as_loky_would(own_map, tmp_path, monkeypatch):
    started = []

    class CountedCluster(distributed.LocalCluster):
        def __init__(self, *args, **kwargs):
            started.append(kwargs["n_workers"])
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(distributed, "LocalCluster", CountedCluster)
    sets = ["--set", "label.sweeps=2", "--set", "label.batch_sweeps=5"]
    result = runner.invoke(app, ["reproduce", str(grid_yaml(own_map, tmp_path)), *sets, "--backend", "dask", "--jobs", "2",
                                 "--results-dir", str(tmp_path / "dask"), "--cache-dir", str(tmp_path / "cache")])
    assert result.exit_code == 0, result.output
    assert started == [2]

    shutil.copytree(tmp_path / "dask" / "grid" / "runs", tmp_path / "loky" / "grid" / "runs")
    shutil.copy(tmp_path / "dask" / "grid" / "config.yaml", tmp_path / "loky" / "grid")
    result = runner.invoke(app, ["label", str(tmp_path / "loky" / "grid"), *sets, "--jobs", "2", "--no-reuse",
                                 "--cache-dir", str(tmp_path / "cache")])
    assert result.exit_code == 0 and "labelled 8 runs" in result.stdout, result.output
    assert label_contents(tmp_path / "loky" / "grid") == label_contents(tmp_path / "dask" / "grid")


def test_label_backend_mistakes_and_an_unreachable_scheduler(own_map, tmp_path):
    config, folder = small_experiment(own_map, tmp_path)
    result = runner.invoke(app, ["label", str(folder), "--scheduler", "tcp://127.0.0.1:8786"])
    assert result.exit_code == 2 and "needs --backend dask" in result.stderr

    with dask.config.set({"distributed.comm.timeouts.connect": "2s"}):
        result = runner.invoke(app, ["label", str(folder), "--backend", "dask", "--scheduler", "tcp://127.0.0.1:1",
                                     "--cache-dir", str(tmp_path / "cache")])
    assert result.exit_code == 1, result.output
    assert result.stderr.startswith("Error: cannot reach the Dask scheduler at tcp://127.0.0.1:1")
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.output
    assert not (folder / "labels").exists()


def test_a_runs_labels_do_not_depend_on_the_block_it_was_labelled_in(own_map, tmp_path):
    """Blocks of 1, 3 and 16 chains, on 1 and 2 workers, write the same label files byte for byte
    (the 8 runs' chains, the 4 second chains of restart 0 included, grouped three ways)."""
    config, folder = small_experiment(own_map, tmp_path / "first")
    contents = []
    for chains_per_block, jobs in ((16, 2), (1, 1), (3, 2)):
        copy = tmp_path / f"block-{chains_per_block}"
        shutil.copytree(folder, copy / config.name)
        label_experiment(config, copy / config.name, cache_dir=tmp_path / "first" / "cache", jobs=jobs,
                         chains_per_block=chains_per_block, reuse=False)
        contents.append(label_contents(copy / config.name))
    assert len([key for key in contents[0] if "/examples/" not in key and key.startswith("labels/")]) == 8
    assert contents[1] == contents[0] and contents[2] == contents[0]
