"""Results of record: a study's small tables kept beside the code, pooled with the seeds a later run computes.

A study takes longer than one sitting on a 2-core machine, and ``results/`` is not kept.
``curiosity reproduce multiverse --record studies/multiverse`` takes each seed of each
specification recorded there instead of computing it, computes the others, records each
as it finishes, and pools them all in ``SWEEP.md``: a later run adds a seed. Only a
study keeps a record (a config that declares specifications and sweeps nothing but
``seed``), one folder per seed and specification::

    <record>/seed-<S>/<specification>/
        mi.csv  steering.csv  mechanism.csv     per run: what pooling reads
        headline.csv  revisits.csv              per map: SWEEP.md's headline of that experiment
        config.yaml  provenance.yaml  maps.csv  how they were made (the experiment's own files)
        runs.csv                                per run: its path and the SHA-256 of its Φ_p at each checkpoint
        record.yaml                             the tables' sizes and SHA-256, and the recipes below

A recorded folder is taken only while it is what computing it now would make:
``record.yaml`` holds, per map, the inputs of its runs' recipes (walker and restart
aside), of its batch reference's and of its label files' (which run and batch reference
aside) (:mod:`~curiosity_cli.experiment.recipes`), and the walkers and restarts of the
grid. The study's config and maps as they are now give them again; a folder whose recipes
differ (another label setting, an image changed, a new label format) is refused before
anything runs, naming the difference, and so is a table edited since it was recorded.
Runs and label files are not kept, so a recorded seed is never labelled or evaluated
again: computing it again elsewhere gives the same tables, byte for byte.

A new measure needs the runs again (their Φ_p to label, their paths). ``runs.csv`` pins
them: computing a recorded seed again explores the same runs (its recipes say so), and
:func:`same_runs` checks that they are, path by path and Φ_p by Φ_p, before the new
measure is read beside the record's. Φ_p itself is not kept: compressed, it is as large as
a label file's tables (about 300 KB for a map's 40 runs at one checkpoint: some 20 MB for
the positive control's three seeds and 80 MB for one seed of the multiverse), where
``runs.csv`` is about 20 KB a map. Folders recorded before ``runs.csv`` existed are still
taken; they have nothing to check a recomputation against.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from curiosity_cli.errors import CuriosityError
from curiosity_cli.experiment.experiment import Experiment
from curiosity_cli.experiment.recipes import ABSENT, change_in_words, differences, label_recipe
from curiosity_cli.experiment.wholeness import changed, records
from curiosity_cli.files import display_path

if TYPE_CHECKING:
    from curiosity_cli.study.types import Combination, Sweep

#: The files a recorded experiment keeps, its own under the same names.
TABLES = (
    "mi.csv", "steering.csv", "mechanism.csv", "headline.csv", "revisits.csv", "config.yaml", "provenance.yaml", "maps.csv",
)
#: Each recorded run's path and Φ_p digests (module docstring); folders recorded before it existed lack it.
RUNS = "runs.csv"
#: What a recorded folder was made from (module docstring).
RECORD_FILE = "record.yaml"
#: The keys a study's record is filed by: its specification, then its seed.
RECORD_KEYS = ["specification", "seed"]


class RecordError(CuriosityError):
    """A record that cannot be kept or taken: not a study, or a recorded folder made otherwise."""


def recipes(experiment: Experiment) -> dict:
    """What ``record.yaml`` records of an experiment's recipes: per map, its runs', batch reference's and
    label files' inputs but those that tell one run from another and what label files hold (``tables``); and
    the grid's walkers and restarts.

    Parameters
    ----------
    experiment : Experiment
        With the config it was (or would be) explored with; its maps are read as they are now.

    Returns
    -------
    dict
        JSON-ready.
    """
    config = experiment.config
    maps = {}
    for name, facts in experiment.maps.items():
        run = experiment.run_recipe(name, "", 0).inputs
        label = label_recipe("", "", config, facts.labels_digest, 0).inputs
        maps[name] = {
            "run": {key: value for key, value in run.items() if key not in ("weight_function", "restart")},
            "batch": experiment.batch_recipe(name).inputs,
            # what label files hold beside Z_p's draws ("tables") changes no recorded table
            "label": {key: value for key, value in label.items() if key not in ("run", "batch", "second_start", "tables")},
        }
    grid = {"weight_functions": list(config.explore.weight_functions), "restarts": config.explore.restarts}
    return {"maps": maps, "grid": grid}


class StudyRecord:
    """A study's record folder: which of its combinations it holds, taking them, keeping new ones.

    Parameters
    ----------
    root : str or Path
        The record, e.g. ``studies/multiverse``; made when the first combination is kept.
    sweep : Sweep
        The study (:func:`~curiosity_cli.study.sweep.plan_sweep`).

    Raises
    ------
    RecordError
        ``sweep`` is not a study that sweeps only ``seed``, or ``root`` is a file.
    """

    def __init__(self, root: str | Path, sweep: Sweep):
        self.root = Path(root)
        if sweep.keys != RECORD_KEYS:
            swept = ", ".join(key for key in sweep.keys if key not in RECORD_KEYS) or "no seeds"
            what = "no specifications" if not sweep.specifications else f"sweeps {swept}"
            raise RecordError(
                f"--record {display_path(self.root)}: keeps a study's seeds, one folder per seed and specification; "
                f"{display_path(sweep.config_path)} declares {what}"
            )
        if self.root.exists() and not self.root.is_dir():
            raise RecordError(f"--record {display_path(self.root)}: expected a folder, found a file")
        self.sweep = sweep

    def check_writable(self) -> None:
        """Refuse a record folder that cannot be written (read-only, a symlink loop, under a file) before anything
        is computed, not after the first combination.

        Raises
        ------
        RecordError
        """
        from curiosity_cli.files import unwritable

        if (why := unwritable(self.root)) is not None:
            raise RecordError(
                f"--record {display_path(self.root)}: cannot be written ({why}); give a folder this user can write"
            )

    def folder(self, combination: Combination) -> Path:
        """Where ``combination``'s tables are recorded: ``<record>/seed-<S>/<specification>``."""
        values = dict(text.split("=", 1) for text in combination.overrides)
        return self.root / f"seed-{values['seed']}" / values["specification"]

    def recorded(self) -> dict[int, Path]:
        """The study's combinations this record holds, by index, each checked.

        Raises
        ------
        RecordError
            A recorded folder that is incomplete, holds a table edited since it was
            recorded, or was made from other recipes than the study's config and maps
            give now: the first such folder, and what differs.
        """
        taken, loaded = {}, {}
        for combination in self.sweep.combinations:
            folder = self.folder(combination)
            if folder.is_dir():
                self._check(folder, combination, loaded)
                taken[combination.index] = folder
        return taken

    def _check(self, folder: Path, combination: Combination, loaded: dict) -> None:
        import yaml

        where = display_path(folder)
        remedy = "remove it to compute it again, or give another --record folder"
        missing = [name for name in (*TABLES, RECORD_FILE) if not (folder / name).is_file()]
        if missing:
            raise RecordError(f"{where}: an incomplete record (no {', '.join(missing)}); {remedy}")
        try:
            record = yaml.safe_load((folder / RECORD_FILE).read_text())
        except (OSError, ValueError, yaml.YAMLError) as exc:
            raise RecordError(f"{where}/{RECORD_FILE}: unreadable ({exc}); {remedy}") from None
        tables = record.get("tables") if isinstance(record, dict) else None
        recorded = record.get("recipes") if isinstance(record, dict) else None
        # every table, each with its size and digest: a record that leaves one out would let it pass unchecked
        whole = isinstance(tables, dict) and set(TABLES) <= set(tables) <= {*TABLES, RUNS} and all(
            isinstance(entry, dict) and {"size", "sha256"} <= set(entry) for entry in tables.values()
        )
        if not whole or not isinstance(recorded, dict) or not {"maps", "grid"} <= set(recorded):
            raise RecordError(
                f"{where}/{RECORD_FILE}: expected a mapping of tables (the size and sha256 of each of "
                f"{', '.join(TABLES)}, and of {RUNS} if kept) and recipes (maps, grid), as a record is written; {remedy}"
            )
        if (change := changed(folder, tables)) is not None:
            path, why = change
            raise RecordError(f"{display_path(path)}: not the table that was recorded ({why}); {remedy}")
        now = recipes(Experiment(folder, combination.config, _maps(combination, loaded)))
        if set(recorded["maps"]) != set(now["maps"]):  # another study's record: removing it would lose that study
            raise RecordError(
                f"{where}: a record of the maps {', '.join(sorted(recorded['maps']))}, not this study's "
                f"({', '.join(sorted(now['maps']))}): another study's record, perhaps; give this study's own --record folder"
            )
        found = [_in_words(keys, old, new) for keys, old, new in differences(recorded, now)]
        if found:
            more = f"; and {len(found) - 1} more" if len(found) > 1 else ""
            raise RecordError(
                f"{where}: recorded from another recipe than the study gives now ({found[0]}{more}); {remedy}"
            )

    def keep(self, combination: Combination, experiment: Path) -> Path:
        """Record an evaluated experiment's tables as ``combination``'s; returns the recorded folder.

        The folder appears whole or not at all (written beside it, then renamed). One that
        another process recorded meanwhile is kept as it is.

        Raises
        ------
        StaleTablesError
            The experiment's tables are not one current set (:meth:`~curiosity_cli.experiment.experiment.Experiment.check_tables`).
        """
        return keep_experiment(Path(experiment), self.folder(combination))


def keep_experiment(experiment: Path, target: Path) -> Path:
    """Copy an evaluated experiment's :data:`TABLES` to ``target`` with its :data:`RUNS` and ``record.yaml``;
    returns ``target``.

    As :meth:`StudyRecord.keep`, for any experiment folder (``scripts/record_study.py``).
    """
    import yaml

    opened = Experiment.open(experiment)
    opened.check_tables()
    target.parent.mkdir(parents=True, exist_ok=True)
    for leftover in target.parent.glob(f".{target.name}.tmp-*"):  # a killed keeper's
        shutil.rmtree(leftover, ignore_errors=True)
    staging = target.parent / f".{target.name}.tmp-{os.getpid()}"
    staging.mkdir()
    try:
        for name in TABLES:
            shutil.copyfile(experiment / name, staging / name)
        run_fingerprints(experiment).to_csv(staging / RUNS, index=False)
        record = {"tables": records(staging, [*TABLES, RUNS]), "recipes": recipes(opened)}
        # the staging folder is renamed whole below: its files need no rename of their own
        (staging / RECORD_FILE).write_text(
            "# What the tables here were made from: curiosity reproduce --record takes them only while the\n"
            "# study's config and maps give these recipes and the tables are these bytes (curiosity_cli/study/record.py)\n"
            + yaml.safe_dump(record, sort_keys=False)
        )
        try:
            os.replace(staging, target)
        except OSError:
            if not target.is_dir():  # else recorded by another process meanwhile: that one stands
                raise
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return target


def run_fingerprints(experiment: Path):
    """Every run of an experiment folder: its path and the digest of its Φ_p at each checkpoint.

    Parameters
    ----------
    experiment : Path
        An explored experiment folder.

    Returns
    -------
    pandas.DataFrame
        One row per run, sorted by ``dataset``, ``weight_function``, ``restart``: ``cells``
        (the path's cells, row-major, space-separated) and ``phi_<L>`` for each checkpoint
        length ``L``: the SHA-256 of Φ_p after ``L`` steps
        (:meth:`~curiosity_cli.explore.walker.SparseCounts.hash_into`).

    Raises
    ------
    RunError
        A run folder that is not whole (:func:`~curiosity_cli.explore.runs.read_run`).
    """
    import hashlib

    import pandas as pd

    from curiosity_cli.experiment.layout import ExperimentFolder
    from curiosity_cli.explore.runs import read_run
    from curiosity_cli.explore.walker import SparseCounts

    rows = []
    for folder in ExperimentFolder(experiment).run_folders():
        run = read_run(folder)
        row = {
            "dataset": run.meta["dataset"], "weight_function": run.meta["weight_function"],
            "restart": run.meta["restart"], "cells": " ".join(map(str, run.path)),
        }
        for length in run.meta["checkpoints"]:
            digest = hashlib.sha256()
            SparseCounts.of(run.phi(length)).hash_into(digest)
            row[f"phi_{length}"] = digest.hexdigest()
        rows.append(row)
    return pd.DataFrame(rows).sort_values(["dataset", "weight_function", "restart"], ignore_index=True)


def same_runs(recorded: Path, experiment: Path) -> str | None:
    """Whether an experiment explored the runs a recorded folder pins: ``None`` when every run's path and Φ_p
    are the recorded ones, else the first difference in words.

    Parameters
    ----------
    recorded : Path
        A recorded folder (``<record>/seed-<S>/<specification>``) with its :data:`RUNS`.
    experiment : Path
        The same combination computed again.

    Raises
    ------
    RecordError
        ``recorded`` has no :data:`RUNS` (recorded before it was kept), or it is not a table of runs.
    """
    import pandas as pd

    path = Path(recorded) / RUNS
    if not path.is_file():
        raise RecordError(f"{display_path(path)}: not there; the folder was recorded before runs were kept")
    try:
        kept = pd.read_csv(path, dtype=str, keep_default_na=False)
    except (ValueError, OSError) as exc:
        raise RecordError(f"{display_path(path)}: unreadable ({exc})") from None
    runs = ["dataset", "weight_function", "restart"]
    if list(kept.columns[:4]) != [*runs, "cells"] or not all(name.startswith("phi_") for name in kept.columns[4:]):
        raise RecordError(
            f"{display_path(path)}: expected columns {', '.join(runs)}, cells, phi_<length>..., as a record writes"
        )
    now = run_fingerprints(experiment).astype(str)
    if list(now.columns) != list(kept.columns):
        return f"the runs have columns {', '.join(now.columns)}, the record {', '.join(kept.columns)}"
    if len(now) != len(kept):
        return f"{len(now)} runs, the record {len(kept)}"
    if (other := np.flatnonzero((now[runs] != kept[runs]).any(axis=1))).size:
        return f"run {'/'.join(now.loc[other[0], runs])} where the record has {'/'.join(kept.loc[other[0], runs])}"
    for column in kept.columns[3:]:
        differ = np.flatnonzero(now[column].to_numpy() != kept[column].to_numpy())
        if differ.size:
            run = "/".join(now.loc[differ[0], runs])
            what = "path" if column == "cells" else f"Φ_p after {column.removeprefix('phi_')} steps"
            return f"{run}: its {what} is not the recorded one ({differ.size} runs differ so)"
    return None


def _maps(combination: Combination, loaded: dict) -> dict:
    """The facts of ``combination``'s maps, each map loaded once for the whole record."""
    from curiosity_cli.experiment.maps import MapFacts
    from curiosity_cli.maps.map_data import load_map

    facts = {}
    for entry in combination.config.datasets:
        if entry not in loaded:
            loaded[entry] = load_map(entry)
        one = MapFacts.of(entry, loaded[entry], combination.config.words)
        facts[one.name] = one
    return facts


def _in_words(keys: tuple, old, new) -> str:
    """One difference between recorded and current recipes: ``aerial-mosaic's run recipe: explore.candidates was 4, now 8``."""
    if keys[0] == "maps" and len(keys) == 2:
        return f"map {keys[1]} {'is not recorded' if old is ABSENT else 'is not in the study now'}"
    if keys[0] == "maps":
        return f"{keys[1]}'s {keys[2]} recipe: {change_in_words(keys[3:], old, new)}"
    return change_in_words(keys, old, new)
