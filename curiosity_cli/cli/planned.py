"""Commands that later issues implement: each says so plainly instead of pretending."""

from __future__ import annotations

import typer

from curiosity_cli.cli import app

# (command, what it will do, the issue that builds it)
_PLANNED = (
    ("label", "Label a whole map with the topic models learned on the paths.", 6),
    ("evaluate", "Mutual information of path labels against human and batch labels.", 6),
    ("plot", "The paper's figures from the results tables.", 6),
    ("reproduce", "Run the whole pipeline for an experiment config.", 6),
    ("drive", "Drive a robot over a serial port with live curiosity on a camera.", 7),
)


def _register(name: str, summary: str, issue: int) -> None:
    def command() -> None:
        typer.echo(
            f"Error: `curiosity {name}` is not implemented yet; it arrives with issue #{issue}.",
            err=True,
        )
        raise typer.Exit(1)

    app.command(
        name,
        help=f"{summary} (Not implemented yet: issue #{issue}.)",
        short_help=f"(not implemented yet) {summary}",
        context_settings={"allow_extra_args": True, "ignore_unknown_options": True},
    )(command)


for _entry in _PLANNED:
    _register(*_entry)
