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
  NMI follow from them exactly, in kilobytes instead of a megabyte per checkpoint. For a
  map with human labels also ``class_first_step`` ((C,) int32): the step at which the
  path first stood in a cell where class ``h`` covers at least ``CLASS_SHARE_PERCENT`` %
  of the pixels, -1 if never (the classes found within ``n`` steps are those below
  ``n``); ``meta["class_share_percent"]`` records the share.
- ``labels/<dataset>/examples/<weight function>-restart-<NNN>-<length>.npz``: the pixel
  label map Z_p (``labels``, (H, W) int16) of restart 0 at path length 80 and at its
  last checkpoint, for the figures.

Every file is written atomically; a killed ``label`` resumes with the runs not yet done.

Batch references and runs are tasks of :class:`~curiosity_cli.parallel.Workers`. With
loky, batch references are computed in this process, one map after the other on ``jobs``
threads, and a worker reads each map's word store, human labels and Z_b once. On a Dask
cluster, batch references are tasks too, each map's word store goes to the cluster once
and its human labels and Z_b pixel labels once; each run's ``run.json`` and checkpoint
counts Φ_p (a few kilobytes) travel with its task, so workers need no copy of the maps,
stores or results. Either way this process writes every file, and the same functions
compute the labels, so the results are identical.
"""

from __future__ import annotations

import contextlib
import json
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from curiosity_cli.config import ExperimentConfig, to_dict
from curiosity_cli.errors import CuriosityError
from curiosity_cli.files import CorruptFileError, atomic_path, display_path, note, open_npz

if TYPE_CHECKING:
    from curiosity_cli.evaluate.labeling import PathLabeller
    from curiosity_cli.explore.grid import StoreInfo
    from curiosity_cli.explore.runs import Run
    from curiosity_cli.parallel import Workers
    from curiosity_cli.words.store import WordStore

LABEL_FORMAT = 1
#: A human class counts as found in a visited cell when it covers at least this share
#: (percent) of the cell's pixels: enough to be seen, not a sliver at the cell's edge.
CLASS_SHARE_PERCENT = 10
#: Path lengths whose Z_p maps are kept for restart 0 (besides the last checkpoint).
EXAMPLE_LENGTHS = (80,)
# tags that keep the label streams apart from the runs' own
_PATH_TAG, _BATCH_TAG = 1, 2
#: Whole-map labelling models a thread keeps, one per map.
_LABELLERS_PER_THREAD = 4
_per_thread = threading.local()


class LabelError(CuriosityError):
    """Labels that cannot be computed or do not belong to the runs they claim."""


@dataclass(frozen=True)
class MapInputs:
    """What labelling one map needs, by file, so workers can load it once."""

    name: str
    entry: str  # the config's datasets entry (a name or a YAML path)
    store_path: str
    batch_path: str


class MapArrays(NamedTuple):
    """A map as its runs' labelling needs it in a worker: read there once (loky) or shipped once (Dask)."""

    store: WordStore
    human: np.ndarray | None  # (H, W) class ids
    n_classes: int
    batch: np.ndarray  # (H, W) Z_b
    shape: tuple[int, int]
    cell_classes: np.ndarray | None  # (n_cells, C) pixels of each class per cell, None without human labels


@dataclass(frozen=True)
class RunInputs:
    """A run as labelling needs it, read by this process and sent with its task.

    Attributes
    ----------
    folder : Path
    meta : dict
        Its ``run.json``.
    checkpoints : dict of int to SparseCounts
        The word-topic counts Φ_p at each checkpoint length, as stored.
    path : (L,) int64 ndarray
        Row-major cell of each step, for the classes found.
    """

    folder: Path
    meta: dict
    checkpoints: dict
    path: np.ndarray

    @classmethod
    def of(cls, run: Run) -> RunInputs:
        """Read a run's checkpoints.

        Raises
        ------
        RunError
            A missing or corrupt ``checkpoints.npz``, naming it.
        """
        from curiosity_cli.explore.walker import SparseCounts

        return cls(run.folder, run.meta, {n: SparseCounts.of(run.phi(n)) for n in run.meta["checkpoints"]}, run.path)

    def phi(self, length: int) -> np.ndarray:
        """(V, K) int32 ndarray: the word-topic counts Φ_p after ``length`` steps."""
        return self.checkpoints[length].dense()


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


#: What every label file's ``meta`` names: a file without one of these is corrupt.
LABEL_META_KEYS = ("dataset", "weight_function", "restart", "run_seed", "store", "vocabulary_hashes", "sweeps")


def read_meta(npz, required: tuple[str, ...] = ()) -> dict:
    """The JSON ``meta`` of a batch reference or label file, with the ``required`` keys.

    Raises
    ------
    KeyError, ValueError
        No meta, not a JSON object, or a required key missing: read inside
        :func:`~curiosity_cli.files.open_npz`, the file is reported as corrupt.
    """
    meta = json.loads(str(npz["meta"]))
    if not isinstance(meta, dict):
        raise ValueError("its meta is not a JSON object")
    missing = [key for key in required if key not in meta]
    if missing:
        raise KeyError(f"its meta lacks {', '.join(missing)}")
    return meta


def _batch_is_current(path: Path, config: ExperimentConfig, info: StoreInfo) -> bool:
    """Whether a batch reference file exists and was made from this store with these settings.

    A corrupt one is not, and is noted on stderr as computed again.
    """
    try:
        with open_npz(path) as npz:
            stored = read_meta(npz)
    except FileNotFoundError:
        return False
    except CorruptFileError as exc:
        note(f"{exc}; computing it again")
        return False
    stored.pop("seconds", None)
    return stored == _batch_meta(config, info.path.name, info.vocabulary_hashes)


def _compute_batch(
    info: StoreInfo, config: ExperimentConfig, store: WordStore, image_shape: tuple[int, int], *, threads: int = 1,
    on_sweep: Callable[[int], None] | None = None,
) -> tuple:
    """A map's batch reference, in this process or a worker: ``(pixel labels, word labels, trace, seconds)``."""
    from curiosity_cli.evaluate.labeling import batch_labels, pixel_labels
    from curiosity_cli.explore.grid import name_key

    seed = int(np.random.SeedSequence((config.seed, name_key(info.name), _BATCH_TAG)).generate_state(1, np.uint64)[0])
    started = time.perf_counter()
    word_labels, trace = batch_labels(
        store, config.model, sweeps=config.label.batch_sweeps, seed=seed, threads=threads, on_sweep=on_sweep
    )
    seconds = time.perf_counter() - started
    return pixel_labels(store, word_labels, image_shape), word_labels, trace, seconds


def _write_batch(path: Path, config: ExperimentConfig, info: StoreInfo, labels, word_labels, trace, seconds: float) -> None:
    meta = {**_batch_meta(config, info.path.name, info.vocabulary_hashes), "seconds": round(seconds, 2)}
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as handle:
            np.savez_compressed(
                handle, labels=labels, word_labels=word_labels, log_likelihood=trace, meta=json.dumps(meta, sort_keys=True)
            )


def path_seed(run_seed) -> int:
    """The seed of a run's labelling chain, from the run's own seed entropy."""
    return int(np.random.SeedSequence((*run_seed, _PATH_TAG)).generate_state(1, np.uint64)[0])


def _labeller(store_path: str, model, store: WordStore) -> PathLabeller:
    """One whole-map labelling model per map and thread, reused for every run.

    Per thread, not per process: a labeller holds its chain's topics, and a Dask worker
    runs tasks on several threads. ``store`` is the map's words, named by ``store_path``.
    """
    from curiosity_cli.evaluate.labeling import PathLabeller

    cache = _per_thread.__dict__.setdefault("labellers", {})
    key = (store_path, model)
    if key not in cache:
        if len(cache) == _LABELLERS_PER_THREAD:
            del cache[next(iter(cache))]  # the oldest
        cache[key] = PathLabeller(store, model)
    return cache[key]


def _map_references(entry: str, batch_file: str) -> tuple:
    """A map's (human labels or None, number of classes, batch pixel labels, image shape, class pixels per cell or None)."""
    from curiosity_cli.data import load_map
    from curiosity_cli.evaluate.information import cell_class_pixels

    map_data = load_map(entry)
    n_classes = max(c.id for c in map_data.legend) + 1 if map_data.labels is not None else 0
    with open_npz(batch_file) as npz:
        batch = npz["labels"]
    cell_classes = None
    if map_data.labels is not None:
        cell_classes = cell_class_pixels(map_data.labels, map_data.config.cell_width, n_classes)
    return map_data.labels, n_classes, batch, map_data.image.shape[:2], cell_classes


@lru_cache(maxsize=4)
def _map_arrays(entry: str, store_path: str, batch_file: str) -> MapArrays:
    """A map's arrays, read once per (loky) worker."""
    from curiosity_cli.words.store import load_store

    return MapArrays(load_store(Path(store_path)), *_map_references(entry, batch_file))


def label_run(run: RunInputs, inputs: MapInputs, arrays: MapArrays, config: ExperimentConfig, threads: int = 1):
    """Z_p of every checkpoint of one run, as contingency tables; ``(tables, examples, meta)``.

    ``inputs`` names the map's files, ``arrays`` holds their contents; the run was made
    from the map's current word store (:func:`label_experiment` checks).
    """
    from curiosity_cli.evaluate.information import contingency
    from curiosity_cli.evaluate.labeling import pixel_labels

    store, human, n_classes, batch, shape, cell_classes = arrays
    k = config.model.topics
    lengths = run.meta["checkpoints"]
    tables = {"human": [], "batch": []}
    examples = {}
    last = lengths[-1]
    labels = _labeller(inputs.store_path, config.model, store).label_path(
        [run.phi(n) for n in lengths], seed=path_seed(run.meta["seed"]), sweeps=config.label.sweeps,
        warm_sweeps=config.label.warm_sweeps, threads=threads,
    )
    for length, words in zip(lengths, labels):
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
        "warm_sweeps": config.label.warm_sweeps, "batch": Path(inputs.batch_path).name,
    }
    arrays = {"lengths": np.array(lengths, np.int32), "batch": np.stack(tables["batch"])}
    if tables["human"]:
        arrays["human"] = np.stack(tables["human"])
        arrays["class_first_step"] = class_first_steps(run.path, cell_classes, store, inputs.store_path)
        meta["class_share_percent"] = CLASS_SHARE_PERCENT
    return arrays, examples, meta


def class_first_steps(path: np.ndarray, cell_classes: np.ndarray, store: WordStore, store_path: str) -> np.ndarray:
    """(C,) int32: the step at which ``path`` first reached each human class (-1: never), at ``CLASS_SHARE_PERCENT``.

    Raises
    ------
    LabelError
        The map's grid (``cell_classes``, from its cell width) is not the word store's.
    """
    from curiosity_cli.evaluate.information import classes_present, first_steps

    if cell_classes.shape[0] != store.n_cells:
        raise LabelError(
            f"{display_path(Path(store_path))}: {store.n_cells} cells, but the map's labels at its cell width "
            f"make {cell_classes.shape[0]}; run `curiosity extract` again"
        )
    return first_steps(path, classes_present(cell_classes, CLASS_SHARE_PERCENT)).astype(np.int32)


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
    """Whether a run's label file exists and was made from this run with these settings.

    A map's file with human contingency tables but no classes found at the current
    ``CLASS_SHARE_PERCENT`` (made before they were recorded) is not current. Nor is a
    corrupt one, which is noted on stderr as labelled again.
    """
    path = label_path(folder, run_meta["dataset"], run_meta["weight_function"], run_meta["restart"])
    try:
        with open_npz(path) as npz:
            meta = read_meta(npz, LABEL_META_KEYS)
            members = set(npz.files)
    except FileNotFoundError:
        return False
    except CorruptFileError as exc:
        note(f"{exc}; labelling the run again")
        return False
    # a file from before classes found were recorded, or with another share, is redone
    classes_current = "human" not in members or (
        "class_first_step" in members and meta.get("class_share_percent") == CLASS_SHARE_PERCENT
    )
    return (
        meta["run_seed"] == run_meta["seed"] and meta["store"] == run_meta["store"]
        and meta["sweeps"] == config.label.sweeps and meta.get("warm_sweeps") == config.label.warm_sweeps
        and classes_current
    )


def label_experiment(
    config: ExperimentConfig,
    folder: Path,
    *,
    cache_dir: Path = Path("results/cache"),
    jobs: int | None = None,
    force: bool = False,
    on_stage: Callable[[str, int], None] | None = None,
    on_done: Callable[[], None] | None = None,
    backend: str = "loky",
    scheduler: str | None = None,
    workers: Workers | None = None,
) -> dict:
    """Label every finished run of an experiment (and each map's batch reference).

    Parameters
    ----------
    config : ExperimentConfig
        The experiment's settings.
    folder : Path
        The experiment folder: its runs are read and its labels written there, whatever
        its name (a copied or renamed experiment labels itself, not its original).
    jobs : int, optional
        Worker processes (of ``loky``, or of the local Dask cluster); default the number
        of cores. Ignored with a ``scheduler``.
    force : bool
        Recompute labels (and batch references) that are up to date.
    on_stage : callable, optional
        ``on_stage(description, units)`` when a stage starts (units of ``on_done``).
    on_done : callable, optional
        Called after each unit of work.
    backend : {"loky", "dask"}
        Where batch references and runs are computed (module docstring); the results do
        not depend on it.
    scheduler : str, optional
        With ``backend="dask"``: a running scheduler's address; without one, a local
        cluster of ``jobs`` workers is started for the labelling.
    workers : Workers, optional
        Where to compute instead of new workers from ``backend``, ``scheduler`` and
        ``jobs``: open ones another stage shares (``curiosity reproduce``).

    Returns
    -------
    dict
        ``labelled``, ``skipped``, ``batch_reused`` counts, ``seconds``, and ``left_out``:
        a line per run folder without a ``run.json`` (not labelled), naming it.

    Raises
    ------
    LabelError
        No finished runs; or, after labelling the others, runs that could not be
        labelled (corrupt, made from another word store, a task that raised, a batch
        reference that failed), all of them named.
    ParameterError, BackendError
        As :class:`~curiosity_cli.parallel.Workers`; and a Dask scheduler that cannot be
        reached or has unusable workers.
    """
    from curiosity_cli.explore.grid import prepare_stores
    from curiosity_cli.explore.runs import RunError, read_run
    from curiosity_cli.parallel import Workers
    from curiosity_cli.words.store import load_store

    started = time.perf_counter()
    owned = Workers(backend, scheduler, jobs) if workers is None else None  # checks the backend before any work
    workers = workers or owned
    folder = Path(folder)
    stores = prepare_stores(config, cache_dir)
    names = {info.name for info in stores.values()}
    folders = sorted(p for p in (folder / "runs").glob("*/*/restart-*") if p.parent.parent.name in names)
    runs = [p for p in folders if (p / "run.json").is_file()]
    left_out = [
        f"{display_path(p)}: no run.json; run `curiosity explore` to redo it" for p in folders if p not in runs
    ]
    if not runs:
        raise LabelError(f"{display_path(folder / 'runs')}: no finished runs; run `curiosity explore` first")

    with owned or contextlib.nullcontext():  # new workers (a local cluster) stop with the labelling
        batch_files, reused, problems = _batch_references(folder, config, stores, workers, force, on_stage, on_done)
        inputs = {
            info.name: MapInputs(info.name, entry, str(info.path), str(batch_files[info.name]))
            for entry, info in stores.items() if info.name in batch_files
        }
        skipped, tasks = 0, []
        for run_path in runs:
            try:
                run = read_run(run_path)
                if not force and is_labelled(folder, run.meta, config):
                    skipped += 1
                elif run_path.parent.parent.name in inputs:  # else its batch reference failed, named in problems
                    tasks.append(_run_task(run, inputs[run_path.parent.parent.name]))
            except (RunError, LabelError) as exc:
                problems.append(str(exc))
        todo = len(runs) - skipped
        shipped = {}  # loky workers read the maps' files themselves
        if workers.ships:  # before the stage starts: an unusable cluster is the only message
            for name, map_inputs in {m.name: m for _, m in tasks}.items():
                store = workers.ship_file(map_inputs.store_path, load_store)
                shipped[name] = workers.ship(
                    MapArrays, store, *_map_references(map_inputs.entry, map_inputs.batch_path), key=f"map-{name}"
                )
        if on_stage is not None:
            on_stage("labelling runs", len(tasks))
        labelled = 0
        computed = workers.compute(
            _label_task, tasks, args=lambda task: (config, shipped.get(task[1].name)),
            key=lambda task: "label-{dataset}/{weight_function}/restart-{restart:03d}".format(**task[0].meta),
        )
        with computed as results:
            for (run, _), outcome in results:
                if isinstance(outcome, str):
                    problems.append("{dataset} / {weight_function} / restart {restart}: ".format(**run.meta) + outcome)
                else:
                    write_labels(folder, *outcome)
                    labelled += 1
                if on_done is not None:
                    on_done()
    if problems:
        raise LabelError(
            f"{todo - labelled} of {todo} runs could not be labelled (the others are written): "
            + "; ".join([*problems, *left_out])
        )
    return {
        "labelled": labelled, "skipped": skipped, "batch_reused": reused, "seconds": time.perf_counter() - started,
        "left_out": left_out,
    }


def _batch_references(
    folder: Path, config: ExperimentConfig, stores: dict[str, StoreInfo], workers: Workers, force: bool,
    on_stage: Callable[[str, int], None] | None, on_done: Callable[[], None] | None,
) -> tuple[dict[str, Path], int, list[str]]:
    """Each map's batch reference, computed where missing or out of date; ``(files by map, how many reused, problems)``.

    With loky, in this process, one map after the other on ``jobs`` threads with a
    progress unit per sweep; an error stops the command. On a Dask cluster, as tasks, a
    map's sweeps counted when it arrives; a map whose reference failed is left out of the
    files and named in the problems.
    """
    from curiosity_cli.data import load_map
    from curiosity_cli.words.store import load_store

    sweeps = config.label.batch_sweeps
    files = {info.name: batch_path(folder, info.name) for info in stores.values()}
    stale = {entry: info for entry, info in stores.items() if force or not _batch_is_current(files[info.name], config, info)}
    problems = []

    def swept(*_) -> None:
        if on_done is not None:
            on_done()

    if not workers.ships:
        for entry, info in stale.items():
            if on_stage is not None:
                on_stage(f"batch reference {info.name}", sweeps)
            image_shape = load_map(entry).image.shape[:2]
            computed = _compute_batch(info, config, load_store(info.path), image_shape, threads=workers.jobs, on_sweep=swept)
            _write_batch(files[info.name], config, info, *computed)
    elif stale:
        threads = workers.whole_machine_threads(len(stale))  # reaches a scheduler first: no stage for an unusable one
        shapes = {info.name: load_map(entry).image.shape[:2] for entry, info in stale.items()}
        if on_stage is not None:
            on_stage(f"batch references of {', '.join(info.name for info in stale.values())}", len(stale) * sweeps)
        computed = workers.compute(
            _compute_batch, list(stale.values()),
            args=lambda info: (config, workers.ship_file(info.path, load_store), shapes[info.name]),
            key=lambda info: f"batch-{info.name}", threads=threads,
        )
        with computed as results:
            for info, outcome in results:
                if isinstance(outcome, str):
                    problems.append(f"the batch reference of {info.name}: {outcome}; its runs were not labelled")
                    del files[info.name]
                else:
                    _write_batch(files[info.name], config, info, *outcome)
                for _ in range(sweeps):
                    swept()
    return files, len(stores) - len(stale), problems


def _run_task(run: Run, inputs: MapInputs) -> tuple[RunInputs, MapInputs]:
    """A run to label and its map, checked and read here (so a bad run is named without a worker).

    Raises
    ------
    LabelError
        The run was made from another word store than the map's current one.
    RunError
        Its checkpoints are missing or corrupt.
    """
    if run.meta["store"] != Path(inputs.store_path).name:
        raise LabelError(
            f"{display_path(run.folder)}: made from word store {run.meta['store']}, but {inputs.name}'s words are now "
            f"{Path(inputs.store_path).name}; run `curiosity explore --force` to redo the runs"
        )
    return RunInputs.of(run), inputs


def _label_task(
    task: tuple[RunInputs, MapInputs], config: ExperimentConfig, arrays: MapArrays | None = None, *, threads: int = 1,
):
    """Label one run in a worker: ``(arrays, examples, meta)``; ``arrays`` are its map's when shipped (Dask), else read once."""
    run, inputs = task
    if arrays is None:
        arrays = _map_arrays(inputs.entry, inputs.store_path, inputs.batch_path)
    return label_run(run, inputs, arrays, config, threads)
