"""A study's curve tested as a whole: every point under one permutation of the walkers.

The points of a specification curve are not independent tests. Specifications that
change only how topic perplexity scores a candidate share the other walkers' runs, and
every specification shares its maps, seeds and start cells, so one lucky comparator moves
several points at once, and under no difference at all the count of points with p < 0.05
is far more spread than a binomial count (mean 5.5 of 110 at 0.05, but P(>= 7) about a
third). This module draws the curve's null distribution as one object (Simonsohn,
Simmons & Nelson's specification-curve inference; Westfall & Young 1993 for the
per-point correction):

- a restart is a map, a seed and a restart index (its start cell and streams); in every
  permutation each restart's walkers are shuffled once, and **that same shuffle is
  applied to every specification's run of that restart**, so runs that are shared stay
  shared and the dependence between points is kept;
- in each permutation every point's next-best ratio and its intersection-union p
  (:func:`~curiosity_cli.evaluate.multiplicity.intersection_union_p`, the paired Wilcoxon
  p against each walker) are computed again, and the point's null p is the share of the
  permutations (the data counted among them) whose ratio is at least its own;
- the joint tests: the number of points that lead each walker (``leads``), the number
  with null p < 0.05 (``null_p_below``), the median ratio (``median_ratio``) and, per
  specification, the most maps of one specification that lead or reach null p < 0.05
  (``most_maps_led``, ``most_maps_null_p_below``: is some specification ahead on more
  maps than chance gives), each against its distribution over the permutations;
- the Westfall-Young single-step min-P adjusted p of each point, for both p's: the share
  of permutations in which the smallest p over the whole curve is at most the point's.

Which walkers are exchangeable is the null's choice: all of them ("no walker differs"),
or all but :data:`~curiosity_cli.evaluate.headline.NOT_EXCHANGEABLE` ("topic perplexity
does not differ from the walkers that could equal it"), whose runs then keep their
walker. Both are computed; the report reads the second.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from curiosity_cli.evaluate.comparisons import PERMUTATIONS, _next_best_ratios
from curiosity_cli.evaluate.statistics import ALPHA, CONFIDENCE, wilcoxon_pair_p

#: Permutations per batch: the arrays of one batch stay within a few tens of MB.
_CHUNK = 500
#: The joint statistics, in the order the report gives them.
STATISTICS = ("leads", "null_p_below", "median_ratio", "most_maps_led", "most_maps_null_p_below")


@dataclass(frozen=True)
class CurvePoint:
    """One (specification, map) point of a curve: its runs at the headline's length.

    Attributes
    ----------
    specification : str
        What names the specification (the points of one specification share it).
    dataset : str
    restarts : sequence of (int, int)
        Each row's replicate (seed) and restart: with ``dataset``, the restart whose
        permutation the row takes.
    values : (n, w) float ndarray
        MI per restart (rows) and walker (columns, in the walkers' order given to
        :func:`joint_null`, topic perplexity first); rows complete.
    """

    specification: str
    dataset: str
    restarts: Sequence[tuple[int, int]]
    values: np.ndarray


@dataclass(frozen=True)
class JointNull:
    """The curve under its joint null (:func:`joint_null`).

    Attributes
    ----------
    null_p : (P,) float ndarray
        Each point's next-best ratio's null p from the shared permutations.
    null_p_wy, p_each_wy : (P,) float ndarray
        Westfall-Young min-P adjusted null p and intersection-union p.
    p_each : (P,) float ndarray
        Each point's intersection-union p on the data.
    statistics : pandas.DataFrame
        A row per statistic of :data:`STATISTICS`: ``observed``, the null's ``null_median``,
        ``null_low`` and ``null_high`` (its central 95 %), and ``p``, the share of
        permutations (the data among them) at least as large as observed.
    permutations : int
    """

    null_p: np.ndarray
    null_p_wy: np.ndarray
    p_each: np.ndarray
    p_each_wy: np.ndarray
    statistics: object
    permutations: int


@lru_cache(maxsize=None)
def _signed_rank_cdf(n: int) -> np.ndarray:
    """P(W+ <= w) for w = 0 .. n(n+1)/2 under the null of Wilcoxon's signed-rank test, ``n`` pairs without ties."""
    counts = np.zeros(n * (n + 1) // 2 + 1)
    counts[0] = 1.0
    for rank in range(1, n + 1):
        counts[rank:] = counts[rank:] + counts[:-rank].copy()
    return np.cumsum(counts) / counts.sum()


def signed_rank_p(differences) -> np.ndarray:
    """Two-sided paired Wilcoxon p of each row of differences, as ``scipy.stats.wilcoxon`` gives it.

    Rows without zeros or tied magnitudes take the exact null distribution, vectorised;
    the others (rare with continuous MI) are taken one by one
    (:func:`~curiosity_cli.evaluate.statistics.wilcoxon_pair_p`), so every row's p is scipy's.

    Parameters
    ----------
    differences : (c, n) float array_like
        Paired differences, a test per row.

    Returns
    -------
    (c,) float ndarray
        1 for a row of zeros.
    """
    d = np.asarray(differences, np.float64)
    if d.ndim != 2:
        raise ValueError(f"differences: got shape {d.shape}, expected (c, n)")
    c, n = d.shape
    p = np.empty(c)
    magnitude = np.abs(d)
    order = np.argsort(magnitude, axis=1, kind="stable")
    ordered = np.take_along_axis(magnitude, order, axis=1)
    awkward = (ordered[:, 0] == 0) | (np.diff(ordered, axis=1) == 0).any(axis=1) if n else np.ones(c, bool)
    plain = ~awkward
    if plain.any():
        rows = np.nonzero(plain)[0]
        rank = np.empty((rows.size, n))
        np.put_along_axis(rank, order[rows], np.broadcast_to(np.arange(1.0, n + 1), (rows.size, n)), axis=1)
        w = np.rint((rank * (d[rows] > 0)).sum(axis=1)).astype(np.int64)
        cdf = _signed_rank_cdf(n)
        below = cdf[w]  # P(W+ <= w)
        above = 1.0 - np.where(w > 0, cdf[np.maximum(w - 1, 0)], 0.0)  # P(W+ >= w)
        p[rows] = np.minimum(1.0, 2.0 * np.minimum(below, above))
    for row in np.nonzero(awkward)[0]:
        p[row] = wilcoxon_pair_p(d[row])
    return p


def _iu_p(values: np.ndarray) -> np.ndarray:
    """Intersection-union p of stacked samples: ``values`` (c, n, w), topic perplexity in column 0 -> (c,)."""
    means = values.mean(axis=1)  # (c, w)
    p = np.ones(values.shape[0])
    ahead = (means[:, :1] > means[:, 1:]).all(axis=1)
    if ahead.any():
        rows = values[ahead]
        worst = np.zeros(rows.shape[0])
        for other in range(1, values.shape[2]):
            worst = np.maximum(worst, signed_rank_p(rows[..., 0] - rows[..., other]))
        p[ahead] = worst
    return p


def _share_at_least(samples: np.ndarray) -> np.ndarray:
    """Per column of ``samples`` (S, P), each sample's share of the column at least as large (NaN stays NaN)."""
    size = samples.shape[0]
    shares = np.full(samples.shape, np.nan)
    for j in range(samples.shape[1]):
        column = samples[:, j]
        known = np.isfinite(column)
        ordered = np.sort(column[known])
        # a tolerance so a ratio recomputed from the same values counts as "at least" itself
        shares[known, j] = (ordered.size - np.searchsorted(ordered, column[known] * (1 - 1e-12), "left")) / size
    return shares


def _most_maps(significant: np.ndarray, specifications: np.ndarray) -> np.ndarray:
    """Per sample (row of ``significant``, (S, P) bool), the most points of one specification that are significant."""
    names = np.unique(specifications)
    return np.stack([significant[:, specifications == name].sum(axis=1) for name in names], axis=1).max(axis=1)


def joint_null(
    points: Sequence[CurvePoint], exchangeable, permutations: int = PERMUTATIONS, seed: int = 0,
) -> JointNull:
    """The curve's points under one shared permutation of the walkers per restart (module docstring).

    Parameters
    ----------
    points : sequence of CurvePoint
        Every point of the curve, its columns in one walkers' order, topic perplexity first.
    exchangeable : (w - 1,) bool array_like
        Which of the other walkers are permuted with topic perplexity.
    permutations : int
        Random permutations, drawn from ``seed``; the data count as one more.

    Returns
    -------
    JointNull
    """
    import pandas as pd

    if not points:
        raise ValueError("points: expected at least one point of a curve")
    width = points[0].values.shape[1]
    if any(p.values.ndim != 2 or p.values.shape[1] != width or len(p.restarts) != p.values.shape[0] for p in points):
        raise ValueError("points: expected each point's values as (n, w) with a restart per row, w the same for all")
    mask = np.asarray(exchangeable, bool)
    if mask.shape != (width - 1,):
        raise ValueError(f"exchangeable: got shape {mask.shape}, expected ({width - 1},), a flag per other walker")
    slots = np.concatenate([[0], 1 + np.nonzero(mask)[0]])  # the permuted columns, topic perplexity first
    keys: dict[tuple, int] = {}
    rows = [np.array([keys.setdefault((p.dataset, *r), len(keys)) for r in p.restarts], np.int64) for p in points]
    size = permutations + 1
    ratios, p_each = np.empty((size, len(points))), np.empty((size, len(points)))
    rng = np.random.default_rng(seed)
    for start in range(0, size, _CHUNK):
        count = min(_CHUNK, size - start)
        order = np.argsort(rng.random((count, len(keys), slots.size)), axis=-1)
        if start == 0:
            order[0] = np.arange(slots.size)  # the data: every walker keeps its runs
        for j, (point, at) in enumerate(zip(points, rows)):
            values = np.broadcast_to(point.values, (count, *point.values.shape)).copy()
            values[..., slots] = np.take_along_axis(values[..., slots], order[:, at], axis=-1)
            ratios[start:start + count, j] = _next_best_ratios(values[..., 0], values[..., 1:])
            p_each[start:start + count, j] = _iu_p(values)
    null_p = _share_at_least(ratios)
    # min-P: a permutation's smallest p over the curve, against each point's observed p
    smallest_null = np.nanmin(np.where(np.isfinite(null_p), null_p, np.inf), axis=1)
    smallest_each = np.nanmin(np.where(np.isfinite(p_each), p_each, np.inf), axis=1)
    null_p_wy = np.array([np.mean(smallest_null <= q * (1 + 1e-12)) if np.isfinite(q) else np.nan for q in null_p[0]])
    p_each_wy = np.array([np.mean(smallest_each <= q * (1 + 1e-12)) if np.isfinite(q) else np.nan for q in p_each[0]])
    specifications = np.array([p.specification for p in points])
    samples = {
        "leads": (p_each < ALPHA).sum(axis=1),
        "null_p_below": (null_p < ALPHA).sum(axis=1),
        "median_ratio": np.nanmedian(np.where(np.isfinite(ratios), ratios, np.nan), axis=1),
        "most_maps_led": _most_maps(p_each < ALPHA, specifications),
        "most_maps_null_p_below": _most_maps(null_p < ALPHA, specifications),
    }
    rows_out = []
    for name in STATISTICS:
        values = samples[name].astype(np.float64)
        low, median, high = np.quantile(values[1:], [(1 - CONFIDENCE) / 2, 0.5, (1 + CONFIDENCE) / 2])
        rows_out.append({
            "statistic": name, "observed": values[0], "null_median": median, "null_low": low, "null_high": high,
            "p": float(np.mean(values >= values[0] - 1e-12 * abs(values[0]))),
        })
    return JointNull(null_p[0], null_p_wy, p_each[0], p_each_wy, pd.DataFrame(rows_out), permutations)
