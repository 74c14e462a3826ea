"""The rules of an experiment's saved ``config.yaml``: what may change once runs exist.

``explore`` writes the resolved config into the experiment folder; every later command
reads it back from there (:func:`load_saved_config`). Afterwards only two kinds of keys
may differ: those that choose which runs the grid holds (``explore.weight_functions``,
``explore.restarts``: :data:`SELECTION_KEYS`), and the ``label`` section, which a
``label`` with other settings records as the experiment's (:func:`record_label_settings`).
Everything else a run's numbers depend on (:data:`RUN_SECTIONS`) is fixed by the runs
already there (:func:`check_saved_config`).
"""

from __future__ import annotations

import contextlib
import typing
from pathlib import Path

from curiosity_cli.config import ExperimentConfig, load_config
from curiosity_cli.config_yaml import is_drive_yaml, saved_yaml, to_dict
from curiosity_cli.errors import RERUN, ConfigError
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.experiment.recipes import SELECTION_KEYS, differences
from curiosity_cli.files import atomic_path, display_path, note

#: The config sections a run's numbers depend on (but :data:`SELECTION_KEYS`).
RUN_SECTIONS = ("seed", "model", "words", "explore")


def load_saved_config(folder: str | Path, overrides: typing.Iterable[str] = ()) -> ExperimentConfig:
    """The config an experiment folder was explored with (its ``config.yaml``), plus ``overrides``.

    Raises
    ------
    ConfigError
        The folder has no ``config.yaml`` (explore it first), or it does not validate, naming it.
    """
    saved = ExperimentFolder(folder).config
    if not saved.is_file():
        raise ConfigError(f"{display_path(saved)}: not found; {RERUN} makes the experiment", rerun="explore", force=False)
    refuse_drive_folder(folder)
    config = load_config(saved)  # the file alone first: a broken one is named, not an override that met it
    return load_config(saved, overrides) if overrides else config


def refuse_drive_folder(folder: str | Path) -> None:
    """Refuse a drive's run folder given where an experiment folder is expected, pointing to what reads it.

    Raises
    ------
    ConfigError
        Its ``config.yaml`` is a drive's (an unreadable one passes: :func:`load_saved_config` names it).
    """
    with contextlib.suppress(OSError, UnicodeDecodeError):
        if is_drive_yaml(ExperimentFolder(folder).config.read_text()):
            raise ConfigError(
                f"{display_path(Path(folder))}: a drive's run folder, not an experiment; its frames are read with "
                "curiosity_cli.api.open_mission (frames.parquet), its timeline drawn by curiosity drive --timeline"
            )


def run_sections(config: ExperimentConfig) -> dict:
    """The settings of ``config`` a run's numbers depend on, as nested dicts."""
    sections = {key: to_dict(getattr(config, key)) for key in RUN_SECTIONS}
    sections["explore"] = config.explore.run_settings()
    return sections


def check_saved_config(folder: Path, config: ExperimentConfig) -> None:
    """Refuse to add runs to an experiment folder whose saved config computes runs differently.

    Raises
    ------
    ConfigError
        Naming the first key that differs, with both values; or the saved config itself
        does not validate (empty, not YAML, not a mapping, a bad key), naming it.
    """
    saved_path = ExperimentFolder(folder).config
    if not saved_path.is_file():
        return
    for keys, old, new in differences(run_sections(load_config(saved_path)), run_sections(config)):
        if keys not in SELECTION_KEYS:
            raise ConfigError(
                f"{display_path(saved_path)}: {'.'.join(keys)} was {old!r} for the runs already there, now {new!r}; "
                "use another experiment name or another results folder"
            )


def record_label_settings(folder: Path, config: ExperimentConfig) -> None:
    """Write ``config`` as the experiment's ``config.yaml`` when only its ``label`` section differs.

    Labels are made with the settings the folder records, so a label setting overridden
    for one command becomes the experiment's, with a note saying which; every other
    setting was fixed when the runs were explored.

    Raises
    ------
    ConfigError
        ``config`` differs from the saved config outside ``label``, naming the first key.
    """
    saved_path = ExperimentFolder(folder).config
    saved = to_dict(load_config(saved_path)) if saved_path.is_file() else {}
    changed = list(differences(saved, to_dict(config)))
    for keys, old, new in changed:
        if keys[0] != "label" and saved:
            raise ConfigError(
                f"{'.'.join(keys)}: the experiment in {display_path(folder)} was explored with {old!r}, not {new!r}; "
                "only label settings can change once its runs exist"
            )
    if not changed:
        return
    with atomic_path(saved_path) as tmp:
        tmp.write_text(saved_yaml(config))
    if saved:
        shown = ", ".join(f"{'.'.join(keys)}={new!r}" for keys, _, new in changed)
        note(f"recorded {shown} in {display_path(saved_path)}; labels made otherwise are made again")
