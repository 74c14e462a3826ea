"""``curiosity config``: inspect experiment configs."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli import app

config_app = typer.Typer(help="Inspect experiment configs.", no_args_is_help=True)
app.add_typer(config_app, name="config")


@config_app.command("show")
def show(
    config: Path = typer.Argument(..., help="Experiment YAML, e.g. configs/quick.yaml."),
    overrides: list[str] = typer.Option(
        [], "--set", metavar="KEY=VALUE", help="Override a key, e.g. --set explore.restarts=3."
    ),
) -> None:
    """Validate a config and print it resolved (base files and --set applied), as a run saves it."""
    from curiosity_cli.config import load_config, to_yaml

    typer.echo(to_yaml(load_config(config, overrides)), nl=False)
