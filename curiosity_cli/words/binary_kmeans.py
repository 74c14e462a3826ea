"""k-majority clustering of binary descriptors: learns an ORB vocabulary.

k-means with Hamming distance, where a centre is the bitwise majority of its members
(the binary word minimising the summed Hamming distance to them). Paper section 5.1
learns a 5000-word ORB dictionary "by extracting features from a completely unrelated
dataset"; this is the clustering step.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.checks import check_int
from curiosity_cli.errors import ParameterError
from curiosity_cli.words.hamming import as_words64, check_descriptors, nearest_with_distance

_INITS = ("k-means++", "random")


def _distinct_first_indices(descriptors: np.ndarray) -> np.ndarray:
    """Ascending index of the first occurrence of each distinct row of (N, 32) uint8."""
    rows = descriptors.view(np.dtype((np.void, descriptors.shape[1]))).ravel()
    _, first = np.unique(rows, return_index=True)
    return np.sort(first)


def _too_few(k: int, n_distinct: int) -> ParameterError:
    return ParameterError(f"k: got {k}, expected at most {n_distinct} (the number of distinct descriptors)")


def _initial_centres(descriptors: np.ndarray, k: int, init: str, rng: np.random.Generator) -> np.ndarray:
    """k distinct descriptors, chosen by ``init``; (k, 32) uint8."""
    if init == "random":
        candidates = _distinct_first_indices(descriptors)
        if candidates.size < k:
            raise _too_few(k, candidates.size)
        chosen = np.sort(rng.choice(candidates.size, size=k, replace=False))
        return descriptors[candidates[chosen]].copy()

    from curiosity_cli.words import _hamming_kernels

    first = int(rng.integers(descriptors.shape[0]))
    uniforms = rng.random(k - 1)
    seeds = np.empty(k, np.int64)
    n_seeds = _hamming_kernels.kmeanspp_seeds(as_words64(descriptors), first, uniforms, seeds)
    if n_seeds < k:
        raise _too_few(k, n_seeds)
    return descriptors[seeds].copy()


def _majority(descriptors: np.ndarray, labels: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Bitwise majority of each centre's members (ties → 0): (k, 32) uint8, and (k,)
    member counts. Rows of empty centres are all zeros."""
    from curiosity_cli.words import _hamming_kernels

    counts = np.zeros((k, 8 * descriptors.shape[1]), np.int32)
    sizes = np.zeros(k, np.int64)
    _hamming_kernels.bit_counts(descriptors, labels, counts, sizes)
    return np.packbits(2 * counts > sizes[:, None], axis=1), sizes


def _reseed_empty(
    centres: np.ndarray, empty: np.ndarray, descriptors: np.ndarray, distance: np.ndarray
) -> None:
    """Move empty centres, in place, onto the descriptors farthest from their centres.

    Candidates in order of decreasing distance (ties: lower index first), skipping rows
    equal to one already taken; a centre with no candidate left keeps its old word.
    """
    order = np.lexsort((np.arange(distance.size), -distance))
    taken: set[bytes] = set()
    slots = iter(empty)
    slot = next(slots, None)
    for i in order:
        if slot is None or distance[i] == 0:
            # Distance 0 rows equal a centre already: moving there would duplicate it.
            break
        key = descriptors[i].tobytes()
        if key in taken:
            continue
        taken.add(key)
        centres[slot] = descriptors[i]
        slot = next(slots, None)


def binary_kmeans(
    descriptors,
    k: int,
    *,
    seed: int,
    iterations: int = 20,
    init: str = "k-means++",
) -> np.ndarray:
    """Cluster binary descriptors into ``k`` binary words (k-majority).

    Each iteration assigns every descriptor to its nearest centre by Hamming distance
    (ties to the lowest index), then sets each centre's bits to the majority vote of
    its members' bits (a tie, possible with an even member count, gives 0). A centre
    left without members moves onto the descriptor farthest from its own centre
    (the farthest first, distinct rows only). Stops when the centres no longer change
    or after ``iterations`` iterations.

    Integer arithmetic throughout: for a given seed the result is identical on any
    number of threads.

    Parameters
    ----------
    descriptors : (N, 32) uint8 array_like
        Binary descriptors, e.g. ORB; at least ``k`` distinct rows.
    k : int
        Number of words, >= 1.
    seed : int
        Seed (>= 0) of the initialisation, the only random step.
    iterations : int, default 20
        Most assignment + majority iterations, >= 0; 0 returns the initial centres.
    init : {"k-means++", "random"}, default "k-means++"
        ``"k-means++"``: seeds drawn one by one with probability proportional to the
        squared Hamming distance to the nearest seed so far (Arthur & Vassilvitskii
        2007); ``"random"``: k distinct descriptors drawn uniformly.

    Returns
    -------
    (k, 32) uint8 ndarray
        The centres (vocabulary words), in initialisation order.

    Raises
    ------
    ParameterError
        Naming the parameter: bad shapes or settings, or ``k`` above the number of
        distinct descriptors.
    """
    descriptors = check_descriptors("descriptors", descriptors)
    # centre ids are int32 in the kernels
    k = check_int("k", k, 1, 2**31 - 1)
    seed = check_int("seed", seed, 0)
    iterations = check_int("iterations", iterations, 0)
    if init not in _INITS:
        raise ParameterError(f"init: got {init!r}, expected one of {', '.join(map(repr, _INITS))}")
    if descriptors.shape[0] < k:
        raise ParameterError(f"k: got {k}, expected at most {descriptors.shape[0]} (the number of descriptors)")

    rng = np.random.default_rng(seed)
    centres = _initial_centres(descriptors, k, init, rng)
    words64 = as_words64(descriptors)
    for _ in range(iterations):
        labels, distance = nearest_with_distance(words64, centres)
        updated, sizes = _majority(descriptors, labels, k)
        empty = np.flatnonzero(sizes == 0)
        if empty.size:
            # An empty centre's majority is meaningless; start from its old word.
            updated[empty] = centres[empty]
            _reseed_empty(updated, empty, descriptors, distance)
        if np.array_equal(updated, centres):
            break
        centres = updated
    return centres
