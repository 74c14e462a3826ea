"""``curiosity config``: inspect experiment configs."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli.app import app, usage_errors

config_app = typer.Typer(help="Inspect experiment configs, or start one of your own.", no_args_is_help=True)
app.add_typer(config_app, name="config")


@config_app.command("show")
@usage_errors
def show(
    config: Path = typer.Argument(..., metavar="CONFIG", help="Experiment YAML, or a shipped config's name (quick, paper, paper-grid, readings)."),
    overrides: list[str] = typer.Option(
        [], "--set", metavar="KEY=VALUE", help="Override a key, e.g. --set explore.restarts=3."
    ),
) -> None:
    """Validate a config and print it resolved (base files and --set applied), as a run saves it.

    A base config that names no experiment (paper) prints its parameter sections.
    """
    from curiosity_cli import api

    typer.echo(api.show_config(config, overrides), nl=False)


@config_app.command("init")
@usage_errors
def init(
    name: str = typer.Argument(..., metavar="NAME", help="The experiment's name; writes NAME.yaml in the current folder."),
    source: str = typer.Option("quick", "--from", help="The shipped config to copy: quick, paper-grid or readings."),
) -> None:
    """Write an editable, commented copy of a shipped config into the current folder, named NAME.

    Its `base: paper.yaml` resolves to the shipped parameters wherever the file is; edit any key to override them, then run `curiosity reproduce NAME.yaml`.
    """
    from curiosity_cli import api
    from curiosity_cli.files import display_path

    path = api.init_config(name, source)
    typer.echo(f"wrote {display_path(path)} (a copy of the shipped {source}); run `curiosity reproduce {display_path(path)}`")
