"""Benchmark the grid and its labelling on loky and on a Dask cluster of this machine: runs per minute, overhead per task.

A small grid (one map, the quick config's weight functions x --restarts, --steps steps) is run whole
(``run_grid(..., force=True)`` into a temporary folder, the map's word store cached),
--repeats times on each of:

- ``loky, warm``: ``--backend loky --jobs W`` with joblib's worker processes already
  running (after one untimed warm-up: the pool is reused);
- ``dask, warm``: ``--backend dask --scheduler ADDRESS`` on a LocalCluster of W
  one-thread workers started once (after one untimed warm-up);
- ``loky, cold``: the same as ``loky, warm`` after shutting the pool down, so the
  workers start (and load numba's cached kernels) again, as in a new command;
- ``dask, cold``: ``--backend dask --jobs W``: every repeat starts a LocalCluster of W
  one-thread workers and shuts it down, as a command does.

The table gives the median wall time, runs per minute, and the cost over loky in the
same state (warm against warm, cold against cold). The labelling of the grid's runs
(``label_experiment``, its label files deleted before each repeat; the map's batch
reference, of --batch-sweeps sweeps, computed once untimed and reused) is timed the same
way, in a second table. The overhead per task is measured apart, with --noop tasks that do nothing: wall time x W
/ tasks, i.e. the worker time each task costs the backend (joblib's loky pool, and
``client.submit`` + ``as_completed`` on the running cluster).

    python scripts/bench_scaleout.py [--restarts 4] [--steps 80] [--repeats 3] [--workers 2] [--batch-sweeps 20]
    python scripts/bench_scaleout.py --smoke    # one restart of 5 steps on the smallest map, 1 worker: seconds

Prints and never asserts: timings depend on the machine. Needs the distributed extra (pip install -e '.[distributed]').
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import shutil
import statistics
import tempfile
import time
from pathlib import Path

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.label.stage import label_experiment
from curiosity_cli.explore.grid import run_grid
from curiosity_cli.paths import DEFAULT_CACHE


def noop(i: int) -> int:
    return i


def timed_grid(config, results: Path, cache: Path, **backend) -> tuple[float, int]:
    summary = run_grid(config, results_dir=results, cache_dir=cache, force=True, **backend)
    return summary.seconds, summary.ran


def timed_labels(config, results: Path, cache: Path, **backend) -> tuple[float, int]:
    shutil.rmtree(results / config.name / "labels", ignore_errors=True)
    done = label_experiment(config, results / config.name, cache_dir=cache, reuse=False, **backend)
    return done["seconds"], done["labelled"]


def timed_backends(timed, backends: dict, repeats: int) -> dict[str, list[float]]:
    """Wall times of ``timed(**backend)`` for each backend, ``repeats`` times, after a warm-up of the warm ones."""
    from joblib.externals.loky import get_reusable_executor

    for name in ("loky, warm", "dask, warm"):  # word store, pools, numba; for labels also the batch reference
        timed(**backends[name])
    times = {name: [] for name in backends}
    for _ in range(repeats):  # interleaved, so a slow phase of the machine hits all four
        for name, backend in backends.items():
            if name == "loky, cold":
                get_reusable_executor().shutdown(wait=True)
            times[name].append(timed(**backend)[0])
    return times


def print_table(times: dict[str, list[float]], runs: int) -> None:
    print(f"{'backend':<20} {'wall s':>8} {'runs/min':>9} {'vs loky':>8}")
    for name, values in times.items():
        wall, loky = statistics.median(values), statistics.median(times[name.replace("dask", "loky")])
        print(f"{name:<20} {wall:>8.2f} {runs / wall * 60:>9.1f} {(wall / loky - 1) * 100:>+7.1f}%")


def loky_noop_seconds(tasks: int, workers: int) -> float:
    from joblib import Parallel, delayed

    Parallel(n_jobs=workers, backend="loky")(delayed(noop)(i) for i in range(workers))  # start the pool
    start = time.perf_counter()
    for _ in Parallel(n_jobs=workers, backend="loky", return_as="generator_unordered")(delayed(noop)(i) for i in range(tasks)):
        pass
    return time.perf_counter() - start


def dask_noop_seconds(client, tasks: int) -> float:
    from distributed import as_completed

    start = time.perf_counter()
    futures = [client.submit(noop, i, pure=False) for i in range(tasks)]
    for future in as_completed(futures, loop=client.loop):
        future.result()
        future.release()
    return time.perf_counter() - start


def main() -> None:
    from distributed import Client, LocalCluster

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--map", default="aerial-mosaic")
    parser.add_argument("--restarts", type=int, default=4)
    parser.add_argument("--steps", type=int, default=80)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--noop", type=int, default=500, help="no-op tasks for the overhead per task")
    parser.add_argument("--batch-sweeps", type=int, default=20,
                        help="of the batch reference, computed once and untimed (it does not change the labelling's speed)")
    parser.add_argument("--label-sweeps", type=int, help="label.sweeps and label.warm_sweeps (default: quick's)")
    parser.add_argument("--cache-dir", type=Path, default=DEFAULT_CACHE)
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.map, args.restarts, args.steps, args.repeats, args.workers, args.noop = "rare-patches", 1, 5, 1, 1, 5
        args.batch_sweeps = args.label_sweeps = 1

    base = load_config(CONFIG_DIR / "quick.yaml")
    config = dataclasses.replace(
        base, name="bench", datasets=(args.map,),
        explore=dataclasses.replace(base.explore, restarts=args.restarts, path_length=args.steps,
                                    checkpoints=tuple(c for c in base.explore.checkpoints if c < args.steps) + (args.steps,)),
        label=dataclasses.replace(
            base.label, batch_sweeps=args.batch_sweeps, sweeps=args.label_sweeps or base.label.sweeps,
            warm_sweeps=args.label_sweeps or base.label.warm_sweeps,
        ),
    )
    w = args.workers
    with tempfile.TemporaryDirectory() as tmp, LocalCluster(
        n_workers=w, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None,
        silence_logs=logging.ERROR, scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
    ) as cluster, Client(cluster, set_as_default=False) as client:
        results = Path(tmp)
        backends = {
            "loky, warm": dict(jobs=w),
            "dask, warm": dict(backend="dask", scheduler=cluster.scheduler_address),
            "loky, cold": dict(jobs=w),
            "dask, cold": dict(jobs=w, backend="dask"),
        }
        times = timed_backends(lambda **backend: timed_grid(config, results, args.cache_dir, **backend), backends, args.repeats)
        label_times = timed_backends(
            lambda **backend: timed_labels(config, results, args.cache_dir, **backend), backends, args.repeats
        )
        runs = len(list((results / config.name / "runs").glob("*/*/restart-*")))
        noop_loky = [loky_noop_seconds(args.noop, w) for _ in range(args.repeats)]
        noop_dask = [dask_noop_seconds(client, args.noop) for _ in range(args.repeats)]

    print(f"{args.map}: {runs} runs of {args.steps} steps ({len(config.explore.weight_functions)} weight functions x "
          f"{args.restarts} restarts), "
          f"{w} workers of 1 thread, median of {args.repeats}")
    print_table(times, runs)
    print(f"\nlabelling the same {runs} runs (label.sweeps {config.label.sweeps}, label.warm_sweeps "
          f"{config.label.warm_sweeps}; batch reference reused), median of {args.repeats}")
    print_table(label_times, runs)
    per_run = statistics.median(times["loky, warm"]) * w / runs
    print(f"\noverhead per task ({args.noop} no-op tasks, worker time = wall x {w} / tasks), "
          f"against {per_run * 1e3:.0f} ms of worker time per run on loky:")
    for name, values in (("loky, warm", noop_loky), ("dask, warm", noop_dask)):
        overhead = statistics.median(values) * w / args.noop
        print(f"{name:<20} {overhead * 1e3:>8.2f} ms  ({overhead / per_run * 100:.2f}% of a run)")


if __name__ == "__main__":  # worker processes are spawned and re-import this file
    main()
