"""An experiment as one unit: its folder, the config it was explored with, its maps as they
are now, every recipe, and whether its tables are the current ones.

The stages after ``explore`` open an experiment (:meth:`Experiment.open`) rather than a
folder, and ask it before reading anything:

- the recipes a run, a map's batch reference and a run's label file must record now
  (:meth:`Experiment.run_recipe`, :meth:`~Experiment.batch_recipe`,
  :meth:`~Experiment.label_recipe`), built from the saved config and the maps' facts as
  they are now (:mod:`~curiosity_cli.experiment.maps`), never as a file recorded
  them;
- the grid's runs, from the config (:meth:`~Experiment.planned`);
- whether the tables of ``evaluate`` are one complete set made from the files there are
  now (:meth:`~Experiment.check_tables`): ``evaluate`` records, beside the tables, the
  size and digest of each table and of every file and map fact they were made from
  (``tables.json``, :meth:`~Experiment.record_tables`); ``plot`` and the report refuse
  tables whose record no longer holds, naming the first file that differs.
"""

from __future__ import annotations

import json
import typing
from dataclasses import dataclass
from pathlib import Path

from curiosity_cli.config import ExperimentConfig
from curiosity_cli.errors import RERUN, CuriosityError
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.experiment.maps import MapFacts, map_facts
from curiosity_cli.experiment.recipes import Recipe, batch_recipe, label_recipe, recorded_digest, run_recipe
from curiosity_cli.experiment.saved_config import load_saved_config
from curiosity_cli.experiment.wholeness import changed, record, records
from curiosity_cli.files import display_path

#: What ``tables.json`` records the tables' sizes and digests under, and their inputs'.
_TABLES, _INPUTS = "tables", "inputs"


class StaleTablesError(CuriosityError):
    """Tables that are not one complete set made from the experiment's files as they are now."""


@dataclass(frozen=True)
class PlannedRun:
    """One run of an experiment's grid."""

    dataset: str
    weight_function: str
    restart: int


class Experiment:
    """An experiment folder with its config and its maps' facts.

    Parameters
    ----------
    root : str or Path
        The experiment folder.
    config : ExperimentConfig
        Its ``config.yaml`` (:meth:`open`), or the config ``explore`` and ``label`` are
        about to record there.
    maps : dict of str to MapFacts, optional
        The maps' facts by name, when the caller has just read the maps
        (:func:`~curiosity_cli.experiment.maps.prepare_stores`); else read when first asked.
    """

    def __init__(self, root: str | Path, config: ExperimentConfig, maps: dict[str, MapFacts] | None = None):
        self.folder = ExperimentFolder(root)
        self.config = config
        self._maps = maps

    @classmethod
    def open(cls, root: str | Path, overrides: typing.Iterable[str] = ()) -> Experiment:
        """The experiment in folder ``root``, with its saved config (plus ``overrides``).

        Raises
        ------
        ConfigError
            No ``config.yaml`` there, or one that does not validate, naming it.
        """
        return cls(root, load_saved_config(root, overrides))

    @property
    def maps(self) -> dict[str, MapFacts]:
        """Each of the config's maps, by name, as it is now (:func:`~curiosity_cli.experiment.maps.map_facts`).

        Raises
        ------
        CuriosityError
            A map that cannot be loaded, naming it.
        """
        if self._maps is None:
            facts = (map_facts(entry, self.config.words) for entry in self.config.datasets)
            self._maps = {f.name: f for f in facts}
        return self._maps

    def paper_maps(self) -> dict[str, str]:
        """The paper's map each of the experiment's maps stands in for, by map name (maps that stand in for none left out)."""
        return {name: facts.stands_in_for for name, facts in self.maps.items() if facts.stands_in_for}

    def run_recipe(self, dataset: str, weight_function: str, restart: int) -> Recipe:
        """What a run of the grid must have been made from, given the config and the map now."""
        facts = self.maps[dataset]
        return run_recipe(
            self.config, dataset, facts.store, facts.vocabulary_hashes, weight_function, restart, facts.labels_digest
        )

    def batch_recipe(self, dataset: str) -> Recipe:
        """What a map's batch reference must have been made from now."""
        facts = self.maps[dataset]
        return batch_recipe(self.config, facts.store, facts.vocabulary_hashes)

    def label_recipe(self, run_meta: dict) -> Recipe:
        """What the label file of the run whose ``run.json`` is ``run_meta`` must have been made from now."""
        dataset = run_meta["dataset"]
        return label_recipe(
            recorded_digest(run_meta), self.batch_recipe(dataset).digest, self.config,
            self.maps[dataset].labels_digest, run_meta["restart"],
        )

    def planned(self) -> list[PlannedRun]:
        """Every run of the grid the config holds: each map's restarts, each with every weight function."""
        explore = self.config.explore
        return [
            PlannedRun(name, weight_function, restart)
            for name in self.maps for restart in range(explore.restarts) for weight_function in explore.weight_functions
        ]

    # ------------------------------------------------------------------ the tables as one set

    def inputs(self) -> dict:
        """What the tables are made from, as it is now: the saved config, the maps table, every
        run's ``run.json``, ``path.csv`` and ``candidates.csv`` (steering), label file, example
        map and batch reference (size and digest), and each map's facts."""
        layout = self.folder
        root = layout.root
        files = [layout.config, layout.maps_csv]
        run_files = (layout.RUN_META, layout.RUN_PATH, layout.RUN_CANDIDATES)
        files += [run / name for run in layout.run_folders() for name in run_files]
        files += layout.label_files() + sorted(layout.labels.glob("*/examples/*.npz")) + sorted(layout.batches.glob("*.npz"))
        names = [str(path.relative_to(root)) for path in files if path.is_file()]
        return {
            "files": records(root, names),
            "maps": {name: facts.record() for name, facts in self.maps.items()},
        }

    def record_tables(self, tables: dict[str, Path], inputs: dict) -> str:
        """The text of ``tables.json``: each table's size and digest (``tables``: its name in
        the folder to the file holding it now, e.g. a temporary file about to replace it)
        and the ``inputs`` (:meth:`inputs`) they were made from."""
        recorded = {name: record(path) for name, path in tables.items()}
        return json.dumps({_TABLES: recorded, _INPUTS: inputs}, indent=1, sort_keys=True) + "\n"

    def check_tables(self) -> list[str]:
        """Refuse tables that are not one complete set made from the files there are now; the files of the set.

        Returns
        -------
        list of str
            The set's files, relative to the folder (``mi.csv``, ..., ``skipped.json``).

        Raises
        ------
        StaleTablesError
            No ``tables.json``, a table that is not as ``evaluate`` wrote it (a set
            mixed by a failed write, an edit), or a file or map fact the tables were made
            from that changed since, naming the first.
        """
        path = self.folder.tables_record
        remedy = f"{RERUN} makes them again"
        try:
            recorded = json.loads(path.read_text())
            tables, inputs = recorded[_TABLES], recorded[_INPUTS]
        except FileNotFoundError:
            raise StaleTablesError(
                f"{display_path(path)}: not found, so the tables are not known to be one set; {remedy}",
                rerun="evaluate", force=False,
            ) from None
        except (ValueError, KeyError, TypeError) as exc:
            raise StaleTablesError(f"{display_path(path)}: corrupt ({exc}); {remedy}", rerun="evaluate", force=False) from None
        if (change := changed(self.folder.root, tables)) is not None:
            table, why = change
            raise StaleTablesError(
                f"{display_path(table)}: not the table evaluate wrote with the others ({why}); {remedy}",
                rerun="evaluate", force=False,
            )
        if (difference := _first_difference(inputs, self.inputs(), self.folder.root)) is not None:
            raise StaleTablesError(
                f"{display_path(self.folder.table('mi'))}: made from other files than the experiment holds now "
                f"({difference}); {remedy}", rerun="evaluate", force=False,
            )
        return sorted(tables)


def _first_difference(recorded: dict, now: dict, root: Path) -> str | None:
    """The first file or map fact that differs between two :meth:`Experiment.inputs`, in words."""
    old_files, new_files = recorded.get("files", {}), now["files"]
    for name in sorted(set(old_files) | set(new_files)):
        if name not in new_files:
            return f"{display_path(root / name)} is gone"
        if name not in old_files:
            return f"{display_path(root / name)} is new"
        if old_files[name] != new_files[name]:
            return f"{display_path(root / name)} changed"
    old_maps = recorded.get("maps", {})
    for name in sorted(set(old_maps) | set(now["maps"])):
        old, new = old_maps.get(name), now["maps"].get(name)
        if old is None or new is None:
            return f"map {name} is {'new' if old is None else 'no longer in the config'}"
        if old["store"] != new["store"]:
            return f"map {name}'s image or word settings changed"
        if old["human"] != new["human"]:
            return f"map {name}'s human labels changed"
    return None

