"""``curiosity explore``: the exploration grid of an experiment config."""

from __future__ import annotations

import enum
from pathlib import Path

import typer

from curiosity_cli.cli.app import app, usage_errors
from curiosity_cli.paths import DEFAULT_CACHE, DEFAULT_RESULTS


class Backend(str, enum.Enum):
    """Where runs are computed (``curiosity_cli.workers.BACKENDS``)."""

    loky = "loky"
    dask = "dask"


@app.command("explore")
@usage_errors
def explore(
    config: Path = typer.Argument("quick", metavar="CONFIG", help="Experiment YAML, or a shipped config's name (quick, paper-grid, readings)."),
    maps: list[str] = typer.Option([], "--map", help="Only this map (repeatable); default the config's datasets."),
    weights: str = typer.Option(None, "--weights", help="Comma-separated weight functions, e.g. random-walk,topic-perplexity."),
    restarts: int = typer.Option(None, "--restarts", min=1, help="Restarts per weight function."),
    steps: int = typer.Option(None, "--steps", min=1, help="Path length; checkpoints beyond it are dropped, and it becomes the last."),
    overrides: list[str] = typer.Option([], "--set", metavar="KEY=VALUE", help="Override any config key, e.g. --set model.eta=0.8."),
    jobs: int = typer.Option(None, "--jobs", min=1, help="Parallel runs; default the number of cores."),
    force: bool = typer.Option(False, "--force", help="Redo runs that are already finished."),
    results_dir: Path = typer.Option(DEFAULT_RESULTS, "--results-dir", help="Experiment folders go here."),
    cache_dir: Path = typer.Option(DEFAULT_CACHE, "--cache-dir", help="Where word stores are kept."),
    backend: Backend = typer.Option(Backend.loky, "--backend", help="loky: processes on this machine; dask: a Dask cluster (needs the distributed extra)."),
    scheduler: str = typer.Option(None, "--scheduler", metavar="ADDRESS", help="With --backend dask: a running scheduler, e.g. tcp://10.0.0.5:8786; default a local cluster of --jobs workers."),
) -> None:
    """Run every weight function from every restart on every map, and save paths and topic models.

    Finished runs are kept: run the same command again to resume a stopped grid.
    """
    from curiosity_cli import api
    from curiosity_cli.files import display_path

    with api.Progress() as progress:

        def prepared(name: str, to_run: int, skipped: int) -> None:
            typer.echo(f"{name}: {to_run} runs to do, {skipped} already finished", err=True)
            progress.stage("exploring", to_run)

        summary = api.explore(
            config, maps=maps, weights=None if weights is None else [walker.strip() for walker in weights.split(",")],
            restarts=restarts, steps=steps, overrides=overrides, jobs=jobs, force=force, results_dir=results_dir,
            cache_dir=cache_dir, backend=backend.value, scheduler=scheduler, on_prepared=prepared, on_run=progress.advance,
        )
    typer.echo(
        f"wrote {summary.ran} runs ({summary.bytes_written / 1e6:.1f} MB) to {display_path(summary.folder)} "
        f"in {summary.seconds:.0f} s; {summary.skipped} were already there"
    )
    if summary.fallbacks:
        typer.echo(f"{summary.fallbacks} moves fell back to a uniform draw (no positive weight)")
