"""``curiosity label`` and ``curiosity evaluate``: labelings of whole maps, and their mutual information."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli import app
from curiosity_cli.cli.explore import Backend
from curiosity_cli.cli.progress import StagedProgress
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.paths import DEFAULT_CACHE, DEFAULT_RESULTS

#: Skipped pieces named on the terminal by `evaluate` (skipped.json lists them all).
_SHOWN = 3

EXPERIMENT = typer.Argument(DEFAULT_RESULTS / "quick", help="Experiment folder written by `curiosity explore`.")


@app.command("label")
def label(
    folder: Path = EXPERIMENT,
    overrides: list[str] = typer.Option([], "--set", metavar="KEY=VALUE", help="Override a label setting, e.g. --set label.sweeps=8; it is recorded in the experiment's config.yaml."),
    jobs: int = typer.Option(None, "--jobs", min=1, help="Parallel runs; default the number of cores."),
    force: bool = typer.Option(False, "--force", help="Recompute labels that are up to date."),
    cache_dir: Path = typer.Option(DEFAULT_CACHE, "--cache-dir", help="Where word stores are kept."),
    backend: Backend = typer.Option(Backend.loky, "--backend", help="loky: processes on this machine; dask: a Dask cluster (needs the distributed extra)."),
    scheduler: str = typer.Option(None, "--scheduler", metavar="ADDRESS", help="With --backend dask: a running scheduler, e.g. tcp://10.0.0.5:8786; default a local cluster of --jobs workers."),
    converged: bool = typer.Option(False, "--converged", help="Converged labels: 256 sweeps from random topics at every checkpoint (label.sweeps=256, label.warm_sweeps=null), about ten times the labelling time."),
) -> None:
    """Label each map with every run's checkpoint models (Z_p) and in batch mode (Z_b)."""
    from curiosity_cli.config import with_converged_labels
    from curiosity_cli.evaluate.label_stage import label_experiment
    from curiosity_cli.experiment.saved_config import load_saved_config

    if scheduler is not None and backend is not Backend.dask:
        raise typer.BadParameter("needs --backend dask", param_hint="--scheduler")
    config = load_saved_config(folder, with_converged_labels(overrides) if converged else overrides)
    with StagedProgress() as progress:
        done = label_experiment(
            config, folder, cache_dir=cache_dir, jobs=jobs, force=force,
            on_stage=progress.stage, on_done=progress.advance, backend=backend.value, scheduler=scheduler,
        )
    typer.echo(
        f"labelled {done['labelled']} runs in {done['seconds']:.0f} s ({done['skipped']} were up to date; "
        f"batch references: {done['batch_reused']} reused)"
    )


@app.command("evaluate")
def evaluate(
    folder: Path = EXPERIMENT,
    partial: bool = typer.Option(False, "--partial", help="Evaluate the runs that have usable labels, leaving out (and listing) those that do not."),
) -> None:
    """Mutual information of the path labelings against human and batch labels, with statistics.

    Every run of the grid needs its labels; with --partial, runs without usable labels are left out and listed in skipped.json.
    """
    from curiosity_cli.errors import CuriosityError
    from curiosity_cli.evaluate.report import verdict
    from curiosity_cli.evaluate.tables import IncompleteLabelsError, evaluate_experiment
    from curiosity_cli.experiment.recipes import first_of
    from curiosity_cli.files import display_path

    try:
        result = evaluate_experiment(folder, partial=partial)
    except IncompleteLabelsError as exc:
        raise CuriosityError(
            f"{len(exc.left_out)} runs of the grid have no usable labels ({first_of(exc.left_out)}); `curiosity label` "
            "makes them once their runs are explored, or `curiosity evaluate --partial` leaves them out"
        ) from None
    if result.skipped:
        # the first few on the terminal; every one is in skipped.json
        shown = "; ".join(result.skipped[:_SHOWN])
        more = f"; and {len(result.skipped) - _SHOWN} more" if len(result.skipped) > _SHOWN else ""
        typer.echo(f"skipped {len(result.skipped)} (listed in skipped.json): {shown}{more}", err=True)
    typer.echo(
        f"wrote {display_path(ExperimentFolder(folder).table('mi'))} ({len(result.mi)} rows), summary.csv, tests.csv, effects.csv, "
        "classes.csv, classes_summary.csv, headline.csv"
    )
    for row in result.headline.to_dict("records"):
        typer.echo(verdict(row))
