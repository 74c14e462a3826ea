"""A map's batch reference Z_b, for the ``label`` stage: computed in a worker, written by the command, read back.

``batch/<dataset>.npz`` (:meth:`~curiosity_cli.experiment.layout.ExperimentFolder.batch`):
``labels`` (H, W) int16 pixel topics, ``word_labels`` (N,) int16, ``log_likelihood``
(batch_sweeps,) float64 and ``meta`` (JSON: its recipe,
:meth:`~curiosity_cli.experiment.experiment.Experiment.batch_recipe`, and seconds). It is
reused while its recipe is the one the experiment's settings give; otherwise computed again,
with a note saying what changed. The stage (:mod:`~curiosity_cli.label.stage`)
computes every stale map's at once, before its label blocks or beside them; a block that
runs beside reads Z_b when it first needs it (:class:`WrittenBatch`). ``curiosity
reproduce`` computes them earlier still, beside the exploration (:func:`beside_exploration`):
they depend on the words and the model, not on the runs.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from curiosity_cli.config import ExperimentConfig
from curiosity_cli.experiment.recipes import RECIPE_KEY, Recipe
from curiosity_cli.files import CorruptFileError, atomic_path, display_path, note, open_npz, read_meta

if TYPE_CHECKING:
    from curiosity_cli.experiment.experiment import Experiment
    from curiosity_cli.experiment.maps import StoreInfo
    from curiosity_cli.workers import Workers
    from curiosity_cli.words.store import WordStore


class BatchTask(NamedTuple):
    """A map's batch reference, computed in a worker on ``threads`` threads."""

    info: StoreInfo
    threads: int

    @property
    def key(self) -> str:
        """Its name on the Dask dashboard."""
        return f"batch-{self.info.name}"


def batch_is_current(path: Path, recipe: Recipe) -> bool:
    """Whether a batch reference file exists and was made from ``recipe``.

    A corrupt one is not, nor one made otherwise; each is noted on stderr, saying why,
    as computed again.
    """
    try:
        with open_npz(path) as npz:
            change = recipe.changes(read_meta(npz))
    except FileNotFoundError:
        return False
    except CorruptFileError as exc:
        note(f"{exc}; computing it again")
        return False
    if change is not None:
        note(f"{display_path(path)}: {change}; computing it again")
    return change is None


def batch_task(task: BatchTask, config: ExperimentConfig, store: WordStore | None = None, *, threads: int = 1) -> tuple:
    """A map's batch reference, in a worker, on ``task.threads`` threads: ``(pixel labels, word labels, trace,
    seconds)``; from its word ``store`` when shipped (Dask), else read here. (``threads``, the worker's share, is the
    same for every task of a stage; a batch reference beside label blocks has its own.)"""
    from curiosity_cli.label.sampling import batch_labels, pixel_labels
    from curiosity_cli.seeds import BATCH_TAG, name_key
    from curiosity_cli.words.store import load_store

    info = task.info
    store = load_store(info.path) if store is None else store
    seed = int(np.random.SeedSequence((config.seed, name_key(info.name), BATCH_TAG)).generate_state(1, np.uint64)[0])
    started = time.perf_counter()
    word_labels, trace = batch_labels(store, config.model, sweeps=config.label.batch_sweeps, seed=seed, threads=task.threads)
    seconds = time.perf_counter() - started
    return pixel_labels(store, word_labels, info.facts.shape), word_labels, trace, seconds


def write_batch(path: Path, recipe: Recipe, labels, word_labels, trace, seconds: float) -> None:
    """Write a map's batch reference (as :func:`batch_task` returns it) to ``path``, atomically, with its ``recipe``."""
    meta = {RECIPE_KEY: recipe.record(), "seconds": round(seconds, 2)}
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as handle:
            np.savez_compressed(
                handle, labels=labels, word_labels=word_labels, log_likelihood=trace, meta=json.dumps(meta, sort_keys=True)
            )


def compute_batch_references(
    config: ExperimentConfig, stale: list[StoreInfo], files: dict[str, Path], recipes: dict[str, Recipe], workers: Workers,
    on_stage: Callable[[str, int], None] | None, on_done: Callable[[], None] | None,
) -> list[str]:
    """Compute the ``stale`` maps' batch references before any label block, and write them to ``files`` (by map name);
    a line for each that failed, whose map is then left out of ``files``.

    Every map's at once, each a task on its share of the cores
    (:meth:`~curiosity_cli.workers.Workers.whole_machine_threads`): its sweeps
    scale with threads less well than maps side by side do. A map's sweeps are counted
    when it arrives.
    """
    from curiosity_cli.words.store import load_store

    sweeps = config.label.batch_sweeps
    problems = []
    if stale:
        threads = workers.whole_machine_threads(len(stale))  # reaches a scheduler first: no stage for an unusable one
        if on_stage is not None:
            what = "batch reference" + ("s of " if len(stale) > 1 else " ")
            on_stage(what + ", ".join(info.name for info in stale), len(stale) * sweeps)
        computed = workers.compute(
            batch_task, [BatchTask(info, threads) for info in stale], key=lambda task: task.key,
            args=lambda task: (config, workers.ship_file(task.info.path, load_store) if workers.ships else None),
        )
        with computed as results:
            for task, outcome in results:
                if isinstance(outcome, str):
                    problems.append(f"the batch reference of {task.info.name}: {outcome}; its runs were not labelled")
                    del files[task.info.name]
                else:
                    write_batch(files[task.info.name], recipes[task.info.name], *outcome)
                if on_done is not None:
                    for _ in range(sweeps):
                        on_done()
    return problems


def beside_exploration(
    config: ExperimentConfig, experiment: Experiment, stores: dict[str, StoreInfo], jobs: int, shared=None,
) -> list[threading.Thread]:
    """Start computing the maps' stale batch references in threads of this process, beside the exploration's workers.

    A map's batch reference depends on its words and the model only, so it need not
    wait for the runs: computed while they are explored, it is current when the label
    stage starts, which then labels without it on its critical path. Each stale map gets
    a thread of ``max(1, jobs // (2 * maps))`` sampler threads (a share that leaves the
    exploration's ``jobs`` workers their cores), and is written to the experiment's
    ``batch/`` (and kept in the ``shared`` items, a
    :class:`~curiosity_cli.label.shared_items.SharedItems` or None) as the label stage
    would write it. A map whose batch reference is current, or in ``shared`` for the
    label stage to take, is left alone. A batch reference that fails here is left for
    the label stage, which computes it again and names the error; the threads are daemons,
    so a stopped command does not wait for them (a file half-written is a temporary file
    that the label stage removes).

    Returns
    -------
    list of threading.Thread
        Started; join them before the label stage.
    """
    from curiosity_cli.label.shared_items import BATCH

    todo = []
    for info in stores.values():
        path, recipe = experiment.folder.batch(info.name), experiment.batch_recipe(info.name)
        if not batch_is_current(path, recipe) and (shared is None or shared.find(BATCH, recipe.digest) is None):
            todo.append((info, path, recipe))
    threads = max(1, jobs // (2 * max(1, len(todo))))

    def compute(info: StoreInfo, path: Path, recipe: Recipe) -> None:
        try:
            write_batch(path, recipe, *batch_task(BatchTask(info, threads), config))
            if shared is not None:
                shared.keep_file(BATCH, recipe.digest, path)
        except Exception:  # noqa: BLE001  the label stage computes it again and reports what fails there
            return

    started = [threading.Thread(target=compute, args=item, daemon=True, name=f"batch-{item[0].name}") for item in todo]
    for thread in started:
        thread.start()
    return started


#: How often (s) a label task that needs Z_b checks whether its batch reference is written.
BATCH_POLL_SECONDS = 0.2


class WrittenBatch:
    """Z_b's tables (:class:`~curiosity_cli.label.pixel_tables.PixelTables`) from the batch file at ``path`` made
    from the recipe ``digest``, read when first needed: a label task may start while its map's batch reference is
    still being computed beside it, and waits for the file only when it first compares a Z_p with Z_b.

    The command that runs the task writes the file (atomically) or, when the batch
    reference fails, stops the task; a command killed outright takes its workers with it.
    """

    def __init__(self, path: str, digest: str, pixel_words: np.ndarray, topics: int):
        self._path, self._digest, self._pixel_words, self._topics = Path(path), digest, pixel_words, topics
        self._tables = None

    def tables(self, word_labels: np.ndarray, n_labels: int, kept: np.ndarray | None = None) -> np.ndarray:
        """As :meth:`PixelTables.tables <curiosity_cli.label.pixel_tables.PixelTables.tables>`, once the file is there."""
        from curiosity_cli.label.pixel_tables import PixelTables

        if self._tables is None:
            self._tables = PixelTables(self._pixel_words, self._wait(), self._topics)
        return self._tables.tables(word_labels, n_labels, kept)

    def _wait(self) -> np.ndarray:
        """Z_b's (H, W) pixel labels, once the file made from the recipe is there."""
        from curiosity_cli.experiment.recipes import recorded_digest

        while True:
            try:
                with open_npz(self._path) as npz:
                    if recorded_digest(read_meta(npz)) == self._digest:
                        return npz["labels"]
            except (FileNotFoundError, CorruptFileError):
                pass  # not written yet, or the one before it
            time.sleep(BATCH_POLL_SECONDS)
