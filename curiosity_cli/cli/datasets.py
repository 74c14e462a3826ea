"""``curiosity datasets``: list the registered maps, show one with its legend and a preview."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli.app import app, usage_errors

datasets_app = typer.Typer(help="List and preview the maps (embedded or your own).", no_args_is_help=True)
app.add_typer(datasets_app, name="datasets")


def _table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in [header, *rows]]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


@datasets_app.command("list")
@usage_errors
def list_datasets(
    as_json: bool = typer.Option(False, "--json", help="One JSON object per map (name, size, cell_width, grid, classes, pixels, source, licence; sizes as [rows, cols], null where unknown), as a JSON list."),
) -> None:
    """The maps registered in configs/datasets/, with size, grid and provenance.

    A fetched map that is not cached yet is listed from its YAML; nothing is downloaded.
    """
    import json

    from curiosity_cli import api

    if as_json:
        typer.echo(json.dumps([row._asdict() for row in api.list_datasets()], indent=1))
        return
    rows = [
        [
            row.name,
            f"{row.size[0]} x {row.size[1]}" if row.size is not None else "?",
            str(row.cell_width),
            f"{row.grid[0] * row.grid[1]} ({row.grid[0]} x {row.grid[1]})" if row.grid is not None else "?",
            "?" if row.classes is None else str(row.classes),
            row.pixels,
            row.source,
            row.licence,
        ]
        for row in api.list_datasets()
    ]
    typer.echo(_table(["name", "size (px)", "cell width", "cells", "classes", "pixels", "source", "licence"], rows))


@datasets_app.command("show")
@usage_errors
def show(
    datasets: list[str] = typer.Argument(..., metavar="MAP...", help="Registered names or paths to dataset YAMLs."),
    out: Path = typer.Option(
        None,
        "--out",
        help="Preview PNG or PDF to write; default results/datasets/NAME.png "
        "(results/datasets/overview.png for several maps).",
    ),
) -> None:
    """Print each map's legend and write a preview: the image beside its colour-coded labels."""
    import numpy as np

    from curiosity_cli import api
    from curiosity_cli.files import display_path

    preview = api.show_datasets(datasets, out=out)
    for m, notes in zip(preview.maps, preview.notes):
        rows, cols = m.grid.shape
        typer.echo(
            f"{m.config.name}: {m.image.shape[0]} x {m.image.shape[1]} px, {m.config.cell_width} px cells "
            f"({rows} x {cols} = {rows * cols}), words every {m.config.word_stride} px"
        )
        if m.config.generate is not None:
            typer.echo("  image: the truth in the legend's colours; the words are drawn from `generate:`, not seen")
        else:
            typer.echo(f"  image: {m.rendering.describe()}")
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
    typer.echo(f"wrote {display_path(preview.path)}")
