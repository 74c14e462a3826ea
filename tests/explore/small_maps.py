"""Small synthetic maps and the real configs, shrunk, for the exploration tests."""

from __future__ import annotations

import dataclasses

import numpy as np

from curiosity_cli.config import CONFIG_DIR, ExperimentConfig, load_config
from curiosity_cli.words.store import WordStore, WordType, build_store

CELL = 8  # pixels per cell side of the synthetic stores


def synthetic_store(region_of_cell: np.ndarray, words_per_cell: int = 64, seed: int = 0) -> WordStore:
    """A word store whose cell ``c`` draws its words uniformly from 100 ids of its region.

    Region ``r`` owns word ids ``100 r .. 100 r + 99``, so regions share no words.

    Parameters
    ----------
    region_of_cell : (rows, cols) int ndarray
    """
    rng = np.random.default_rng(seed)
    rows, cols = region_of_cell.shape
    n_regions = int(region_of_cell.max()) + 1
    cell = np.repeat(np.arange(rows * cols), words_per_cell)
    words = 100 * region_of_cell.ravel()[cell] + rng.integers(0, 100, cell.size)
    pixel_rows = (cell // cols) * CELL + rng.integers(0, CELL, cell.size)
    pixel_cols = (cell % cols) * CELL + rng.integers(0, CELL, cell.size)
    types = (WordType("texton", f"synthetic-{100 * n_regions}", 0, 100 * n_regions, "synthetic"),)
    return build_store(pixel_rows, pixel_cols, words, (rows * CELL, cols * CELL), CELL, types, {"dataset": "synthetic"})


def small_config(**explore) -> ExperimentConfig:
    """quick.yaml with 8 topics, a small budget and short paths (``explore`` keys override)."""
    config = load_config(CONFIG_DIR / "quick.yaml")
    settings = dict(path_length=30, checkpoints=(10, 30), samples_per_step=5000, restarts=2)
    settings.update(explore)
    return dataclasses.replace(
        config,
        model=dataclasses.replace(config.model, topics=8),
        explore=dataclasses.replace(config.explore, **settings),
    )


def two_region_store() -> WordStore:
    """A 6 x 8 grid: the left half one region, the right half another."""
    regions = np.zeros((6, 8), int)
    regions[:, 4:] = 1
    return synthetic_store(regions)
