"""Distinct cells, revisits and boxed-in steps of real runs, against their path.csv."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
from small_maps import grid_config

from curiosity_cli.label.stage import label_experiment
from curiosity_cli.evaluate.revisits import revisit_counts
from curiosity_cli.evaluate.stage import evaluate_experiment
from curiosity_cli.explore.grid import run_grid


def test_counts_by_hand_on_a_short_path():
    # 4 -> 1 -> 4 -> 5 -> 4: three distinct cells; step 2 was boxed in (say)
    path = np.array([4, 1, 4, 5, 4])
    boxed = np.array([False, False, True, False, True])
    assert revisit_counts(path, boxed, 5) == {"distinct_cells": 3, "revisit_steps": 2, "boxed_in_steps": 1}
    assert revisit_counts(path, boxed, 2) == {"distinct_cells": 2, "revisit_steps": 0, "boxed_in_steps": 0}
    # the last step's flag is the move after the path: not counted
    assert revisit_counts(path, boxed, 3)["boxed_in_steps"] == 0
    with pytest.raises(ValueError, match="length"):
        revisit_counts(path, boxed, 6)


@pytest.mark.slow
@pytest.mark.parametrize("coverage", ["literal", "clamp"])
def test_mi_csv_counts_agree_with_every_runs_path_csv(own_map, tmp_path, coverage):
    # 40 steps on 48 cells: walkers revisit, and the literal reading gets boxed in
    config = grid_config(own_map, path_length=40, checkpoints=(10, 40), coverage=coverage)
    config = dataclasses.replace(config, label=dataclasses.replace(config.label, sweeps=2, batch_sweeps=4))
    run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    folder = tmp_path / config.name
    label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1)
    evaluate_experiment(folder)
    mi = pd.read_csv(folder / "mi.csv")
    checked = 0
    for row in mi.itertuples():
        steps = pd.read_csv(folder / "runs" / row.dataset / row.weight_function / f"restart-{row.restart:03d}" / "path.csv")
        first = steps.iloc[: row.path_length]
        assert row.distinct_cells == first["cell"].nunique() == first["first_visit"].sum()
        assert row.revisit_steps == row.path_length - row.distinct_cells
        assert row.boxed_in_steps == steps["boxed_in"].iloc[: row.path_length - 1].sum()
        checked += 1
    assert checked == len(mi) > 0
    assert (mi["revisit_steps"] > 0).any() and (mi["replicate"] == config.seed).all()
    if coverage == "literal":
        assert (mi["boxed_in_steps"] > 0).any()
    revisits = pd.read_csv(folder / "revisits.csv")
    distinct = revisits[revisits["measure"] == "distinct_cells"].set_index(["dataset", "weight_function", "path_length"])
    means = mi.groupby(["dataset", "weight_function", "path_length"])["distinct_cells"].mean()
    np.testing.assert_allclose(distinct.loc[means.index, "mean"], means)
