"""Mutual information between two labelings of the same pixels, in bits; per-class recall; classes found.

Everything goes through the contingency table (joint counts) of the two labelings, which
is also what ``curiosity label`` stores per checkpoint: a few kilobytes instead of a
label map per run, and MI, entropies, NMI and the per-class recall of a one-to-one
topic-to-class matching all follow from it exactly.

Classes found (:func:`classes_found`, from the first steps a label file records,
:mod:`curiosity_cli.maps.cell_classes`) say which human classes a path's cells touched
within a length: evidence about the path itself, independent of what the model learned
from it.
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


def expected_mutual_information(table: np.ndarray) -> float:
    """The MI in bits two labelings with the margins of ``table`` share by chance.

    The expectation under the hypergeometric model: every labeling with the same class
    sizes equally likely, i.e. one labeling's pixels permuted at random against the
    other's (Vinh, Epps & Bailey, JMLR 11, 2010, eq. 24a). Exact but for the terms of
    each cell whose probability is below e^-50 of the cell's most likely count.

    Parameters
    ----------
    table : (n_a, n_b) integer ndarray
        A contingency table (:func:`contingency`); empty rows and columns take no part.

    Returns
    -------
    float
        In bits, at least 0; 0 for an empty table.
    """
    from curiosity_cli.evaluate._chance_kernels import expected_mi_kernel

    table = np.asarray(table)
    if table.ndim != 2:
        raise ParameterError(f"table: got shape {table.shape}, expected (n_a, n_b)")
    total = int(table.sum())
    if total == 0:
        return 0.0
    rows, columns = table.sum(axis=1).astype(np.int64), table.sum(axis=0).astype(np.int64)
    logs = _logs(int(min(rows.max(), columns.max())))
    return max(0.0, float(expected_mi_kernel(rows, columns, total, logs)) / np.log(2))


_LOGS = np.zeros(0)


def _logs(largest: int) -> np.ndarray:
    """``log(n)`` for ``n`` up to at least ``largest``: kept between calls, as a map's tables share their sizes.
    ``log(0)`` is -inf, never read: a count of 0 adds nothing."""
    global _LOGS
    if _LOGS.size <= largest:
        with np.errstate(divide="ignore"):
            _LOGS = np.log(np.arange(largest + 1, dtype=np.float64))
    return _LOGS


def adjusted_mutual_information(table: np.ndarray) -> float:
    """``(I - E[I]) / ((H(A) + H(B)) / 2 - E[I])``: MI corrected for chance, at most 1.

    ``E[I]`` is :func:`expected_mutual_information`: 0 when the labelings share no more than
    labelings of the same class sizes drawn at random would, below 0 when less. With the
    normalisation of :func:`normalised_mutual_information` (the arithmetic mean of the
    entropies); both labelings constant: 1.0, as scikit-learn's
    ``adjusted_mutual_info_score``. The correction grows with the labels each side uses (a
    labeling with more topics shares more by chance) and shrinks with the pixels: over a
    whole map's pixels it is small.
    """
    table = np.asarray(table)
    h_a, h_b = entropy(table.sum(axis=1)), entropy(table.sum(axis=0))
    if h_a == 0 and h_b == 0:
        return 1.0
    expected = expected_mutual_information(table)
    denominator = (h_a + h_b) / 2 - expected
    if denominator <= 0:  # margins so lopsided that chance alone reaches the normalisation
        return float("nan")
    return min(1.0, (mutual_information(table) - expected) / denominator)


def matched_recall(table: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-class recall of a topic labelling under the best one-to-one topic-to-class matching.

    A class's recall under a topic is the share of the class's pixels that carry the
    topic. Each class is matched to at most one topic and each topic to at most one
    class, so that the sum of the matched recalls is largest (the Hungarian algorithm,
    :func:`scipy.optimize.linear_sum_assignment`). With fewer topics than classes the
    classes left unmatched get recall 0. Classes without pixels take no part.

    Parameters
    ----------
    table : (K, C) integer ndarray
        ``table[k, h]`` = pixels with topic ``k`` and class ``h`` (a contingency table).

    Returns
    -------
    recall : (C,) float64 ndarray
        In [0, 1]; NaN for a class without pixels.
    topic : (C,) int64 ndarray
        The topic matched to each class; -1 for a class unmatched or without pixels.
    """
    from scipy.optimize import linear_sum_assignment

    table = np.asarray(table)
    if table.ndim != 2:
        raise ParameterError(f"table: got shape {table.shape}, expected (K, C)")
    pixels = table.sum(axis=0)
    present = np.flatnonzero(pixels > 0)
    recall = np.full(table.shape[1], np.nan)
    topic = np.full(table.shape[1], -1, np.int64)
    shares = table[:, present] / pixels[present]  # (K, C'): recall of each class under each topic
    rows, cols = linear_sum_assignment(shares, maximize=True)
    recall[present] = 0.0  # unmatched (K < C) until a topic is assigned below
    recall[present[cols]] = shares[rows, cols]
    topic[present[cols]] = rows
    return recall, topic


def mean_recall(table: np.ndarray) -> float:
    """Mean over the classes with pixels of :func:`matched_recall`'s recall; NaN without any."""
    recall, _ = matched_recall(table)
    present = recall[np.isfinite(recall)]
    return float(present.mean()) if present.size else float("nan")


def classes_found(first_step: np.ndarray, length: int) -> int:
    """How many classes a path reached within its first ``length`` steps, from :func:`~curiosity_cli.maps.cell_classes.first_steps`."""
    first_step = np.asarray(first_step)
    return int(np.count_nonzero((first_step >= 0) & (first_step < length)))
