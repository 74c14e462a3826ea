"""Slow, obviously-correct twins of every numba kernel, for the tests to compare against.

Each function says plainly what its fast counterpart computes, with plain loops, float64
or unpacked bits, and textbook library calls.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

# --------------------------------------------------------------------------- textons
# Twins of curiosity_cli/words/_texton_kernels.py and the MR8 filtering in filterbank.py.

def nearest_centres_naive(vectors: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """Twin of ``_texton_kernels.nearest_centres_kernel``: float64 brute force.

    For each row, the squared distance to every centre, summed over dimensions from the
    first upward in float64, and the first index of the smallest (``np.argmin``).
    """
    v64 = np.asarray(vectors, dtype=np.float32).astype(np.float64)
    c64 = np.asarray(centres, dtype=np.float32).astype(np.float64)
    out = np.empty(len(v64), np.int32)
    for n, v in enumerate(v64):
        dist = np.zeros(len(c64))
        for j in range(c64.shape[1]):
            dist += (v[j] - c64[:, j]) ** 2
        out[n] = np.argmin(dist)
    return out


def mr8_responses_naive(image: np.ndarray, filters, standardise: bool = True) -> np.ndarray:
    """Twin of ``filterbank.mr8_responses``: explicit sliding-window correlation in float64.

    The image is mirrored with ``np.pad(mode="symmetric")`` (``cba|abc``, OpenCV's
    ``BORDER_REFLECT``), then each output pixel is the sum of kernel times the window
    centred on it. (Not ``scipy.ndimage.correlate``: with ``mode="reflect"`` it returns
    garbage once the kernel overhangs the image several times, e.g. a 49 x 49 kernel on a
    5 x 7 image, in scipy 1.17.)
    """
    image = np.asarray(image, dtype=np.float64)
    if standardise:
        image = image - image.mean()
        if image.std() > 0:
            image = image / image.std()
    support = filters.support
    windows = sliding_window_view(np.pad(image, support // 2, mode="symmetric"), (support, support))

    def correlate(kernel):
        return np.einsum("rcij,ij->rc", windows, kernel.astype(np.float64))

    channels = []
    for bank, absolute in ((filters.edge, True), (filters.bar, False)):
        for scale in range(bank.shape[0]):
            per_orientation = [correlate(kernel) for kernel in bank[scale]]
            if absolute:
                per_orientation = [np.abs(r) for r in per_orientation]
            channels.append(np.max(per_orientation, axis=0))
    channels.append(correlate(filters.gaussian))
    channels.append(correlate(filters.log))
    return np.stack(channels, axis=-1)


def normalise_responses_naive(responses: np.ndarray, scale: float = 0.03) -> np.ndarray:
    """Twin of ``filterbank.normalise_responses``, one vector at a time."""
    responses = np.asarray(responses, dtype=np.float64)
    flat = responses.reshape(-1, responses.shape[-1])
    out = np.zeros_like(flat)
    for i, f in enumerate(flat):
        length = math.sqrt(sum(x * x for x in f))
        if length > 0:
            out[i] = f * math.log(1 + length / scale) / length
    return out.reshape(responses.shape)


# --------------------------------------------------------------------------- ORB words
# Twins of curiosity_cli/words/_hamming_kernels.py. Pure numpy on unpacked bits: a Hamming
# distance is the number of differing bits. Arguments take the public layout
# ((N, 32) uint8 descriptors) rather than the kernels' 64-bit views.

BLOCK = 1024  # the kernels' block size for k-means++ block sums


def hamming_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, K) int64 Hamming distances between rows of (N, 32) and (K, 32) uint8."""
    bits_a = np.unpackbits(a, axis=1).astype(np.int64)
    bits_b = np.unpackbits(b, axis=1).astype(np.int64)
    return (bits_a[:, None, :] != bits_b[None, :, :]).sum(axis=2)


def nearest_words(descriptors: np.ndarray, vocabulary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Twin of ``nearest_words``: (index, distance), ties to the lowest index."""
    distances = hamming_matrix(descriptors, vocabulary)
    index = np.argmin(distances, axis=1)  # argmin returns the first minimum
    return index.astype(np.int32), distances[np.arange(len(descriptors)), index].astype(np.int32)


def lower_min_distance(
    descriptors: np.ndarray, centre: np.ndarray, min_sq: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Twin of ``_lower_min_distance``: (new min_sq, block sums)."""
    sq = hamming_matrix(descriptors, centre[None, :])[:, 0] ** 2
    new = np.minimum(min_sq, sq)
    n_blocks = -(-len(new) // BLOCK)
    sums = np.array([new[b * BLOCK : (b + 1) * BLOCK].sum() for b in range(n_blocks)], np.int64)
    return new, sums


def sample_weighted(weights: np.ndarray, target: int) -> int:
    """Twin of ``_sample_weighted``: first i with weights[:i + 1].sum() > target."""
    for i in range(len(weights)):
        if weights[: i + 1].sum() > target:
            return i
    raise AssertionError("target not below the total")


def kmeanspp_seeds(descriptors: np.ndarray, first: int, uniforms: np.ndarray, k: int) -> list[int]:
    """Twin of ``kmeanspp_seeds``: the seed indices (fewer than k if the rows run out)."""
    distances = hamming_matrix(descriptors, descriptors)
    seeds = [first]
    while len(seeds) < k:
        weights = distances[:, seeds].min(axis=1) ** 2
        total = int(weights.sum())
        if total == 0:
            break
        target = min(int(uniforms[len(seeds) - 1] * total), total - 1)
        seeds.append(int(np.searchsorted(np.cumsum(weights), target, side="right")))
    return seeds


def bit_counts(descriptors: np.ndarray, labels: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Twin of ``bit_counts``: (k, 256) set-bit counts per centre, (k,) member counts."""
    bits = np.unpackbits(descriptors, axis=1)
    counts = np.zeros((k, bits.shape[1]), np.int64)
    sizes = np.zeros(k, np.int64)
    for c in range(k):
        members = bits[labels == c]
        counts[c] = members.sum(axis=0)
        sizes[c] = len(members)
    return counts, sizes
