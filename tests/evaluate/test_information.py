"""Mutual information against a naive double loop and cases worked by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from naive import expected_mutual_information_naive, mutual_information_naive

from curiosity_cli.errors import ParameterError
from curiosity_cli.evaluate.information import (
    adjusted_mutual_information,
    contingency,
    entropy,
    expected_mutual_information,
    mutual_information,
    normalised_mutual_information,
)


def mi(a, b, n_a=None, n_b=None) -> float:
    a, b = np.asarray(a), np.asarray(b)
    return mutual_information(contingency(a, b, n_a or int(a.max()) + 1, n_b or int(b.max()) + 1))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 4), st.integers(0, 3)), min_size=1, max_size=60))
def test_mi_matches_the_double_loop(pairs):
    a, b = (np.array(column) for column in zip(*pairs))
    assert mi(a, b, 5, 4) == pytest.approx(mutual_information_naive(a, b), abs=1e-12)


def test_mi_of_a_labeling_with_itself_is_its_entropy():
    a = np.array([0, 0, 1, 1, 1, 2, 3, 3])
    h = -sum(p * math.log2(p) for p in (2 / 8, 3 / 8, 1 / 8, 2 / 8))
    assert mi(a, a) == pytest.approx(h, rel=1e-12)
    assert entropy(np.bincount(a)) == pytest.approx(h, rel=1e-12)
    assert normalised_mutual_information(contingency(a, a, 4, 4)) == pytest.approx(1.0)


def test_mi_of_independent_labelings_is_zero():
    # every (i, j) pair equally often: exactly independent
    a, b = np.meshgrid(np.arange(4), np.arange(3), indexing="ij")
    assert mi(a, b) == pytest.approx(0.0, abs=1e-12)
    rng = np.random.default_rng(0)
    assert mi(rng.integers(0, 8, 200_000), rng.integers(0, 5, 200_000)) < 1e-3


def test_mi_and_nmi_do_not_change_when_labels_are_renamed():
    rng = np.random.default_rng(1)
    a = rng.integers(0, 6, 500)
    b = (a + rng.integers(0, 2, 500)) % 6
    renamed = np.array([4, 0, 5, 2, 1, 3])[a]
    assert mi(renamed, b) == pytest.approx(mi(a, b), rel=1e-12)
    nmi = normalised_mutual_information
    assert nmi(contingency(renamed, b, 6, 6)) == pytest.approx(nmi(contingency(a, b, 6, 6)), rel=1e-12)


def test_a_worked_example():
    # a = [0, 0, 1, 1], b = [0, 1, 1, 1]: H(a) = 1, H(b) = H(1/4), H(a, b) = 1.5
    h_b = -(0.25 * math.log2(0.25) + 0.75 * math.log2(0.75))
    assert mi([0, 0, 1, 1], [0, 1, 1, 1]) == pytest.approx(1 + h_b - 1.5, rel=1e-12)
    assert normalised_mutual_information(contingency(np.array([0, 0, 1, 1]), np.array([0, 1, 1, 1]), 2, 2)) == pytest.approx(
        (1 + h_b - 1.5) / ((1 + h_b) / 2), rel=1e-12
    )


def test_contingency_refuses_mismatched_or_out_of_range_labels():
    with pytest.raises(ParameterError, match="b: got 3 labels, expected as many as a"):
        contingency(np.zeros(4, int), np.zeros(3, int), 1, 1)
    with pytest.raises(ParameterError, match=r"a: labels 0 \.\. 5, expected 0 \.\. 4"):
        contingency(np.array([0, 5]), np.array([0, 0]), 5, 1)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 4), st.integers(0, 3)), min_size=1, max_size=80))
def test_expected_mi_matches_the_whole_hypergeometric_sum(pairs):
    a, b = (np.array(column) for column in zip(*pairs))
    table = contingency(a, b, 5, 4)
    assert expected_mutual_information(table) == pytest.approx(expected_mutual_information_naive(table), abs=1e-12)


def test_expected_mi_is_the_mean_mi_over_random_permutations():
    # the hypergeometric model is one labeling's pixels shuffled against the other's
    rng = np.random.default_rng(2)
    a, b = rng.integers(0, 6, 120), rng.integers(0, 3, 120)
    shuffled = np.array([mi(rng.permutation(a), b, 6, 3) for _ in range(4000)])
    expected = expected_mutual_information(contingency(a, b, 6, 3))
    assert expected > 0.03  # 120 pixels in 18 cells: chance alone shares a good deal
    assert abs(shuffled.mean() - expected) < 4 * shuffled.std() / np.sqrt(shuffled.size)


def test_expected_mi_walks_its_tails_on_a_map_sized_table():
    # a million pixels: the chi-square approximation (r - 1)(c - 1) / (2 N ln 2) holds closely
    rng = np.random.default_rng(3)
    rows, columns = rng.multinomial(1_000_000, np.full(64, 1 / 64)), rng.multinomial(1_000_000, np.full(8, 1 / 8))
    table = np.zeros((64, 8), np.int64)
    table[:, 0] = rows  # only the margins matter
    table[0] += columns - np.eye(8, dtype=np.int64)[0] * columns.sum()
    assert table.sum(axis=0).tolist() == columns.tolist() and table.sum(axis=1).tolist() == rows.tolist()
    approximation = 63 * 7 / (2 * 1_000_000 * math.log(2))
    assert expected_mutual_information(table) == pytest.approx(approximation, rel=0.01)


def test_ami_is_one_for_the_same_labeling_and_near_zero_for_independent_ones():
    rng = np.random.default_rng(4)
    a = rng.integers(0, 5, 300)
    assert adjusted_mutual_information(contingency(a, a, 5, 5)) == pytest.approx(1.0)
    renamed = np.array([3, 1, 4, 0, 2])[a]
    assert adjusted_mutual_information(contingency(renamed, a, 5, 5)) == pytest.approx(1.0)
    independent = [adjusted_mutual_information(contingency(rng.integers(0, 5, 300), a, 5, 5)) for _ in range(200)]
    # MI of independent labelings is positive; chance-corrected it is zero on average
    assert abs(np.mean(independent)) < 4 * np.std(independent) / np.sqrt(len(independent))
    assert np.mean([mi(rng.integers(0, 5, 300), a, 5, 5) for _ in range(50)]) > 0.02


def test_ami_of_constant_labelings():
    assert adjusted_mutual_information(np.array([[7]])) == 1.0
    # one side constant: nothing shared, nothing shared by chance
    assert adjusted_mutual_information(np.array([[3, 4, 5]])) == pytest.approx(0.0, abs=1e-12)


def test_ami_is_below_nmi_by_what_chance_gives():
    rng = np.random.default_rng(5)
    a = rng.integers(0, 8, 400)
    b = np.where(rng.random(400) < 0.5, a % 4, rng.integers(0, 4, 400))
    table = contingency(a, b, 8, 4)
    h = (entropy(table.sum(axis=1)) + entropy(table.sum(axis=0))) / 2
    expected = expected_mutual_information(table)
    assert adjusted_mutual_information(table) == pytest.approx((mutual_information(table) - expected) / (h - expected))
    assert adjusted_mutual_information(table) < normalised_mutual_information(table)
