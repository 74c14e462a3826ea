"""Topic perplexity against the other walkers, compared without selection bias.

The paper's claim is that topic perplexity gathers more mutual information than each
other walker. Two ways of reading that from paired restarts (the same start cells and
streams, :data:`~curiosity_cli.evaluate.statistics.PAIR_KEYS`):

**Against each walker, pre-specified.** Topic perplexity's mean MI over each other
walker's, with a 95 % interval (:func:`ratio_interval`) and the paired Wilcoxon p
(``effects.csv``). The walkers are those the config runs, named before anything ran, so
no comparison is chosen after seeing the data; "leads every walker" is an
intersection-union test: a higher mean and p < 0.05 against each (``beats_all``).

**Against the next best, with a null reference.** The ratio to the highest of the other
walkers' means is a summary only: the next best is chosen after seeing the data, so the
ratio is biased toward "no lead". With four equal walkers and 10 pairs its median is
about 0.95-0.98 and it is below 1 in about three draws out of four. So it comes with:

- a bootstrap interval that chooses the next best again in every resample
  (:func:`next_best_interval`; one that keeps the observed next best fixed under-covers);
- its distribution when topic perplexity is exchangeable with the other walkers
  (:func:`next_best_null`): the walkers' labels permuted within each restart, which is
  exactly "no walker differs from another", the null under which the selection of the
  next best does its work. Its median and 95 % interval say where "no difference" lies;
  the null-referenced p is the share of permutations whose ratio is at least the
  observed one. Permuting every walker tests "no walker differs"; when one walker is
  somewhat worse than the others and topic perplexity equals the best, that p is a
  little small (``scripts/null_reference.py``, 10 pairs: below 0.05 in 9.0 % of draws
  with one walker 10 % worse, 6.5 % with 20 %, 1.6 % with 50 %). So the reports read it
  with the random walk, far below the others on every map, left out of the permuted
  walkers (``exchangeable``): "topic perplexity does not differ from the walkers that could
  equal it". The per-walker tests, not this p, decide a lead.

The interval of a ratio of paired means is a studentized (bootstrap-t) interval of its
logarithm: with 10 pairs of equal walkers the percentile bootstrap covered the true
ratio in 90.4 % of simulated draws, the studentized one in 95.0 % (the same script;
``tests/evaluate/test_comparisons.py`` checks the one used).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Bootstrap resamples of an interval, and permutations of a null reference: fixed, with a
#: fixed seed, so a report is the same every time it is written.
RESAMPLES = 10_000
PERMUTATIONS = 10_000
CONFIDENCE = 0.95


def _pairs(a, b) -> tuple[np.ndarray, np.ndarray]:
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    if a.shape != b.shape or a.ndim != 1:
        raise ValueError(f"a, b: got shapes {a.shape} and {b.shape}, expected two (n,) arrays of pairs")
    return a, b


def _log_ratio_se(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The delta-method standard error of ``log(mean(a) / mean(b))`` along the last axis."""
    n = a.shape[-1]
    linear = a / a.mean(axis=-1, keepdims=True) - b / b.mean(axis=-1, keepdims=True)
    return linear.std(axis=-1, ddof=1) / np.sqrt(n)


def ratio_interval(
    a, b, confidence: float = CONFIDENCE, resamples: int = RESAMPLES, seed: int = 0,
) -> tuple[float, float]:
    """Studentized paired-bootstrap interval of ``mean(a) / mean(b)``.

    Pairs are resampled; each resample's log ratio is studentized by its own
    delta-method standard error, and the quantiles of that statistic set the interval
    around the observed log ratio (bootstrap-t; Efron & Tibshirani 1993, ch. 12).

    Parameters
    ----------
    a, b : (n,) float array_like
        Paired values: the same restart of two walkers.
    confidence : float
        Of the interval, in (0, 1).
    resamples : int
        Bootstrap resamples, drawn from ``seed``.

    Returns
    -------
    (float, float)
        Lower and upper bound; NaN for fewer than three pairs, a mean that is not
        positive, or pairs whose ratio has no spread to studentize by.
    """
    a, b = _pairs(a, b)
    if a.size < 3 or not (a.mean() > 0 and b.mean() > 0):
        return np.nan, np.nan
    observed = np.log(a.mean() / b.mean())
    spread = float(_log_ratio_se(a, b))
    if not spread > 0:
        return np.nan, np.nan
    picks = np.random.default_rng(seed).integers(0, a.size, (resamples, a.size))
    ra, rb = a[picks], b[picks]
    with np.errstate(divide="ignore", invalid="ignore"):  # a resample of equal pairs has no spread: left out
        t = (np.log(ra.mean(axis=1) / rb.mean(axis=1)) - observed) / _log_ratio_se(ra, rb)
    t = t[np.isfinite(t)]
    if t.size < resamples // 2:
        return np.nan, np.nan
    high_t, low_t = np.quantile(t, [(1 + confidence) / 2, (1 - confidence) / 2])
    return float(np.exp(observed - high_t * spread)), float(np.exp(observed - low_t * spread))


def next_best_ratio(ours, others) -> float:
    """``mean(ours)`` over the highest of the other walkers' means; NaN when that is not positive.

    Parameters
    ----------
    ours : (n,) float array_like
        Topic perplexity's MI per restart.
    others : (n, m) float array_like
        The other walkers' MI for the same restarts, a column each.
    """
    ours, others = _block(ours, others)
    best = others.mean(axis=0).max()
    return float(ours.mean() / best) if best > 0 else np.nan


def _block(ours, others) -> tuple[np.ndarray, np.ndarray]:
    ours, others = np.asarray(ours, np.float64), np.asarray(others, np.float64)
    if ours.ndim != 1 or others.ndim != 2 or others.shape[0] != ours.shape[0] or others.shape[1] < 1:
        raise ValueError(f"ours, others: got shapes {ours.shape} and {others.shape}, expected (n,) and (n, m), m >= 1")
    return ours, others


def _next_best_ratios(ours: np.ndarray, others: np.ndarray) -> np.ndarray:
    """Ratios of stacked samples: ``ours`` (..., n), ``others`` (..., n, m) -> (...)."""
    best = others.mean(axis=-2).max(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(best > 0, ours.mean(axis=-1) / best, np.nan)


def next_best_interval(
    ours, others, confidence: float = CONFIDENCE, resamples: int = RESAMPLES, seed: int = 0,
) -> tuple[float, float]:
    """Percentile paired-bootstrap interval of :func:`next_best_ratio`, choosing the next best in every resample.

    Parameters
    ----------
    ours : (n,) float array_like
    others : (n, m) float array_like
        As :func:`next_best_ratio`.

    Returns
    -------
    (float, float)
        NaN for fewer than two restarts or a resample without a positive next best.
    """
    ours, others = _block(ours, others)
    if ours.size < 2:
        return np.nan, np.nan
    picks = np.random.default_rng(seed).integers(0, ours.size, (resamples, ours.size))
    ratios = _next_best_ratios(ours[picks], others[picks])
    if not np.isfinite(ratios).all():
        return np.nan, np.nan
    low, high = np.quantile(ratios, [(1 - confidence) / 2, (1 + confidence) / 2])
    return float(low), float(high)


@dataclass(frozen=True)
class NullReference:
    """Where the next-best ratio lies when no walker differs (:func:`next_best_null`).

    Attributes
    ----------
    median, low, high : float
        The null distribution's median and central 95 % interval.
    p_value : float
        The share of permutations (the observed labelling counted among them) whose ratio
        is at least the observed one: small when topic perplexity's lead is larger than
        exchangeable walkers give.
    """

    median: float
    low: float
    high: float
    p_value: float


def next_best_null(
    ours, others, permutations: int = PERMUTATIONS, confidence: float = CONFIDENCE, seed: int = 0,
    exchangeable=None,
) -> NullReference:
    """The null reference of :func:`next_best_ratio`: the walkers' labels permuted within each restart.

    In each permutation every restart's values (topic perplexity's and the exchangeable
    others') are shuffled among those walkers independently, topic perplexity takes the
    first, and the ratio to the next best of the rest is computed again, the next best
    chosen anew, as on the data. A walker left out of the exchangeable set keeps its
    values (and may still be the next best): the null is then "topic perplexity does not
    differ from the walkers in the set", not "no walker differs".

    Parameters
    ----------
    ours : (n,) float array_like
    others : (n, m) float array_like
        As :func:`next_best_ratio`.
    permutations : int
        Random permutations, drawn from ``seed``.
    exchangeable : (m,) bool array_like, optional
        Which of ``others``' columns are permuted with topic perplexity; default all.

    Returns
    -------
    NullReference
        NaN throughout for fewer than two restarts or when the observed ratio is undefined.
    """
    ours, others = _block(ours, others)
    observed = next_best_ratio(ours, others)
    if ours.size < 2 or not np.isfinite(observed):
        return NullReference(np.nan, np.nan, np.nan, np.nan)
    mask = np.ones(others.shape[1], bool) if exchangeable is None else np.asarray(exchangeable, bool)
    if mask.shape != (others.shape[1],):
        raise ValueError(f"exchangeable: got shape {mask.shape}, expected ({others.shape[1]},), a flag per other walker")
    values = np.column_stack([ours, others[:, mask]])  # (n, e + 1): the exchangeable walkers
    fixed = others[:, ~mask]
    rng = np.random.default_rng(seed)
    ratios = np.empty(permutations)
    chunk = max(1, 2_000_000 // values.size)  # permutations per batch: bounded memory
    for start in range(0, permutations, chunk):
        count = min(chunk, permutations - start)
        order = np.argsort(rng.random((count, *values.shape)), axis=-1)
        shuffled = np.take_along_axis(np.broadcast_to(values, order.shape), order, axis=-1)
        rest = np.concatenate([shuffled[..., 1:], np.broadcast_to(fixed, (count, *fixed.shape))], axis=-1)
        ratios[start:start + count] = _next_best_ratios(shuffled[..., 0], rest)
    ratios = ratios[np.isfinite(ratios)]
    if not ratios.size:
        return NullReference(np.nan, np.nan, np.nan, np.nan)
    low, median, high = np.quantile(ratios, [(1 - confidence) / 2, 0.5, (1 + confidence) / 2])
    # a tolerance so the identity permutation's own ratio, recomputed, counts as "at least"
    p = (1 + np.count_nonzero(ratios >= observed * (1 - 1e-12))) / (1 + ratios.size)
    return NullReference(float(median), float(low), float(high), float(p))
