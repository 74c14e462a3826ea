"""Weight functions and the move draw against the paper's formulas, evaluated naively."""

from __future__ import annotations

import math

import numpy as np
import pytest

from curiosity_cli.cell_grid import SquareGrid
from curiosity_cli.config import WALKER_NAMES
from curiosity_cli.explore.walker import draw_move
from curiosity_cli.explore.weights import WEIGHT_FUNCTIONS, Candidates, coverage_potential


def potential_naive(candidate, visits: dict, cols: int, min_d2: float | None) -> float:
    """Σ_j n_j / max(d², min_d2), one visited cell at a time; eq. 8 as written (n / 0 = ∞) without a clamp."""
    row, col = divmod(candidate, cols)
    total = 0.0
    for cell, n in visits.items():
        r, c = divmod(cell, cols)
        d2 = (row - r) ** 2 + (col - c) ** 2
        if min_d2 is None and d2 == 0:
            return math.inf
        total += n / (d2 if min_d2 is None else max(d2, min_d2))
    return total


def test_every_name_a_config_may_give_has_a_walker_and_every_walker_a_name():
    # the config layer checks names without importing this stage: the two lists must agree, in order
    assert tuple(WEIGHT_FUNCTIONS) == WALKER_NAMES


@pytest.mark.parametrize("min_d2", [0.25, 1.0, 2.0])
def test_coverage_potential_matches_the_sum_with_the_clamp(min_d2):
    cols = 5
    visits = {0: 3, 6: 1, 7: 2, 24: 1}  # 7 is also a candidate: d = 0 hits the clamp
    candidates = np.array([1, 7, 12, 23])
    got = coverage_potential(candidates, np.array(list(visits)), np.array(list(visits.values())), SquareGrid(5, cols), min_d2)
    expected = [potential_naive(int(c), visits, cols, min_d2) for c in candidates]
    np.testing.assert_allclose(got, expected, rtol=1e-15)
    # the visited candidate (7) gets n / min_d2 from itself
    assert got[1] >= 2 / min_d2


def test_without_a_clamp_a_visited_candidate_has_infinite_potential_and_weight_0():
    cols = 5
    visits = {0: 3, 6: 1, 7: 2, 24: 1}
    candidates = np.array([1, 7, 12, 23])
    got = coverage_potential(candidates, np.array(list(visits)), np.array(list(visits.values())), SquareGrid(5, cols), None)
    expected = [potential_naive(int(c), visits, cols, None) for c in candidates]
    np.testing.assert_allclose(got, expected, rtol=1e-15)
    assert got[1] == math.inf and np.isfinite(got[[0, 2, 3]]).all()
    facts = Candidates(candidates, got, np.full(4, 5.0), np.full(4, 3.0))
    for name in ("stochastic-coverage", "word-perplexity", "topic-perplexity"):
        weights = WEIGHT_FUNCTIONS[name](facts)
        assert weights[1] == 0 and (weights[[0, 2, 3]] > 0).all()


def test_the_four_weight_functions_are_the_papers_formulas():
    candidates = Candidates(
        cells=np.array([3, 5, 9]),
        coverage=np.array([0.5, 2.0, 4.0]),
        word_perplexity=np.array([10.0, 20.0, 1.0]),
        topic_perplexity=np.array([3.0, 1.5, 8.0]),
    )
    expected = {
        "random-walk": [1.0, 1.0, 1.0],
        "stochastic-coverage": [1 / 0.5, 1 / 2.0, 1 / 4.0],
        "word-perplexity": [10 / 0.5, 20 / 2.0, 1 / 4.0],
        "topic-perplexity": [3 / 0.5, 1.5 / 2.0, 8 / 4.0],
    }
    assert list(WEIGHT_FUNCTIONS)[:4] == list(expected)
    for name, weights in expected.items():
        np.testing.assert_allclose(WEIGHT_FUNCTIONS[name](candidates), weights, rtol=1e-15)


def test_draw_follows_the_weights_and_falls_back_to_uniform_only_without_positive_weight():
    rng = np.random.default_rng(0)
    weights = np.array([1.0, 0.0, 3.0, np.nan])
    draws = [draw_move(weights, rng) for _ in range(4000)]
    assert not any(fell for _, fell in draws)
    counts = np.bincount([i for i, _ in draws], minlength=4)
    assert counts[1] == counts[3] == 0
    assert counts[2] / counts[0] == pytest.approx(3.0, rel=0.15)
    for dead in ([0.0, 0.0], [np.nan, np.inf], [0.0, -np.inf]):
        index, fell = draw_move(np.array(dead), rng)
        assert fell and index in (0, 1)


def test_random_walk_draws_are_uniform_over_in_bounds_neighbours():
    # chi-square goodness of fit, 3 degrees of freedom: 16.27 is the 0.1 % critical value
    rng = np.random.default_rng(7)
    n = 8000
    counts = np.zeros(4)
    for _ in range(n):
        index, _ = draw_move(WEIGHT_FUNCTIONS["random-walk"](_candidates(4)), rng)
        counts[index] += 1
    chi2 = ((counts - n / 4) ** 2 / (n / 4)).sum()
    assert chi2 < 16.27, counts


def _candidates(n: int) -> Candidates:
    ones = np.ones(n)
    return Candidates(np.arange(n), ones, ones, ones)


def test_the_clamp_keeps_a_revisited_cell_reachable():
    # unclamped, a candidate the walker stands on would have infinite potential
    cols = 3
    potential = coverage_potential(np.array([4]), np.array([4]), np.array([1]), SquareGrid(3, cols), 0.25)
    assert math.isfinite(potential[0]) and potential[0] == pytest.approx(4.0)
