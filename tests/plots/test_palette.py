"""The topic palette and the Z_p → Z_b colour matching."""

from __future__ import annotations

import numpy as np
import pytest

from curiosity_cli.errors import ParameterError
from curiosity_cli.plots.palette import PALETTE_SIZE, _srgb_to_lab, match_topics, paint_topics, rank_topics, topic_palette


def test_palette_is_fixed_distinct_and_readable():
    colours = topic_palette()
    assert colours.shape == (PALETTE_SIZE, 3) and colours.dtype == np.uint8
    assert np.array_equal(colours, topic_palette())
    first = topic_palette(127)
    assert len({tuple(c) for c in first}) == 127
    lab = _srgb_to_lab(first / 255)
    distances = np.sqrt(((lab[:, None] - lab[None]) ** 2).sum(-1))[np.triu_indices(127, 1)]
    assert distances.min() > 12  # CIELAB ΔE: clearly different side by side
    assert np.sqrt(((lab[0] - lab[1]) ** 2).sum()) > 60  # the first colours are the most distinct
    with pytest.raises(ParameterError):
        topic_palette(0)


def test_lab_conversion_of_reference_colours():
    lab = _srgb_to_lab(np.array([[1.0, 1.0, 1.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]))
    assert np.allclose(lab[0], [100, 0, 0], atol=0.05)
    assert np.allclose(lab[1], [0, 0, 0], atol=0.05)
    assert np.allclose(lab[2], [53.24, 80.09, 67.20], atol=0.05)


def test_rank_topics_orders_by_size_and_marks_absent_ids():
    labels = np.array([[5, 5, 5], [2, 2, 0]])
    assert rank_topics(labels).tolist() == [2, -1, 1, -1, -1, 0]


def test_a_relabelled_copy_matches_perfectly():
    rng = np.random.default_rng(1)
    z_b = rng.integers(0, 10, (40, 30))
    perm = rng.permutation(10)
    slots_p, slots_b, agreement = match_topics(perm[z_b], z_b)
    assert agreement == 1.0
    assert np.array_equal(paint_topics(perm[z_b], slots_p), paint_topics(z_b, slots_b))


def test_a_split_topic_keeps_its_own_colour():
    z_b = np.zeros((4, 6), int)
    z_b[:, 3:] = 1  # two batch topics, equal size
    z_p = np.array([[7, 7, 7, 3, 3, 3]] * 4)
    z_p[2:, :3] = 9  # the path model split batch topic 0 into 7 and 9
    slots_p, slots_b, agreement = match_topics(z_p, z_b)
    assert slots_b.tolist() == [0, 1]
    assert slots_p[3] == 1 and slots_p[7] == 0  # 7 and 9 overlap topic 0 equally: the lower id wins
    assert slots_p[9] == 2  # unmatched: a colour no batch topic uses
    assert agreement == pytest.approx(18 / 24)
    painted = paint_topics(z_p, slots_p)
    assert painted.shape == (4, 6, 3) and painted.dtype == np.uint8
    assert len({tuple(c) for c in painted.reshape(-1, 3)}) == 3


def test_match_refuses_maps_of_different_shapes():
    with pytest.raises(ParameterError, match="same map"):
        match_topics(np.zeros((3, 3), int), np.zeros((3, 4), int))
    with pytest.raises(ParameterError, match=">= 0"):
        rank_topics(np.array([[-1, 0]]))
