"""A resolved config written as YAML: every key (:func:`to_yaml`), as an experiment folder saves
it (:func:`saved_yaml`), and as a drive run folder saves what it used (:func:`drive_yaml`).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from curiosity_cli.yamlfile import dump_yaml

#: The shipped config a saved experiment config builds on (:func:`saved_yaml`).
SAVED_BASE = "paper.yaml"


def to_dict(config) -> dict:
    """A config as plain YAML-ready data (paths as strings or their names, tuples as lists)."""

    def plain(value, named=None):
        if dataclasses.is_dataclass(value):
            return {f.name: plain(getattr(value, f.name), f.metadata.get("named")) for f in dataclasses.fields(value)}
        if isinstance(value, tuple):
            return [plain(v) for v in value]
        if isinstance(value, Path):
            return next((name for name, path in (named or {}).items() if value == path), str(value))
        return value

    return plain(config)


def to_yaml(config) -> str:
    """The resolved config as YAML: every key."""
    return dump_yaml(to_dict(config))


#: The sections of an experiment config that ``curiosity drive`` reads (with its seed).
DRIVE_SECTIONS = ("model", "words", "drive")


def drive_yaml(config, seed: int) -> str:
    """What a drive run folder saves of ``config``: the seed it ran with and :data:`DRIVE_SECTIONS`, every key.

    A drive has no maps or grid; the experiment's name, datasets, exploration and
    labelling would only mislead a reader of the run folder.
    """
    data = to_dict(config)
    return (
        f"# the settings of {config.name}'s config {_DRIVE_MARK} (its maps, exploration and labels are not used)\n"
        + dump_yaml({"seed": seed, **{key: data[key] for key in DRIVE_SECTIONS}})
    )


def is_drive_yaml(text: str) -> bool:
    """Whether a saved config's ``text`` is a drive run folder's (:func:`drive_yaml`), not an experiment's."""
    first = text.partition("\n")[0]
    return first.startswith("# the settings of ") and _DRIVE_MARK in first


_DRIVE_MARK = "that this drive ran with"


def saved_yaml(config) -> str:
    """The config as an experiment folder saves it: every key, on top of the shipped ``paper.yaml``.

    Every key is written, so the file says what the experiment ran with; the ``base``
    gives a key added to the project after the file was saved its default from
    ``configs/paper.yaml``, so the folder still loads. A file made with another value
    than that default is then refused or made again by its recipe
    (:mod:`curiosity_cli.experiment.recipes`), never taken as made with it.
    """
    return f"base: {SAVED_BASE}  # the shipped configs/{SAVED_BASE}: defaults for keys added after saving\n" + to_yaml(config)
