"""``curiosity reproduce``: extract, explore, label, evaluate and plot, then write REPORT.md.

Each stage is resumable on its own (finished runs, labels and batch references are kept),
so a stopped reproduction picks up where it was.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from curiosity_cli.config import ExperimentConfig
from curiosity_cli.paths import DEFAULT_CACHE, DEFAULT_RESULTS, experiment_root


def reproduce(
    config: ExperimentConfig,
    *,
    results_dir: Path = DEFAULT_RESULTS,
    cache_dir: Path = DEFAULT_CACHE,
    jobs: int | None = None,
    force: bool = False,
    backend: str = "loky",
    scheduler: str | None = None,
    on_stage: Callable[[str, int], None] | None = None,
    on_done: Callable[[], None] | None = None,
    reuse: bool = True,
) -> Path:
    """Run the whole pipeline for ``config`` and return the path of its ``REPORT.md``.

    ``backend`` and ``scheduler`` say where the exploration runs and the labelling go
    (see :class:`~curiosity_cli.workers.Workers`); both stages share the workers, so
    ``backend="dask"`` without a scheduler starts one local cluster, not two.
    ``on_stage(description, units)`` announces each stage and ``on_done()`` marks a unit
    of it done, for a progress display. ``reuse`` takes label files and batch references
    another experiment computed from the same inputs (:mod:`~curiosity_cli.label.shared_items`).
    With loky workers labelling on the CPU, the maps' batch references are computed in this
    process while the runs are explored
    (:func:`~curiosity_cli.label.batch_references.beside_exploration`), not in the label
    stage: the same files, off its critical path.
    """
    from curiosity_cli.evaluate.stage import evaluate_experiment
    from curiosity_cli.explore.grid import run_grid
    from curiosity_cli.label.batch_references import beside_exploration
    from curiosity_cli.label.shared_items import SharedItems
    from curiosity_cli.label.stage import label_experiment
    from curiosity_cli.plots.figures import write_figures
    from curiosity_cli.workers import Workers

    def stage(description: str, units: int) -> None:
        if on_stage is not None:
            on_stage(description, units)

    def done(*_) -> None:
        if on_done is not None:
            on_done()

    from curiosity_cli.topics.devices import DEVICES, resolve_device

    device = resolve_device(config.label.device)  # a GPU that is not there stops the pipeline before it explores, not after
    folder = experiment_root(results_dir, config.name)
    stage("words and exploration set-up", 0)
    batches = []  # threads computing batch references beside the exploration

    def start_batches(experiment, stores) -> None:
        # a Dask cluster's workers may be elsewhere, this process's cores too few to share;
        # force makes the label stage compute them again anyway. On a device that frees the
        # cores (a GPU) the label stage's blocks leave them to the references (on 16 cores they
        # were written at 20 s of a 36-s stage), and beside the exploration they slowed it
        # (55 to 73 s): not then
        if not workers.ships and not force and not DEVICES[device].frees_cores:
            shared = SharedItems(cache_dir) if reuse else None
            batches.extend(beside_exploration(config, experiment, stores, workers.jobs, shared))

    with Workers(backend, scheduler, jobs) as workers:
        run_grid(
            config, results_dir=results_dir, cache_dir=cache_dir, force=force, workers=workers,
            on_prepared=lambda to_run, skipped: stage(f"exploring ({skipped} runs already done)", to_run), on_run=done,
            beside=start_batches,
        )
        for thread in batches:  # not when the grid failed or was stopped: a stopped command does not wait for them
            thread.join()
        label_experiment(
            config, folder, cache_dir=cache_dir, force=force, workers=workers, on_stage=stage, on_done=done, reuse=reuse,
        )
    stage("evaluating", 0)
    evaluate_experiment(folder, cache_dir=cache_dir)
    stage("plotting", 0)
    return write_figures(folder).report
