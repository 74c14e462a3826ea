"""The tests of a declared lead: the sign flips against their exact enumeration, the stratified t against its
formula and scipy, a planted lead found and a sham one not."""

from __future__ import annotations

import numpy as np
import pytest
from naive import sign_flip_p_naive
from scipy import stats

from curiosity_cli.errors import ParameterError
from curiosity_cli.evaluate.confirmation import Stratified, plan_scales, planned_power, sign_flip_test, stratified_t


def test_the_stratified_mean_weighs_each_map_once_however_many_pairs_it_has():
    stratified = Stratified.of([1.0, 1.0, 1.0, 4.0], ["a", "a", "a", "b"])
    assert stratified.statistic == pytest.approx((1.0 + 4.0) / 2)
    assert stratified.weights.sum() == pytest.approx(1.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_drawn_sign_flips_give_the_exact_p_of_every_flip(seed):
    rng = np.random.default_rng(seed)
    differences = rng.normal(0.3, 1.0, 11)
    strata = ["a"] * 4 + ["b"] * 7
    exact = sign_flip_p_naive(differences, strata)
    drawn = sign_flip_test(Stratified.of(differences, strata), 200_000, np.random.default_rng(seed + 10))
    # the drawn p is (1 + hits) / (1 + B): within a few binomial errors of the exact share
    assert drawn == pytest.approx(exact, abs=4 * np.sqrt(exact * (1 - exact) / 200_000) + 1e-5)


def test_a_sign_flip_p_is_never_below_one_over_the_draws_and_is_1_for_all_leads_negative():
    stratified = Stratified.of([5.0] * 30, ["a"] * 30)
    assert sign_flip_test(stratified, 999, np.random.default_rng(0)) == pytest.approx(1 / 1000)
    assert sign_flip_test(Stratified.of([-5.0] * 30, ["a"] * 30), 999, np.random.default_rng(0)) == 1.0


def test_one_map_s_stratified_t_is_scipy_s_one_sample_t():
    rng = np.random.default_rng(3)
    differences = rng.normal(0.2, 1.0, 25)
    result = stratified_t(Stratified.of(differences, ["a"] * 25))
    reference = stats.ttest_1samp(differences, 0.0, alternative="greater")
    assert result.p_value == pytest.approx(reference.pvalue)
    assert result.dof == pytest.approx(24)
    half = stats.t.ppf(0.975, 24) * differences.std(ddof=1) / np.sqrt(25)
    assert (result.ci_low, result.ci_high) == pytest.approx((differences.mean() - half, differences.mean() + half))


def test_the_stratified_t_of_two_maps_is_the_mean_of_their_means_over_its_welch_error():
    a, b = np.array([0.5, 1.5, 1.0, 2.0]), np.array([-1.0, 0.0, 3.0, 1.0, 0.5, 2.5])
    result = stratified_t(Stratified.of(np.concatenate([a, b]), ["a"] * 4 + ["b"] * 6))
    parts = np.array([a.var(ddof=1) / 4, b.var(ddof=1) / 6]) / 4
    statistic, error = (a.mean() + b.mean()) / 2, np.sqrt(parts.sum())
    dof = parts.sum() ** 2 / (parts[0] ** 2 / 3 + parts[1] ** 2 / 5)
    assert result.statistic == pytest.approx(statistic) and result.standard_error == pytest.approx(error)
    assert result.dof == pytest.approx(dof)
    assert result.p_value == pytest.approx(stats.t.sf(statistic / error, dof))


def test_a_planted_lead_is_found_and_a_sham_one_is_rejected_at_its_level():
    """Five maps of ten pairs each, on different scales, each divided by its scale as a plan declares: a lead of
    0.8 of a standard deviation everywhere is found by both tests; with none, each rejects at 5 % about 5 % of the
    time."""
    rng = np.random.default_rng(7)
    strata = np.repeat(np.arange(5), 10)
    spread = np.repeat([0.5, 1.0, 2.0, 1.0, 3.0], 10)
    planted = Stratified.of(rng.normal(0.8 * spread, spread) / spread, strata)
    assert sign_flip_test(planted, 9_999, rng) < 0.01 and stratified_t(planted).p_value < 0.01
    flips, ts = [], []
    for _ in range(400):
        sham = Stratified.of(rng.normal(0.0, spread) / spread, strata)
        flips.append(sign_flip_test(sham, 499, rng) <= 0.05)
        ts.append(stratified_t(sham).p_value <= 0.05)
    # 400 tests at 5 %: 20 expected, 3 binomial errors either side is 7 to 33
    assert 7 <= sum(flips) <= 33 and 7 <= sum(ts) <= 33


@pytest.mark.parametrize(
    "differences, strata, message",
    [
        ([1.0, 2.0], ["a"], "differences, strata: got shapes (2,) and (1,), expected two (n,) arrays"),
        ([], [], "differences: got none, expected at least one paired difference"),
        ([1.0, np.nan], ["a", "a"], "differences: expected finite values"),
    ],
)
def test_bad_differences_are_refused_naming_the_parameter(differences, strata, message):
    with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(")", r"\)")):
        Stratified.of(differences, strata)


def test_no_sign_flips_is_refused():
    with pytest.raises(ParameterError, match="draws: got 0, expected at least 1"):
        sign_flip_test(Stratified.of([1.0], ["a"]), 0, np.random.default_rng(0))


def test_a_plan_s_scale_is_the_spread_of_a_map_s_leads_pooled_over_its_comparators():
    leads = {"a": np.array([[1.0, 2.0], [3.0, 2.0], [5.0, 8.0]]), "b": np.array([[0.0, 0.0], [0.0, 1.0]])}
    scales = plan_scales(leads)
    assert scales["a"] == pytest.approx(np.sqrt((4.0 + 12.0) / 2))
    assert scales["b"] == pytest.approx(np.sqrt((0.0 + 0.5) / 2))
    with pytest.raises(ParameterError, match="leads: c: the leads never vary"):
        plan_scales({"c": np.ones((3, 2))})
    with pytest.raises(ParameterError, match=r"leads: d: got shape \(1, 2\), expected \(n, C\) with at least two pairs"):
        plan_scales({"d": np.ones((1, 2))})


def test_a_plan_s_power_is_high_for_a_clear_lead_and_at_most_its_level_for_none():
    rng = np.random.default_rng(11)
    leads = {name: rng.normal(0.5 * spread, spread, (30, 3)) for name, spread in (("a", 1.0), ("b", 3.0), ("c", 0.2))}
    scales = plan_scales(leads)
    assert planned_power(leads, scales, 50, 0.0125, 200, rng, effect=1.0) > 0.9
    # with no lead the intersection-union test rejects less often than its level (each comparator must reject)
    assert planned_power(leads, scales, 50, 0.0125, 400, rng, effect=0.0) <= 0.0125 + 3 * np.sqrt(0.0125 / 400)
