"""``curiosity plot``: the paper's figures from an experiment folder's results tables."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli.app import app, usage_errors
from curiosity_cli.paths import DEFAULT_RESULTS


@app.command("plot")
@usage_errors
def plot(
    folder: Path = typer.Argument(
        DEFAULT_RESULTS / "quick", metavar="EXPERIMENT",
        help="Experiment folder holding mi.csv and summary.csv from `curiosity evaluate`.",
    ),
    animate: str = typer.Option(None, "--animate", metavar="MAP/WALKER/RESTART", help="Instead of the figures, an animation of one run: its path growing over the map beside Z_p at each checkpoint, e.g. aerial-mosaic/topic-perplexity/0."),
    out: Path = typer.Option(None, "--out", help="With --animate: the .gif (or .mp4, with FFmpeg) to write; default figures/animation-MAP-WALKER-NNN.gif."),
    cache_dir: Path = typer.Option(None, "--cache-dir", help="With --animate: where word stores are kept."),
) -> None:
    """The paper's figures from the results tables: MI against path length, paths and label maps; then REPORT.md.

    Writes PNG and PDF under EXPERIMENT_DIR/figures/: MI against path length versus human and versus batch labels, an example path beside its labelling, the label maps side by side, and the batch model's convergence.

    A figure whose inputs are missing (a map without human labels, no batch labels yet) is skipped with a note on stderr.
    """
    from curiosity_cli import api
    from curiosity_cli.files import display_path

    if animate is not None:
        path = api.animate(folder, *api.run_named(animate, "animate"), out=out, cache_dir=cache_dir)
        typer.echo(f"wrote {display_path(path)}")
        return
    if out is not None or cache_dir is not None:
        raise typer.BadParameter("goes with --animate", param_hint="--out" if out is not None else "--cache-dir")
    written = api.plot(folder)
    for note in written.skipped:
        typer.echo(f"skipped: {note}", err=True)
    for path in written:
        typer.echo(f"wrote {display_path(path)}")
    if not written:
        typer.echo(f"no figures written to {display_path(Path(folder) / 'figures')}", err=True)
    if written.report is not None:
        typer.echo(f"wrote {display_path(written.report)}")
