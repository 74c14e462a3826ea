"""Experiments the tests of several stages share: a small grid explored on own_map, and a
folder's label files read back byte for byte."""

from __future__ import annotations

import dataclasses
import json
import zipfile

import numpy as np
from small_maps import grid_config

from curiosity_cli.explore.grid import run_grid


def small_experiment(own_map, tmp_path, **explore):
    """A grid of 4 weight functions x 2 restarts x 12 steps on own_map, explored and labelled."""
    config = grid_config(own_map, **explore)
    config = dataclasses.replace(config, label=dataclasses.replace(config.label, sweeps=2, batch_sweeps=8))
    run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    return config, tmp_path / "grid"


def label_contents(folder) -> dict:
    """Each label and batch file's arrays, byte for byte (the zip's timestamps and a batch reference's timing aside)."""
    out = {}
    for path in sorted([*(folder / "labels").rglob("*.npz"), *(folder / "batch").glob("*.npz")]):
        with zipfile.ZipFile(path) as npz:
            members = {name: npz.read(name) for name in npz.namelist()}
        if path.parent.name == "batch":
            with np.load(path) as npz:
                meta = json.loads(str(npz["meta"]))
            assert meta.pop("seconds") >= 0
            members["meta.npy"] = meta
        out[path.relative_to(folder).as_posix()] = members
    return out
