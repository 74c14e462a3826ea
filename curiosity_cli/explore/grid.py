"""The experiment grid: maps x weight functions x restarts, in parallel, resumable.

Design, in the order a grid runs:

- **Paired start cells.** For each map, one seeded permutation of its cells (from the
  experiment seed and the map's name); restart ``r`` starts at its ``r``-th cell for
  every weight function, so weight functions can be compared restart by restart. A
  restart's start cell does not depend on how many restarts the grid has.
- **Seeds.** Each run draws from ``SeedSequence((seed, crc32(map), crc32(weight
  function), restart))``: the same numbers whatever ``jobs`` is and in whatever order
  runs finish.
- **Parallel.** Runs are joblib tasks (``loky`` processes by default). A worker loads
  the map's word store from the cache once and keeps it; each worker's numba threads
  are capped so the workers together use the cores once.
- **Or on a Dask cluster** (``backend="dask"``): at ``scheduler``'s address, or on a
  ``LocalCluster`` of ``jobs`` one-thread worker processes started for the grid and shut
  down after it. Each map's store file goes to the cluster once, as the argument of a
  task that loads it (no shared filesystem needed); runs depend on that task, so a
  worker gets the loaded store once, from a peer, and if every copy is lost with its
  workers the scheduler loads it again (scattered data could not be recomputed). Each
  run is one task, all submitted at once and collected as they finish
  (``distributed.as_completed``). A task lost with its worker is rescheduled on another
  by the scheduler (up to ``distributed.scheduler.allowed-failures`` times); a run whose
  workers keep dying is reported by name like a run that raised. The same
  :func:`compute_run` computes every run on either backend, so results are identical.
- **Written by the caller.** A task returns its :class:`Exploration`; this process
  writes the run folder atomically (:mod:`curiosity_cli.explore.runs`), so where a run
  was computed never matters and a killed grid loses only the runs in flight.
- **Resumable.** Finished runs are skipped unless ``force``; the experiment folder
  keeps the resolved config, ``provenance.yaml`` (seed, version, commit) and
  ``runs.csv`` (every run's start cell and seed). A resumed grid must agree with the
  saved config on everything that changes a run's numbers.
"""

from __future__ import annotations

import contextlib
import os
import time
import traceback
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from curiosity_cli.config import ExperimentConfig, to_dict, to_yaml
from curiosity_cli.errors import ConfigError, CuriosityError, ParameterError
from curiosity_cli.files import atomic_path, display_path

#: Where the runs of a grid can be computed: joblib's loky processes, or a Dask cluster.
BACKENDS = ("loky", "dask")

#: Seconds a grid waits for a first worker to join a Dask scheduler that has none.
WORKER_WAIT_SECONDS = 60

#: The config sections a run's numbers depend on ...
_RUN_SECTIONS = ("seed", "model", "words", "explore")
#: ... except these keys, which choose which runs a grid holds.
_SELECTION_KEYS = {("explore", "weight_functions"), ("explore", "restarts")}


class GridError(CuriosityError):
    """Some runs of a grid failed; the others were written."""


class BackendError(CuriosityError):
    """The Dask backend cannot run: its optional dependency is missing, or its cluster is unusable."""


@dataclass(frozen=True)
class RunTask:
    """One run of the grid, everything a worker needs to compute it."""

    dataset: str
    weight_function: str
    restart: int
    start_cell: int
    seed: tuple[int, ...]
    store_path: str


@dataclass(frozen=True)
class StoreInfo:
    """A map's cached word store, as the grid needs it."""

    name: str
    path: Path
    grid_shape: tuple[int, int]
    vocabulary_size: int
    vocabulary_hashes: list[str]
    word_counts: dict[str, int]  # words of each kind ("orb", "texton", "hue")
    stands_in_for: str | None  # the paper's map it compares with


@dataclass(frozen=True)
class GridSummary:
    """What a call to :func:`run_grid` did."""

    folder: Path
    ran: int
    skipped: int
    failed: list[str]
    fallbacks: int
    bytes_written: int
    seconds: float


def threads_per_job(jobs: int) -> int:
    """Threads each of ``jobs`` parallel jobs may use so that together they use the cores once."""
    return max(1, (os.cpu_count() or 1) // max(1, jobs))


def name_key(name: str) -> int:
    """A map's or weight function's name as seed entropy (CRC-32, the same on every machine)."""
    return zlib.crc32(name.encode())


def start_cells(seed: int, dataset: str, n_cells: int, restarts: int) -> np.ndarray:
    """(restarts,) int64 ndarray: the start cells of a map's restarts, shared by all weight functions.

    Raises
    ------
    ConfigError
        More restarts than the map has cells.
    """
    if restarts > n_cells:
        raise ConfigError(f"explore.restarts: got {restarts}, but {dataset} has only {n_cells} cells to start from")
    rng = np.random.default_rng(np.random.SeedSequence((seed, name_key(dataset))))
    return rng.permutation(n_cells)[:restarts].astype(np.int64)


def plan_runs(config: ExperimentConfig, stores: dict[str, StoreInfo]) -> list[RunTask]:
    """Every run of the grid, ordered by map, restart, then weight function.

    Parameters
    ----------
    config : ExperimentConfig
    stores : dict of str to StoreInfo
        For each entry of ``config.datasets``, its map's name and cached word store.

    Raises
    ------
    ConfigError
        A map with fewer cells than the path length or the restarts need.
    """
    tasks = []
    for entry in config.datasets:
        dataset = stores[entry].name
        grid_shape = stores[entry].grid_shape
        n_cells = grid_shape[0] * grid_shape[1]
        if config.explore.path_length > n_cells:
            raise ConfigError(
                f"explore.path_length: got {config.explore.path_length} steps, but {dataset} has only {n_cells} "
                f"cells ({grid_shape[0]} x {grid_shape[1]}); use fewer steps or a smaller cell width"
            )
        starts = start_cells(config.seed, dataset, n_cells, config.explore.restarts)
        for restart, start in enumerate(starts):
            for weight_function in config.explore.weight_functions:
                seed = (config.seed, name_key(dataset), name_key(weight_function), restart)
                tasks.append(RunTask(dataset, weight_function, restart, int(start), seed, str(stores[entry].path)))
    return tasks


def check_saved_config(folder: Path, config: ExperimentConfig) -> None:
    """Refuse to add runs to an experiment folder whose saved config computes runs differently.

    Raises
    ------
    ConfigError
        Naming the first key that differs, with both values.
    """
    import yaml

    saved_path = Path(folder) / "config.yaml"
    if not saved_path.is_file():
        return
    saved = yaml.safe_load(saved_path.read_text())
    current = to_dict(config)
    for keys, old, new in _differences({k: saved.get(k) for k in _RUN_SECTIONS}, {k: current[k] for k in _RUN_SECTIONS}):
        if keys not in _SELECTION_KEYS:
            raise ConfigError(
                f"{display_path(saved_path)}: {'.'.join(keys)} was {old!r} for the runs already there, now {new!r}; "
                "use another experiment name or another results folder"
            )


def _differences(old, new, keys: tuple = ()):
    if isinstance(old, dict) and isinstance(new, dict):
        for key in sorted(set(old) | set(new)):
            yield from _differences(old.get(key), new.get(key), keys + (key,))
    elif old != new:
        yield keys, old, new


def run_grid(
    config: ExperimentConfig,
    *,
    results_dir: Path = Path("results"),
    cache_dir: Path = Path("results/cache"),
    jobs: int | None = None,
    force: bool = False,
    on_prepared: Callable[[int, int], None] | None = None,
    on_run: Callable[[RunTask, int], None] | None = None,
    backend: str = "loky",
    scheduler: str | None = None,
) -> GridSummary:
    """Run every missing run of an experiment grid and write it under ``results_dir/<name>``.

    Parameters
    ----------
    config : ExperimentConfig
    results_dir, cache_dir : Path
        Experiment folders go under ``results_dir``; word stores are cached in ``cache_dir``.
    jobs : int, optional
        Worker processes (of ``loky``, or of the local Dask cluster); default the number
        of cores. Ignored with a ``scheduler``: the cluster's worker threads decide.
    force : bool
        Redo finished runs too.
    on_prepared : callable, optional
        Called as ``on_prepared(to_run, skipped)`` before the first run starts.
    on_run : callable, optional
        Called as ``on_run(task, bytes_written)`` as each run is written (bytes 0 if it failed).
    backend : {"loky", "dask"}
        Where runs are computed (module docstring); the results do not depend on it.
    scheduler : str, optional
        With ``backend="dask"``: a running scheduler's address, e.g.
        ``tcp://10.0.0.5:8786``; without one, a local cluster is started for the grid.

    Raises
    ------
    ConfigError
        A saved config that disagrees, or a map too small for the grid.
    ParameterError
        An unknown backend, or a scheduler without ``backend="dask"``.
    BackendError
        ``backend="dask"`` without Dask distributed installed, a scheduler that cannot be
        reached or gets no worker, or workers with other versions of the package, numpy
        or numba than this process.
    GridError
        After the whole grid, if some runs raised: each named with its traceback's last line.
    """
    from curiosity_cli.explore.runs import is_complete, remove_partial_runs, run_folder

    started = time.perf_counter()
    if backend not in BACKENDS:
        raise ParameterError(f"backend: got {backend!r}, expected one of {', '.join(BACKENDS)}")
    if scheduler is not None and backend != "dask":
        raise ParameterError(f"scheduler: got {scheduler!r} with backend {backend!r}; a scheduler needs backend 'dask'")
    if backend == "dask":
        _import_distributed()  # a missing extra is reported before any work
    jobs = (os.cpu_count() or 1) if jobs is None else jobs
    folder = Path(results_dir) / config.name
    check_saved_config(folder, config)
    stores = prepare_stores(config, cache_dir)
    tasks = plan_runs(config, stores)
    by_name = {info.name: info for info in stores.values()}
    _write_experiment_files(folder, config, tasks, by_name)
    remove_partial_runs(folder)

    todo = [t for t in tasks if force or not is_complete(run_folder(folder, t.dataset, t.weight_function, t.restart))]
    if on_prepared is not None:
        on_prepared(len(todo), len(tasks) - len(todo))
    failed, fallbacks, written = [], 0, 0
    with _computed_runs(todo, config, backend=backend, scheduler=scheduler, jobs=jobs) as results:
        for task, outcome in results:
            size = 0
            if isinstance(outcome, str):
                failed.append(f"{task.dataset} / {task.weight_function} / restart {task.restart}: {outcome}")
            else:
                exploration, seconds = outcome
                size = _write(folder, task, exploration, seconds, config, by_name[task.dataset])
                fallbacks += int(exploration.fallback.sum())
                written += size
            if on_run is not None:
                on_run(task, size)
    summary = GridSummary(folder, len(todo) - len(failed), len(tasks) - len(todo), failed, fallbacks, written,
                          time.perf_counter() - started)
    if failed:
        raise GridError(f"{len(failed)} of {len(todo)} runs failed (the others are written): " + "; ".join(failed))
    return summary


def prepare_stores(config: ExperimentConfig, cache_dir: Path) -> dict[str, StoreInfo]:
    """Each entry of ``config.datasets``: its map's word store, extracted now if not cached.

    Raises
    ------
    ConfigError
        Two entries naming maps of the same name (their runs would share folders).
    """
    from curiosity_cli.data import load_map
    from curiosity_cli.words.extract import extract_words

    stores = {}
    for entry in config.datasets:
        map_data = load_map(entry)
        name = map_data.config.name
        if any(info.name == name for info in stores.values()):
            raise ConfigError(f"datasets: two entries are maps named {name!r}; runs are filed by map name")
        extraction = extract_words(map_data, config.words, cache_dir=cache_dir)
        store = extraction.store
        stores[entry] = StoreInfo(
            name, extraction.path, store.grid_shape, store.vocabulary_size, [t.sha256 for t in store.types],
            store.count_by_type(), map_data.config.stands_in_for,
        )
    return stores


@lru_cache(maxsize=4)
def _load_store(path: str):
    from curiosity_cli.words.store import load_store

    return load_store(Path(path))


def compute_run(task: RunTask, config: ExperimentConfig, threads: int = 1, store=None):
    """Compute one run in a worker: ``(task, (Exploration, seconds))``, or ``(task, error text)``.

    An error comes back as text rather than raised so that one failing run does not
    stop the others. ``store`` is the map's :class:`WordStore` when it was shipped to
    the worker (Dask); without it the worker loads ``task.store_path`` once.
    """
    import numba

    from curiosity_cli.explore.walker import explore

    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    started = time.perf_counter()
    try:
        exploration = explore(
            _load_store(task.store_path) if store is None else store, task.weight_function, task.start_cell,
            model=config.model, settings=config.explore, seed=task.seed,
        )
    except Exception as exc:  # noqa: BLE001 - reported with the run's name, the grid goes on
        return task, "".join(traceback.format_exception_only(exc)).strip()
    return task, (exploration, time.perf_counter() - started)


@contextlib.contextmanager
def _computed_runs(todo: list[RunTask], config: ExperimentConfig, *, backend: str, scheduler: str | None, jobs: int):
    """An iterator of :func:`compute_run`'s ``(task, outcome)`` for every task, in the order they finish.

    Whatever the backend, each run is ``compute_run(task, config, threads[, store])``
    and its outcome is consumed (written) by the caller. Leaving the context early
    stops the runs still in flight (and a local cluster).
    """
    if backend == "loky":
        from joblib import Parallel, delayed

        threads = threads_per_job(jobs)
        results = Parallel(n_jobs=jobs, backend="loky", return_as="generator_unordered")(
            delayed(compute_run)(task, config, threads) for task in todo
        )
        with contextlib.closing(results):
            yield results
    elif not todo:  # nothing to compute: start no cluster
        yield iter(())
    else:
        with _dask_client(scheduler, jobs) as (client, threads):
            with contextlib.closing(_dask_runs(client, todo, config, threads)) as results:
                yield results


def _import_distributed():
    try:
        import distributed
    except ImportError as exc:
        raise BackendError(
            f"the dask backend needs Dask distributed, which is not installed ({exc}); "
            "install it from the checkout with: pip install -e '.[distributed]'"
        ) from None
    return distributed


@contextlib.contextmanager
def _dask_client(scheduler: str | None, jobs: int):
    """A client of the cluster at ``scheduler`` (or of a local cluster started here), and each run's numba threads.

    On a local cluster of ``jobs`` one-thread processes, runs share the machine's cores
    as with loky; on a cluster someone started, a run gets one numba thread per worker
    thread (give workers one thread per core, ``dask worker``'s default).
    """
    import logging

    distributed = _import_distributed()
    with contextlib.ExitStack() as stack:
        if scheduler is None:
            cluster = stack.enter_context(distributed.LocalCluster(
                n_workers=jobs, threads_per_worker=1, processes=True, host="127.0.0.1",
                dashboard_address=None, silence_logs=logging.ERROR,
                # no dashboard, and the scheduler's HTTP routes on a free port, not on 8787
                scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
            ))
            client = stack.enter_context(distributed.Client(cluster, set_as_default=False))
            threads = threads_per_job(jobs)
        else:
            try:
                client = stack.enter_context(distributed.Client(scheduler, set_as_default=False))
            except (OSError, ValueError) as exc:
                raise BackendError(
                    f"cannot reach the Dask scheduler at {scheduler} ({exc}); start one with `dask scheduler` "
                    "and pass the address it prints"
                ) from None
            threads = 1
        try:
            client.wait_for_workers(1, timeout=WORKER_WAIT_SECONDS)
        except TimeoutError:
            raise BackendError(
                f"the Dask scheduler at {scheduler} has no worker after {WORKER_WAIT_SECONDS} s; "
                f"start some with `dask worker {scheduler}`"
            ) from None
        _check_worker_versions(client)
        yield client, threads


def _versions() -> tuple[str, str, str]:
    """What a run's numbers depend on besides its inputs: this package's, numpy's and numba's versions."""
    from importlib.metadata import version

    from curiosity_cli import __version__

    return __version__, version("numpy"), version("numba")


def _check_worker_versions(client) -> None:
    """Refuse workers whose runs could differ from this process's: other package, numpy or numba versions."""
    try:
        found = client.run(_versions)
    except Exception as exc:  # noqa: BLE001 - e.g. the package is not installed on a worker
        raise BackendError(
            f"the Dask workers cannot run curiosity ({type(exc).__name__}: {exc}); "
            "install the same version of curiosity on every worker machine"
        ) from None
    here = _versions()
    for address, theirs in sorted(found.items()):
        if tuple(theirs) != here:
            names = ("curiosity", "numpy", "numba")
            diff = ", ".join(f"{n} {t} (here {h})" for n, t, h in zip(names, theirs, here) if t != h)
            raise BackendError(
                f"the Dask worker at {address} has {diff}; its runs could differ, so install the same versions "
                "on every worker machine"
            )


def _store_from_bytes(name: str, data: bytes):
    """A word store from its file's bytes: how a Dask worker gets a map's store."""
    import tempfile

    from curiosity_cli.words.store import load_store

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / name
        path.write_bytes(data)
        return load_store(path)


def _dask_runs(client, todo: list[RunTask], config: ExperimentConfig, threads: int):
    """Yield ``(task, outcome)`` as the cluster finishes each run (module docstring)."""
    import uuid

    from distributed import KilledWorker, as_completed

    token = uuid.uuid4().hex[:8]
    shipped = {
        path: client.submit(_store_from_bytes, Path(path).name, Path(path).read_bytes(), key=f"store-{Path(path).stem}-{token}")
        for path in sorted({task.store_path for task in todo})
    }
    futures = {
        client.submit(
            compute_run, task, config, threads, shipped[task.store_path],
            key=f"explore-{task.dataset}/{task.weight_function}/restart-{task.restart:03d}-{token}",
        ): task
        for task in todo
    }
    try:
        for future in as_completed(futures, loop=client.loop):
            task = futures[future]
            try:
                result = future.result()
            except KilledWorker:
                result = task, "KilledWorker: every worker that ran it died (out of memory?); see the workers' logs"
            except Exception as exc:  # noqa: BLE001 - e.g. its store was lost with the workers; the grid goes on
                result = task, f"{type(exc).__name__}: {exc}"
            future.release()
            yield result
    finally:  # stopped early: the cluster need not finish the rest
        client.cancel([future for future in futures if not future.done()])


def _write(folder: Path, task: RunTask, exploration, seconds: float, config: ExperimentConfig, store: StoreInfo) -> int:
    from curiosity_cli import __version__
    from curiosity_cli.explore.runs import run_folder, write_run

    grid_shape = store.grid_shape
    meta = {
        "dataset": task.dataset,
        "weight_function": task.weight_function,
        "restart": task.restart,
        "start_cell": task.start_cell,
        "start_row": task.start_cell // grid_shape[1],
        "start_col": task.start_cell % grid_shape[1],
        "seed": list(task.seed),
        "store": store.path.name,
        "vocabulary_hashes": store.vocabulary_hashes,
        "grid_shape": list(grid_shape),
        "vocabulary_size": store.vocabulary_size,
        "n_topics": config.model.topics,
        "path_length": config.explore.path_length,
        "fallbacks": int(exploration.fallback.sum()),
        "words_sampled": int(exploration.words_sampled.sum()),
        "seconds": round(seconds, 3),
        "curiosity": __version__,
    }
    return write_run(run_folder(folder, task.dataset, task.weight_function, task.restart), exploration, meta, grid_shape[1])


def _write_experiment_files(folder: Path, config: ExperimentConfig, tasks: list[RunTask], stores) -> None:
    import pandas as pd
    import yaml

    from curiosity_cli.provenance import provenance

    folder.mkdir(parents=True, exist_ok=True)
    with atomic_path(folder / "config.yaml") as tmp:
        tmp.write_text(to_yaml(config))
    with atomic_path(folder / "provenance.yaml") as tmp:
        tmp.write_text(yaml.safe_dump(provenance(config.seed), sort_keys=False))
    rows = []
    for t in tasks:
        cols = stores[t.dataset].grid_shape[1]
        rows.append(
            {"dataset": t.dataset, "weight_function": t.weight_function, "restart": t.restart,
             "start_row": t.start_cell // cols, "start_col": t.start_cell % cols,
             "seed": " ".join(map(str, t.seed)), "store": Path(t.store_path).name}
        )
    with atomic_path(folder / "runs.csv") as tmp:
        pd.DataFrame(rows).to_csv(tmp, index=False)
    maps = []
    for name, info in stores.items():
        total = sum(info.word_counts.values())
        maps.append(
            {"dataset": name, "stands_in_for": info.stands_in_for or "", "cells": info.grid_shape[0] * info.grid_shape[1],
             "words": total, **{f"{kind}_words": n for kind, n in info.word_counts.items()},
             "orb_share": info.word_counts.get("orb", 0) / total if total else float("nan"), "store": info.path.name}
        )
    with atomic_path(folder / "maps.csv") as tmp:
        pd.DataFrame(maps).to_csv(tmp, index=False)
