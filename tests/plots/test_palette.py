"""The topic palette and the Z_p → Z_b colour matching."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from curiosity_cli.errors import ParameterError
from curiosity_cli.plots.palette import PALETTE_SIZE, _palette, _srgb_to_lab, match_topics, paint_topics, rank_topics


def test_palette_is_fixed_distinct_and_readable():
    colours = _palette()
    assert colours.shape == (PALETTE_SIZE, 3) and colours.dtype == np.uint8 and not colours.flags.writeable
    _palette.cache_clear()
    assert np.array_equal(colours, _palette())
    first = colours[:127]
    assert len({tuple(c) for c in first}) == 127
    lab = _srgb_to_lab(first / 255)
    distances = np.sqrt(((lab[:, None] - lab[None]) ** 2).sum(-1))[np.triu_indices(127, 1)]
    assert distances.min() > 12  # CIELAB ΔE: clearly different side by side
    assert np.sqrt(((lab[0] - lab[1]) ** 2).sum()) > 60  # the first colours are the most distinct


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


def maps_of(table: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(1, N) label maps Z_p and Z_b with ``table[p, b]`` pixels of Z_p topic p and Z_b topic b."""
    pairs = [(p, b) for (p, b), count in np.ndenumerate(table) for _ in range(count)]
    z_p, z_b = np.array(pairs).T
    return z_p[None, :], z_b[None, :]


def padded(slots: np.ndarray, n: int) -> np.ndarray:
    """``slots`` with -1 for the ids past its end (topics absent from the map), to length ``n``."""
    return np.concatenate([slots, np.full(n - slots.size, -1)])


def shared_pixels(table: np.ndarray, slots_p: np.ndarray, slots_b: np.ndarray) -> int:
    """Pixels the matched pairs share: a Z_p topic is matched to the Z_b topic whose slot it took."""
    slots_p, slots_b = padded(slots_p, table.shape[0]), padded(slots_b, table.shape[1])
    return sum(int(table[p, b]) for p, b in np.ndindex(table.shape) if slots_p[p] == slots_b[b] >= 0)


def best_shared_pixels(table: np.ndarray) -> int:
    """The most pixels any one-to-one matching shares, by trying every matching."""
    if table.shape[0] > table.shape[1]:
        table = table.T
    rows = range(table.shape[0])
    return max(sum(int(table[i, j]) for i, j in zip(rows, cols)) for cols in itertools.permutations(range(table.shape[1]), len(rows)))


def test_matching_shares_the_most_pixels_where_greedy_would_not():
    # greedy takes the largest overlap, (0, 0), first and leaves Z_p topic 1 without a
    # partner: 5 shared pixels; swapping partners shares 4 + 4
    table = np.array([[5, 4], [4, 0]])
    slots_p, slots_b, agreement = match_topics(*maps_of(table))
    assert slots_b.tolist() == [0, 1]
    assert slots_p.tolist() == [1, 0]
    assert shared_pixels(table, slots_p, slots_b) == best_shared_pixels(table) == 8
    assert agreement == pytest.approx(8 / 13)


@pytest.mark.parametrize("seed", range(40))
def test_matching_shares_as_many_pixels_as_the_best_of_every_matching(seed):
    rng = np.random.default_rng(seed)
    shape = tuple(rng.integers(1, 5, 2))
    table = rng.integers(0, 6, shape) * (rng.random(shape) < 0.6)  # zeros: pairs that share nothing
    table[0, 0] += 1  # at least one pixel
    slots_p, slots_b, agreement = match_topics(*maps_of(table))
    assert shared_pixels(table, slots_p, slots_b) == best_shared_pixels(table)
    assert agreement == pytest.approx(shared_pixels(table, slots_p, slots_b) / table.sum())
    # every present Z_p topic has a slot of its own: its partner's, or one no Z_b topic uses
    slots_p, slots_b = padded(slots_p, table.shape[0]), padded(slots_b, table.shape[1])
    present = table.sum(axis=1) > 0
    assert (slots_p[present] >= 0).all() and len(set(slots_p[present].tolist())) == present.sum()
    assert (slots_p[~present] == -1).all()
    for p in np.flatnonzero(present):
        partner = np.flatnonzero(slots_b == slots_p[p])
        assert partner.size == 0 or table[p, partner[0]] > 0  # no match without a shared pixel


def test_equally_good_matchings_go_to_the_lower_ids():
    # Z_p topics 0 and 1 share one pixel each with Z_b topic 1: either can be its partner
    table = np.array([[0, 1], [0, 1], [1, 2]])
    slots_p, slots_b, _ = match_topics(*maps_of(table))
    assert slots_b.tolist() == [1, 0]
    assert slots_p.tolist() == [0, 2, 1]  # 0 takes topic 1's slot, 2 topic 0's, 1 a slot of its own


def test_match_refuses_maps_of_different_shapes():
    with pytest.raises(ParameterError, match="same map"):
        match_topics(np.zeros((3, 3), int), np.zeros((3, 4), int))
    with pytest.raises(ParameterError, match=">= 0"):
        rank_topics(np.array([[-1, 0]]))
