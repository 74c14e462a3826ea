"""The curve's joint null (evaluate/joint_null.py): scipy's Wilcoxon p, shared runs kept shared, a planted lead
recovered after correction and a sham one not."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from curiosity_cli.evaluate.comparisons import next_best_ratio
from curiosity_cli.evaluate.joint_null import STATISTICS, CurvePoint, joint_null, signed_rank_p
from curiosity_cli.evaluate.multiplicity import intersection_union_p

#: Walkers of the simulated curve: topic perplexity, then random walk, stochastic coverage, word perplexity.
WITHOUT_RANDOM_WALK = (False, True, True)


def test_signed_rank_p_is_scipys_exact_p_and_its_fallback_for_ties_and_zeros():
    rng = np.random.default_rng(3)
    for n in (3, 10, 30):
        d = rng.normal(0.2, 1.0, (50, n))
        d[0] = 0.0
        d[1, :3] = [0.5, -0.5, 0.0]  # a tie and a zero: scipy leaves the exact distribution
        expected = [stats.wilcoxon(row).pvalue if row.any() else 1.0 for row in d]
        assert signed_rank_p(d) == pytest.approx(expected, rel=1e-12)


def _curve(rng, specifications=6, maps=3, restarts=20, lead=None, shared=True):
    """Points of a curve whose walkers do not differ but for ``lead`` (specification -> topic perplexity's factor).

    A restart's MI depends on its start (a common level), each walker adds noise; the random walk is 40 % lower.
    With ``shared``, every specification's comparators are the same runs (only topic perplexity changes).
    """
    lead = lead or {}
    level = rng.uniform(0.5, 1.5, (maps, restarts))
    comparators = level[..., None] * rng.normal(1.0, 0.1, (maps, restarts, 3)) * [0.6, 1.0, 1.0]
    points = []
    for s in range(specifications):
        if not shared:
            comparators = level[..., None] * rng.normal(1.0, 0.1, (maps, restarts, 3)) * [0.6, 1.0, 1.0]
        ours = level * rng.normal(1.0, 0.1, (maps, restarts)) * lead.get(s, 1.0)
        for m in range(maps):
            values = np.column_stack([ours[m], comparators[m]])
            points.append(CurvePoint(f"spec-{s}", f"map-{m}", [(0, r) for r in range(restarts)], values))
    return points


def test_the_data_are_one_of_the_permutations_and_their_p_is_each_points_own():
    points = _curve(np.random.default_rng(0))
    result = joint_null(points, WITHOUT_RANDOM_WALK, permutations=199)
    for point, p in zip(points, result.p_each):
        ours, others = point.values[:, 0], point.values[:, 1:]
        walkers = [stats.wilcoxon(ours, others[:, k]).pvalue for k in range(3)]
        assert p == pytest.approx(intersection_union_p(ours.mean(), others.mean(axis=0), walkers))
    assert ((result.null_p > 0) & (result.null_p <= 1)).all() and (result.null_p >= 1 / 200).all()
    assert (result.p_each_wy >= result.p_each - 1e-12).all(), "adjusted never below raw (p_each as scipy gives it)"
    assert list(result.statistics["statistic"]) == list(STATISTICS)
    observed = result.statistics.set_index("statistic")["observed"]
    ratios = [next_best_ratio(p.values[:, 0], p.values[:, 1:]) for p in points]
    assert observed["median_ratio"] == pytest.approx(np.median(ratios))
    assert observed["leads"] == (result.p_each < 0.05).sum()


def test_a_restart_takes_one_permutation_for_every_specification_so_shared_runs_stay_shared():
    points = _curve(np.random.default_rng(1), specifications=2)
    twins = points[:3] + [CurvePoint("twin", p.dataset, p.restarts, p.values) for p in points[:3]]
    result = joint_null(twins, WITHOUT_RANDOM_WALK, permutations=99)
    assert result.null_p[:3] == pytest.approx(result.null_p[3:])
    assert result.p_each_wy[:3] == pytest.approx(result.p_each_wy[3:])
    # a twin moves with its point in every permutation: one specification is ahead on a map exactly when the other is
    most = result.statistics.set_index("statistic")
    assert most.loc["most_maps_led", "observed"] == (result.p_each[:3] < 0.05).sum()


def test_a_planted_lead_is_found_after_correction_and_the_other_points_are_not():
    points = _curve(np.random.default_rng(2), lead={4: 1.15})
    result = joint_null(points, WITHOUT_RANDOM_WALK, permutations=999)
    planted = np.array([p.specification == "spec-4" for p in points])
    assert (result.p_each_wy[planted] < 0.05).all() and (result.null_p_wy[planted] < 0.05).all()
    assert (result.p_each_wy[~planted] >= 0.05).all()
    joint = result.statistics.set_index("statistic")
    assert joint.loc["most_maps_led", "observed"] == 3 and joint.loc["most_maps_led", "p"] < 0.01
    assert joint.loc["leads", "p"] < 0.05


@pytest.mark.slow
def test_with_nothing_planted_the_joint_tests_reject_at_about_their_level():
    # 40 curves without any lead, shared comparators: each joint test and the smallest corrected p reject at 5 %
    # about as often as 5 % (a binomial 2 of 40; at most 6 allows for chance), far from a count against 5 % per point
    rng = np.random.default_rng(4)
    rejected = {"leads": 0, "null_p_below": 0, "most_maps_led": 0, "wy": 0, "any raw": 0}
    for _ in range(40):
        result = joint_null(_curve(rng), WITHOUT_RANDOM_WALK, permutations=199)
        joint = result.statistics.set_index("statistic")["p"]
        for name in ("leads", "null_p_below", "most_maps_led"):
            rejected[name] += joint[name] < 0.05
        rejected["wy"] += min(result.p_each_wy.min(), result.null_p_wy.min()) < 0.05
        rejected["any raw"] += result.null_p.min() < 0.05
    assert max(rejected[k] for k in ("leads", "null_p_below", "most_maps_led", "wy")) <= 6, rejected
    assert rejected["any raw"] >= 15, f"18 points tested alone find something in most curves: {rejected}"


def test_leaving_the_random_walk_out_keeps_its_runs_with_it():
    points = _curve(np.random.default_rng(5), specifications=1, maps=1)
    strict = joint_null(points, WITHOUT_RANDOM_WALK, permutations=499)
    every = joint_null(points, (True, True, True), permutations=499)
    # permuting the random walk in puts topic perplexity on its lower runs in a third of the draws: the null ratios
    # fall, so the same data look better against it
    assert every.null_p[0] < strict.null_p[0]
    with pytest.raises(ValueError, match="exchangeable"):
        joint_null(points, (True, True))
    with pytest.raises(ValueError, match="points"):
        joint_null([], WITHOUT_RANDOM_WALK)
