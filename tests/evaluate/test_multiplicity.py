"""Adjusted p-values (evaluate/multiplicity.py) against hand computations, and the headline's family of maps."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from curiosity_cli.evaluate.multiplicity import benjamini_hochberg, holm, intersection_union_p
from curiosity_cli.evaluate.headline import ADJUSTED_COLUMNS, with_adjusted


def test_holm_steps_down_and_keeps_the_order_of_its_input():
    # sorted 0.01, 0.02, 0.03, 0.04 of m = 4: 4 x 0.01, 3 x 0.02, 2 x 0.03, 1 x 0.04 -> 0.04, 0.06, 0.06 (monotone), 0.06
    assert holm([0.03, 0.01, 0.04, 0.02]) == pytest.approx([0.06, 0.04, 0.06, 0.06])
    assert holm([0.5, 0.9]) == pytest.approx([1.0, 1.0]), "capped at 1"
    assert holm([0.2]) == pytest.approx([0.2])


def test_benjamini_hochberg_against_its_step_up_rule():
    # m = 4, sorted 0.01 0.02 0.03 0.2: 4/1 x 0.01 = 0.04, 4/2 x 0.02 = 0.04, 4/3 x 0.03 = 0.04, 0.2; minimum from above
    assert benjamini_hochberg([0.2, 0.03, 0.01, 0.02]) == pytest.approx([0.2, 0.04, 0.04, 0.04])


def test_an_untested_hypothesis_stays_out_of_the_family():
    adjusted = holm([0.01, np.nan, 0.04])
    assert np.isnan(adjusted[1]) and adjusted[[0, 2]] == pytest.approx([0.02, 0.04])
    assert np.isnan(benjamini_hochberg([np.nan])).all()
    with pytest.raises(ValueError, match="p-values in"):
        holm([0.5, 1.5])
    with pytest.raises(ValueError, match="expected a"):
        benjamini_hochberg([[0.1]])


def test_the_lead_needs_a_higher_mean_than_each_walker_and_takes_the_largest_p():
    assert intersection_union_p(1.0, [0.5, 0.9], [0.001, 0.03]) == 0.03
    assert intersection_union_p(1.0, [0.5, 1.0], [0.001, 0.03]) == 1.0, "a tie is not a lead"
    assert np.isnan(intersection_union_p(1.0, [0.5], [np.nan]))
    assert np.isnan(intersection_union_p(1.0, [], []))


def test_a_headline_is_corrected_over_its_maps_per_labels_it_is_measured_against():
    top = pd.DataFrame({
        "against": ["human", "human", "human", "batch"],
        "p_each": [0.01, 0.04, 1.0, 0.01],
        "null_no_rw_p": [0.02, 0.5, 0.03, 0.2],
        "null_p": [0.01, 0.5, 0.02, 0.2],
    })
    adjusted = with_adjusted(top)
    assert list(adjusted.columns[-len(ADJUSTED_COLUMNS):]) == ADJUSTED_COLUMNS
    assert adjusted["p_each_holm"].tolist() == pytest.approx([0.03, 0.08, 1.0, 0.01])
    assert adjusted["null_no_rw_p_bh"].tolist() == pytest.approx([0.045, 0.5, 0.045, 0.2])
    assert top.columns.tolist() == ["against", "p_each", "null_no_rw_p", "null_p"], "the input is left as it was"
