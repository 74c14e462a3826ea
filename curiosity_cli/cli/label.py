"""``curiosity label``: labelings of whole maps by every run's checkpoint models and in batch mode."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli.app import app, usage_errors
from curiosity_cli.cli.explore import Backend
from curiosity_cli.paths import DEFAULT_CACHE, DEFAULT_RESULTS

EXPERIMENT = typer.Argument(DEFAULT_RESULTS / "quick", metavar="EXPERIMENT", help="Experiment folder written by `curiosity explore`.")


@app.command("label")
@usage_errors
def label(
    folder: Path = EXPERIMENT,
    overrides: list[str] = typer.Option([], "--set", metavar="KEY=VALUE", help="Override a label setting, e.g. --set label.sweeps=8; it is recorded in the experiment's config.yaml."),
    jobs: int = typer.Option(None, "--jobs", min=1, help="Parallel runs; default the number of cores."),
    force: bool = typer.Option(False, "--force", help="Recompute labels that are up to date."),
    cache_dir: Path = typer.Option(DEFAULT_CACHE, "--cache-dir", help="Where word stores are kept."),
    backend: Backend = typer.Option(Backend.loky, "--backend", help="loky: processes on this machine; dask: a Dask cluster (needs the distributed extra)."),
    scheduler: str = typer.Option(None, "--scheduler", metavar="ADDRESS", help="With --backend dask: a running scheduler, e.g. tcp://10.0.0.5:8786; default a local cluster of --jobs workers."),
    converged: bool = typer.Option(False, "--converged", help="Converged labels: 256 sweeps from random topics at every checkpoint (label.sweeps=256, label.warm_sweeps=null), about ten times the labelling time."),
    reuse: bool = typer.Option(True, "--reuse/--no-reuse", help="Take label files and batch references another experiment computed from the same inputs (kept in --cache-dir's shared/ folder); --no-reuse computes them all."),
) -> None:
    """Label each map with every run's checkpoint models (Z_p) and in batch mode (Z_b)."""
    from curiosity_cli import api

    with api.Progress() as progress:
        done = api.label(
            folder, overrides=overrides, jobs=jobs, force=force, cache_dir=cache_dir, backend=backend.value,
            scheduler=scheduler, converged=converged, on_stage=progress.stage, on_done=progress.advance, reuse=reuse,
        )
    shared = done["shared"]
    typer.echo(
        f"labelled {done['labelled']} runs in {done['seconds']:.0f} s ({done['skipped']} were up to date; "
        f"batch references: {done['batch_reused']} reused; taken from other experiments' shared items: "
        f"{shared['labels']} label files, {shared['batches']} batch references)"
    )
