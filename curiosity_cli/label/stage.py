"""``curiosity label`` for a whole experiment: Z_b per map, Z_p per run and checkpoint.

Written under ``results/<experiment>/``: ``batch/<dataset>.npz``, the batch reference Z_b
of a map (:mod:`~curiosity_cli.label.batch_references`), and each run's label file and
example maps (:mod:`~curiosity_cli.label.label_files`). A label file is current while
its recipe (:meth:`~curiosity_cli.experiment.experiment.Experiment.label_recipe`: its
run's and batch reference's digests, the label settings, the share and the human labels)
is the one they give now; the others are labelled again, and how many and why is noted.

Every file is written atomically; a killed ``label`` resumes with the runs not yet done.

Batch references and blocks of runs are tasks of :class:`~curiosity_cli.workers.Workers`.
A map's runs to label are cut into blocks
(:func:`~curiosity_cli.label.blocks.plan_blocks`: sizes that keep every worker busy
to the end, around the device's block size,
:attr:`~curiosity_cli.topics.devices.Device.block_chains`: a few vectors' worth of
chains on the CPU, every chain of the map on a GPU), a run's chains (and a checked run's
second chain) in one block, whose chains advance in lock-step in one task; a run's labels
depend only on the run, never on its block, so a killed ``label`` relabels what it lost to
the same bytes. Batch references are
computed every map's at once, each a task on its share of the cores: beside the blocks
where each task gets a worker of its own at once (a GPU's one block per map; a block
needs Z_b only to compare its first Z_p with it, and waits for the file then,
:class:`~curiosity_cli.label.batch_references.WrittenBatch`), else before them. With loky, a worker reads each map's word
store, human labels and Z_b once. On a Dask cluster, each
map's word store goes to the cluster once and its human labels and Z_b pixel labels
once; each run's ``run.json`` and checkpoint counts Φ_p
(a few kilobytes) travel with its block, so workers need no copy of the maps, stores or
results. Either way this process writes every file, and the same functions
(:mod:`~curiosity_cli.label.sampling`) compute the labels, so the results are
identical.
"""

from __future__ import annotations

import json
import time
from concurrent.futures import ThreadPoolExecutor
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import lru_cache, partial
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from curiosity_cli.config import ExperimentConfig
from curiosity_cli.errors import RERUN, CuriosityError
from curiosity_cli.experiment.experiment import Experiment
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.experiment.recipes import CLASS_SHARE_PERCENT, LABEL_FORMAT, RECIPE_KEY, first_of, is_checked
from curiosity_cli.experiment.saved_config import record_label_settings
from curiosity_cli.experiment.stage_seconds import record_stage_seconds
from curiosity_cli.files import atomic_path, display_path, note, open_npz, remove_leftovers
from curiosity_cli.label.block_progress import BlockProgress, SweepCounter
from curiosity_cli.label.batch_references import (
    BatchTask, WrittenBatch, batch_is_current, batch_task, compute_batch_references, write_batch,
)
from curiosity_cli.label.label_files import (
    EXAMPLE_LENGTHS, HELDOUT_BITS, HELDOUT_WORDS, NOT_LABELLED, SECOND_PREFIX, VISITED_PREFIX, label_changes,
    write_labels,
)
from curiosity_cli.label.shared_items import BATCH, SharedItems, label_key
from curiosity_cli.label.sampling import path_seed
from curiosity_cli.paths import DEFAULT_CACHE

if TYPE_CHECKING:
    from curiosity_cli.label.profile import LabelProfile
    from curiosity_cli.topics.devices import Device
    from curiosity_cli.label.pixel_tables import PixelTables
    from curiosity_cli.workers import Workers
    from curiosity_cli.explore.runs import Run
    from curiosity_cli.words.store import WordStore

#: Threads writing label files and example maps in this process.
WRITERS = 4


class LabelError(CuriosityError):
    """Labels that cannot be computed or do not belong to the runs they claim."""


@dataclass(frozen=True)
class MapInputs:
    """What labelling one map needs, by file, so workers can load it once."""

    name: str
    entry: str  # the config's datasets entry (a name or a YAML path)
    store_path: str
    batch_path: str
    batch_digest: str  # of the batch reference's recipe: the file a worker may use is the one made from it


class MapArrays(NamedTuple):
    """A map as its runs' labelling needs it in a worker: made there once (loky) or shipped once (Dask).

    Made by :func:`map_arrays`.
    """

    store: WordStore
    pixel_words: np.ndarray  # (H, W): the word whose label each pixel takes
    human: PixelTables | None  # tables against the human labels, None for a map without them
    batch: PixelTables | WrittenBatch  # tables against Z_b
    cell_classes: np.ndarray | None  # (n_cells, C) pixels of each class per cell, None without human labels


def map_arrays(
    store: WordStore, human: np.ndarray | None, n_classes: int, shape: tuple[int, int], cell_classes, batch,
    *, topics: int,
) -> MapArrays:
    """A map's :class:`MapArrays` from its words, its (H, W) human labels (or None) of ``n_classes``, its image
    ``shape``, its class pixels per cell (or None) and its Z_b of ``topics``: the (H, W) pixel labels, or
    ``(path, digest)`` of the batch file this command writes (:class:`~curiosity_cli.label.batch_references.WrittenBatch`)."""
    from curiosity_cli.label.sampling import pixel_words
    from curiosity_cli.label.pixel_tables import PixelTables

    words = pixel_words(store, shape)
    human_tables = None if human is None else PixelTables(words, human, n_classes)
    batch_tables = PixelTables(words, batch, topics) if isinstance(batch, np.ndarray) else WrittenBatch(*batch, words, topics)
    return MapArrays(store, words, human_tables, batch_tables, cell_classes)


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
    def of(cls, run: Run, shape: tuple[int, int]) -> RunInputs:
        """Read a run's checkpoints, which must be (V, K) = ``shape``, the map's vocabulary and the model's topics.

        Checked here, not in the worker: a run is labelled in a block with others, and
        one that cannot be labelled must not take the block with it.

        Raises
        ------
        RunError
            A missing or corrupt ``checkpoints.npz``, or counts of another shape, naming it.
        """
        from curiosity_cli.explore.runs import RunError
        from curiosity_cli.explore.walker import SparseCounts

        checkpoints = {n: SparseCounts.of(run.phi(n)) for n in run.meta["checkpoints"]}
        for length, counts in checkpoints.items():
            if counts.shape != tuple(shape):
                raise RunError(
                    f"{display_path(run.folder / 'checkpoints.npz')}: the counts at {length} steps are {counts.shape}, "
                    f"expected (V, K) = {tuple(shape)} for the map's words and model.topics; {RERUN} redoes the run",
                    rerun="explore",
                )
        return cls(run.folder, run.meta, checkpoints, run.path)

    def phi(self, length: int) -> np.ndarray:
        """(V, K) int32 ndarray: the word-topic counts Φ_p after ``length`` steps."""
        return self.checkpoints[length].dense()

    def phis(self) -> _DenseCheckpoints:
        """Φ_p at each checkpoint, shortest path first, each made dense only when read."""
        return _DenseCheckpoints(self)


class _DenseCheckpoints(Sequence):
    """A run's Φ_p by checkpoint, dense on reading: a block holds 16 runs, whose 6 checkpoints
    each, all dense, would be 150 MB at once."""

    def __init__(self, run: RunInputs):
        self._run = run

    def __len__(self) -> int:
        return len(self._run.meta["checkpoints"])

    def __getitem__(self, j: int) -> np.ndarray:
        return self._run.phi(self._run.meta["checkpoints"][j])



def _map_references(entry: str) -> tuple:
    """A map's (human labels or None, number of classes, image shape, class pixels per cell or None)."""
    from curiosity_cli.maps.map_data import load_map
    from curiosity_cli.maps.cell_classes import map_class_pixels

    map_data = load_map(entry)
    return map_data.labels, map_data.n_classes, map_data.image.shape[:2], map_class_pixels(map_data)


@lru_cache(maxsize=4)
def _map_arrays(inputs: MapInputs, topics: int) -> MapArrays:
    """A map's arrays, made once per (loky) worker; its Z_b read when first needed (:class:`~curiosity_cli.label.batch_references.WrittenBatch`)."""
    from curiosity_cli.words.store import load_store

    return map_arrays(
        load_store(Path(inputs.store_path)), *_map_references(inputs.entry), (inputs.batch_path, inputs.batch_digest),
        topics=topics,
    )


def label_block(
    runs: list[RunInputs], inputs: MapInputs, arrays: MapArrays, config: ExperimentConfig, *, device: str = "cpu",
    clock: dict | None = None, on_sweep=None,
) -> list[tuple]:
    """Z_p of every checkpoint of some runs of one map, as contingency tables; ``(tables, examples, meta)`` per run.

    The chains run on ``device``, a name in :data:`~curiosity_cli.topics.devices.DEVICES`
    (the same bytes on each). ``clock``, when given, gets the seconds spent in the chains'
    sweeps (``kernel``), in the held-out chains' sweeps and scores (``heldout``) and in the
    tables and example maps made from their labels (``tables``, with any wait for a Z_b
    computed beside). ``on_sweep(chains)`` is called after each sweep of the label chains
    (:mod:`~curiosity_cli.label.block_progress`).

    ``inputs`` names the map's files, ``arrays`` holds their contents; the runs were made
    from the map's current word store (:func:`label_experiment` checks). Their chains,
    and the second chain of each restart below ``label.check_restarts`` (from a placed
    start), advance in lock-step (:func:`~curiosity_cli.label.sampling.label_paths`), and
    so do the runs' chains over the observed half of the map's words, which score the
    held-out half (:mod:`~curiosity_cli.label.heldout`); a run's labels and scores depend
    only on the run, never on the runs labelled with it.
    """
    from curiosity_cli.label.heldout import heldout_chains, heldout_sums, map_split
    from curiosity_cli.label.sampling import label_paths
    from curiosity_cli.seeds import HELDOUT_CHAIN_TAG, PATH_TAG, SECOND_CHAIN_TAG

    from curiosity_cli.label.readings import Reading

    store, pixel_words, human, batch, cell_classes = arrays
    reading = Reading.of(config.label)
    k = reading.labels(config.model.topics)
    word_cells = store.word_cells()
    chains = []  # (run index, array-name prefix: how the chain starts)
    for index, run in enumerate(runs):
        chains.append((index, ""))
        if is_checked(config, run.meta["restart"]):
            chains.append((index, SECOND_PREFIX))
    lengths = [run.meta["checkpoints"] for run in runs]
    phis = [run.phis() for run in runs]
    tables = [{} for _ in runs]
    examples = [{} for _ in runs]
    labelled = label_paths(
        store, config.model, [phis[index] for index, _ in chains],
        [path_seed(runs[index].meta["seed"], SECOND_CHAIN_TAG if prefix else PATH_TAG) for index, prefix in chains],
        placed=[bool(prefix) for _, prefix in chains], sweeps=config.label.sweeps, warm_sweeps=config.label.warm_sweeps,
        reading=reading, device=device, on_sweep=on_sweep,
    )
    held = map_split(store, config.seed, inputs.name)
    held_cells = word_cells[held]
    # a chain per run over the observed words, stepped beside the label chains; its sweeps are not counted
    # in the progress (a chain sweep there is one over the whole map), which they slow evenly
    scored = heldout_chains(
        store, config.model, held, phis, [path_seed(run.meta["seed"], HELDOUT_CHAIN_TAG) for run in runs],
        sweeps=config.label.sweeps, warm_sweeps=config.label.warm_sweeps, device=device,
    )
    clock = {} if clock is None else clock
    clock.update(kernel=0.0, tables=0.0, heldout=0.0)
    while True:
        began = time.perf_counter()
        step = next(labelled, None)  # the chains sweep when asked for the next checkpoint's labels
        clock["kernel"] += time.perf_counter() - began
        if step is None:
            break
        began = time.perf_counter()
        _, _, scores = next(scored)  # the same checkpoint, for the runs of the first chains, in order
        clock["heldout"] += time.perf_counter() - began
        began = time.perf_counter()
        j, active, labels = step
        owners = [chains[c][0] for c in active]  # the run of each column
        firsts = [column for column, c in enumerate(active) if not chains[c][1]]
        # per first chain, the cells its path had visited: its tables again over their words' pixels, and its
        # held-out words scored apart in the others
        seen = [visited_cells(runs[owners[column]].path, lengths[owners[column]][j], store.n_cells) for column in firsts]
        visited = np.stack([cells[word_cells] for cells in seen], axis=1)
        for against, reference in (("human", human), ("batch", batch)):
            if reference is None:
                continue
            for column, table in enumerate(reference.tables(labels, k)):
                tables[owners[column]].setdefault(chains[active[column]][1] + against, []).append(table)
            for column, table in zip(firsts, reference.tables(labels[:, firsts], k, visited)):
                tables[owners[column]].setdefault(VISITED_PREFIX + against, []).append(table)
        for column, cells, score in zip(firsts, seen, scores):
            bits, words = heldout_sums(score, ~cells[held_cells])
            tables[owners[column]].setdefault(HELDOUT_BITS, []).append(bits)
            tables[owners[column]].setdefault(HELDOUT_WORDS, []).append(words)
        for column, c in enumerate(active):
            index, prefix = chains[c]
            length = lengths[index][j]
            if not prefix and runs[index].meta["restart"] == 0 and (
                length in EXAMPLE_LENGTHS or length == lengths[index][-1]
            ):
                examples[index][length] = labels[pixel_words, column]
        clock["tables"] += time.perf_counter() - began
    out = []
    for index, run in enumerate(runs):
        arrays_out = {"lengths": np.array(lengths[index], np.int32)}
        arrays_out.update({name: np.stack(table) for name, table in tables[index].items()})
        if human is not None:
            arrays_out["class_first_step"] = class_first_steps(run.path, cell_classes, store, inputs.store_path)
        out.append((arrays_out, examples[index], label_meta(run.meta, inputs, config, human is not None)))
    return out


def label_meta(run_meta: dict, inputs: MapInputs, config: ExperimentConfig, human: bool) -> dict:
    """A run's label file's meta (its recipe aside): what it labels, and with what; ``human`` whether the map has
    human labels (then the share that makes a class found)."""
    meta = {
        "format": LABEL_FORMAT, "dataset": inputs.name, "weight_function": run_meta["weight_function"],
        "restart": run_meta["restart"], "run_seed": run_meta["seed"], "store": run_meta["store"],
        "vocabulary_hashes": run_meta["vocabulary_hashes"], "sweeps": config.label.sweeps,
        "warm_sweeps": config.label.warm_sweeps, "batch": Path(inputs.batch_path).name,
    }
    if human:
        meta["class_share_percent"] = CLASS_SHARE_PERCENT
    return meta


def visited_cells(path: np.ndarray, length: int, n_cells: int) -> np.ndarray:
    """(n_cells,) bool ndarray: the cells of ``path``'s first ``length`` steps, whose words Φ_p holds then.

    ``path`` (L,) is the row-major cell of each step.
    """
    visited = np.zeros(n_cells, bool)
    visited[np.asarray(path[:length], np.int64)] = True
    return visited


def class_first_steps(path: np.ndarray, cell_classes: np.ndarray, store: WordStore, store_path: str) -> np.ndarray:
    """(C,) int32: the step at which ``path`` first reached each human class (-1: never), at ``CLASS_SHARE_PERCENT``.

    Raises
    ------
    LabelError
        The map's grid (``cell_classes``, from its cell width) is not the word store's.
    """
    from curiosity_cli.maps.cell_classes import classes_present, first_steps

    if cell_classes.shape[0] != store.n_cells:
        raise LabelError(
            f"{display_path(Path(store_path))}: {store.n_cells} cells, but the map's labels at its cell width "
            f"make {cell_classes.shape[0]}; {RERUN} makes the store again", rerun="extract"
        )
    return first_steps(path, classes_present(cell_classes, CLASS_SHARE_PERCENT)).astype(np.int32)


def label_experiment(
    config: ExperimentConfig,
    folder: Path,
    *,
    cache_dir: Path = DEFAULT_CACHE,
    jobs: int | None = None,
    force: bool = False,
    on_stage: Callable[[str, int], None] | None = None,
    on_done: Callable[[], None] | None = None,
    backend: str = "loky",
    scheduler: str | None = None,
    workers: Workers | None = None,
    chains_per_block: int | None = None,
    reuse: bool = True,
) -> dict:
    """Label every finished run of an experiment (and each map's batch reference).

    Parameters
    ----------
    config : ExperimentConfig
        The experiment's settings: its ``config.yaml``, whose ``label`` section may differ
        (it is then recorded there, :func:`~curiosity_cli.experiment.saved_config.record_label_settings`).
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
    chains_per_block : int, optional
        On a device whose blocks run side by side (the CPU), the block size past which
        lock-step chains gain no more speed (:func:`~curiosity_cli.label.blocks.plan_blocks`
        cuts blocks around it); default the device's
        (:attr:`~curiosity_cli.topics.devices.Device.block_chains`). The labels do not
        depend on it.
    reuse : bool
        Take label files and batch references that another experiment already computed
        from the same inputs from ``cache_dir``'s shared items, and keep what this one
        computes there (:mod:`~curiosity_cli.label.shared_items`): the same bytes, timing
        fields aside. False computes everything and keeps nothing.

    Returns
    -------
    dict
        ``labelled``, ``skipped``, ``batch_reused`` counts, ``seconds``, ``shared``
        (the label files and batch references taken from the shared items: ``labels``,
        ``batches``), and ``relabelled``: a line per label file made again because it was
        made otherwise (other settings, another run or batch reference), saying what changed.

    Raises
    ------
    ConfigError
        ``config`` differs from the saved one outside its ``label`` section.
    LabelError
        No finished runs; runs made otherwise than ``config`` makes them (before any
        work, naming them); or, after labelling the others, runs that could not be
        labelled (corrupt, without a ``run.json``, a task that raised, a batch reference
        that failed), all of them named.
    ParameterError, BackendError
        As :class:`~curiosity_cli.workers.Workers`; and a Dask scheduler that cannot be
        reached or has unusable workers.
    FolderInUseError
        Another process works in the folder (:mod:`~curiosity_cli.experiment.lock`).
    """
    from curiosity_cli.experiment.maps import prepare_stores
    from curiosity_cli.workers import Workers
    from curiosity_cli.topics.devices import DEVICES, resolve_device
    from curiosity_cli.experiment.lock import working_in
    from curiosity_cli.label.profile import LabelProfile

    with working_in(folder, "label"):
        started = time.perf_counter()
        profile = LabelProfile(started)
        device = DEVICES[resolve_device(config.label.device)]  # before any work: a missing GPU is the only message
        computing = Workers.shared(workers, backend, scheduler, jobs)
        folder = Path(folder)
        layout = ExperimentFolder(folder)
        record_label_settings(folder, config)
        for written in (layout.labels, layout.batches):  # what a killed label was writing
            remove_leftovers(written)
        stores = prepare_stores(config, cache_dir)
        by_name = {info.name: info for info in stores.values()}
        words = {name: sum(info.word_counts.values()) for name, info in by_name.items()}
        experiment = Experiment(folder, config, {name: info.facts for name, info in by_name.items()})
        runs, left_out = _explored_runs(experiment)
        finished, problems = _runs_as_configured(experiment, runs)

        with computing as workers:
            shared = SharedItems(cache_dir) if reuse else None
            if shared is not None and (why := shared.writable()) is not None:
                raise LabelError(
                    f"{why}: the shared items of labels are stored there; give a --cache-dir this user can write, "
                    "or --no-reuse to label without them"
                )
            batches = _plan_batches(experiment, list(stores.values()), shared, force)
            plan = _plan_runs(experiment, by_name, finished, shared, force)
            problems += plan.problems
            if plan.relabelled:
                note(
                    f"labelling {len(plan.relabelled)} runs again whose label files were made otherwise, "
                    f"e.g. {plan.relabelled[0]}"
                )
            todo = len(runs) - plan.skipped
            inputs = {
                info.name: MapInputs(
                    info.name, entry, str(info.path), str(batches.files[info.name]), batches.recipes[info.name].digest
                )
                for entry, info in stores.items()
            }
            for run, arrays, examples in plan.taken:  # the same file computing it would write
                meta = label_meta(run.meta, inputs[run.meta["dataset"]], config, "class_first_step" in arrays)
                write_labels(folder, arrays, examples, {**meta, RECIPE_KEY: plan.recipes[run.folder].record()})
            blocks = _plan_blocks(config, plan.to_label, inputs, words, device, workers.jobs, chains_per_block)
            stale = batches.stale
            beside, tasks, batch_problems = _schedule(config, batches, blocks, workers, profile, on_stage, on_done)
            problems += batch_problems
            shipped = _ship_maps(workers, blocks, config)  # before the stage starts: an unusable cluster is the only message
            if on_stage is not None:
                what = "labelling runs" + (f" on {device.shown}" if device.announced else "")
                if beside:
                    what += " beside the batch reference" + ("s of " if len(stale) > 1 else " of ") + ", ".join(i.name for i in stale)
                on_stage(what + " (chain sweeps)", stage_sweeps(config, tasks))
            labelled, task_problems = _compute_and_write(
                workers, tasks, shipped, config=config, folder=folder, plan=plan, batches=batches, words=words,
                shared=shared, profile=profile, on_done=on_done,
            )
            problems += task_problems
            profile.mark("writing")
            labelled += len(plan.taken)
            if shared is not None:  # what this call computed, for the next experiment that needs it
                for info in stale:  # a map whose batch reference failed has left batches.files
                    if info.name in batches.files and batch_is_current(batches.files[info.name], batches.recipes[info.name]):
                        shared.keep_file(BATCH, batches.recipes[info.name].digest, batches.files[info.name])
        shared_counts = {"labels": len(plan.taken), "batches": len(batches.taken), "labelled": labelled}
        seconds = _record_call(
            layout, shared_counts, profile, started, made=bool(todo or stale or batches.taken), force=force,
        )
        if problems or left_out:
            failed = todo - labelled + len(left_out)
            raise LabelError(
                f"{failed} of {todo + len(left_out)} runs could not be labelled (the others are written): "
                + "; ".join([*problems, *left_out])
            )
        return {
            "labelled": labelled, "skipped": plan.skipped, "batch_reused": len(stores) - len(stale), "seconds": seconds,
            "relabelled": plan.relabelled, "shared": {k: shared_counts[k] for k in ("labels", "batches")},
        }


def _explored_runs(experiment: Experiment) -> tuple[list[Path], list[str]]:
    """The run folders of the grid the config holds that are explored, and a line for each that is not.

    A run folder outside the grid (a config narrowed since) is not labelled.

    Raises
    ------
    LabelError
        None of them is explored.
    """
    layout = experiment.folder
    folders = [layout.run(r.dataset, r.weight_function, r.restart) for r in experiment.planned()]
    runs = [p for p in folders if (p / ExperimentFolder.RUN_META).is_file()]
    left_out = [unexplored(p, layout) for p in folders if p not in runs]
    if not runs:
        raise LabelError(
            f"{display_path(layout.runs)}: none of the runs of the grid of {display_path(layout.config)} is explored "
            f"({first_of(left_out)}); {RERUN} makes them", rerun="explore", force=False,
        )
    return runs, left_out


def _schedule(config, batches, blocks: list, workers, profile, on_stage, on_done) -> tuple[bool, list, list[str]]:
    """(whether the stale batch references go beside the blocks, the tasks to compute, a line per batch reference
    that failed).

    Beside the blocks where every task gets a worker at once, so no block waits for a worker a
    batch reference holds (loky only: a Dask worker cannot see the file it waits for); else
    they are computed here, before them, and a map whose reference failed loses its blocks
    (its runs are not labelled: counted as failed, named in the problems).
    """
    stale = batches.stale
    beside = bool(stale) and not workers.ships and len(stale) + len(blocks) <= workers.jobs
    if beside:
        threads = max(1, (workers.jobs - len(blocks)) // len(stale))  # the job slots the blocks leave
        return True, [*(BatchTask(info, threads) for info in stale), *blocks], []
    profile.mark("setup")
    problems = compute_batch_references(config, stale, batches.files, batches.recipes, workers, on_stage, on_done)
    profile.mark("batch references before the blocks")
    failed_maps = {info.name for info in stale if info.name not in batches.files}
    for task in [task for task in blocks if task.inputs.name in failed_maps]:
        blocks.remove(task)
    return False, list(blocks), problems


def _record_call(layout: ExperimentFolder, shared_counts: dict, profile, started: float, *, made: bool, force: bool) -> float:
    """Write what a call that made anything leaves beside its labels (``shared.json``, its profile, its seconds in
    the stage's time table); the call's seconds. A call that found every label file current made nothing."""
    if made:
        with atomic_path(layout.shared) as tmp:
            tmp.write_text(json.dumps(shared_counts, indent=1) + "\n")
        profile.mark("closing")
        profile.write(layout.label_profile)
    seconds = time.perf_counter() - started
    if made:
        record_stage_seconds(layout.root, "label", seconds, add=not force)
    return seconds


class _Batches(NamedTuple):
    """The maps' batch references as a label stage finds them (:func:`_plan_batches`)."""

    recipes: dict  # map name -> Recipe: what its batch file must have been made from
    files: dict  # map name -> Path; a map whose batch reference failed leaves it
    stale: list  # StoreInfo: the maps whose batch reference this call computes
    taken: list  # StoreInfo: the maps whose batch reference it took from the shared items


def _plan_batches(experiment: Experiment, stores: list, shared: SharedItems | None, force: bool) -> _Batches:
    """Which of the ``stores``' maps need their batch reference computed; those the shared items hold are copied now."""
    recipes = {info.name: experiment.batch_recipe(info.name) for info in stores}
    files = {info.name: experiment.folder.batch(info.name) for info in stores}
    stale = [info for info in stores if force or not batch_is_current(files[info.name], recipes[info.name])]
    # --force computes: a shared item taken again would undo nothing it is meant to redo
    taken = [] if force else [info for info in stale if _take_batch(shared, files[info.name], recipes[info.name])]
    return _Batches(recipes, files, [info for info in stale if info not in taken], taken)


class _Runs(NamedTuple):
    """The finished runs as a label stage finds them (:func:`_plan_runs`)."""

    skipped: int  # whose label files are current
    to_label: dict  # map name -> [RunInputs]: the runs to compute, in the grid's order
    taken: list  # (RunInputs, arrays, examples): label files the shared items hold
    recipes: dict  # run folder -> Recipe: what its label file is made from, for every run not skipped
    keys: dict  # run folder -> its key in the shared items (with shared items)
    relabelled: list  # a line per label file made again because it was made otherwise, saying what changed
    problems: list  # a line per run whose checkpoints cannot be read


def _plan_runs(experiment: Experiment, by_name: dict, finished: list, shared: SharedItems | None, force: bool) -> _Runs:
    """Which ``finished`` runs to label: those whose label files are current are skipped, and those the shared items
    hold taken; ``by_name`` holds the maps' stores."""
    from curiosity_cli.explore.runs import RunError

    config, layout = experiment.config, experiment.folder
    skipped, to_label, taken, recipes, keys, relabelled, problems = 0, {}, [], {}, {}, [], []
    for run in finished:
        info = by_name[run.meta["dataset"]]
        recipe = experiment.label_recipe(run.meta)
        path = layout.label_file(info.name, run.meta["weight_function"], run.meta["restart"])
        change = None if force else label_changes(path, recipe)
        if not force and change is None:
            skipped += 1
            continue
        if change not in (None, NOT_LABELLED):
            relabelled.append(f"{display_path(path)}: {change}")
        try:
            run_inputs = RunInputs.of(run, (info.vocabulary_size, config.model.topics))
        except RunError as exc:
            problems.append(str(exc))
            continue
        recipes[run.folder] = recipe
        if shared is not None:
            keys[run.folder] = label_key(recipe.inputs, run.meta, run_inputs.checkpoints, run_inputs.path)
            if not force and (stored := shared.labels(keys[run.folder])) is not None:
                taken.append((run_inputs, *stored))
                continue
        to_label.setdefault(info.name, []).append(run_inputs)
    return _Runs(skipped, to_label, taken, recipes, keys, relabelled, problems)


def _plan_blocks(
    config: ExperimentConfig, to_label: dict, inputs: dict, words: dict, device: Device, jobs: int,
    chains_per_block: int | None,
) -> list[LabelTask]:
    """Each map's runs ``to_label`` cut into blocks for ``device`` (:func:`~curiosity_cli.label.blocks.plan_blocks`),
    in the order they are dealt to the ``jobs`` workers; ``words``: each map's, ``inputs``: each map's files."""
    from curiosity_cli.label.blocks import dealing_order, plan_blocks
    from curiosity_cli.topics.chains import LANES

    counts = [[1 + is_checked(config, run.meta["restart"]) for run in map_runs] for map_runs in to_label.values()]
    most = chains_per_block if chains_per_block is not None and device.parallel_blocks else device.block_chains
    map_words = [words[name] for name in to_label]
    plan = plan_blocks(counts, jobs if device.parallel_blocks else 1, lanes=LANES, most=most, words=map_words)
    names = list(to_label)
    return [
        LabelTask([to_label[names[m]][i] for i in plan[m][b]], inputs[names[m]], device.name)
        for m, b in dealing_order(plan, counts, lanes=LANES, words=map_words)
    ]


def _ship_maps(workers: Workers, blocks: list[LabelTask], config: ExperimentConfig) -> dict:
    """The arrays of the maps of ``blocks`` by name, shipped to a Dask cluster once each; empty with loky, whose
    workers read the maps' files themselves."""
    from curiosity_cli.words.store import load_store

    shipped = {}
    if workers.ships:
        for name, map_inputs in {task.inputs.name: task.inputs for task in blocks}.items():
            store = workers.ship_file(map_inputs.store_path, load_store)
            with open_npz(Path(map_inputs.batch_path)) as npz:
                batch = npz["labels"]
            shipped[name] = workers.ship(
                partial(map_arrays, topics=config.model.topics), store, *_map_references(map_inputs.entry), batch,
                key=f"map-{name}",
            )
    return shipped


def _compute_and_write(
    workers: Workers, tasks: list, shipped: dict, *, config: ExperimentConfig, folder: Path, plan: _Runs,
    batches: _Batches, words: dict, shared: SharedItems | None, profile: LabelProfile,
    on_done: Callable[[], None] | None,
) -> tuple[int, list[str]]:
    """Compute ``tasks`` (batch references and blocks) and write each file as its task returns:
    ``(label files written, a line per run or batch reference that failed)``.

    The files are written by threads (zlib and SHA-256 let go of the GIL) while results
    arrive: a GPU's block returns a whole map's runs at once. ``on_done`` is called once per
    chain sweep (:func:`stage_sweeps`), as the blocks make them where their workers share
    this machine's files (:mod:`~curiosity_cli.label.block_progress`), else as they end.
    """
    problems = []
    planned = {task.key: _task_sweeps(config, task) for task in tasks}
    progress = BlockProgress(planned, on_done, local=not workers.ships)
    computed = workers.compute(
        _stage_task, tasks, threads=1, key=lambda task: task.key,
        args=lambda task: (
            config, shipped.get(task.inputs.name) if isinstance(task, LabelTask) else None, progress.path(task.key),
        ),
    )
    profile.jobs = workers.jobs
    profile.mark("setup")
    labelled = 0
    with progress, computed as results, ThreadPoolExecutor(WRITERS) as writers:
        writes, keeps = [], []
        results = profile.waiting(results)
        for task, outcome in results:
            if isinstance(task, BatchTask):
                if isinstance(outcome, str):  # its map's blocks would wait for it: stop them all
                    problems.append(f"the batch reference of {task.info.name}: {outcome}; labelling stopped there")
                    break
                write_batch(batches.files[task.info.name], batches.recipes[task.info.name], *outcome)
                profile.batch(task.info.name, outcome[-1])
            elif isinstance(outcome, str):
                problems += ["{dataset} / {weight_function} / restart {restart}: ".format(**run.meta) + outcome
                             for run in task.runs]
            else:
                chains = sum(1 + is_checked(config, run.meta["restart"]) for run in task.runs)
                profile.block(
                    chains, words[task.inputs.name], planned[task.key], len(task.runs), task.inputs.name, outcome.seconds,
                )
                writes += [
                    writers.submit(write_labels, folder, arrays, examples, {**meta, RECIPE_KEY: plan.recipes[run.folder].record()})
                    for run, (arrays, examples, meta) in zip(task.runs, outcome.runs)
                ]
                if shared is not None:
                    keeps += [
                        writers.submit(shared.keep_labels, plan.keys[run.folder], arrays, examples)
                        for run, (arrays, examples, _) in zip(task.runs, outcome.runs)
                    ]
            progress.ended(task.key)
        profile.mark("handling results")
        for write in writes:
            write.result()  # a file that could not be written stops the stage, as it did
            labelled += 1
        for keep in keeps:
            keep.result()
    return labelled, problems


def stage_sweeps(config: ExperimentConfig, tasks: list) -> int:
    """The units of a label stage's progress: its blocks' chain sweeps, and each batch reference's sweeps (one chain's
    over the whole map, as a block's chain sweeps are)."""
    return sum(_task_sweeps(config, task) for task in tasks)


def _task_sweeps(config: ExperimentConfig, task) -> int:
    """A task's chain sweeps: every chain of a block's runs over their checkpoints, or a batch reference's sweeps."""
    if isinstance(task, BatchTask):
        return config.label.batch_sweeps
    return sum(
        (1 + is_checked(config, run.meta["restart"])) * _sweeps(config, len(run.meta["checkpoints"])) for run in task.runs
    )


def _sweeps(config: ExperimentConfig, checkpoints: int) -> int:
    """The sweeps of one chain over a run's ``checkpoints``: ``label.sweeps`` at the first, then ``warm_sweeps`` at
    each later one (or ``sweeps`` again, from a cold start, without)."""
    later = config.label.warm_sweeps if config.label.warm_sweeps is not None else config.label.sweeps
    return config.label.sweeps + (checkpoints - 1) * later


def _take_batch(shared: SharedItems | None, path: Path, recipe) -> bool:
    """Whether a map's batch reference was taken from the shared items (copied to ``path``, where it is current)."""
    if shared is None or (stored := shared.find(BATCH, recipe.digest)) is None:
        return False
    with atomic_path(path) as tmp:
        tmp.write_bytes(stored.read_bytes())
    if batch_is_current(path, recipe):
        return True
    shared.discard(stored, "not the batch reference its name says it is")  # taken again it would fail again
    return False


def unexplored(run: Path, layout: ExperimentFolder) -> str:
    """Why a run of the grid has no ``run.json``, in words: never explored, or its folder is not whole."""
    if run.is_dir():
        return f"{display_path(run)}: no run.json; explore redoes the run"
    return (
        f"{display_path(run)}: not explored, though the grid of {display_path(layout.config)} holds it "
        "(explore.weight_functions, explore.restarts, datasets); explore makes it"
    )


def _runs_as_configured(experiment: Experiment, runs: list[Path]) -> tuple[list, list[str]]:
    """The finished runs of ``runs`` read back, and a line for each that cannot be read.

    Raises
    ------
    LabelError
        Runs made otherwise than ``config`` and the maps' current word stores make them
        (:meth:`~curiosity_cli.experiment.experiment.Experiment.run_recipe`): labelling them would compare
        them with a batch reference and settings they were not made with.
    """
    from curiosity_cli.explore.runs import RunError, read_run

    finished, problems, otherwise = [], [], []
    for run_path in runs:
        try:
            run = read_run(run_path)
        except RunError as exc:
            problems.append(str(exc))
            continue
        # the run its folder is, not the one its run.json names: a folder copied over another's is made otherwise
        change = experiment.run_recipe(*experiment.folder.run_of(run_path)).changes(run.meta)
        if change is None:
            finished.append(run)
        else:
            otherwise.append(f"{display_path(run_path / 'run.json')}: {change}")
    if otherwise:
        raise LabelError(
            f"{len(otherwise)} runs were made otherwise than {display_path(experiment.folder.config)} and the maps' "
            f"words make them now ({first_of(otherwise)}); restore the config, or run {RERUN} to redo the runs",
            rerun="explore",
        )
    return finished, problems


class LabelTask(NamedTuple):
    """A block of one map's runs, labelled in lock-step in a worker on ``device``."""

    runs: list[RunInputs]
    inputs: MapInputs
    device: str

    @property
    def key(self) -> str:
        """Its name on the Dask dashboard."""
        return "label-{dataset}/{weight_function}/restart-{restart:03d}".format(**self.runs[0].meta) + f"+{len(self.runs) - 1}"


def _stage_task(
    task: BatchTask | LabelTask, config: ExperimentConfig, shipped=None, progress: str | None = None, *, threads: int = 1,
):
    """A task of the stage in a worker: a batch reference (:func:`~curiosity_cli.label.batch_references.batch_task`)
    or a block of runs (:func:`_label_task`);
    ``shipped`` is its map's word store (a batch reference) or arrays (a block) on Dask, else None; ``progress``
    where a block writes its chain sweeps (:mod:`~curiosity_cli.label.block_progress`), or None."""
    if isinstance(task, BatchTask):
        return batch_task(task, config, shipped)
    return _label_task(task, config, shipped, progress)


class LabelledBlock(NamedTuple):
    """What a block's task returns: ``(arrays, examples, meta)`` per run, and where its seconds went in the worker:
    ``began`` (``time.time()`` when it started), ``reading`` (its map's arrays, made once per worker), ``kernel`` and
    ``tables`` (:func:`label_block`)."""

    runs: list[tuple]
    seconds: dict


def _label_task(
    task: LabelTask, config: ExperimentConfig, arrays: MapArrays | None = None, progress: str | None = None,
) -> LabelledBlock:
    """Label a block of runs in a worker on its device; ``arrays`` are its map's when shipped (Dask), else made once
    per worker; ``progress``, where its chain sweeps are written as it makes them. One thread: the blocks keep every
    worker busy."""
    began, wall_clock = time.perf_counter(), time.time()
    if arrays is None:
        arrays = _map_arrays(task.inputs, config.model.topics)
    seconds = {"began": wall_clock, "reading": time.perf_counter() - began}
    runs = label_block(
        task.runs, task.inputs, arrays, config, device=task.device, clock=seconds, on_sweep=SweepCounter(progress),
    )
    return LabelledBlock(runs, seconds)
