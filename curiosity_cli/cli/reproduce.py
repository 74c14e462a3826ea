"""``curiosity reproduce``: the whole pipeline for an experiment config, with a report."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli.app import app, usage_errors
from curiosity_cli.cli.explore import Backend
from curiosity_cli.paths import DEFAULT_CACHE, DEFAULT_RESULTS


@app.command("reproduce")
@usage_errors
def reproduce(
    config: Path = typer.Argument(None, metavar="CONFIG", help="Experiment YAML, or a shipped config's name; default quick, as explore's (minutes on a laptop); the paper's full grid is paper-grid.", show_default=False),
    quick: bool = typer.Option(False, "--quick", help="Run configs/quick.yaml (the default): the real Zurich map, 10 restarts, paths up to 160 steps; minutes, not the full grid."),
    overrides: list[str] = typer.Option([], "--set", metavar="KEY=VALUE", help="Override any config key, e.g. --set seed=1."),
    sweeps: list[str] = typer.Option(
        [], "--sweep", metavar="KEY=V1,V2,...",
        help="Run every combination of the --sweep options' values (their product), each as its own experiment "
        "under results/<name>-sweep/, and compare their headlines in SWEEP.md; e.g. --sweep model.topics=16,32. "
        "Values are split on commas outside brackets; one value just fixes the key. A config's own `sweep:` "
        "runs the same way; --sweep replaces the values of a key it declares. A config's `specifications:` run "
        "every combination under each, and SWEEP.md leads with their specification curve.",
    ),
    jobs: int = typer.Option(None, "--jobs", min=1, help="Parallel runs; default the number of cores."),
    force: bool = typer.Option(False, "--force", help="Redo runs and labels that are already finished."),
    backend: Backend = typer.Option(Backend.loky, "--backend", help="Where exploration and labelling run: loky (this machine) or dask (a Dask cluster, needs the distributed extra)."),
    scheduler: str = typer.Option(None, "--scheduler", metavar="ADDRESS", help="With --backend dask: a running scheduler; default a local cluster of --jobs workers, shared by both stages."),
    results_dir: Path = typer.Option(DEFAULT_RESULTS, "--results-dir", help="Experiment folders go here."),
    cache_dir: Path = typer.Option(DEFAULT_CACHE, "--cache-dir", help="Where word stores are kept."),
    converged: bool = typer.Option(False, "--converged", help="Converged labels: 256 sweeps from random topics at every checkpoint (label.sweeps=256, label.warm_sweeps=null), about ten times the labelling time."),
    reuse: bool = typer.Option(True, "--reuse/--no-reuse", help="Take label files and batch references another experiment computed from the same inputs (kept in --cache-dir's shared/ folder); --no-reuse computes them all."),
    measure: str = typer.Option("mi", "--measure", metavar="NAME", help="A study's specification curve of this measure too, e.g. nmi, ami, classes_found or mean_recall (MI's is always drawn); only for a config that declares specifications."),
    record: Path = typer.Option(None, "--record", metavar="DIR", help="A study's record, e.g. studies/multiverse: the seeds and specifications recorded there are taken (their tables, checked against the recipes the study gives now), not computed; each one computed is recorded there. For a config with specifications that sweeps only seed.", show_default=False),
) -> None:
    """Extract, explore, label, evaluate and plot, then write results/<experiment>/REPORT.md.

    Every stage keeps what it finished: run the same command again to resume. With
    --sweep, or a config that declares a sweep, once per combination of values, then
    results/<experiment>-sweep/SWEEP.md.
    """
    from curiosity_cli import api
    from curiosity_cli.files import display_path

    if quick and config is not None:
        raise typer.BadParameter(f"runs configs/quick.yaml; give it or a CONFIG ({config}), not both", param_hint="--quick")
    with api.Progress() as progress:
        report = api.reproduce(
            config if config is not None else "quick", overrides=overrides, sweeps=sweeps,
            jobs=jobs, force=force, backend=backend.value, scheduler=scheduler, results_dir=results_dir,
            cache_dir=cache_dir, converged=converged, on_stage=progress.stage, on_done=progress.advance, reuse=reuse,
            record=record, measure=measure, on_status=lambda line: typer.echo(line, err=True),
        )
    typer.echo(f"wrote {display_path(report)}")
    for line in api.verdict(report):  # the answer of each map, its evidence in the report
        typer.echo(f"  {line.split('; ', 1)[0]}")
