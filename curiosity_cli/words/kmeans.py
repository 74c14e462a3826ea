"""Seeded k-means (Lloyd, k-means++ start) for texton vocabularies."""

from __future__ import annotations

import numpy as np

from curiosity_cli.checks import check_int
from curiosity_cli.errors import ParameterError
from curiosity_cli.words.textons import as_float32_matrix, nearest_centres


def kmeans(vectors: np.ndarray, k: int, *, seed: int, iterations: int = 30) -> np.ndarray:
    """Cluster real vectors into ``k`` centres.

    k-means++ seeding from ``np.random.default_rng(seed)``, then Lloyd iterations until the
    assignment stops changing or ``iterations`` is reached. Assignment is the exact
    nearest-centre kernel and means are float64 sums in a fixed order, so a seed gives
    the same centres on any machine and thread count. An emptied cluster moves onto the
    vector farthest from its centre.

    Parameters
    ----------
    vectors : (N, D) ndarray
        Finite values, ``N >= k``.
    k : int
        Number of centres, >= 1.
    seed : int
        Seed (>= 0) of the k-means++ start, the only random step.
    iterations : int, default 30
        Most Lloyd iterations, >= 0; 0 returns the k-means++ start.

    Returns
    -------
    (k, D) float32 ndarray

    Raises
    ------
    ParameterError
        Naming the parameter: a bad setting, fewer vectors than ``k``, or ``vectors`` not
        a finite 2-D real array.
    """
    k = check_int("k", k, 1)
    seed = check_int("seed", seed, 0)
    iterations = check_int("iterations", iterations, 0)
    vectors = as_float32_matrix(vectors, "vectors", "(N, D)")
    if vectors.shape[0] < k:
        raise ParameterError(f"vectors: got shape {vectors.shape}, expected (N, D) with N >= k = {k}")
    rng = np.random.default_rng(seed)
    data = vectors.astype(np.float64)
    centres = np.empty((k, data.shape[1]))
    centres[0] = data[rng.integers(data.shape[0])]
    nearest_d2 = ((data - centres[0]) ** 2).sum(axis=1)
    for j in range(1, k):
        # D^2 sampling: far points are likely picks, so the start covers the data
        cumulative = np.cumsum(nearest_d2)
        pick = int(np.searchsorted(cumulative, rng.random() * cumulative[-1], side="right"))
        centres[j] = data[min(pick, data.shape[0] - 1)]
        np.minimum(nearest_d2, ((data - centres[j]) ** 2).sum(axis=1), out=nearest_d2)

    labels = None
    for _ in range(iterations):
        new_labels = nearest_centres(vectors, centres.astype(np.float32))
        if labels is not None and np.array_equal(new_labels, labels):
            break
        labels = new_labels
        counts = np.bincount(labels, minlength=k)
        for d in range(data.shape[1]):
            sums = np.bincount(labels, weights=data[:, d], minlength=k)
            centres[:, d] = np.where(counts > 0, sums / np.maximum(counts, 1), centres[:, d])
        empty = np.flatnonzero(counts == 0)
        if empty.size:
            d2 = ((data - centres[labels]) ** 2).sum(axis=1)
            centres[empty] = data[np.argsort(-d2, kind="stable")[: empty.size]]
    return centres.astype(np.float32)
