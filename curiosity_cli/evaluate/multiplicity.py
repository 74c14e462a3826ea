"""Claims corrected for how many were made: adjusted p-values over a family of tests.

An experiment tests topic perplexity on each of its maps, and a study's curve on every
(specification, map) point: 110 points tested at 0.05 give about five p below 0.05
when nothing differs. Each p is reported beside its adjusted values:

- **Holm** (:func:`holm`): the step-down Bonferroni correction; the chance of any false
  claim in the family stays below the level under any dependence between the tests, as
  between points that share their comparators' runs. The verdicts read it.
- **Benjamini-Hochberg** (:func:`benjamini_hochberg`): the expected share of false
  claims among the claims made stays below the level when the tests are positively
  dependent (PRDS), as shared runs make them; a screening figure, not a decision.
- **Westfall-Young min-P** over a study's curve, the one correction that uses how the
  points depend on each other (:mod:`~curiosity_cli.evaluate.joint_null`).

What is corrected is the **intersection-union p** of "topic perplexity leads every other
walker" (:func:`intersection_union_p`): a lead needs a higher mean than each walker and a
paired Wilcoxon p below the level against each, so its p is the largest of the walkers'
(Berger 1982: the intersection-union test needs no correction across the walkers
themselves), and 1 where its mean is not above every walker's.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def _family(p) -> tuple[np.ndarray, np.ndarray]:
    """``p`` as a float array, and where it is a p-value (NaN: not tested, left out of the family)."""
    p = np.asarray(p, np.float64)
    if p.ndim != 1:
        raise ValueError(f"p: got shape {p.shape}, expected a (m,) array of p-values")
    tested = np.isfinite(p)
    if ((p[tested] < 0) | (p[tested] > 1)).any():
        raise ValueError("p: expected p-values in [0, 1] (NaN for an untested hypothesis)")
    return p, tested


def holm(p) -> np.ndarray:
    """Holm's step-down adjusted p-values (Holm 1979).

    Parameters
    ----------
    p : (m,) float array_like
        Raw p-values; NaN for a hypothesis not tested, which stays NaN and does not
        count in the family.

    Returns
    -------
    (m,) float ndarray
        The i-th smallest of the ``m'`` tested p-values becomes the largest of
        ``(m' - j) * p_(j)`` over ``j <= i`` (from 0), capped at 1: a hypothesis is
        rejected at level a exactly where its adjusted p is at most a.
    """
    p, tested = _family(p)
    adjusted = np.full_like(p, np.nan)
    values = p[tested]
    order = np.argsort(values, kind="stable")
    m = values.size
    stepped = np.maximum.accumulate((m - np.arange(m)) * values[order])
    out = np.empty(m)
    out[order] = np.minimum(stepped, 1.0)
    adjusted[tested] = out
    return adjusted


def benjamini_hochberg(p) -> np.ndarray:
    """Benjamini-Hochberg adjusted p-values (q-values), NaN kept out of the family.

    Parameters
    ----------
    p : (m,) float array_like
        Raw p-values; NaN for a hypothesis not tested.

    Returns
    -------
    (m,) float ndarray
        ``scipy.stats.false_discovery_control(p, method='bh')`` over the tested ones.
    """
    from scipy.stats import false_discovery_control

    p, tested = _family(p)
    adjusted = np.full_like(p, np.nan)
    if tested.any():
        adjusted[tested] = false_discovery_control(p[tested], method="bh")
    return adjusted


def adjusted_columns(p_columns: Sequence[str]) -> list[str]:
    """The columns :func:`with_adjusted_p` writes for ``p_columns``, in its order."""
    return [f"{p}_{method}" for p in p_columns for method in ("holm", "bh")]


def with_adjusted_p(table, by, p_columns: Sequence[str]):
    """``table`` with each column of ``p_columns`` Holm-adjusted (``<column>_holm``) and Benjamini-Hochberg-adjusted
    (``<column>_bh``) over each family of rows that share ``by`` (a column or a list of them); a column of ``table``
    of that name is replaced in its place, another added at the end."""
    table = table.copy()
    for column in adjusted_columns(p_columns):
        table[column] = np.nan
    for _, rows in table.groupby(by, sort=False):
        for p in p_columns:
            values = rows[p].to_numpy(float)
            table.loc[rows.index, f"{p}_holm"] = holm(values)
            table.loc[rows.index, f"{p}_bh"] = benjamini_hochberg(values)
    return table


def intersection_union_p(ours: float, others: Sequence[float], p_values: Sequence[float]) -> float:
    """The p of "topic perplexity leads each of these walkers" (module docstring).

    Parameters
    ----------
    ours : float or sequence of float
        Topic perplexity's mean, or its mean over the pairs of each other walker.
    others, p_values : sequence of float
        Each other walker's mean, and the paired Wilcoxon p of topic perplexity against it.

    Returns
    -------
    float
        The largest of ``p_values`` where ``ours`` is above every one of ``others``; 1
        where it is not; NaN with no walker, or a p or mean that is NaN.
    """
    ours, others, p_values = (np.asarray(x, np.float64) for x in (ours, others, p_values))
    if others.shape != p_values.shape or others.ndim != 1 or ours.ndim > 1 or ours.size not in (1, others.size):
        raise ValueError(
            f"ours, others, p_values: got shapes {ours.shape}, {others.shape} and {p_values.shape}, expected two (m,) "
            "arrays and a float or a third"
        )
    if not others.size or not np.isfinite(ours).all() or not (np.isfinite(others).all() and np.isfinite(p_values).all()):
        return np.nan
    return float(p_values.max()) if (ours > others).all() else 1.0
