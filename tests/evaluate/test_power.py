"""The headline's interval and power against simulations whose truth is known."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from curiosity_cli.evaluate.power import (
    detectable_difference,
    pairs_needed,
    ratio_interval,
    t_test_power,
)


def paired_runs(rng, pairs: int, ratio: float, spread: float = 0.04):
    """MI of two walkers over ``pairs`` shared starts: b around 0.25 bits, a = ratio x b plus noise."""
    start = rng.normal(0.25, 0.05, pairs)  # what a start cell gives both walkers
    b = start + rng.normal(0, spread, pairs)
    a = ratio * start + rng.normal(0, spread, pairs)
    return a, b


def test_the_bootstrap_interval_covers_the_true_ratio_about_95_times_in_100():
    rng = np.random.default_rng(1)
    covered = 0
    for _ in range(300):
        a, b = paired_runs(rng, 30, 1.1)
        low, high = ratio_interval(a, b, resamples=2000)
        covered += low <= 1.1 <= high
    # a percentile bootstrap is a little narrow at 30 pairs; 300 trials put 95 % within about +-2.5 points
    assert 0.90 <= covered / 300 <= 0.985, covered


def test_the_interval_is_reproducible_and_refuses_unpaired_arrays():
    a, b = paired_runs(np.random.default_rng(2), 12, 1.0)
    assert ratio_interval(a, b) == ratio_interval(a, b)
    assert np.isnan(ratio_interval(a[:1], b[:1])).all()
    with pytest.raises(ValueError, match="a, b"):
        ratio_interval(a, b[:-1])


def test_power_matches_the_share_of_simulated_experiments_that_find_the_difference():
    rng = np.random.default_rng(3)
    sd, pairs = 0.05, 20
    difference = detectable_difference(sd, pairs)
    assert t_test_power(difference, sd, pairs) == pytest.approx(0.8, abs=1e-6)
    found = sum(
        stats.ttest_rel(d := rng.normal(difference, sd, pairs), np.zeros(pairs)).pvalue < 0.05 and d.mean() > 0
        for _ in range(4000)
    )
    # 4000 experiments: the share is within +-2 points of 0.8 (2.5 standard errors)
    assert found / 4000 == pytest.approx(0.8, abs=0.02)


def test_the_pairs_needed_are_the_fewest_with_80_percent_power():
    # a half-standard-deviation difference needs 34 pairs, as power tables for the paired t-test give
    assert pairs_needed(0.5, 1.0) == 34
    assert t_test_power(0.5, 1.0, 33) < 0.8 <= t_test_power(0.5, 1.0, 34)
    n = pairs_needed(0.02, 0.05)
    assert t_test_power(0.02, 0.05, n - 1) < 0.8 <= t_test_power(0.02, 0.05, n)
    # detectable and needed agree: with the needed pairs the difference is (just) detectable
    assert detectable_difference(0.05, n) <= 0.02 < detectable_difference(0.05, n - 1)


def test_no_spread_or_too_few_pairs_say_nothing():
    assert np.isnan(detectable_difference(0.0, 10)) and np.isnan(detectable_difference(0.1, 2))
    assert pairs_needed(0.1, 0.0) is None and pairs_needed(0.0, 0.1) is None
    assert pairs_needed(1e-6, 1.0) is None, "beyond a million pairs"
