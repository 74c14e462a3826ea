"""The config commands as functions: ``config show`` and ``config init``."""

from __future__ import annotations

import typing
from pathlib import Path


def show_config(config: str | Path, overrides: typing.Iterable[str] = ()) -> str:
    """``curiosity config show``: a config validated and resolved (base files and ``overrides`` applied), as
    YAML, every key, as a run saves it; a base that names no experiment (``paper``), its parameter sections.
    As :func:`curiosity_cli.config.show_config`."""
    from curiosity_cli.api.arguments import name_or_path, overrides_argument
    from curiosity_cli.config import show_config as shown

    return shown(name_or_path(config, "config"), overrides_argument(overrides))


def init_config(name: str, source: str = "quick", folder: Path = Path(".")) -> Path:
    """``curiosity config init``: an editable, commented copy of the shipped config ``source`` written to
    ``folder/NAME.yaml``; returns its path. As :func:`curiosity_cli.config.init_config`."""
    from curiosity_cli.api.arguments import folder_argument, name_or_path
    from curiosity_cli.config import init_config as initialised

    return initialised(name_or_path(name, "name"), name_or_path(source, "source"), folder_argument(folder))
