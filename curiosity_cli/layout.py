"""Where an experiment's files live: one object owns the layout of an experiment folder.

Every stage reads and writes the folder it is given through :class:`ExperimentFolder`,
so the layout is spelled out here once (``mne_bids.BIDSPath`` and hydra's paths config
are the models)::

    results/<experiment>/
        config.yaml  provenance.yaml  runs.csv  maps.csv          (explore)
        runs/<map>/<walker>/restart-NNN/                          (explore, one run)
        batch/<map>.npz                                           (label, Z_b)
        labels/<map>/<walker>/restart-NNN.npz                     (label, Z_p tables)
        labels/<map>/examples/<walker>-restart-NNN-<length>.npz   (label, Z_p maps)
        <table>.csv  mi.parquet  skipped.json                     (evaluate)
        figures/  REPORT.md                                       (plot, reproduce)

:func:`experiment_root` says where an experiment of a name lives under a results folder,
and the default places of experiment folders and of the word-store cache are
:data:`DEFAULT_RESULTS` and :data:`DEFAULT_CACHE`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

#: Where experiment folders go unless ``--results-dir`` says otherwise.
DEFAULT_RESULTS = Path("results")
#: Where word stores are cached unless ``--cache-dir`` says otherwise.
DEFAULT_CACHE = DEFAULT_RESULTS / "cache"


def experiment_root(results_dir: Path, name: str) -> Path:
    """Where the experiment ``name`` lives: ``results_dir/<name>``."""
    return Path(results_dir) / name


@dataclass(frozen=True)
class ExperimentFolder:
    """An experiment folder, given its root: every path in it.

    Attributes
    ----------
    root : Path
        ``results/<experiment>``, or wherever a copied or renamed experiment lives.
    """

    root: Path

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

    def table(self, name: str, suffix: str = ".csv") -> Path:
        """An evaluation table, e.g. ``table("mi")`` or ``table("mi", ".parquet")``."""
        return self.root / f"{name}{suffix}"

    def run(self, dataset: str, weight_function: str, restart: int) -> Path:
        """A run's folder."""
        return self.runs / dataset / weight_function / f"restart-{restart:03d}"

    def run_folders(self) -> list[Path]:
        """Every run folder under its real name (finished or not), sorted."""
        return sorted(self.runs.glob("*/*/restart-*"))

    @property
    def batches(self) -> Path:
        return self.root / "batch"

    def batch(self, dataset: str) -> Path:
        """A map's batch reference Z_b."""
        return self.batches / f"{dataset}.npz"

    def label_file(self, dataset: str, weight_function: str, restart: int) -> Path:
        """A run's label file (Z_p's contingency tables)."""
        return self.labels / dataset / weight_function / f"restart-{restart:03d}.npz"

    def label_files(self) -> list[Path]:
        """Every run's label file there is, sorted."""
        return sorted(self.labels.glob("*/*/restart-*.npz"))

    def example(self, dataset: str, weight_function: str, restart: int, length: int) -> Path:
        """A run's Z_p pixel map at one path length, kept for the figures."""
        return self.labels / dataset / "examples" / f"{weight_function}-restart-{restart:03d}-{length}.npz"

    def examples(self, dataset: str) -> Path:
        """The folder of a map's example Z_p maps."""
        return self.labels / dataset / "examples"
