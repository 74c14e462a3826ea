"""The ``curiosity`` command line: thin commands over the library.

Every command module registers itself on :data:`app`. A library :class:`CuriosityError`
becomes ``Error: …`` on stderr and exit code 1; usage mistakes exit 2 (click's own).
Heavy libraries are imported inside commands so ``curiosity --help`` stays instant.
"""

from __future__ import annotations

import typer
from typer.core import TyperGroup

from curiosity_cli import __version__
from curiosity_cli.errors import CuriosityError


class _ErrorMappingGroup(TyperGroup):
    """Turns a library error anywhere below into one line and exit code 1, never a traceback."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except CuriosityError as exc:
            typer.echo(f"Error: {exc}", err=True)
            raise typer.Exit(1) from None


app = typer.Typer(
    cls=_ErrorMappingGroup,
    help="Curiosity-driven exploration experiments (Girdhar & Dudek) on map mosaics, "
    "and a serial robot driver with the same model.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _print_version(value: bool) -> None:
    if value:
        typer.echo(f"curiosity {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_print_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """Curiosity-driven exploration experiments on map mosaics."""


# Registration order is the order `--help` lists the commands: the pipeline's order.
from curiosity_cli.cli import datasets, vocab, extract, explore, label, plot, reproduce, drive, config_cmd  # noqa: E402,F401


def main() -> None:
    """Entry point of the ``curiosity`` console script."""
    app()
