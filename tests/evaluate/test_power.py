"""The headline's power against simulations whose truth is known."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from curiosity_cli.evaluate.power import (
    detectable_difference,
    pairs_needed,
    t_test_power,
)


@pytest.mark.slow
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
