"""Mutual information between two labelings of the same pixels, in bits.

Everything goes through the contingency table (joint counts) of the two labelings, which
is also what ``curiosity label`` stores per checkpoint: a few kilobytes instead of a
label map per run, and MI, entropies and NMI all follow from it exactly.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.errors import ParameterError


def contingency(a: np.ndarray, b: np.ndarray, n_a: int, n_b: int) -> np.ndarray:
    """Joint counts of two labelings.

    Parameters
    ----------
    a, b : (...) integer ndarrays of one shape
        Labels in ``0 .. n_a - 1`` and ``0 .. n_b - 1``.
    n_a, n_b : int
        Number of labels of each.

    Returns
    -------
    (n_a, n_b) int64 ndarray
        ``table[i, j]`` = number of positions with ``a == i`` and ``b == j``.

    Raises
    ------
    ParameterError
        Shapes differ or a label is out of range.
    """
    a = np.asarray(a).ravel()
    b = np.asarray(b).ravel()
    if a.shape != b.shape:
        raise ParameterError(f"b: got {b.size} labels, expected as many as a ({a.size})")
    for name, labels, n in (("a", a, n_a), ("b", b, n_b)):
        if labels.size and (labels.min() < 0 or labels.max() >= n):
            raise ParameterError(f"{name}: labels {labels.min()} .. {labels.max()}, expected 0 .. {n - 1}")
    joint = a.astype(np.int64) * n_b + b
    return np.bincount(joint, minlength=n_a * n_b).reshape(n_a, n_b)


def entropy(counts: np.ndarray) -> float:
    """Shannon entropy in bits of the distribution proportional to ``counts`` (any shape); 0 if empty."""
    counts = np.asarray(counts, np.float64).ravel()
    total = counts.sum()
    if total == 0:
        return 0.0
    p = counts[counts > 0] / total
    return float(-(p * np.log2(p)).sum())


def mutual_information(table: np.ndarray) -> float:
    """``I(A; B) = H(A) + H(B) - H(A, B)`` in bits, from a (n_a, n_b) contingency table.

    Never negative: rounding below zero is clipped to 0.
    """
    table = np.asarray(table)
    return max(0.0, entropy(table.sum(axis=1)) + entropy(table.sum(axis=0)) - entropy(table))


def normalised_mutual_information(table: np.ndarray) -> float:
    """``I(A; B) / ((H(A) + H(B)) / 2)`` (arithmetic-mean normalisation), in [0, 1].

    Both labelings constant: 1.0 if they are the same size, as two identical labelings
    would be, which is the convention of scikit-learn's ``normalized_mutual_info_score``.
    """
    table = np.asarray(table)
    h = (entropy(table.sum(axis=1)) + entropy(table.sum(axis=0))) / 2
    if h == 0:
        return 1.0
    return min(1.0, mutual_information(table) / h)
