"""Numba kernels for 256-bit binary (ORB) descriptors: Hamming nearest word, k-means++
seeding, per-centre bit counts.

Private: arrays and scalars in, arrays out; no validation. The public wrappers are
:func:`curiosity_cli.words.hamming.nearest_binary_words` and
:func:`curiosity_cli.words.binary_kmeans.binary_kmeans`. A descriptor is 32 bytes viewed
as 4 ``uint64`` words; the slow twins live in ``tests/naive_orb.py``.

Every kernel gives the same result on any number of threads: the one parallel loop
(over descriptors in :func:`nearest_words`) only writes per-row outputs, and all sums
are integers.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from curiosity_cli._numba import njit

# Numba turns uint64 mixed with a Python int into float64, so every constant is a uint64.
_M1 = np.uint64(0x5555555555555555)
_M2 = np.uint64(0x3333333333333333)
_M4 = np.uint64(0x0F0F0F0F0F0F0F0F)
_H01 = np.uint64(0x0101010101010101)
_ONE = np.uint64(1)
_TWO = np.uint64(2)
_FOUR = np.uint64(4)
_FIFTY_SIX = np.uint64(56)
_THIRTY_TWO = np.uint64(32)
_LOW32 = np.uint64(0xFFFFFFFF)
_ALL_ONES = np.uint64(0xFFFFFFFFFFFFFFFF)

# Descriptors per block when updating block sums in k-means++ sampling.
_BLOCK = 1024


@njit(inline="always")
def _popcount64(x):
    # The classic SWAR popcount: LLVM recognises this exact idiom and emits the POPCNT
    # instruction where the CPU has one (measured ~16x faster than a 256-entry byte table).
    x = x - ((x >> _ONE) & _M1)
    x = (x & _M2) + ((x >> _TWO) & _M2)
    x = (x + (x >> _FOUR)) & _M4
    return (x * _H01) >> _FIFTY_SIX


@njit(parallel=True)
def nearest_words(descriptors, vocabulary_t, out_index, out_distance):
    """Exact Hamming nearest vocabulary word of every descriptor; ties to the lowest index.

    Parameters
    ----------
    descriptors : (N, 4) uint64, C-contiguous
    vocabulary_t : (4, K) uint64, C-contiguous
        The vocabulary transposed, so the inner loop over words reads contiguous memory.
    out_index : (N,) int32
        Written: index of the nearest word.
    out_distance : (N,) int32
        Written: its Hamming distance, 0..256.
    """
    n = descriptors.shape[0]
    k = vocabulary_t.shape[1]
    v0 = vocabulary_t[0]
    v1 = vocabulary_t[1]
    v2 = vocabulary_t[2]
    v3 = vocabulary_t[3]
    for i in prange(n):
        a0 = descriptors[i, 0]
        a1 = descriptors[i, 1]
        a2 = descriptors[i, 2]
        a3 = descriptors[i, 3]
        # One key (distance << 32 | index) makes the minimum branch-free (0.9 ns per
        # pair against 1.4 ns with an if) and breaks ties to the lowest index for free.
        best = _ALL_ONES
        for j in range(k):
            d = (
                _popcount64(a0 ^ v0[j])
                + _popcount64(a1 ^ v1[j])
                + _popcount64(a2 ^ v2[j])
                + _popcount64(a3 ^ v3[j])
            )
            key = (d << _THIRTY_TWO) | np.uint64(j)
            best = min(best, key)
        out_index[i] = np.int32(best & _LOW32)
        out_distance[i] = np.int32(best >> _THIRTY_TWO)


@njit
def _lower_min_distance(descriptors, centre, min_sq, block_sums):
    """Lower each descriptor's squared distance to its nearest centre so far with
    ``centre``, and refresh the per-block sums of ``min_sq``."""
    # Serial on purpose: k-means++ calls this once per seed (5000 times for an ORB
    # vocabulary) on ~1 ms of work; on 2 busy cores the thread start-up and barrier of
    # a parallel loop made seeding 3x slower than one thread.
    n = descriptors.shape[0]
    n_blocks = block_sums.shape[0]
    c0 = centre[0]
    c1 = centre[1]
    c2 = centre[2]
    c3 = centre[3]
    for b in range(n_blocks):
        start = b * _BLOCK
        stop = min(start + _BLOCK, n)
        total = np.int64(0)
        for i in range(start, stop):
            d = np.int64(
                _popcount64(descriptors[i, 0] ^ c0)
                + _popcount64(descriptors[i, 1] ^ c1)
                + _popcount64(descriptors[i, 2] ^ c2)
                + _popcount64(descriptors[i, 3] ^ c3)
            )
            sq = d * d
            if sq < min_sq[i]:
                min_sq[i] = sq
            total += min_sq[i]
        block_sums[b] = total


@njit
def _sample_weighted(min_sq, block_sums, target):
    """First index i with sum(min_sq[:i + 1]) > target, for 0 <= target < sum(min_sq)."""
    b = 0
    running = np.int64(0)
    while running + block_sums[b] <= target:
        running += block_sums[b]
        b += 1
    i = b * _BLOCK
    while True:
        running += min_sq[i]
        if running > target:
            return i
        i += 1


@njit
def kmeanspp_seeds(descriptors, first, uniforms, out_seeds):
    """k-means++ seeding on squared Hamming distance.

    Parameters
    ----------
    descriptors : (N, 4) uint64, C-contiguous
    first : int
        Index of the first seed.
    uniforms : (k - 1,) float64 in [0, 1)
        One draw per further seed.
    out_seeds : (k,) int64
        Written: the seed indices, in the order chosen.

    Returns
    -------
    int
        How many seeds were chosen: fewer than k when the descriptors ran out of rows
        distinct from every seed (all remaining weights zero).
    """
    n = descriptors.shape[0]
    k = out_seeds.shape[0]
    # Squared distance is at most 256 ** 2, so int64 sums are exact: the draw depends
    # only on the seed, never on summation order or thread count.
    min_sq = np.full(n, np.int64(1) << np.int64(40))
    n_blocks = (n + _BLOCK - 1) // _BLOCK
    block_sums = np.zeros(n_blocks, np.int64)
    out_seeds[0] = first
    for s in range(1, k):
        _lower_min_distance(descriptors, descriptors[out_seeds[s - 1]], min_sq, block_sums)
        total = np.int64(0)
        for b in range(n_blocks):
            total += block_sums[b]
        if total == 0:
            return s
        target = np.int64(uniforms[s - 1] * total)
        if target >= total:  # guards against float rounding of u * total
            target = total - 1
        out_seeds[s] = _sample_weighted(min_sq, block_sums, target)
    return k


@njit
def bit_counts(descriptors, labels, out_counts, out_sizes):
    """Per-centre count of set bits, for the majority vote of k-majority.

    Parameters
    ----------
    descriptors : (N, 32) uint8, C-contiguous
    labels : (N,) int32
        Centre of each descriptor, 0..k-1.
    out_counts : (k, 256) int32, zeroed
        Written: ``out_counts[c, 8 * byte + bit]`` counts the members of centre c with
        that bit set; bit 0 is the byte's most significant bit (``np.unpackbits`` order).
    out_sizes : (k,) int64, zeroed
        Written: members per centre.
    """
    n = descriptors.shape[0]
    for i in range(n):
        c = labels[i]
        out_sizes[c] += 1
        for byte in range(32):
            value = descriptors[i, byte]
            if value == 0:
                continue
            for bit in range(8):
                out_counts[c, 8 * byte + bit] += (value >> (7 - bit)) & 1
