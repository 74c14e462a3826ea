"""The checks of the API's arguments: a wrong type is a :class:`~curiosity_cli.errors.ParameterError`
naming the argument, as a wrong value is, never a ``TypeError`` from deep inside.

The command line cannot give these wrong (its options are parsed into the right types),
but for an empty path, which it checks here too (:func:`~curiosity_cli.cli.app.usage_errors`);
a notebook can.
"""

from __future__ import annotations

import os
import typing
from pathlib import Path

from curiosity_cli.errors import ParameterError, UsageError
from curiosity_cli.yamlfile import shown


def _given(value) -> str:
    return f"{shown(value)} ({type(value).__name__})"


def config_argument(config):
    """``config``: a shipped config's name, a YAML path, or an ``ExperimentConfig``, as given."""
    from curiosity_cli.config import ExperimentConfig

    if isinstance(config, (str, os.PathLike, ExperimentConfig)):
        return config
    raise ParameterError(
        f"config: got {_given(config)}, expected a shipped config's name, a path to a YAML config or an ExperimentConfig"
    )


def folder_argument(folder, name: str = "folder") -> Path:
    """A folder's path, given as a string or a path, not an empty one (:func:`path_argument`), nor a file's."""
    path = path_argument(folder, name, "the path of a folder")
    if path.exists() and not path.is_dir():
        raise ParameterError(f"{name}: got {path}, which is a file; expected a folder")
    return path


def name_or_path(value, name: str) -> str:
    """A registered name, or a path given as a string or a path; as a string."""
    if isinstance(value, (str, os.PathLike)):
        return os.fspath(value)
    raise ParameterError(f"{name}: got {_given(value)}, expected a name or a path")


def optional_path(value, name: str) -> Path | None:
    """A path, given as a string or a path, not an empty one (:func:`path_argument`), or None."""
    return None if value is None else path_argument(value, name)


def path_argument(value, name: str, expected: str = "a path") -> Path:
    """``value``, a string or a path, as a path; ``expected`` says what it should be in an error.

    An empty string is refused as a :class:`~curiosity_cli.errors.UsageError` naming
    ``name``: ``Path("")`` is the current folder, and an empty string is far more often an
    unset shell variable than a wish to write there.
    """
    if not isinstance(value, (str, os.PathLike)):
        raise ParameterError(f"{name}: got {_given(value)}, expected {expected}")
    if os.fspath(value) == "":
        raise UsageError(f"{name}: got '' (an empty path), expected {expected}", parameter=name)
    return Path(value)


def strings(value, name: str, example: str) -> list[str]:
    """A list of strings (a sequence, not one string, which would be read letter by letter)."""
    if isinstance(value, (str, bytes)) or not isinstance(value, typing.Iterable):
        raise ParameterError(f"{name}: got {_given(value)}, expected a list of strings, e.g. [{example!r}]")
    value = list(value)
    for item in value:
        if not isinstance(item, str):
            raise ParameterError(f"{name}: got {_given(item)} in the list, expected strings, e.g. [{example!r}]")
    return value


def overrides_argument(overrides) -> list[str]:
    """``overrides``: ``KEY=VALUE`` strings."""
    return strings(overrides, "overrides", "explore.restarts=4")


def optional_count(value, name: str, minimum: int = 1) -> int | None:
    """An int of at least ``minimum`` (a bool is not one), or None."""
    from curiosity_cli.checks import check_int

    return None if value is None else check_int(name, value, minimum)


def boolean(value, name: str) -> bool:
    """``True`` or ``False`` (a string such as ``"no"`` is refused, not taken as true)."""
    if isinstance(value, bool):
        return value
    raise ParameterError(f"{name}: got {_given(value)}, expected True or False")


def callback(value, name: str):
    """A function to call, or None (a callback that cannot be called fails as itself, not deep in the work)."""
    if value is None or callable(value):
        return value
    raise ParameterError(f"{name}: got {_given(value)}, expected a function to call, or None")


def name_text(value, name: str) -> str:
    """A string (a name, a topic), not anything else."""
    if isinstance(value, str):
        return value
    raise ParameterError(f"{name}: got {_given(value)}, expected a string")
