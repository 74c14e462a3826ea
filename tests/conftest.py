"""Shared fixtures: a small bring-your-own dataset written as real files."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

LEGEND = {
    "classes": [
        {"id": 0, "name": "sand", "colour": "#e0c080", "description": "left half"},
        {"id": 1, "name": "rock", "colour": "#606060", "description": "right half"},
    ]
}


@pytest.fixture
def own_map(tmp_path: Path) -> Path:
    """A 96 x 128 px map with two classes, as a user would lay it out; returns its YAML."""
    rng = np.random.default_rng(0)
    image = rng.integers(0, 256, size=(96, 128, 3), dtype=np.uint8)
    labels = np.zeros((96, 128), dtype=np.uint8)
    labels[:, 64:] = 1
    cv2.imwrite(str(tmp_path / "map.png"), image)
    cv2.imwrite(str(tmp_path / "labels.png"), labels)
    (tmp_path / "legend.yaml").write_text(yaml.safe_dump(LEGEND))
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
    path = tmp_path / "own.yaml"
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    return path
