"""The fair comparison: per-walker intervals and the next-best ratio's null reference,
against simulations whose truth is known and small cases counted by hand."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from curiosity_cli.evaluate.comparisons import (
    next_best_interval,
    next_best_null,
    next_best_ratio,
    ratio_interval,
)


def equal_walkers(rng, pairs: int = 10, walkers: int = 4):
    """MI of equal walkers over shared starts: around 0.3 bits, a per-run coefficient of variation of
    0.10-0.25 and a correlation of 0-0.5 between the walkers of a restart (what a start cell gives all)."""
    cv, rho = rng.uniform(0.10, 0.25), rng.uniform(0.0, 0.5)
    shared = rng.standard_normal((pairs, 1))
    own = rng.standard_normal((pairs, walkers))
    return 0.3 * (1 + cv * (np.sqrt(rho) * shared + np.sqrt(1 - rho) * own))


@pytest.mark.slow
def test_with_four_equal_walkers_the_null_reference_rejects_about_5_in_100_and_intervals_cover_the_truth():
    rng = np.random.default_rng(2026)
    draws, rejected, covered, intervals, ratios = 2000, 0, 0, 0, []
    for i in range(draws):
        mi = equal_walkers(rng)
        ours, others = mi[:, 0], mi[:, 1:]
        ratios.append(next_best_ratio(ours, others))
        rejected += next_best_null(ours, others, permutations=1000, seed=i).p_value < 0.05
        for j in range(others.shape[1]):
            low, high = ratio_interval(ours, others[:, j], resamples=1000, seed=i)
            covered += low <= 1.0 <= high
            intervals += 1
    # the bias the null reference corrects: the next best is the highest of three equal walkers
    assert 0.94 <= np.median(ratios) <= 0.98
    assert np.mean(np.array(ratios) < 1) > 0.65
    assert 0.03 <= rejected / draws <= 0.07, rejected
    assert 0.93 <= covered / intervals <= 0.97, covered / intervals


def test_a_real_lead_is_found_by_both():
    rng = np.random.default_rng(5)
    found, excluded = 0, 0
    for i in range(200):
        mi = equal_walkers(rng)
        mi[:, 0] *= 1.3
        found += next_best_null(mi[:, 0], mi[:, 1:], permutations=1000, seed=i).p_value < 0.05
        excluded += ratio_interval(mi[:, 0], mi[:, 1], resamples=1000, seed=i)[0] > 1
    assert found / 200 > 0.8 and excluded / 200 > 0.8


def test_the_null_reference_of_two_walkers_and_two_restarts_matches_the_four_labellings_counted_by_hand():
    # ours (2, 2) against (1, 1): swapping a restart's pair gives ratios 2, 1, 1 and 0.5, each a quarter
    null = next_best_null([2.0, 2.0], [[1.0], [1.0]], permutations=20_000)
    assert null.median == pytest.approx(1.0)
    assert (null.low, null.high) == pytest.approx((0.5, 2.0))
    assert null.p_value == pytest.approx(0.25, abs=0.01)


def test_the_null_permutes_every_walker_and_chooses_the_next_best_anew():
    # three walkers, two restarts: the exact null over all 6 x 6 labellings, by brute force
    values = np.array([[3.0, 1.0, 2.0], [1.0, 4.0, 2.0]])
    exact = []
    for first, second in itertools.product(itertools.permutations(values[0]), itertools.permutations(values[1])):
        block = np.array([first, second])
        exact.append(block[:, 0].mean() / block[:, 1:].mean(axis=0).max())
    observed = next_best_ratio(values[:, 0], values[:, 1:])
    null = next_best_null(values[:, 0], values[:, 1:], permutations=40_000)
    assert null.median == pytest.approx(np.median(exact))
    assert null.p_value == pytest.approx(np.mean(np.array(exact) >= observed - 1e-12), abs=0.01)


def test_the_next_best_interval_chooses_the_next_best_in_every_resample():
    rng = np.random.default_rng(3)
    ours, others = rng.uniform(0.2, 0.4, 8), rng.uniform(0.2, 0.4, (8, 3))
    picks = np.random.default_rng(0).integers(0, 8, (500, 8))
    twin = [ours[p].mean() / others[p].mean(axis=0).max() for p in picks]
    assert next_best_interval(ours, others, resamples=500) == pytest.approx(tuple(np.quantile(twin, [0.025, 0.975])))


def test_results_are_reproducible_and_bad_shapes_are_refused():
    mi = equal_walkers(np.random.default_rng(4))
    assert next_best_null(mi[:, 0], mi[:, 1:]) == next_best_null(mi[:, 0], mi[:, 1:])
    assert ratio_interval(mi[:, 0], mi[:, 1]) == ratio_interval(mi[:, 0], mi[:, 1])
    assert np.isnan(ratio_interval(mi[:2, 0], mi[:2, 1])).all()  # two pairs: nothing to studentize by
    assert np.isnan(next_best_interval(mi[:1, 0], mi[:1, 1:])).all()
    assert np.isnan(next_best_null(mi[:1, 0], mi[:1, 1:]).p_value)
    with pytest.raises(ValueError, match="a, b"):
        ratio_interval(mi[:, 0], mi[:-1, 1])
    with pytest.raises(ValueError, match="ours, others"):
        next_best_null(mi[:, 0], mi[:, 1])
