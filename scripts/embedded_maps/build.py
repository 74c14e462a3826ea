"""Building one embedded map by name, and the data format it must meet before it is written."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from curiosity_cli.errors import DatasetError

from .aerial_mosaic import build_aerial_mosaic
from .rare_patches import build_rare_patches
from .reef_mosaic import build_reef_mosaic
from .seeding import MAP_NAMES
from .sentinel_coast import build_sentinel_coast

#: Each map's builder: source cache folder -> (image, labels, legend).
BUILDERS = {
    "aerial-mosaic": build_aerial_mosaic,
    "sentinel-coast": build_sentinel_coast,
    "reef-mosaic": build_reef_mosaic,
    "rare-patches": build_rare_patches,
}


def build_map(name: str, cache: Path) -> tuple[np.ndarray, np.ndarray, list[dict]]:
    """Build one map in memory.

    Parameters
    ----------
    name : str
        One of `MAP_NAMES`.
    cache : Path
        Source cache folder (see `curiosity_cli.maps.sources.sources_dir`).

    Returns
    -------
    image : (rows, cols, 3) uint8 RGB
    labels : (rows, cols) uint8 class ids
    legend : list of dict with keys id, name, colour, description
    """
    if name not in BUILDERS:
        raise ValueError(f"unknown map {name!r}; expected one of {', '.join(MAP_NAMES)}")
    return BUILDERS[name](cache)


def validate_map(name: str, image: np.ndarray, labels: np.ndarray, legend: list[dict]) -> None:
    """Refuse a map whose arrays or legend break the data format promised in data/README.md.

    Raises
    ------
    DatasetError
    """
    ids = [c["id"] for c in legend]
    if ids != list(range(len(ids))):
        raise DatasetError(f"{name}: legend ids {ids} are not 0..{len(ids) - 1}")
    if image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3:
        raise DatasetError(f"{name}: image is {image.dtype} {image.shape}, expected uint8 (rows, cols, 3)")
    if labels.dtype != np.uint8 or labels.shape != image.shape[:2]:
        raise DatasetError(f"{name}: labels are {labels.dtype} {labels.shape}, expected uint8 {image.shape[:2]}")
    present = set(np.unique(labels).tolist())
    if present != set(ids):
        raise DatasetError(f"{name}: label ids {sorted(present)} do not match the legend's {ids}")
