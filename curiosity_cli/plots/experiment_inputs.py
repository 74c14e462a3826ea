"""Reading what the figures are drawn from, out of an experiment folder ``results/<experiment>/``.

- ``mi.csv`` and ``summary.csv`` (``curiosity evaluate``): the MI tables;
- ``config.yaml`` (``curiosity explore``): the resolved config, which names the maps;
- ``runs/<dataset>/<weight function>/restart-<NNN>/path.csv`` (``curiosity explore``);
- ``labels/<dataset>/examples/<weight function>-restart-<NNN>-<length>.npz`` (``curiosity
  label``): example path labelings Z_p, key ``labels``, (H, W) topic ids;
- ``batch/<dataset>.npz`` (``curiosity label``): the batch labelling Z_b (``labels``) and
  its log-likelihood trace (``log_likelihood``).

The two tables are required (a missing or malformed one raises :class:`PlotError`).
Everything else is optional: a reader returns None, or skips an entry, and says why in a
one-line note, so one missing or corrupt input costs one figure, never the others.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from curiosity_cli.errors import CuriosityError
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.files import CorruptFileError, display_path, open_npz

if TYPE_CHECKING:
    from curiosity_cli.config import ExperimentConfig

MI_COLUMNS = (
    "dataset", "weight_function", "restart", "path_length",
    "mi_human", "mi_batch", "nmi_human", "nmi_batch", "seed",
)
SUMMARY_COLUMNS = ("dataset", "weight_function", "path_length", "against", "n", "mean", "std", "ci_low", "ci_high")

_EXAMPLE_NAME = re.compile(r"^(?P<weight>.+)-restart-(?P<restart>\d+)-(?P<length>\d+)\.npz$")


class PlotError(CuriosityError):
    """An experiment folder the figures cannot be drawn from."""


def load_maps(config: ExperimentConfig, notes: list[str]) -> dict:
    """The experiment's maps by dataset name, in the config's order.

    Parameters
    ----------
    config : ExperimentConfig
        The experiment's saved config.
    notes : list of str
        Appended to: one line per map that cannot be loaded.

    Returns
    -------
    dict of str to MapData
    """
    from curiosity_cli.maps.map_data import load_map

    maps = {}
    for entry in config.datasets:
        try:
            m = load_map(entry)
        except CuriosityError as exc:
            notes.append(f"no figures of map {entry}: {exc}")
            continue
        maps[m.config.name] = m
    return maps


@dataclass(frozen=True)
class Example:
    """One example path labelling Z_p on disk."""

    weight_function: str
    restart: int
    length: int
    path: Path


def find_examples(experiment_dir: Path, dataset: str) -> list[Example]:
    """Every example labelling of a map, sorted by weight function, restart and length."""
    folder = ExperimentFolder(experiment_dir).examples(dataset)
    found = []
    for path in folder.glob("*.npz") if folder.is_dir() else ():
        match = _EXAMPLE_NAME.match(path.name)
        if match:
            found.append(Example(match["weight"], int(match["restart"]), int(match["length"]), path))
    return sorted(found, key=lambda e: (e.weight_function, e.restart, e.length))


def read_label_map(path: Path, shape: tuple[int, int], notes: list[str]) -> np.ndarray | None:
    """A topic label map from an ``.npz`` file's ``labels`` key, or None with a note.

    Parameters
    ----------
    path : Path
    shape : (int, int)
        The map's (rows, cols) in pixels; a label map of another shape is refused.
    notes : list of str
        Appended to when the file is missing, corrupt or of the wrong shape.

    Returns
    -------
    (H, W) int64 ndarray or None
        Topic ids >= 0.
    """
    arrays = _read_npz(path, ["labels"], notes)
    if arrays is None:
        return None
    labels = arrays["labels"]
    if labels.ndim != 2 or labels.dtype.kind not in "iu" or tuple(labels.shape) != tuple(shape):
        notes.append(
            f"{display_path(path)}: labels are {labels.dtype} of shape {labels.shape}, "
            f"expected integer topic ids of the map's shape {tuple(shape)}; not drawn"
        )
        return None
    if labels.size and labels.min() < 0:
        notes.append(f"{display_path(path)}: negative topic id {int(labels.min())}; not drawn")
        return None
    return labels.astype(np.int64)


def read_log_likelihood(path: Path, notes: list[str]) -> np.ndarray | None:
    """The batch model's per-sweep log-likelihood trace, (n_sweeps,) float64, or None with a note."""
    arrays = _read_npz(path, ["log_likelihood"], notes)
    if arrays is None:
        return None
    trace = np.asarray(arrays["log_likelihood"], dtype=np.float64)
    if trace.ndim != 1 or trace.size == 0:
        notes.append(f"{display_path(path)}: log_likelihood has shape {trace.shape}, expected (n_sweeps,); not drawn")
        return None
    return trace


def read_path(experiment_dir: Path, dataset: str, weight_function: str, restart: int, notes: list[str]):
    """A run's path in cells, or None with a note.

    Returns
    -------
    (L,) int64 ndarray, or None
        The row-major cell of each step, in step order.
    """
    import pandas as pd

    path = ExperimentFolder(experiment_dir).run(dataset, weight_function, restart) / ExperimentFolder.RUN_PATH
    if not path.is_file():
        notes.append(f"{display_path(path)}: not found; no path figure (explore the experiment first)")
        return None
    try:
        table = pd.read_csv(path, usecols=["step", "cell"])
    except (ValueError, pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        notes.append(f"{display_path(path)}: unreadable ({exc}); no path figure")
        return None
    table = table.sort_values("step")
    return table["cell"].to_numpy(np.int64)


def _read_npz(path: Path, keys: list[str], notes: list[str]) -> dict | None:
    path = Path(path)
    if not path.is_file():
        notes.append(f"{display_path(path)}: not found (label the experiment first)")
        return None
    try:
        with open_npz(path) as npz:
            return {key: npz[key] for key in keys}
    except CorruptFileError as exc:
        notes.append(f"{exc}; not drawn")
    return None
