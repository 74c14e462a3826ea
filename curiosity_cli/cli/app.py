"""The ``curiosity`` application that every command module registers on (:data:`app`), and
how an error below a command becomes one line: a library :class:`CuriosityError` becomes
``Error: …`` on stderr and exit code 1; usage mistakes exit 2 (click's own, and a
:class:`UsageError` of the API, :func:`usage_errors`)."""

from __future__ import annotations

import functools
import inspect
from pathlib import Path

import typer
from typer.core import TyperGroup

from curiosity_cli import __version__
from curiosity_cli.errors import CuriosityError, UsageError, unwinding_interrupt, with_options


class _ErrorMappingGroup(TyperGroup):
    """Turns a library error or an OS error anywhere below into one line and exit code 1, never a traceback.

    An OS error (a full disk, a read-only folder, a file where a folder belongs) is the
    user's machine speaking, not a bug: it is reported by the path it concerns. A broken
    pipe on stdout is left to click, which exits quietly, and an error raised while Ctrl-C
    unwinds the command is left to :func:`main`, which reports the interrupt.
    """

    def invoke(self, ctx):
        from curiosity_cli.files import os_error_message

        try:
            return super().invoke(ctx)
        except CuriosityError as exc:
            if unwinding_interrupt(exc):
                raise
            typer.echo(f"Error: {_command_line_message(exc, self.get_command(ctx, ctx.invoked_subcommand or ''))}", err=True)
            raise typer.Exit(1) from None
        except BrokenPipeError:
            raise
        except OSError as exc:
            if unwinding_interrupt(exc):
                raise
            typer.echo(f"Error: {os_error_message(exc)}", err=True)
            raise typer.Exit(1) from None


def _command_line_message(exc: CuriosityError, command) -> str:
    """``exc`` in the command line's words: the option that gave the argument at fault, and
    the command that makes the files at fault anew (every stage spells ``force`` ``--force``).

    ``command`` is the command (or group of commands) the user ran; the argument is
    looked up by name among its options and, for a group, its commands' options.
    """
    flags = dict(reversed(list(_options(command))))  # a name's first flag where commands below share it
    option = flags.get(exc.parameter) if exc.parameter is not None else None
    remedy = f"`curiosity {exc.rerun}{' --force' if exc.force else ''}`" if exc.rerun else None
    # another argument the message names in backquotes, as the command line spells it
    return with_options(exc.render(option=option, rerun=remedy), flags)


def _options(command):
    """(parameter name, first flag) of every option of ``command`` and of the commands below it."""
    if command is None:
        return
    for param in command.params:
        if param.opts and param.opts[0].startswith("-"):
            yield param.name, param.opts[0]
    for sub in getattr(command, "commands", {}).values():
        yield from _options(sub)


def usage_errors(command):
    """``command`` with the API's :class:`UsageError` reported as click's usage error (exit code 2) on the
    option that gave its parameter, other arguments it names written as their options.

    Its ``Path`` options and arguments reach it as the API checks a path
    (:func:`~curiosity_cli.api.arguments.optional_path`): an empty one is such a usage error.
    """
    parameters = inspect.signature(command).parameters
    flags = {
        name: param.default.param_decls[0] for name, param in parameters.items()
        if isinstance(param.default, typer.models.OptionInfo) and param.default.param_decls
    }
    paths = [
        name for name, param in parameters.items()
        if param.annotation in (Path, "Path") and isinstance(param.default, typer.models.ParameterInfo)
    ]
    for name in paths:
        # typer would make an empty string Path(""), the current folder: let the string through to be checked
        parameters[name].default.path_type = str

    @functools.wraps(command)
    def reporting(*args, **kwargs):
        from curiosity_cli.api.arguments import optional_path

        try:
            for name in paths:
                kwargs[name] = optional_path(kwargs[name], name)
            return command(*args, **kwargs)
        except UsageError as exc:
            raise typer.BadParameter(exc.detail(flags), param_hint=flags.get(exc.parameter, exc.parameter)) from None

    return reporting


app = typer.Typer(
    cls=_ErrorMappingGroup,
    help="Curiosity-driven exploration experiments (Girdhar & Dudek) on map mosaics, "
    "and a serial robot driver with the same model.",
    no_args_is_help=True,
    add_completion=True,
    # click's plain help: flags as flags (rich's panels show every one as `<bool>`), our text as written
    rich_markup_mode=None,
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
