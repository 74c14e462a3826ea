"""Where an experiment's files live: one object owns the layout of an experiment folder.

Every stage reads and writes the folder it is given through :class:`ExperimentFolder`,
so the layout is spelled out here once (``mne_bids.BIDSPath`` and hydra's paths config
are the models)::

    results/<experiment>/
        config.yaml  provenance.yaml  runs.csv  maps.csv          (explore)
        runs/<map>/<walker>/restart-NNN/                          (explore, one run)
            run.json  path.csv  candidates.csv  checkpoints.npz
        batch/<map>.npz  shared.json                              (label, Z_b; items taken from other experiments)
        labels/<map>/<walker>/restart-NNN.npz                     (label, Z_p tables)
        labels/<map>/examples/<walker>-restart-NNN-<length>.npz   (label, Z_p maps)
        <table>.csv  mi.parquet  skipped.json  tables.json        (evaluate)
        stage_seconds.json                                        (every stage: its time)
        label_profile.json                                        (label: where its time went)
        figures/  REPORT.md                                       (plot)

Where an experiment of a name lives by default is :mod:`curiosity_cli.paths`' business.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

#: A run folder's name: ``restart-NNN`` (a killed writer's ``.restart-NNN.tmp-*`` is not one).
_RUN_NAME = re.compile(r"restart-\d+")


def _restart(restart: int) -> str:
    """How a run's folder and files spell its restart: ``restart-NNN``."""
    return f"restart-{restart:03d}"


def _run_named(path: Path) -> tuple[str, str, int]:
    """``(dataset, weight function, restart)`` of ``<dataset>/<weight function>/restart-NNN[.npz]``."""
    path = Path(path)
    return path.parent.parent.name, path.parent.name, int(path.stem.removeprefix("restart-"))

@dataclass(frozen=True)
class ExperimentFolder:
    """An experiment folder, given its root: every path in it.

    Attributes
    ----------
    root : Path
        ``results/<experiment>``, or wherever a copied or renamed experiment lives.
    """

    root: Path

    # the files of a run folder (:meth:`run`), named here once for every stage that reads them
    #: A run's record: what it was, its recipe, and the size and digest of its other files.
    RUN_META = "run.json"
    #: A run's steps, one row per step.
    RUN_PATH = "path.csv"
    #: The neighbours a run's walker scored, one row per neighbour.
    RUN_CANDIDATES = "candidates.csv"
    #: A run's path and its word-topic counts at each checkpoint length.
    RUN_CHECKPOINTS = "checkpoints.npz"

    def __post_init__(self) -> None:
        object.__setattr__(self, "root", Path(self.root))

    @property
    def config(self) -> Path:
        return self.root / "config.yaml"

    @property
    def provenance(self) -> Path:
        return self.root / "provenance.yaml"

    @property
    def runs_csv(self) -> Path:
        return self.root / "runs.csv"

    @property
    def maps_csv(self) -> Path:
        return self.root / "maps.csv"

    @property
    def runs(self) -> Path:
        return self.root / "runs"

    @property
    def labels(self) -> Path:
        return self.root / "labels"

    @property
    def figures(self) -> Path:
        return self.root / "figures"

    @property
    def report(self) -> Path:
        return self.root / "REPORT.md"

    @property
    def skipped(self) -> Path:
        return self.root / "skipped.json"

    @property
    def shared(self) -> Path:
        """``shared.json``: how many label files and batch references the last ``label`` that made any took from
        other experiments (:mod:`~curiosity_cli.label.shared_items`)."""
        return self.root / "shared.json"

    @property
    def label_profile(self) -> Path:
        """``label_profile.json``: where the last ``label`` that labelled anything spent its seconds
        (:mod:`~curiosity_cli.label.profile`)."""
        return self.root / "label_profile.json"

    @property
    def stage_seconds(self) -> Path:
        """``stage_seconds.json``: the seconds each stage took (:mod:`~curiosity_cli.experiment.stage_seconds`)."""
        return self.root / "stage_seconds.json"

    @property
    def lock(self) -> Path:
        """``.lock``: which process works in the folder (:mod:`~curiosity_cli.experiment.lock`)."""
        return self.root / ".lock"

    @property
    def tables_record(self) -> Path:
        """``tables.json``: what ``evaluate``'s tables are and were made from (:class:`~curiosity_cli.experiment.experiment.Experiment`)."""
        return self.root / "tables.json"

    def table(self, name: str, suffix: str = ".csv") -> Path:
        """An evaluation table, e.g. ``table("mi")`` or ``table("mi", ".parquet")``."""
        return self.root / f"{name}{suffix}"

    def run(self, dataset: str, weight_function: str, restart: int) -> Path:
        """A run's folder."""
        return self.runs / dataset / weight_function / _restart(restart)

    @staticmethod
    def run_of(folder: Path) -> tuple[str, str, int]:
        """``(dataset, weight function, restart)`` of the run folder :meth:`run` names ``folder``."""
        return _run_named(folder)

    def run_folders(self) -> list[Path]:
        """Every run folder under its real name (finished or not), sorted."""
        return sorted(p for p in self.runs.glob("*/*/restart-*") if _RUN_NAME.fullmatch(p.name))

    @property
    def batches(self) -> Path:
        return self.root / "batch"

    def batch(self, dataset: str) -> Path:
        """A map's batch reference Z_b."""
        return self.batches / f"{dataset}.npz"

    def label_file(self, dataset: str, weight_function: str, restart: int) -> Path:
        """A run's label file (Z_p's contingency tables)."""
        return self.labels / dataset / weight_function / f"{_restart(restart)}.npz"

    @classmethod
    def holding_label_file(cls, path: Path) -> ExperimentFolder:
        """The experiment folder a run's label file (:meth:`label_file`) lies in."""
        return cls(Path(path).parents[3])

    @staticmethod
    def run_of_label_file(path: Path) -> tuple[str, str, int]:
        """``(dataset, weight function, restart)`` of the run whose label file :meth:`label_file` names ``path``."""
        return _run_named(path)

    def label_files(self) -> list[Path]:
        """Every run's label file there is, sorted."""
        return sorted(self.labels.glob("*/*/restart-*.npz"))

    def example(self, dataset: str, weight_function: str, restart: int, length: int) -> Path:
        """A run's Z_p pixel map at one path length, kept for the figures."""
        return self.labels / dataset / "examples" / f"{weight_function}-{_restart(restart)}-{length}.npz"

    def examples(self, dataset: str) -> Path:
        """The folder of a map's example Z_p maps."""
        return self.labels / dataset / "examples"
