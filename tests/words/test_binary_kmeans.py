"""k-majority clustering of binary descriptors, and its kernels against their twins."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from naive import BLOCK, hamming_matrix
from naive import bit_counts as naive_bit_counts
from naive import kmeanspp_seeds as naive_kmeanspp_seeds
from naive import lower_min_distance as naive_lower_min_distance
from naive import sample_weighted as naive_sample_weighted

from curiosity_cli.errors import ParameterError
from curiosity_cli.words import _hamming_kernels
from curiosity_cli.words.binary_kmeans import _majority, _reseed_empty, binary_kmeans


def clustered(seed: int, n_prototypes: int, per_prototype: int, n_flips: int):
    """Noisy copies of random prototypes: (descriptors, prototypes)."""
    rng = np.random.default_rng(seed)
    prototypes = rng.integers(0, 256, size=(n_prototypes, 32), dtype=np.uint8)
    bits = np.repeat(np.unpackbits(prototypes, axis=1), per_prototype, axis=0)
    for r in range(len(bits)):
        bits[r, rng.choice(256, size=n_flips, replace=False)] ^= 1
    return np.packbits(bits, axis=1)[rng.permutation(len(bits))], prototypes


def mean_distance(descriptors, centres) -> float:
    return float(hamming_matrix(descriptors, centres).min(axis=1).mean())


# --- kernels vs twins -----------------------------------------------------------------


def test_bit_counts_match_naive_twin():
    rng = np.random.default_rng(0)
    descriptors = rng.integers(0, 256, size=(500, 32), dtype=np.uint8)
    descriptors[:20] = 0
    descriptors[20:40] = 255
    labels = rng.integers(0, 7, size=500).astype(np.int32)
    labels[labels == 3] = 4  # an empty centre
    counts = np.zeros((7, 256), np.int32)
    sizes = np.zeros(7, np.int64)
    _hamming_kernels.bit_counts(descriptors, labels, counts, sizes)
    want_counts, want_sizes = naive_bit_counts(descriptors, labels, 7)
    np.testing.assert_array_equal(counts, want_counts)
    np.testing.assert_array_equal(sizes, want_sizes)


def test_lower_min_distance_and_sampling_match_naive_twins():
    rng = np.random.default_rng(1)
    n = 2 * BLOCK + 37  # a partial last block
    descriptors = rng.integers(0, 256, size=(n, 32), dtype=np.uint8)
    centre = descriptors[5].copy()
    min_sq = rng.integers(0, 256**2, size=n).astype(np.int64)
    want_min_sq, want_sums = naive_lower_min_distance(descriptors, centre, min_sq)
    sums = np.zeros(3, np.int64)
    _hamming_kernels._lower_min_distance(descriptors.view(np.uint64), centre.view(np.uint64), min_sq, sums)
    np.testing.assert_array_equal(min_sq, want_min_sq)
    np.testing.assert_array_equal(sums, want_sums)

    min_sq[::3] = 0  # zero weights must never be drawn
    sums = np.array([min_sq[b * BLOCK : (b + 1) * BLOCK].sum() for b in range(3)], np.int64)
    total = int(sums.sum())
    for target in [0, 1, total // 3, int(sums[0]) - 1, int(sums[0]), total - 1, *rng.integers(0, total, 20)]:
        got = _hamming_kernels._sample_weighted(min_sq, sums, np.int64(target))
        assert got == naive_sample_weighted(min_sq, int(target))


def test_kmeanspp_seeds_match_naive_twin():
    rng = np.random.default_rng(2)
    descriptors = rng.integers(0, 256, size=(300, 32), dtype=np.uint8)
    descriptors[100:150] = descriptors[:50]  # duplicates get weight 0 once seeded
    uniforms = rng.random(59)
    seeds = np.empty(60, np.int64)
    n = _hamming_kernels.kmeanspp_seeds(descriptors.view(np.uint64), 7, uniforms, seeds)
    assert n == 60
    assert seeds.tolist() == naive_kmeanspp_seeds(descriptors, 7, uniforms, 60)
    assert len(set(map(bytes, descriptors[seeds]))) == 60


def test_kmeanspp_stops_when_rows_run_out():
    descriptors = np.repeat(np.arange(3, dtype=np.uint8)[:, None], 32, axis=1)
    descriptors = np.concatenate([descriptors, descriptors])
    seeds = np.empty(5, np.int64)
    n = _hamming_kernels.kmeanspp_seeds(descriptors.view(np.uint64), 0, np.full(4, 0.5), seeds)
    assert n == 3
    assert seeds[:3].tolist() == naive_kmeanspp_seeds(descriptors, 0, np.full(4, 0.5), 5)


# --- majority vote and reseeding ------------------------------------------------------


def test_majority_vote_ties_give_zero():
    descriptors = np.array([[0b11110000] * 32, [0b11001100] * 32, [0b10101010] * 32, [0xFF] * 32], np.uint8)
    labels = np.array([0, 0, 0, 2], np.int32)
    centres, sizes = _majority(descriptors, labels, 3)
    assert sizes.tolist() == [3, 0, 1]
    assert centres[0, 0] == 0b11101000  # bit-wise majority of three
    assert centres[1].tolist() == [0] * 32  # empty
    assert centres[2].tolist() == [0xFF] * 32
    tied, _ = _majority(descriptors[:2], np.zeros(2, np.int32), 1)
    assert tied[0, 0] == 0b11000000  # 1-1 votes give 0


def test_reseed_takes_farthest_distinct_rows():
    descriptors = np.arange(6, dtype=np.uint8)[:, None].repeat(32, axis=1)
    descriptors[4] = descriptors[3]
    distance = np.array([0, 5, 9, 9, 9, 2], np.int32)
    centres = np.zeros((4, 32), np.uint8)
    _reseed_empty(centres, np.array([1, 3]), descriptors, distance)
    # Rows 2, 3, 4 tie at distance 9: lowest index first, and 4 repeats 3.
    assert centres[:, 0].tolist() == [0, 2, 0, 3]


# --- binary_kmeans --------------------------------------------------------------------


@pytest.mark.parametrize("init", ["k-means++", "random"])
def test_recovers_well_separated_prototypes(init):
    descriptors, prototypes = clustered(seed=3, n_prototypes=8, per_prototype=40, n_flips=20)
    centres = binary_kmeans(descriptors, 8, seed=0, init=init)
    assert centres.shape == (8, 32) and centres.dtype == np.uint8
    assert sorted(map(bytes, centres)) == sorted(map(bytes, prototypes))


@pytest.mark.parametrize("init", ["k-means++", "random"])
def test_lowers_mean_distance_below_the_initial_centres(init):
    descriptors, _ = clustered(seed=4, n_prototypes=30, per_prototype=20, n_flips=60)
    start = binary_kmeans(descriptors, 20, seed=5, iterations=0, init=init)
    centres = binary_kmeans(descriptors, 20, seed=5, init=init)
    assert mean_distance(descriptors, centres) < mean_distance(descriptors, start)
    # The initial centres are distinct descriptors.
    assert len({bytes(c) for c in start}) == 20
    assert {bytes(c) for c in start} <= {bytes(d) for d in descriptors}


def test_same_seed_same_words_and_seed_matters():
    rng = np.random.default_rng(6)
    descriptors = rng.integers(0, 256, size=(600, 32), dtype=np.uint8)
    a = binary_kmeans(descriptors, 25, seed=11, iterations=5)
    b = binary_kmeans(descriptors.copy(), 25, seed=11, iterations=5)
    c = binary_kmeans(descriptors, 25, seed=12, iterations=5)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs at least 2 numba threads")
def test_same_words_on_one_or_two_threads():
    rng = np.random.default_rng(7)
    descriptors = rng.integers(0, 256, size=(3000, 32), dtype=np.uint8)
    before = numba.get_num_threads()
    results = []
    try:
        for threads in (1, 2):
            numba.set_num_threads(threads)
            results.append(binary_kmeans(descriptors, 40, seed=3, iterations=4))
    finally:
        numba.set_num_threads(before)
    np.testing.assert_array_equal(results[0], results[1])


def test_k_equal_to_the_number_of_distinct_rows():
    rng = np.random.default_rng(8)
    rows = rng.integers(0, 256, size=(5, 32), dtype=np.uint8)
    descriptors = rows[[0, 1, 2, 3, 4, 0, 1, 2]]
    for init in ("k-means++", "random"):
        centres = binary_kmeans(descriptors, 5, seed=0, init=init)
        assert sorted(map(bytes, centres)) == sorted(map(bytes, rows))


@pytest.mark.parametrize("init", ["k-means++", "random"])
def test_too_few_distinct_descriptors_names_k(init):
    descriptors = np.zeros((10, 32), np.uint8)
    descriptors[5:] = 1
    with pytest.raises(ParameterError, match=r"^k: got 3, expected at most 2 \(the number of distinct descriptors\)$"):
        binary_kmeans(descriptors, 3, seed=0, init=init)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"k": 0}, r"^k: got 0, expected an integer between 1 and 2147483647$"),
        ({"k": 2**31}, r"^k: got 2147483648, expected an integer between 1 and 2147483647$"),
        ({"k": 11}, r"^k: got 11, expected at most 10 \(the number of descriptors\)$"),
        ({"seed": -1}, r"^seed: got -1, expected an integer >= 0$"),
        ({"seed": 1.5}, r"^seed: got 1\.5, expected an integer >= 0$"),
        ({"iterations": -1}, r"^iterations: got -1, expected an integer >= 0$"),
        ({"init": "kmeans"}, r"^init: got 'kmeans', expected one of 'k-means\+\+', 'random'$"),
        ({"descriptors": np.zeros((10, 8), np.uint8)}, r"^descriptors: got shape \(10, 8\)"),
    ],
)
def test_rejects_bad_settings_naming_the_parameter(kwargs, message):
    args = {"descriptors": np.arange(320, dtype=np.int64).reshape(10, 32) % 256, "k": 2, "seed": 0, **kwargs}
    with pytest.raises(ParameterError, match=message):
        binary_kmeans(args.pop("descriptors"), args.pop("k"), **args)
