"""Small synthetic maps, a small map as a user would lay it out, and the real configs, shrunk, for the tests."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import cv2
import numpy as np
import yaml

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


#: The paper's four weight functions, which most tests run (the baseline and ceilings are tested apart).
PAPER_WALKERS = ("random-walk", "stochastic-coverage", "word-perplexity", "topic-perplexity")


def small_config(**explore) -> ExperimentConfig:
    """quick.yaml with 8 topics, a small budget, short paths and the paper's 4 weight functions
    (``explore`` keys override)."""
    config = load_config(CONFIG_DIR / "quick.yaml")
    settings = dict(path_length=30, checkpoints=(10, 30), samples_per_step=5000, restarts=2, weight_functions=PAPER_WALKERS)
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


def grid_config(own_map: Path, **explore):
    """The own_map fixture (6 x 8 cells of 16 px), 4 weight functions, 2 restarts, 12 steps."""
    settings = dict(path_length=12, checkpoints=(5, 12), restarts=2)
    settings.update(explore)
    return dataclasses.replace(small_config(**settings), name="grid", datasets=(str(own_map),))


def grid_yaml(own_map: Path, folder: Path) -> Path:
    """The same grid as a YAML file a user would write."""
    text = {
        "base": str(CONFIG_DIR / "paper.yaml"),
        "name": "grid",
        "seed": 0,
        "datasets": [str(own_map)],
        "model": {"topics": 8},
        "explore": {
            "weight_functions": list(PAPER_WALKERS), "restarts": 2, "path_length": 12, "checkpoints": [5, 12],
            "samples_per_step": 5000,
        },
    }
    path = folder / "grid.yaml"
    path.write_text(yaml.safe_dump(text, sort_keys=False))
    return path


def tiny_yaml(own_map: Path, folder: Path) -> Path:
    """A tiny experiment a user would write: the own_map fixture in 8 px cells (12 x 16),
    2 weight functions x 2 restarts x 80 steps (the headline's length), few samples and sweeps."""
    edit_yaml(own_map, cell_width=8)
    text = {
        "base": str(CONFIG_DIR / "paper.yaml"),
        "name": "tiny",
        "seed": 0,
        "datasets": [str(own_map)],
        "model": {"topics": 4},
        "explore": {
            "weight_functions": ["random-walk", "topic-perplexity"], "restarts": 2, "path_length": 80,
            "checkpoints": [80], "samples_per_step": 1000,
        },
        "label": {"sweeps": 2, "warm_sweeps": 1, "batch_sweeps": 4},
    }
    path = folder / "tiny.yaml"
    path.write_text(yaml.safe_dump(text, sort_keys=False))
    return path


def edit_yaml(path: Path, **changes) -> Path:
    """Rewrite keys of a YAML file in place (a value of ... deletes the key)."""
    data = yaml.safe_load(path.read_text())
    for key, value in changes.items():
        if value is ...:
            data.pop(key)
        else:
            data[key] = value
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


LEGEND = {
    "classes": [
        {"id": 0, "name": "sand", "colour": "#e0c080", "description": "left half"},
        {"id": 1, "name": "rock", "colour": "#606060", "description": "right half"},
    ]
}


def write_own_map(folder: Path) -> Path:
    """A 96 x 128 px map with two classes in ``folder``, as a user would lay it out; returns its YAML."""
    rng = np.random.default_rng(0)
    image = rng.integers(0, 256, size=(96, 128, 3), dtype=np.uint8)
    labels = np.zeros((96, 128), dtype=np.uint8)
    labels[:, 64:] = 1
    cv2.imwrite(str(folder / "map.png"), image)
    cv2.imwrite(str(folder / "labels.png"), labels)
    (folder / "legend.yaml").write_text(yaml.safe_dump(LEGEND))
    config = {
        "name": "own",
        "description": "a test map",
        "image": "map.png",
        "labels": "labels.png",
        "legend": "legend.yaml",
        "cell_width": 16,
        "word_stride": 1,
        "size": [96, 128],
        "source": "random pixels",
        "licence": "CC0",
    }
    path = folder / "own.yaml"
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    return path


#: A tiny generated map's model: 8 x 10 cells, 2 background topics, 2 rare ones in 1-cell patches, disjoint words.
TINY_GENERATE = {
    "seed": 1, "rows": 8, "cols": 10, "vocabulary": 60, "support": 10, "beta": 1.0, "background_topics": 2,
    "rare_topics": 2, "patches_per_topic": 2, "patch_cells": 1, "patch_gap": 1, "overlap": 0.0,
}


def write_generated_map(folder: Path, **generate) -> Path:
    """A tiny generated map's YAML in ``folder`` (:data:`TINY_GENERATE`, ``generate`` keys changed), cells of 8 px
    with a word every 2 px (16 per cell); returns its path."""
    config = {
        "name": "tiny-generated", "cell_width": 8, "word_stride": 2, "licence": "CC0",
        "generate": {**TINY_GENERATE, **generate},
    }
    path = folder / "tiny-generated.yaml"
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    return path
