"""``curiosity plot``: the paper's figures from an experiment folder's results tables."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli import app
from curiosity_cli.paths import DEFAULT_RESULTS


@app.command("plot")
def plot(
    experiment_dir: Path = typer.Argument(
        DEFAULT_RESULTS / "quick", help="Experiment folder holding mi.csv and summary.csv from `curiosity evaluate`."
    ),
) -> None:
    """The paper's figures from the results tables: MI against path length, paths and label maps.

    Writes PNG and PDF under EXPERIMENT_DIR/figures/: MI against path length versus human and versus batch labels, an example path beside its labelling, the label maps side by side, and the batch model's convergence.

    A figure whose inputs are missing (a map without human labels, no batch labels yet) is skipped with a note on stderr.
    """
    from curiosity_cli.files import display_path
    from curiosity_cli.plots.figures import write_figures

    written = write_figures(experiment_dir)
    for note in written.skipped:
        typer.echo(f"skipped: {note}", err=True)
    for path in written:
        typer.echo(f"wrote {display_path(path)}")
    if not written:
        typer.echo(f"no figures written to {display_path(Path(experiment_dir) / 'figures')}", err=True)
