"""The experiment grid on a real (small) map: seeds, parallel runs, resume, run folders."""

from __future__ import annotations

import dataclasses
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from small_maps import grid_config, grid_yaml

from curiosity_cli.config import load_config
from curiosity_cli.errors import ConfigError
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.explore import weights
from curiosity_cli.explore.grid import GridError, run_grid, start_cells
from curiosity_cli.explore.runs import RunError, read_run, remove_partial_runs


def folder_contents(root: Path) -> dict:
    """Every run's files as comparable values (run.json without its timing)."""
    out = {}
    for run in sorted((root / "runs").glob("*/*/restart-*")):
        key = run.relative_to(root).as_posix()
        meta = json.loads((run / "run.json").read_text())
        meta.pop("seconds")
        with np.load(run / "checkpoints.npz") as npz:
            arrays = {name: npz[name].tolist() for name in npz.files}
        out[key] = (meta, (run / "path.csv").read_text(), (run / "candidates.csv").read_text(), arrays)
    return out


def test_a_grid_writes_every_run_with_its_config_seeds_and_provenance(own_map, tmp_path):
    config = grid_config(own_map, weight_functions=tuple(weights.WEIGHT_FUNCTIONS))  # every walker and ceiling
    summary = run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    folder = tmp_path / "grid"
    assert (summary.ran, summary.skipped, summary.failed) == (2 * len(weights.WEIGHT_FUNCTIONS), 0, [])
    assert load_config(folder / "config.yaml") == config
    provenance = yaml.safe_load((folder / "provenance.yaml").read_text())
    assert provenance["seed"] == 0 and len(provenance["git_commit"]) in (40, len("unknown"))
    plan = pd.read_csv(folder / "runs.csv")
    assert len(plan) == 2 * len(weights.WEIGHT_FUNCTIONS) and set(plan.weight_function) == set(weights.WEIGHT_FUNCTIONS)
    # an oracle draws from stochastic coverage's streams, and its recipe holds the truth it read
    seeds = plan.set_index(["weight_function", "restart"])["seed"]
    assert seeds["oracle-0.2", 1] == seeds["stochastic-coverage", 1] != seeds["sham", 1]
    oracle = read_run(ExperimentFolder(folder).run("own", "oracle-0.2", 1)).meta["recipe"]["inputs"]
    assert oracle["truth"]["class_share_percent"] == 10 and len(oracle["truth"]["human"]) == 16
    assert "truth" not in read_run(ExperimentFolder(folder).run("own", "sham", 1)).meta["recipe"]["inputs"]
    # paired design: every walker starts restart r from the same cell
    assert plan.groupby("restart")[["start_row", "start_col"]].nunique().eq(1).all().all()
    run = read_run(ExperimentFolder(folder).run("own", "topic-perplexity", 1))
    assert run.path.size == 12 and run.meta["checkpoints"] == [5, 12]
    assert (run.meta["start_row"], run.meta["start_col"]) == divmod(int(run.path[0]), 8)
    assert run.phi(5).sum() < run.phi(12).sum() or np.unique(run.path).size == np.unique(run.path[:5]).size
    assert summary.bytes_written == sum(p.stat().st_size for p in (folder / "runs").glob("*/*/*/*"))
    mower = read_run(ExperimentFolder(folder).run("own", "lawnmower", 1))
    assert mower.path[0] == run.path[0] and (np.abs(np.diff(np.divmod(mower.path, 8))).sum(axis=0) == 1).all()
    block = read_run(ExperimentFolder(folder).run("own", "compact-block", 1))
    assert block.path[0] == run.path[0]


def test_an_oracle_is_refused_on_a_map_without_human_labels_before_any_run(own_map, tmp_path):
    text = yaml.safe_load(own_map.read_text())
    del text["labels"], text["legend"]
    own_map.write_text(yaml.safe_dump(text))
    config = grid_config(own_map, weight_functions=("stochastic-coverage", "oracle-0.1"))
    with pytest.raises(ConfigError, match="^explore.weight_functions: oracle-0.1 reads a map's human labels, and own has none"):
        run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    assert not (tmp_path / "grid" / "runs").exists()


def test_start_cells_are_shared_and_do_not_depend_on_the_number_of_restarts():
    np.testing.assert_array_equal(start_cells(0, "own", 48, 5)[:2], start_cells(0, "own", 48, 2))
    assert len(set(start_cells(0, "own", 48, 48))) == 48
    assert not np.array_equal(start_cells(0, "own", 48, 5), start_cells(1, "own", 48, 5))


@pytest.mark.slow
def test_results_do_not_depend_on_the_number_of_jobs(own_map, tmp_path):
    config = grid_config(own_map, weight_functions=("topic-perplexity", "lawnmower", "scattered-cells", "compact-block"))
    run_grid(config, results_dir=tmp_path / "one", cache_dir=tmp_path / "cache", jobs=1)
    run_grid(config, results_dir=tmp_path / "two", cache_dir=tmp_path / "cache", jobs=2)
    one, two = folder_contents(tmp_path / "one" / "grid"), folder_contents(tmp_path / "two" / "grid")
    assert len(one) == 8 and one == two


def test_a_finished_grid_is_skipped_and_force_redoes_it(own_map, tmp_path):
    config = grid_config(own_map)
    run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    again = run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    assert (again.ran, again.skipped) == (0, 8)
    forced = run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1, force=True)
    assert (forced.ran, forced.skipped) == (8, 0)


@pytest.mark.slow
def test_force_keeps_a_user_s_file_in_a_run_folder(own_map, tmp_path):
    """Issue 63: explore --force deleted runs/<map>/<walker>/restart-000/notes.txt without a word."""
    config = grid_config(own_map)
    run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    run = next((tmp_path / config.name / "runs").glob("*/*/restart-000"))
    (run / "notes.txt").write_text("the camera fogged here")
    written = sorted(p.name for p in run.iterdir())
    run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1, force=True)
    assert (run / "notes.txt").read_text() == "the camera fogged here"
    assert sorted(p.name for p in run.iterdir()) == written
    read_run(run)  # and the run is whole


def test_a_killed_grid_resumes_to_the_results_of_an_uninterrupted_one(own_map, tmp_path):
    config_path = grid_yaml(own_map, tmp_path)
    command = [sys.executable, "-m", "curiosity_cli", "explore", str(config_path), "--jobs", "1",
               "--cache-dir", str(tmp_path / "cache")]
    whole = subprocess.run([*command, "--results-dir", str(tmp_path / "whole")], capture_output=True, text=True)
    assert whole.returncode == 0, whole.stderr

    killed_root = tmp_path / "killed"
    process = subprocess.Popen([*command, "--results-dir", str(killed_root)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not list((killed_root / "grid" / "runs").glob("*/*/restart-*/run.json")):
        time.sleep(0.02)
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    finished = len(list((killed_root / "grid" / "runs").glob("*/*/restart-*/run.json")))
    assert 1 <= finished < 8, "the kill should land mid-grid"

    resumed = subprocess.run([*command, "--results-dir", str(killed_root)], capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    assert f"{finished} already finished" in resumed.stderr
    assert folder_contents(killed_root / "grid") == folder_contents(tmp_path / "whole" / "grid")
    assert not list((killed_root / "grid" / "runs").glob("*/*/.restart-*")), "no partial run folder is left"


def test_a_grid_refuses_to_mix_runs_of_another_config(own_map, tmp_path):
    run_grid(grid_config(own_map), results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    with pytest.raises(ConfigError, match=r"grid/config.yaml: explore.samples_per_step was 5000 for the runs already there, now 6000"):
        run_grid(grid_config(own_map, samples_per_step=6000), results_dir=tmp_path, cache_dir=tmp_path / "cache")
    # more restarts is the same experiment, grown
    more = run_grid(grid_config(own_map, restarts=3), results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    assert (more.ran, more.skipped) == (4, 8)


@pytest.mark.parametrize(
    "settings, message",
    [
        (dict(path_length=49, checkpoints=(49,)), "explore.path_length: got 49 steps, but own has only 48 cells (6 x 8)"),
        (dict(restarts=49), "explore.restarts: got 49, but own has only 48 cells to start from"),
    ],
)
def test_a_map_too_small_for_the_grid_is_refused(own_map, tmp_path, settings, message):
    with pytest.raises(ConfigError, match=message.replace("(", r"\(").replace(")", r"\)")):
        run_grid(grid_config(own_map, **settings), results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)


def test_a_failing_run_is_named_and_the_others_are_written(own_map, tmp_path, monkeypatch):
    def broken(candidates):
        raise RuntimeError("sensor offline")

    monkeypatch.setitem(weights.WEIGHT_FUNCTIONS, "broken", broken)
    config = grid_config(own_map)
    config = dataclasses.replace(config, explore=dataclasses.replace(config.explore, weight_functions=("random-walk", "broken")))
    with pytest.raises(GridError, match=r"2 of 4 runs failed .*own / broken / restart 0: RuntimeError: sensor offline"):
        run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    assert len(list((tmp_path / "grid" / "runs" / "own" / "random-walk").glob("restart-*/run.json"))) == 2
    assert not (tmp_path / "grid" / "runs" / "own" / "broken").exists()


def test_corrupt_and_partial_run_folders_are_reported_or_removed(own_map, tmp_path):
    run_grid(grid_config(own_map, restarts=1), results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    folder = ExperimentFolder(tmp_path / "grid").run("own", "random-walk", 0)
    (folder / "checkpoints.npz").write_bytes(b"not a zip file")
    with pytest.raises(RunError, match=r"restart-000/checkpoints.npz: corrupt or truncated \(not a .npz archive\); explore redoes the run"):
        read_run(folder)
    (folder / "run.json").write_text("{")
    with pytest.raises(RunError, match=r"restart-000/run.json: corrupt"):
        read_run(folder)
    partial = folder.parent / ".restart-001.tmp-0123abcd"
    partial.mkdir()
    assert remove_partial_runs(tmp_path / "grid") == 1 and not partial.exists()
