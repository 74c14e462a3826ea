"""The two-start check of Z_p: its rule, its table and its section of the report."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.evaluate.report import _convergence_section
from curiosity_cli.evaluate.statistics import CONVERGENCE_TOLERANCE, label_convergence, within_noise


def test_within_noise_is_the_tolerance_or_twice_the_standard_error():
    assert within_noise(0.009, 0.0) and within_noise(-0.009, 0.0)
    assert not within_noise(0.011, 0.005)  # past the tolerance and past 2 SE
    assert within_noise(0.05, 0.026) and not within_noise(0.05, 0.024)
    assert CONVERGENCE_TOLERANCE == 0.01


def checked_mi(gaps: dict[tuple[str, int], list[float]]) -> pd.DataFrame:
    """mi.csv rows of runs labelled twice: the placed chain's MI is the uniform one's minus ``gaps``."""
    rows = []
    for (dataset, length), diffs in gaps.items():
        for restart, gap in enumerate(diffs):
            uniform = 0.5 + 0.1 * restart
            rows.append({
                "dataset": dataset, "weight_function": "random-walk", "restart": restart, "path_length": length,
                "mi_human": uniform, "mi_batch": uniform, "placed_mi_human": uniform - gap, "placed_mi_batch": uniform,
            })
    # a run that was not checked takes no part
    rows.append({**rows[0], "restart": 9, "placed_mi_human": np.nan, "placed_mi_batch": np.nan})
    return pd.DataFrame(rows)


def test_the_table_gives_each_map_and_length_its_mean_gap_standard_error_and_verdict():
    mi = checked_mi({("a", 10): [0.10, 0.12, 0.08, 0.10], ("a", 80): [0.02, -0.02, 0.03, -0.01], ("b", 10): [0.004]})
    table = label_convergence(mi).set_index(["dataset", "path_length", "against"])
    far = table.loc[("a", 10, "human")]
    assert far["n"] == 4 and far["difference"] == pytest.approx(0.10)
    assert far["sem"] == pytest.approx(np.std([0.10, 0.12, 0.08, 0.10], ddof=1) / 2) and not far["converged"]
    assert far["uniform"] == pytest.approx(0.65) and far["placed"] == pytest.approx(0.55)
    noisy = table.loc[("a", 80, "human")]  # a mean of 0.005 ± 0.012: within the tolerance
    assert noisy["converged"]
    single = table.loc[("b", 10, "human")]  # one run: no standard error, the tolerance alone
    assert np.isnan(single["sem"]) and single["converged"]
    assert table.loc[("a", 10, "batch"), "difference"] == 0 and table.loc[("a", 10, "batch"), "converged"]


def test_no_run_labelled_twice_gives_an_empty_table():
    mi = checked_mi({("a", 10): [0.1]}).assign(placed_mi_human=np.nan, placed_mi_batch=np.nan)
    assert label_convergence(mi).empty


def test_the_report_marks_the_cells_where_the_chains_have_not_met():
    config = load_config(CONFIG_DIR / "quick.yaml")
    table = label_convergence(checked_mi({("a", 10): [0.10, 0.12, 0.08, 0.10], ("a", 80): [0.02, -0.02, 0.03, -0.01]}))
    text = "\n".join(_convergence_section(table, config))
    assert "| a | Z_h | +0.100 ± 0.008 ✗ | +0.005 ± 0.012 |" in text
    assert "| a | Z_b | +0.000 ± 0.000 | +0.000 ± 0.000 |" in text
    assert "Restart 0 of every map and weight function was labelled both ways" in text
    assert "have not met in 1 of 4 cells (largest: a at 10 steps against Z_h, +0.100 bits)" in text
    agreeing = label_convergence(checked_mi({("a", 80): [0.02, -0.02, 0.03, -0.01]}))
    assert "The two chains agree on every map and length" in "\n".join(_convergence_section(agreeing, config))


def test_the_report_says_when_nothing_was_checked():
    config = load_config(CONFIG_DIR / "quick.yaml", ["label.check_restarts=0"])
    text = "\n".join(_convergence_section(None, config))
    assert "Not checked: no run was labelled twice (label.check_restarts is 0)" in text
