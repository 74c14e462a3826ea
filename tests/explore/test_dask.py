"""The grid on a Dask cluster: a real LocalCluster on loopback, results bit for bit as with loky."""

from __future__ import annotations

import dataclasses
import logging
import os
import signal
import socket
import subprocess
import sys
import time

import dask
import psutil
import pytest
from distributed import Client, LocalCluster
from small_maps import grid_config, grid_yaml
from test_grid import folder_contents
from typer.testing import CliRunner

import curiosity_cli
from curiosity_cli.cli import app
from curiosity_cli.errors import ParameterError
from curiosity_cli.workers import BackendError
from curiosity_cli.explore.grid import GridError, run_grid

# Registers a weight function that raises, inside a worker process (run there with exec).
BROKEN = """
from curiosity_cli.explore import weights
def broken(candidates):
    raise RuntimeError("sensor offline")
weights.WEIGHT_FUNCTIONS["broken"] = broken
"""

# A worker preload: a weight function that kills the worker process running it.
DEADLY = """
import os
from curiosity_cli.explore import weights
def deadly(candidates):
    os._exit(1)
weights.WEIGHT_FUNCTIONS["deadly"] = deadly
"""


def local_cluster(**worker_kwargs) -> LocalCluster:
    """2 worker processes of 1 thread each, on loopback."""
    return LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None,
        silence_logs=logging.ERROR, scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}, **worker_kwargs,
    )


@pytest.fixture(scope="module")
def cluster():
    with local_cluster() as cluster:
        yield cluster


def children() -> set[int]:
    return {p.pid for p in psutil.Process().children(recursive=True)}


@pytest.mark.slow
def test_a_grid_on_a_cluster_or_a_local_one_equals_the_loky_grid_bit_for_bit(own_map, tmp_path, cluster):
    config = grid_config(own_map)
    cache = tmp_path / "cache"
    run_grid(config, results_dir=tmp_path / "loky", cache_dir=cache, jobs=2)
    loky = folder_contents(tmp_path / "loky" / "grid")

    written = []
    summary = run_grid(config, results_dir=tmp_path / "dask", cache_dir=cache, backend="dask",
                       scheduler=cluster.scheduler_address, on_run=lambda task, size: written.append(size))
    assert (summary.ran, summary.skipped, summary.failed) == (8, 0, [])
    assert len(written) == 8 and all(size > 0 for size in written)
    assert folder_contents(tmp_path / "dask" / "grid") == loky
    for name in ("runs.csv", "config.yaml"):
        assert (tmp_path / "dask" / "grid" / name).read_text() == (tmp_path / "loky" / "grid" / name).read_text()
    again = run_grid(config, results_dir=tmp_path / "dask", cache_dir=cache, backend="dask",
                     scheduler=cluster.scheduler_address)
    assert (again.ran, again.skipped) == (0, 8)

    # without --scheduler the command starts a local cluster of --jobs workers and stops it
    before = children()
    result = CliRunner().invoke(app, ["explore", str(grid_yaml(own_map, tmp_path)), "--backend", "dask", "--jobs", "2",
                                      "--results-dir", str(tmp_path / "local"), "--cache-dir", str(cache)])
    assert result.exit_code == 0, result.output
    assert "grid: 8 runs to do, 0 already finished" in result.stderr and "exploring" in result.stderr
    assert folder_contents(tmp_path / "local" / "grid") == loky
    deadline = time.monotonic() + 60
    while children() - before and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not children() - before, "the local cluster's processes are gone"


@pytest.mark.slow
def test_a_run_lost_with_its_killed_worker_is_computed_again_elsewhere(own_map, tmp_path):
    config = grid_config(own_map, samples_per_step=100_000)  # runs of about a second: the kill lands mid-run
    run_grid(config, results_dir=tmp_path / "loky", cache_dir=tmp_path / "cache", jobs=2)

    killed = []
    with local_cluster() as cluster, Client(cluster, set_as_default=False) as client:
        pids = client.run(os.getpid)

        def kill_a_busy_worker(task, size):
            if not killed:
                busy = {address: len(keys) for address, keys in client.processing().items()}
                victim = max(busy, key=busy.get)
                killed.append((victim, busy[victim]))
                os.kill(pids[victim], signal.SIGKILL)

        summary = run_grid(config, results_dir=tmp_path / "dask", cache_dir=tmp_path / "cache", backend="dask",
                           scheduler=cluster.scheduler_address, on_run=kill_a_busy_worker)
    (victim, tasks_lost), = killed
    assert tasks_lost >= 1, "the killed worker was running a run"
    assert not psutil.pid_exists(pids[victim]) or psutil.Process(pids[victim]).status() == psutil.STATUS_ZOMBIE
    assert (summary.ran, summary.failed) == (8, [])
    assert folder_contents(tmp_path / "dask" / "grid") == folder_contents(tmp_path / "loky" / "grid")


@pytest.mark.slow
def test_a_run_that_raises_on_a_worker_is_named_and_the_others_are_written(own_map, tmp_path, cluster):
    config = grid_config(own_map)
    config = dataclasses.replace(config, explore=dataclasses.replace(config.explore, weight_functions=("random-walk", "broken")))
    with Client(cluster, set_as_default=False) as client:
        client.run(exec, BROKEN, {})
        try:
            with pytest.raises(GridError, match=r"2 of 4 runs failed .*own / broken / restart 0: RuntimeError: sensor offline"):
                run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", backend="dask",
                         scheduler=cluster.scheduler_address)
        finally:
            client.run(exec, "from curiosity_cli.explore import weights\nweights.WEIGHT_FUNCTIONS.pop('broken', None)", {})
    assert len(list((tmp_path / "grid" / "runs" / "own" / "random-walk").glob("restart-*/run.json"))) == 2
    assert not (tmp_path / "grid" / "runs" / "own" / "broken").exists()


@pytest.mark.slow
def test_a_run_that_keeps_killing_its_workers_is_named_and_the_others_are_written(own_map, tmp_path):
    preload = tmp_path / "deadly_weight.py"
    preload.write_text(DEADLY)
    config = grid_config(own_map, restarts=1)
    config = dataclasses.replace(
        config, explore=dataclasses.replace(config.explore, weight_functions=(*config.explore.weight_functions, "deadly"))
    )
    # More runs than twice the threads are queued on the scheduler, and with a saturation
    # of 1.0 a worker holds one run at a time: only the deadly run is lost with a worker.
    # It may kill two workers (allowed-failures 1) before it is given up, not four.
    settings = {"distributed.scheduler.worker-saturation": 1.0, "distributed.scheduler.allowed-failures": 1}
    with dask.config.set(settings), local_cluster(preload=[str(preload)]) as cluster:
        with pytest.raises(GridError, match=r"^1 of 5 runs failed .*: own / deadly / restart 0: KilledWorker: every worker that ran it died"):
            run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", backend="dask",
                     scheduler=cluster.scheduler_address)
    assert len(list((tmp_path / "grid" / "runs" / "own").glob("*/restart-000/run.json"))) == 4
    assert not (tmp_path / "grid" / "runs" / "own" / "deadly").exists()


@pytest.mark.slow
def test_workers_with_another_version_are_refused(own_map, tmp_path, cluster, monkeypatch):
    monkeypatch.setattr(curiosity_cli, "__version__", "9.9.9")
    with pytest.raises(BackendError, match=r"the Dask worker at tcp://127\.0\.0\.1:\d+ has curiosity .+ \(here 9\.9\.9\)"):
        run_grid(grid_config(own_map), results_dir=tmp_path, cache_dir=tmp_path / "cache", backend="dask",
                 scheduler=cluster.scheduler_address)
    assert not list((tmp_path / "grid" / "runs").glob("*/*/restart-*"))


def test_the_missing_extra_is_a_one_line_error(own_map, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if `pip install curiosity` without [distributed]
    result = CliRunner().invoke(app, ["explore", str(grid_yaml(own_map, tmp_path)), "--backend", "dask",
                                      "--results-dir", str(tmp_path / "results"), "--cache-dir", str(tmp_path / "cache")])
    assert result.exit_code == 1, result.output
    assert result.stderr.startswith("Error: the dask backend needs Dask distributed") and result.stderr.count("\n") == 1
    assert "pip install -e '.[distributed]'" in result.stderr and "Traceback" not in result.output
    assert not (tmp_path / "results").exists(), "nothing is done before the error"


def test_backend_and_scheduler_mistakes(own_map, tmp_path):
    result = CliRunner().invoke(app, ["explore", str(grid_yaml(own_map, tmp_path)), "--scheduler", "tcp://127.0.0.1:8786"])
    assert result.exit_code == 2 and "needs --backend dask" in result.stderr
    with pytest.raises(ParameterError, match="backend: got 'spark', expected one of loky, dask"):
        run_grid(grid_config(own_map), results_dir=tmp_path, cache_dir=tmp_path / "cache", backend="spark")


@pytest.mark.slow
def test_an_unreachable_scheduler_is_a_one_line_error(own_map, tmp_path):
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{s.getsockname()[1]}"
    env = {**os.environ, "DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "2s"}
    result = subprocess.run(
        [sys.executable, "-m", "curiosity_cli", "explore", str(grid_yaml(own_map, tmp_path)), "--backend", "dask",
         "--scheduler", address, "--results-dir", str(tmp_path / "results"), "--cache-dir", str(tmp_path / "cache")],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert result.returncode == 1, result.stderr
    assert f"Error: cannot reach the Dask scheduler at {address}" in result.stderr
    assert "Traceback" not in result.stderr
