"""Weight functions and the move draw against the paper's formulas, evaluated naively."""

from __future__ import annotations

import math

import numpy as np
import pytest

from curiosity_cli.config import COVERAGE_READINGS
from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.errors import ParameterError
from curiosity_cli.explore.walker import draw_move, move_probabilities
from curiosity_cli.explore.weights import WEIGHT_FUNCTIONS, Candidates, coverage_potential


def potential_naive(candidate, visits: dict, cols: int, reading: str = "literal", min_d2: float = 0.25) -> float:
    """Σ_j n_j / d², one visited cell at a time, a candidate's own term (d = 0) read as ``reading`` says."""
    row, col = divmod(candidate, cols)
    total = 0.0
    for cell, n in visits.items():
        r, c = divmod(cell, cols)
        d2 = (row - r) ** 2 + (col - c) ** 2
        if d2 == 0 and reading == "literal":
            return math.inf
        if d2 == 0 and reading == "others":
            continue
        total += n / (max(d2, min_d2) if reading == "clamp" else d2)
    return total


def test_each_reading_of_eq_8_by_hand_on_a_3_by_3_grid():
    # cells 0 1 2 / 3 4 5 / 6 7 8; the walker went 4 -> 1 -> 4 -> 5 -> 4 and stands on 4:
    # visits 4: 3, 1: 1, 5: 1. Candidates 1 (visited), 3 and 7 (unvisited), 5 (visited).
    grid = SquareGrid(3, 3)
    visited, visits = np.array([1, 4, 5]), np.array([1, 3, 1])
    candidates = np.array([1, 3, 5, 7])
    # candidate 1: 4 at d² 1 gives 3, 5 at d² 2 gives 1/2, itself 1 / (0, clamped 0.25, or left out)
    # candidate 3: 1 at d² 2 gives 1/2, 4 at d² 1 gives 3, 5 at d² 4 gives 1/4
    # candidate 7: 1 at d² 4 gives 1/4, 4 at d² 1 gives 3, 5 at d² 2 gives 1/2
    expected = {
        "literal": [math.inf, 3.75, math.inf, 3.75],
        "clamp": [3.5 + 4, 3.75, 3.5 + 4, 3.75],
        "others": [3.5, 3.75, 3.5, 3.75],
    }
    assert list(expected) == list(COVERAGE_READINGS)  # a reading added to the table is computed by hand here too
    for reading, values in expected.items():
        got = coverage_potential(candidates, visited, visits, grid, reading, 0.25)
        np.testing.assert_allclose(got, values, rtol=1e-15, err_msg=reading)
        assert got.tolist() == [potential_naive(int(c), dict(zip([1, 4, 5], [1, 3, 1])), 3, reading) for c in candidates]
        weights = WEIGHT_FUNCTIONS["stochastic-coverage"](Candidates(candidates, got, np.ones(4), np.ones(4)))
        if reading == "literal":  # a visited neighbour has weight 0: the walker never steps back
            assert weights.tolist() == [0, 1 / 3.75, 0, 1 / 3.75]
        else:  # it keeps a weight: under the clamp less than an open neighbour's, here more under others
            assert weights[0] > 0 and (weights[0] < weights[1]) == (reading == "clamp")


@pytest.mark.parametrize("reading", COVERAGE_READINGS.values(), ids=lambda reading: reading.name)
def test_every_reading_of_the_table_is_computed_as_its_flags_say(reading):
    # a 1 x 3 corridor after 0 -> 1, standing on 1: candidate 0 visited, 2 not; each gets 1 from cell 1 at d² 1,
    # and 2 gets 1/4 from 0 at d² 4, while 0's own term is what the reading says
    grid = SquareGrid(1, 3)
    visited, visits, candidates = np.array([0, 1]), np.array([1, 1]), np.array([0, 2])
    got = {
        min_d2: coverage_potential(candidates, visited, visits, grid, reading.name, min_d2)
        for min_d2 in ((0.25, 1.0) if reading.reads_min_d2 else (None, 0.25, 1.0))
    }
    for potential in got.values():
        assert math.isinf(potential[0]) == reading.infinite_when_visited and potential[1] == 1.25
    # the floor changes a visited candidate's own term exactly when the reading reads it
    assert (got[0.25][0] != got[1.0][0]) == reading.reads_min_d2
    if reading.reads_min_d2:
        with pytest.raises(ParameterError, match="min_d2"):
            coverage_potential(candidates, visited, visits, grid, reading.name)
    else:
        assert got[None].tolist() == got[0.25].tolist() == got[1.0].tolist()


def test_a_boxed_in_walker_under_each_reading_by_hand():
    # a 1 x 3 corridor after 0 -> 1 -> 2 -> 1: visits 0: 1, 1: 2, 2: 1; standing on 1, both neighbours visited
    grid = SquareGrid(1, 3)
    visited, visits, candidates = np.array([0, 1, 2]), np.array([1, 2, 1]), np.array([0, 2])
    # each candidate: 1 at d² 1 gives 2, the other end at d² 4 gives 1/4, itself 1 / (0, 0.25, left out)
    assert coverage_potential(candidates, visited, visits, grid, "literal").tolist() == [math.inf, math.inf]
    assert coverage_potential(candidates, visited, visits, grid, "clamp", 0.25).tolist() == [6.25, 6.25]
    assert coverage_potential(candidates, visited, visits, grid, "others").tolist() == [2.25, 2.25]


@pytest.mark.parametrize("min_d2", [0.25, 1.0, 2.0])
def test_coverage_potential_matches_the_sum_with_the_clamp(min_d2):
    cols = 5
    visits = {0: 3, 6: 1, 7: 2, 24: 1}  # 7 is also a candidate: d = 0 hits the clamp
    candidates = np.array([1, 7, 12, 23])
    got = coverage_potential(
        candidates, np.array(list(visits)), np.array(list(visits.values())), SquareGrid(5, cols), "clamp", min_d2
    )
    expected = [potential_naive(int(c), visits, cols, "clamp", min_d2) for c in candidates]
    np.testing.assert_allclose(got, expected, rtol=1e-15)
    # the visited candidate (7) gets n / min_d2 from itself
    assert got[1] >= 2 / min_d2


def test_literally_a_visited_candidate_has_infinite_potential_and_weight_0():
    cols = 5
    visits = {0: 3, 6: 1, 7: 2, 24: 1}
    candidates = np.array([1, 7, 12, 23])
    got = coverage_potential(
        candidates, np.array(list(visits)), np.array(list(visits.values())), SquareGrid(5, cols), "literal"
    )
    expected = [potential_naive(int(c), visits, cols) for c in candidates]
    np.testing.assert_allclose(got, expected, rtol=1e-15)
    assert got[1] == math.inf and np.isfinite(got[[0, 2, 3]]).all()
    facts = Candidates(candidates, got, np.full(4, 5.0), np.full(4, 3.0))
    for name in ("stochastic-coverage", "word-perplexity", "topic-perplexity"):
        weights = WEIGHT_FUNCTIONS[name](facts)
        assert weights[1] == 0 and (weights[[0, 2, 3]] > 0).all()


def test_a_reading_the_potential_does_not_know_and_a_clamp_without_a_floor_are_refused():
    grid, cells = SquareGrid(3, 3), np.array([1])
    with pytest.raises(ParameterError, match="reading: got 'clamped'"):
        coverage_potential(cells, np.array([4]), np.array([1]), grid, "clamped")
    with pytest.raises(ParameterError, match="min_d2"):
        coverage_potential(cells, np.array([4]), np.array([1]), grid, "clamp")


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
    for dead in ([0.0, 0.0], [np.nan, np.nan], [0.0, -np.inf]):
        index, fell = draw_move(np.array(dead), rng)
        assert fell and index in (0, 1)


def test_infinite_weights_take_every_chance_among_themselves():
    # the limit of proportional weights as some grow without bound: uniform over those
    probabilities, fell = move_probabilities(np.array([5.0, np.inf, np.nan, np.inf]))
    assert not fell
    np.testing.assert_array_equal(probabilities, [0.0, 0.5, 0.0, 0.5])
    rng = np.random.default_rng(3)
    draws = [draw_move(np.array([1e300, np.inf, 2.0]), rng) for _ in range(200)]
    assert {i for i, _ in draws} == {1} and not any(fell for _, fell in draws)


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
    potential = coverage_potential(np.array([4]), np.array([4]), np.array([1]), SquareGrid(3, cols), "clamp", 0.25)
    assert math.isfinite(potential[0]) and potential[0] == pytest.approx(4.0)
