"""``curiosity label`` for a whole experiment: Z_b per map, Z_p per run and checkpoint.

Written under ``results/<experiment>/``:

- ``batch/<dataset>.npz``: the batch reference Z_b of a map: ``labels`` (H, W) int16
  pixel topics, ``word_labels`` (N,) int16, ``log_likelihood`` (batch_sweeps,) float64
  and ``meta`` (JSON: word store, vocabulary hashes, seed, sweeps, model). Reused while
  its ``meta`` matches the experiment's.
- ``labels/<dataset>/<weight function>/restart-<NNN>.npz``: for one run, per checkpoint
  length (``lengths``), the contingency tables of Z_p against the human labels
  (``human``, (n, K, C) int64, absent for a map without labels) and against Z_b
  (``batch``, (n, K, K) int64), and ``meta`` (JSON). Tables rather than label maps: MI and
  NMI follow from them exactly, in kilobytes instead of a megabyte per checkpoint.
- ``labels/<dataset>/examples/<weight function>-restart-<NNN>-<length>.npz``: the pixel
  label map Z_p (``labels``, (H, W) int16) of restart 0 at path length 80 and at its
  last checkpoint, for the figures.

Every file is written atomically; a killed ``label`` resumes with the runs not yet done.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from curiosity_cli.config import ExperimentConfig, to_dict
from curiosity_cli.errors import CuriosityError
from curiosity_cli.files import atomic_path, display_path

if TYPE_CHECKING:
    from curiosity_cli.explore.grid import StoreInfo

LABEL_FORMAT = 1
#: Path lengths whose Z_p maps are kept for restart 0 (besides the last checkpoint).
EXAMPLE_LENGTHS = (80,)
# tags that keep the label streams apart from the runs' own
_PATH_TAG, _BATCH_TAG = 1, 2


class LabelError(CuriosityError):
    """Labels that cannot be computed or do not belong to the runs they claim."""


@dataclass(frozen=True)
class MapInputs:
    """What labelling one map needs, by file, so workers can load it once."""

    name: str
    entry: str  # the config's datasets entry (a name or a YAML path)
    store_path: str
    batch_path: str


def batch_path(folder: Path, dataset: str) -> Path:
    return Path(folder) / "batch" / f"{dataset}.npz"


def label_path(folder: Path, dataset: str, weight_function: str, restart: int) -> Path:
    return Path(folder) / "labels" / dataset / weight_function / f"restart-{restart:03d}.npz"


def example_path(folder: Path, dataset: str, weight_function: str, restart: int, length: int) -> Path:
    return Path(folder) / "labels" / dataset / "examples" / f"{weight_function}-restart-{restart:03d}-{length}.npz"


def _batch_meta(config: ExperimentConfig, store_name: str, hashes: list[str]) -> dict:
    return {
        "format": LABEL_FORMAT, "store": store_name, "vocabulary_hashes": hashes, "seed": config.seed,
        "sweeps": config.label.batch_sweeps, "model": to_dict(config.model),
    }


def read_meta(npz) -> dict:
    return json.loads(str(npz["meta"]))


def ensure_batch_reference(
    folder: Path, config: ExperimentConfig, entry: str, info: StoreInfo, *, threads: int, force: bool = False,
    on_sweep: Callable[[int], None] | None = None,
) -> tuple[Path, bool]:
    """Compute (or reuse) a map's batch reference Z_b; returns ``(its file, whether it was reused)``.

    ``entry`` is the config's datasets entry and ``info`` its word store (from
    :func:`~curiosity_cli.explore.grid.prepare_stores`); the map and its store are only
    loaded when the reference has to be computed.
    """
    from curiosity_cli.data import load_map
    from curiosity_cli.evaluate.labeling import batch_labels, pixel_labels
    from curiosity_cli.explore.grid import name_key
    from curiosity_cli.words.store import load_store

    meta = _batch_meta(config, info.path.name, info.vocabulary_hashes)
    path = batch_path(folder, info.name)
    if path.is_file() and not force:
        try:
            with np.load(path) as npz:
                stored = read_meta(npz)
                stored.pop("seconds", None)
                if stored == meta:
                    return path, True
        except (OSError, ValueError, KeyError):
            pass  # unreadable: compute it again
    store = load_store(info.path)
    seed = int(np.random.SeedSequence((config.seed, name_key(info.name), _BATCH_TAG)).generate_state(1, np.uint64)[0])
    started = time.perf_counter()
    word_labels, trace = batch_labels(
        store, config.model, sweeps=config.label.batch_sweeps, seed=seed, threads=threads, on_sweep=on_sweep
    )
    meta["seconds"] = round(time.perf_counter() - started, 2)
    labels = pixel_labels(store, word_labels, load_map(entry).image.shape[:2])
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as handle:
            np.savez_compressed(
                handle, labels=labels, word_labels=word_labels, log_likelihood=trace, meta=json.dumps(meta, sort_keys=True)
            )
    return path, False


@lru_cache(maxsize=4)
def _map_arrays(entry: str, store_path: str, batch_file: str):
    """(store, human labels or None, number of classes, batch pixel labels, image shape), once per worker."""
    from curiosity_cli.data import load_map
    from curiosity_cli.words.store import load_store

    map_data = load_map(entry)
    n_classes = max(c.id for c in map_data.legend) + 1 if map_data.labels is not None else 0
    with np.load(batch_file) as npz:
        batch = npz["labels"]
    return load_store(Path(store_path)), map_data.labels, n_classes, batch, map_data.image.shape[:2]


def label_run(run_folder: Path, inputs: MapInputs, config: ExperimentConfig, threads: int = 1):
    """Z_p of every checkpoint of one run, as contingency tables; ``(tables, examples, meta)``.

    Raises
    ------
    LabelError
        The run was made from another word store than the map's current one.
    """
    from curiosity_cli.evaluate.information import contingency
    from curiosity_cli.evaluate.labeling import label_with_phi, pixel_labels
    from curiosity_cli.explore.runs import read_run

    run = read_run(run_folder)
    store, human, n_classes, batch, shape = _map_arrays(inputs.entry, inputs.store_path, inputs.batch_path)
    if run.meta["store"] != Path(inputs.store_path).name:
        raise LabelError(
            f"{display_path(run_folder)}: made from word store {run.meta['store']}, but {inputs.name}'s words are now "
            f"{Path(inputs.store_path).name}; run `curiosity explore --force` to redo the runs"
        )
    k = config.model.topics
    lengths = run.meta["checkpoints"]
    tables = {"human": [], "batch": []}
    examples = {}
    last = lengths[-1]
    for length in lengths:
        seed = np.random.SeedSequence((*run.meta["seed"], length, _PATH_TAG)).generate_state(1, np.uint64)[0]
        words = label_with_phi(store, run.phi(length), config.model, sweeps=config.label.sweeps, seed=int(seed), threads=threads)
        pixels = pixel_labels(store, words, shape)
        if human is not None:
            tables["human"].append(contingency(pixels, human, k, n_classes))
        tables["batch"].append(contingency(pixels, batch, k, k))
        if run.meta["restart"] == 0 and (length in EXAMPLE_LENGTHS or length == last):
            examples[length] = pixels
    meta = {
        "format": LABEL_FORMAT, "dataset": inputs.name, "weight_function": run.meta["weight_function"],
        "restart": run.meta["restart"], "run_seed": run.meta["seed"], "store": run.meta["store"],
        "vocabulary_hashes": run.meta["vocabulary_hashes"], "sweeps": config.label.sweeps,
        "batch": Path(inputs.batch_path).name,
    }
    arrays = {"lengths": np.array(lengths, np.int32), "batch": np.stack(tables["batch"])}
    if tables["human"]:
        arrays["human"] = np.stack(tables["human"])
    return arrays, examples, meta


def write_labels(folder: Path, arrays: dict, examples: dict, meta: dict) -> None:
    """Write a run's label file and its example maps, each atomically (examples first)."""
    for length, pixels in examples.items():
        path = example_path(folder, meta["dataset"], meta["weight_function"], meta["restart"], length)
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as handle:
                np.savez_compressed(handle, labels=pixels)
    path = label_path(folder, meta["dataset"], meta["weight_function"], meta["restart"])
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as handle:
            np.savez_compressed(handle, **arrays, meta=json.dumps(meta, sort_keys=True))


def is_labelled(folder: Path, run_meta: dict, config: ExperimentConfig) -> bool:
    """Whether a run's label file exists and was made from this run with these settings."""
    path = label_path(folder, run_meta["dataset"], run_meta["weight_function"], run_meta["restart"])
    try:
        with np.load(path) as npz:
            meta = read_meta(npz)
    except (OSError, ValueError, KeyError):
        return False
    return meta["run_seed"] == run_meta["seed"] and meta["store"] == run_meta["store"] and meta["sweeps"] == config.label.sweeps


def label_experiment(
    config: ExperimentConfig,
    *,
    results_dir: Path = Path("results"),
    cache_dir: Path = Path("results/cache"),
    jobs: int | None = None,
    force: bool = False,
    on_stage: Callable[[str, int], None] | None = None,
    on_done: Callable[[], None] | None = None,
) -> dict:
    """Label every finished run of an experiment (and each map's batch reference).

    Parameters
    ----------
    config : ExperimentConfig
        The experiment (its folder is ``results_dir / config.name``).
    jobs : int, optional
        Worker processes for the runs; default the number of cores.
    force : bool
        Recompute labels (and batch references) that are up to date.
    on_stage : callable, optional
        ``on_stage(description, units)`` when a stage starts (units of ``on_done``).
    on_done : callable, optional
        Called after each unit of work.

    Returns
    -------
    dict
        ``labelled``, ``skipped``, ``batch_reused`` counts and ``seconds``.

    Raises
    ------
    LabelError
        No finished runs, or runs made from another word store (all of them named).
    """
    import os

    from joblib import Parallel, delayed

    from curiosity_cli.explore.grid import prepare_stores, threads_per_job
    from curiosity_cli.explore.runs import RunError, is_complete, read_run

    started = time.perf_counter()
    folder = Path(results_dir) / config.name
    jobs = (os.cpu_count() or 1) if jobs is None else jobs
    stores = prepare_stores(config, cache_dir)
    runs = sorted(p for p in (folder / "runs").glob("*/*/restart-*") if is_complete(p))
    names = {info.name for info in stores.values()}
    runs = [p for p in runs if p.parent.parent.name in names]
    if not runs:
        raise LabelError(f"{display_path(folder / 'runs')}: no finished runs; run `curiosity explore` first")

    inputs, reused = {}, 0
    for entry, info in stores.items():
        if on_stage is not None:
            on_stage(f"batch reference {info.name}", config.label.batch_sweeps)
        path, was_reused = ensure_batch_reference(
            folder, config, entry, info, threads=jobs, force=force, on_sweep=lambda _: on_done and on_done()
        )
        reused += was_reused
        inputs[info.name] = MapInputs(info.name, entry, str(info.path), str(path))

    todo = []
    for run_path in runs:
        try:
            meta = read_run(run_path).meta
        except RunError:
            todo.append(run_path)  # label_run reports it by name
            continue
        if force or not is_labelled(folder, meta, config):
            todo.append(run_path)
    if on_stage is not None:
        on_stage("labelling runs", len(todo))
    threads = threads_per_job(jobs)
    failed = []
    results = Parallel(n_jobs=jobs, backend="loky", return_as="generator_unordered")(
        delayed(_label_task)(p, inputs[p.parent.parent.name], config, threads) for p in todo
    )
    for run_path, outcome in results:
        if isinstance(outcome, str):
            failed.append(outcome)
        else:
            write_labels(folder, *outcome)
        if on_done is not None:
            on_done()
    if failed:
        raise LabelError(f"{len(failed)} of {len(todo)} runs could not be labelled (the others are written): " + "; ".join(failed))
    return {"labelled": len(todo), "skipped": len(runs) - len(todo), "batch_reused": reused,
            "seconds": time.perf_counter() - started}


def _label_task(run_path: Path, inputs: MapInputs, config: ExperimentConfig, threads: int):
    """``(run_path, (arrays, examples, meta))``, or ``(run_path, error text)`` so one bad run does not stop the rest."""
    try:
        return run_path, label_run(run_path, inputs, config, threads)
    except CuriosityError as exc:
        return run_path, str(exc)
