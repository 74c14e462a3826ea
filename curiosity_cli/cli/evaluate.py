"""``curiosity evaluate``: the mutual information of the path labelings against human and batch labels, with statistics."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli.app import app, usage_errors
from curiosity_cli.cli.label import EXPERIMENT
from curiosity_cli.paths import DEFAULT_CACHE

#: Skipped pieces named on the terminal (skipped.json lists them all).
_SHOWN = 3


@app.command("evaluate")
@usage_errors
def evaluate(
    folder: Path = EXPERIMENT,
    partial: bool = typer.Option(False, "--partial", help="Evaluate the runs that have usable labels, leaving out (and listing) those that do not."),
    cache_dir: Path = typer.Option(DEFAULT_CACHE, "--cache-dir", help="Where word stores are kept."),
) -> None:
    """Mutual information of the path labelings against human and batch labels, with statistics.

    Every run of the grid needs its labels; with --partial, runs without usable labels are left out and listed in skipped.json.
    """
    from curiosity_cli import api
    from curiosity_cli.files import display_path

    result = api.evaluate(folder, partial=partial, cache_dir=cache_dir)
    if result.skipped:
        # the first few on the terminal; every one is in skipped.json
        shown = "; ".join(result.skipped[:_SHOWN])
        more = f"; and {len(result.skipped) - _SHOWN} more" if len(result.skipped) > _SHOWN else ""
        typer.echo(f"skipped {len(result.skipped)} (listed in skipped.json): {shown}{more}", err=True)
    typer.echo(
        f"wrote {display_path(Path(folder) / 'mi.csv')} ({len(result.mi)} rows), summary.csv, tests.csv, effects.csv, "
        "classes.csv, classes_summary.csv, headline.csv, found_effects.csv (what each walker found) and others"
    )
    for line in api.verdict(result):
        typer.echo(line)
