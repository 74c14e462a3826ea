"""The experiment grid: maps x weight functions x restarts, in parallel, resumable.

Design, in the order a grid runs:

- **Paired start cells.** For each map, one seeded permutation of its cells (from the
  experiment seed and the map's name); restart ``r`` starts at its ``r``-th cell for
  every weight function, so weight functions can be compared restart by restart. A
  restart's start cell does not depend on how many restarts the grid has.
- **Seeds.** Each run draws from ``SeedSequence((seed, crc32(map), crc32(weight
  function), restart))``: the same numbers whatever ``jobs`` is and in whatever order
  runs finish.
- **Parallel.** Runs are tasks of :class:`~curiosity_cli.workers.Workers`: joblib's
  ``loky`` processes by default, where a worker loads the map's word store from the cache
  once and keeps it, and each worker's numba threads are capped so the workers together
  use the cores once.
- **Or on a Dask cluster** (``backend="dask"``, :mod:`curiosity_cli.workers`): each
  map's store file goes to the cluster once and runs depend on the task that loads it;
  each run is one task, all submitted at once and collected as they finish. A run lost
  with its worker is computed again on another; a run whose workers keep dying is
  reported by name like a run that raised. The same :func:`compute_run` computes every
  run on either backend, so results are identical.
- **Written by the caller.** A task returns its :class:`Exploration`; this process
  writes the run folder atomically (:mod:`curiosity_cli.explore.runs`), so where a run
  was computed never matters and a killed grid loses only the runs in flight.
- **Resumable.** Finished runs are skipped unless ``force``; the experiment folder
  keeps the resolved config, ``runs.csv`` (every run's start cell and seed),
  ``maps.csv`` and ``provenance.yaml`` (seed, version, commit, and the sizes and digests
  of the two tables, which later stages check). A resumed grid must agree with the
  saved config on everything that changes a run's numbers, and every finished run with
  the recipe this config gives it (:mod:`curiosity_cli.experiment.recipes`): a run made otherwise
  is refused by name before anything is written, or redone with ``force``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from curiosity_cli.config import READS_TRUTH, ExperimentConfig
from curiosity_cli.config_yaml import saved_yaml
from curiosity_cli.errors import RERUN, ConfigError, CuriosityError
from curiosity_cli.experiment.experiment import Experiment
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.experiment.lock import working_in
from curiosity_cli.experiment.stage_seconds import record_stage_seconds
from curiosity_cli.experiment.maps import StoreInfo, prepare_stores
from curiosity_cli.experiment.recipes import RECIPE_KEY, Recipe, first_of
from curiosity_cli.experiment.wholeness import FILES_KEY, records
from curiosity_cli.experiment.saved_config import check_saved_config
from curiosity_cli.explore.weights import stream_name
from curiosity_cli.workers import Workers
from curiosity_cli.files import atomic_path, check_inside, display_path
from curiosity_cli.paths import DEFAULT_CACHE, DEFAULT_RESULTS, experiment_root
from curiosity_cli.seeds import name_key

class GridError(CuriosityError):
    """Some runs of a grid failed; the others were written."""


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
class GridSummary:
    """What a call to :func:`run_grid` did."""

    folder: Path
    ran: int
    skipped: int
    failed: list[str]
    fallbacks: int
    bytes_written: int
    seconds: float


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
        grid = stores[entry].grid
        n_cells = grid.n_cells
        if config.explore.path_length > n_cells:
            raise ConfigError(
                f"explore.path_length: got {config.explore.path_length} steps, but {dataset} has only {n_cells} "
                f"cells ({grid.rows} x {grid.cols}); use fewer steps or a smaller cell width"
            )
        reading = [w for w in config.explore.weight_functions if w in READS_TRUTH]
        if reading and stores[entry].facts.labels_digest is None:
            raise ConfigError(
                f"explore.weight_functions: {reading[0]} reads a map's human labels, and {dataset} has none; "
                "run it on maps with labels"
            )
        starts = start_cells(config.seed, dataset, n_cells, config.explore.restarts)
        for restart, start in enumerate(starts):
            for weight_function in config.explore.weight_functions:
                seed = (config.seed, name_key(dataset), name_key(stream_name(weight_function)), restart)
                tasks.append(RunTask(dataset, weight_function, restart, int(start), seed, str(stores[entry].path)))
    return tasks


def run_grid(
    config: ExperimentConfig,
    *,
    results_dir: Path = DEFAULT_RESULTS,
    cache_dir: Path = DEFAULT_CACHE,
    jobs: int | None = None,
    force: bool = False,
    on_prepared: Callable[[int, int], None] | None = None,
    on_run: Callable[[RunTask, int], None] | None = None,
    backend: str = "loky",
    scheduler: str | None = None,
    workers: Workers | None = None,
    beside: Callable[[Experiment, dict[str, StoreInfo]], None] | None = None,
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
        Redo finished runs too, those made from other recipes included.
    on_prepared : callable, optional
        Called as ``on_prepared(to_run, skipped)`` before the first run starts.
    on_run : callable, optional
        Called as ``on_run(task, bytes_written)`` as each run is written (bytes 0 if it failed).
    backend : {"loky", "dask"}
        Where runs are computed (module docstring); the results do not depend on it.
    scheduler : str, optional
        With ``backend="dask"``: a running scheduler's address, e.g.
        ``tcp://10.0.0.5:8786``; without one, a local cluster is started for the grid.
    workers : Workers, optional
        Where to compute instead of new workers from ``backend``, ``scheduler`` and
        ``jobs``: open ones another stage shares (``curiosity reproduce``).
    beside : callable, optional
        Called as ``beside(experiment, stores)`` (the :class:`Experiment` and the word stores by
        ``datasets`` entry) once the grid is checked, before the first run starts: work to
        start beside the exploration (``curiosity reproduce`` starts the batch references).

    Raises
    ------
    ConfigError
        A saved config that disagrees, finished runs made from other recipes (without
        ``force``), or a map too small for the grid.
    ParameterError
        An unknown backend, or a scheduler without ``backend="dask"``.
    BackendError
        ``backend="dask"`` without Dask distributed installed, a scheduler that cannot be
        reached or gets no worker, or workers with other versions of the package, numpy
        or numba than this process.
    GridError
        After the whole grid, if some runs raised or kept killing their Dask workers: each named, with its error.
    FolderInUseError
        Another process works in the experiment folder (:mod:`~curiosity_cli.experiment.lock`).
    """
    from curiosity_cli.explore.runs import finished_meta, remove_partial_runs
    from curiosity_cli.words.store import load_store

    started = time.perf_counter()
    computing = Workers.shared(workers, backend, scheduler, jobs)
    folder = experiment_root(results_dir, config.name)
    check_inside(folder, results_dir, "name")
    check_saved_config(folder, config)
    stores = prepare_stores(config, cache_dir)
    tasks = plan_runs(config, stores)
    for task in tasks:
        check_inside(ExperimentFolder(folder).run(task.dataset, task.weight_function, task.restart), folder, task.dataset)
    by_name = {info.name: info for info in stores.values()}
    experiment = Experiment(folder, config, {name: info.facts for name, info in by_name.items()})
    recipes = {t: experiment.run_recipe(t.dataset, t.weight_function, t.restart) for t in tasks}
    todo, stale = [], []
    for task in tasks:
        run_path = ExperimentFolder(folder).run(task.dataset, task.weight_function, task.restart)
        meta = None if force else finished_meta(run_path)
        if meta is None:
            todo.append(task)
        elif (change := recipes[task].changes(meta)) is not None:
            stale.append(f"{display_path(run_path / 'run.json')}: {change}")
    if stale:
        raise ConfigError(
            f"{len(stale)} finished runs were made otherwise than this config makes them ({first_of(stale)}); "
            f"use another experiment name or results folder, or run {RERUN} to redo them",
            rerun="explore",
        )
    _write_experiment_files(folder, config, tasks, by_name)
    with working_in(folder, "explore"):  # from here it removes and writes runs
        remove_partial_runs(folder)

        if on_prepared is not None:
            on_prepared(len(todo), len(tasks) - len(todo))
        if beside is not None:
            beside(experiment, stores)
        failed, fallbacks, written = [], 0, 0
        with computing as workers:
            shipped = {}  # loky workers load the stores from the cache themselves
            if workers.ships:
                shipped = {path: workers.ship_file(path, load_store) for path in sorted({t.store_path for t in todo})}
            reading = {t.dataset for t in todo if t.weight_function in READS_TRUTH}
            truths = map_truths([info.facts.entry for info in stores.values() if info.name in reading])
            computed = workers.compute(
                compute_run, todo, args=lambda task: (config, shipped.get(task.store_path), truths.get(task.dataset)),
                key=lambda task: f"explore-{task.dataset}/{task.weight_function}/restart-{task.restart:03d}",
            )
            with computed as results:
                for task, outcome in results:
                    size = 0
                    if isinstance(outcome, str):
                        failed.append(f"{task.dataset} / {task.weight_function} / restart {task.restart}: {outcome}")
                    else:
                        exploration, seconds = outcome
                        size = _write(folder, task, exploration, seconds, recipes[task], config, by_name[task.dataset])
                        fallbacks += int(exploration.fallback.sum())
                        written += size
                    if on_run is not None:
                        on_run(task, size)
        summary = GridSummary(folder, len(todo) - len(failed), len(tasks) - len(todo), failed, fallbacks, written,
                              time.perf_counter() - started)
        if todo:  # a call that found every run done made nothing
            record_stage_seconds(folder, "extract and explore", summary.seconds, add=not force)
        if failed:
            raise GridError(f"{len(failed)} of {len(todo)} runs failed (the others are written): " + "; ".join(failed))
        return summary


@lru_cache(maxsize=4)
def _load_store(path: str):
    from curiosity_cli.words.store import load_store

    return load_store(Path(path))


def map_truths(entries: list[str]) -> dict[str, np.ndarray]:
    """The classes present in each cell of the maps of these ``datasets`` entries, by map name, for the walkers
    that read a map's truth: (n_cells, C) bool ndarrays (:func:`~curiosity_cli.maps.cell_classes.classes_present`
    at the share that counts a class found). Only these maps are loaded: a grid without such a walker loads none."""
    from curiosity_cli.experiment.recipes import CLASS_SHARE_PERCENT
    from curiosity_cli.maps.cell_classes import classes_present, map_class_pixels
    from curiosity_cli.maps.map_data import load_map

    truths = {}
    for entry in entries:
        map_data = load_map(entry)
        truths[map_data.config.name] = classes_present(map_class_pixels(map_data), CLASS_SHARE_PERCENT)
    return truths


def compute_run(task: RunTask, config: ExperimentConfig, store=None, truth=None, *, threads: int = 1):
    """Compute one run in a worker: ``(Exploration, seconds)``.

    ``store`` is the map's :class:`WordStore` when it was shipped to the worker (Dask);
    without it the worker loads ``task.store_path`` once. ``truth``: the classes present in
    each cell, for a walker that reads them (:func:`map_truths`).
    """
    import numba

    from curiosity_cli.explore.walker import explore

    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    started = time.perf_counter()
    exploration = explore(
        _load_store(task.store_path) if store is None else store, task.weight_function, task.start_cell,
        model=config.model, settings=config.explore, seed=task.seed, truth=truth,
    )
    return exploration, time.perf_counter() - started


def _write(
    folder: Path, task: RunTask, exploration, seconds: float, recipe: Recipe, config: ExperimentConfig, store: StoreInfo,
) -> int:
    from curiosity_cli import __version__
    from curiosity_cli.explore.runs import write_run

    start_row, start_col = store.grid.row_col(task.start_cell)
    meta = {
        "dataset": task.dataset,
        "weight_function": task.weight_function,
        "restart": task.restart,
        "start_cell": task.start_cell,
        "start_row": int(start_row),
        "start_col": int(start_col),
        "seed": list(task.seed),
        "store": store.facts.store,
        "vocabulary_hashes": store.facts.vocabulary_hashes,
        "grid_shape": list(store.grid.shape),
        "vocabulary_size": store.vocabulary_size,
        "n_topics": config.model.topics,
        "path_length": config.explore.path_length,
        "fallbacks": int(exploration.fallback.sum()),
        "words_sampled": int(exploration.words_sampled.sum()),
        "seconds": round(seconds, 3),
        "curiosity": __version__,
        RECIPE_KEY: recipe.record(),
    }
    return write_run(ExperimentFolder(folder).run(task.dataset, task.weight_function, task.restart), exploration, meta, store.grid)


def _write_experiment_files(folder: Path, config: ExperimentConfig, tasks: list[RunTask], stores) -> None:
    import pandas as pd
    import yaml

    from curiosity_cli.experiment.provenance import provenance

    folder.mkdir(parents=True, exist_ok=True)
    layout = ExperimentFolder(folder)
    with atomic_path(layout.config) as tmp:
        tmp.write_text(saved_yaml(config))
    rows = []
    for t in tasks:
        start_row, start_col = stores[t.dataset].grid.row_col(t.start_cell)
        rows.append(
            {"dataset": t.dataset, "weight_function": t.weight_function, "restart": t.restart,
             "start_row": int(start_row), "start_col": int(start_col),
             "seed": " ".join(map(str, t.seed)), "store": Path(t.store_path).name}
        )
    with atomic_path(layout.runs_csv) as tmp:
        pd.DataFrame(rows).to_csv(tmp, index=False)
    maps = []
    for name, info in stores.items():
        total = sum(info.word_counts.values())
        maps.append(
            {"dataset": name, "stands_in_for": info.facts.stands_in_for or "", "cells": info.grid.n_cells,
             "words": total, **{f"{kind}_words": n for kind, n in info.word_counts.items()},
             "orb_share": info.word_counts.get("orb", 0) / total if total else float("nan"), "store": info.path.name}
        )
    with atomic_path(layout.maps_csv) as tmp:
        pd.DataFrame(maps).to_csv(tmp, index=False)
    # last, recording the tables it wrote: a later stage reads maps.csv and must not trust an edited one
    record = {**provenance(config.seed), FILES_KEY: records(folder, [layout.runs_csv.name, layout.maps_csv.name])}
    with atomic_path(layout.provenance) as tmp:
        tmp.write_text(yaml.safe_dump(record, sort_keys=False))
