"""``curiosity datasets``: list the registered maps, show one with its legend and a preview."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli import app
from curiosity_cli.paths import DEFAULT_RESULTS

datasets_app = typer.Typer(help="List and preview the maps (embedded or your own).", no_args_is_help=True)
app.add_typer(datasets_app, name="datasets")


def _table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in [header, *rows]]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


@datasets_app.command("list")
def list_datasets() -> None:
    """The maps registered in configs/datasets/, with size, grid and provenance.

    A fetched map that is not cached yet is listed from its YAML; nothing is downloaded.
    """
    from curiosity_cli.cell_grid import map_grid
    from curiosity_cli.config import dataset_path, load_dataset_config
    from curiosity_cli.data import dataset_names, load_map
    from curiosity_cli.fetched import is_fetched

    rows = []
    for name in dataset_names():
        config = load_dataset_config(dataset_path(name))
        cached = "embedded" if config.fetch is None else ("cached" if is_fetched(config.fetch) else "fetched on first use")
        if config.fetch is None or cached == "cached":
            m = load_map(name)
            size, classes = m.image.shape[:2], str(len(m.legend))
        else:
            size, classes = config.size, "?"
        grid = map_grid(size, config.cell_width) if size is not None else None
        rows.append(
            [
                name,
                f"{size[0]} x {size[1]}" if size is not None else "?",
                str(config.cell_width),
                f"{grid.n_cells} ({grid.rows} x {grid.cols})" if grid is not None else "?",
                classes,
                cached,
                config.source,
                config.licence,
            ]
        )
    typer.echo(_table(["name", "size (px)", "cell width", "cells", "classes", "pixels", "source", "licence"], rows))


@datasets_app.command("show")
def show(
    datasets: list[str] = typer.Argument(..., help="Registered names or paths to dataset YAMLs."),
    out: Path = typer.Option(
        None,
        "--out",
        help="Preview PNG or PDF to write; default results/datasets/NAME.png "
        "(results/datasets/overview.png for several maps).",
    ),
) -> None:
    """Print each map's legend and write a preview: the image beside its colour-coded labels."""
    import numpy as np

    from curiosity_cli.data import load_map
    from curiosity_cli.fetched import made_notes
    from curiosity_cli.files import display_path
    from curiosity_cli.plots.preview import write_preview

    maps = [load_map(d) for d in datasets]
    for m in maps:
        rows, cols = m.grid.shape
        typer.echo(
            f"{m.config.name}: {m.image.shape[0]} x {m.image.shape[1]} px, {m.config.cell_width} px cells "
            f"({rows} x {cols} = {rows * cols}), words every {m.config.word_stride} px"
        )
        typer.echo(f"  image: {m.rendering.describe()}")
        if m.config.fetch is not None:
            notes = made_notes(m.config.fetch)
            for key in ("crop", "image"):
                if key in notes:
                    typer.echo(f"  made from: {notes[key]}")
        if m.labels is None:
            typer.echo("  no labels\n")
            continue
        counts = np.bincount(m.labels.ravel(), minlength=max(c.id for c in m.legend) + 1)
        typer.echo(
            _table(
                ["id", "name", "colour", "pixels", "description"],
                [
                    [
                        str(c.id),
                        c.name,
                        "#{:02x}{:02x}{:02x}".format(*c.colour),
                        f"{100 * counts[c.id] / m.labels.size:.2f}%",
                        c.description,
                    ]
                    for c in m.legend
                ],
            )
        )
        typer.echo("")
    if out is None:
        stem = maps[0].config.name if len(maps) == 1 else "overview"
        out = DEFAULT_RESULTS / "datasets" / f"{stem}.png"
    write_preview(maps, out)
    typer.echo(f"wrote {display_path(out)}")
