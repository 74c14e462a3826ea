"""``curiosity extract``: visual words of a map, cut into its cell grid."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli.app import app, usage_errors
from curiosity_cli.paths import DEFAULT_CACHE


@app.command("extract")
@usage_errors
def extract(
    dataset: str = typer.Argument(..., metavar="MAP", help="A registered map name or a path to a dataset YAML."),
    config: Path = typer.Option("paper", "--config", help="Config whose `words` section to use: a YAML file or a shipped config's name."),
    overrides: list[str] = typer.Option([], "--set", metavar="KEY=VALUE", help="Override a words key, e.g. --set words.colour_words=true."),
    stride: int = typer.Option(None, "--stride", min=1, help="Texton words every N pixels, at most the cell width; default the dataset's word_stride."),
    cell_width: int = typer.Option(None, "--cell-width", min=1, help="Cell side in pixels; default the dataset's."),
    cache_dir: Path = typer.Option(DEFAULT_CACHE, "--cache-dir", help="Where word stores are kept."),
    force: bool = typer.Option(False, "--force", help="Extract again even if a cached store exists."),
    density: Path = typer.Option(None, "--density", help="Also write a PNG of words per cell and a sample of words."),
) -> None:
    """Extract ORB and texton words (hue words optional) into a cached word store."""
    import numpy as np

    from curiosity_cli import api
    from curiosity_cli.files import display_path

    result = api.extract(
        dataset, config=config, overrides=overrides, stride=stride, cell_width=cell_width, cache_dir=cache_dir,
        force=force, density=density,
    )
    store = result.store
    per_cell = store.words_per_cell()
    typer.echo(f"{'reused' if result.reused else 'wrote'} {display_path(result.path)}")
    typer.echo(
        f"{len(store.words):,} words in {store.n_cells} cells ({store.grid.rows} x {store.grid.cols}, "
        f"{store.grid.cell_width} px), vocabulary {store.vocabulary_size}"
    )
    for t in store.types:
        typer.echo(f"  {t.kind:<7} {store.count_by_type()[t.kind]:>10,}  ids {t.offset}..{t.offset + t.size - 1} ({t.name})")
    typer.echo(f"ORB share: {100 * result.orb_share:.1f} % of {len(store.words):,} words")
    typer.echo(f"words per cell: min {per_cell.min()}, median {int(np.median(per_cell))}, max {per_cell.max()}")
    if result.seconds:
        typer.echo("seconds: " + ", ".join(f"{k} {v:.2f}" for k, v in result.seconds.items()))
    if density is not None:
        typer.echo(f"wrote {display_path(density)}")
