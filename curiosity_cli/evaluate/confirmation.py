"""One-sided tests of a declared lead, pooled over maps: a stratified sign-flip test and a stratified paired t.

A declared hypothesis (:mod:`curiosity_cli.study.hypotheses`) says that one walker does better than another
on a measure, pooled over several maps. Its data are paired differences, one per pair of runs that share a
map, a seed and a restart (so a start cell), each divided by its map's declared scale so that maps of
different ranges weigh alike, and signed so that a positive difference is the walker's lead. Both tests take
the same statistic, the **stratified mean**: the mean over maps of each map's mean scaled difference (a
map counts once however many of its pairs are missing).

- :func:`sign_flip_test`: under the null that a pair's two runs are exchangeable (the walker changes
  nothing, so each difference is as likely with either sign), flipping the signs of the differences
  independently gives the statistic's null distribution exactly; the flips are drawn (Monte Carlo), and
  ``p = (1 + #{T* >= T}) / (1 + B)`` is a valid p-value for any number of draws ``B``. It assumes no shape of
  the differences: a time to first find is censored at the path length, and its differences are discrete
  and skewed.
- :func:`stratified_t`: the statistic over its standard error, ``sqrt(sum_m s_m^2 / n_m) / M``, on
  Welch-Satterthwaite's degrees of freedom; normal theory, and the interval both reports give.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from curiosity_cli.errors import ParameterError

#: The sign flips drawn at a time: a (CHUNK, n) array of signs stays a few tens of MB for thousands of pairs.
_CHUNK = 4096


@dataclass(frozen=True)
class Stratified:
    """Paired differences grouped by map, checked once for both tests.

    Attributes
    ----------
    differences : (n,) float64 ndarray
        Scaled and signed: positive is the walker's lead.
    strata : (n,) int ndarray
        Each difference's map, 0 .. M - 1, every one present.
    weights : (n,) float64 ndarray
        ``1 / (M n_m)``: the statistic is ``weights @ differences``.
    """

    differences: np.ndarray
    strata: np.ndarray
    weights: np.ndarray

    @classmethod
    def of(cls, differences, strata) -> Stratified:
        """Check and group ``differences`` by ``strata`` (labels of any kind, one per difference).

        Raises
        ------
        ParameterError
            Shapes that differ, no differences, or a difference that is not finite.
        """
        differences = np.asarray(differences, np.float64)
        labels = np.asarray(strata)
        if differences.ndim != 1 or labels.shape != differences.shape:
            raise ParameterError(
                f"differences, strata: got shapes {differences.shape} and {labels.shape}, expected two (n,) arrays"
            )
        if not differences.size:
            raise ParameterError("differences: got none, expected at least one paired difference")
        if not np.isfinite(differences).all():
            raise ParameterError("differences: expected finite values (leave out a pair whose measure is missing)")
        _, codes, counts = np.unique(labels, return_inverse=True, return_counts=True)
        codes = codes.reshape(-1)
        return cls(differences, codes, 1.0 / (counts.size * counts[codes]))

    @property
    def statistic(self) -> float:
        """The stratified mean: the mean over maps of each map's mean difference."""
        return float(self.weights @ self.differences)


def sign_flip_test(stratified: Stratified, draws: int, rng: np.random.Generator) -> float:
    """The one-sided p of a stratified mean above 0, from ``draws`` random sign flips (module docstring).

    Parameters
    ----------
    stratified : Stratified
    draws : int
        At least 1; the smallest p it can give is ``1 / (draws + 1)``.
    rng : numpy.random.Generator

    Returns
    -------
    float
        In ``(0, 1]``.
    """
    if draws < 1:
        raise ParameterError(f"draws: got {draws}, expected at least 1")
    terms = stratified.weights * stratified.differences
    observed = terms.sum()
    # a flip equal to the observed sum up to rounding counts as reaching it (the identity flip must)
    tolerance = 1e-12 * np.abs(terms).sum()
    reached, left = 0, draws
    while left:
        size = min(left, _CHUNK)
        signs = rng.integers(0, 2, size=(size, terms.size), dtype=np.int8) * 2 - 1
        reached += int(np.count_nonzero(signs @ terms >= observed - tolerance))
        left -= size
    return (1 + reached) / (1 + draws)


@dataclass(frozen=True)
class TResult:
    """A stratified t: the statistic, its standard error, degrees of freedom, one-sided p and 95 % interval."""

    statistic: float
    standard_error: float
    dof: float
    p_value: float
    ci_low: float
    ci_high: float


def stratified_t(stratified: Stratified) -> TResult:
    """The one-sided stratified paired t of a stratified mean above 0 (module docstring).

    A map of one pair has no variance of its own: the pooled within-map variance stands in for it. With no
    variance at all (every difference equal) the p is 0 for a positive mean, 1 otherwise, and the interval
    is the mean.

    Returns
    -------
    TResult
        NaN degrees of freedom where no map has two pairs.
    """
    from scipy import stats

    d, codes = stratified.differences, stratified.strata
    m = int(codes.max()) + 1
    n = np.bincount(codes, minlength=m).astype(np.float64)
    means = np.bincount(codes, weights=d, minlength=m) / n
    squares = np.bincount(codes, weights=(d - means[codes]) ** 2, minlength=m)
    spread = n > 1
    if not spread.any():
        return TResult(stratified.statistic, np.nan, np.nan, np.nan, np.nan, np.nan)
    pooled = squares[spread].sum() / (n[spread] - 1).sum()
    variances = np.where(spread, squares / np.maximum(n - 1, 1), pooled)
    parts = variances / n / m**2
    error = float(np.sqrt(parts.sum()))
    statistic = stratified.statistic
    if error == 0.0:
        return TResult(statistic, 0.0, np.nan, 0.0 if statistic > 0 else 1.0, statistic, statistic)
    dof = float(parts.sum() ** 2 / (parts[spread] ** 2 / (n[spread] - 1)).sum())
    half = float(stats.t.ppf(0.975, dof)) * error
    return TResult(statistic, error, dof, float(stats.t.sf(statistic / error, dof)), statistic - half, statistic + half)


# --------------------------------------------------------------------------- planning


def plan_scales(leads) -> dict:
    """Per map, a declared plan's scale: the standard deviation of the walker's paired leads, the root mean of its
    comparators' variances, so that a map's scaled leads have about unit spread.

    Parameters
    ----------
    leads : mapping of str to (n, C) float ndarray
        Per map, a row per pair of earlier seeds and a column per comparator: the walker's signed lead.

    Returns
    -------
    dict of str to float

    Raises
    ------
    ParameterError
        A map with fewer than two pairs, or with leads that never vary (no scale to divide by).
    """
    scales = {}
    for name, values in leads.items():
        values = np.asarray(values, np.float64)
        if values.ndim != 2 or values.shape[0] < 2:
            raise ParameterError(f"leads: {name}: got shape {values.shape}, expected (n, C) with at least two pairs")
        scale = float(np.sqrt(values.var(axis=0, ddof=1).mean()))
        if not scale > 0:
            raise ParameterError(f"leads: {name}: the leads never vary, so there is no scale to divide them by")
        scales[name] = scale
    return scales


def planned_power(
    leads, scales, pairs: int, alpha: float, replicates: int, rng: np.random.Generator, effect: float = 1.0,
) -> float:
    """The chance that a plan's intersection-union test (the largest of its comparators' one-sided stratified t
    p-values at most ``alpha``) confirms a lead, from ``pairs`` new pairs per map drawn from the earlier seeds' pairs.

    Each replicate resamples each map's earlier pairs (whole rows, so the comparators' leads keep their
    correlation), after shifting each comparator's leads on each map so that their mean is ``effect`` times the
    observed one (1: the lead seen; 0.5: half of it; 0: none, where the power is the test's level or less).
    The stratified t stands in for the sign flips, which it matches at hundreds of pairs, at a fraction of the cost.

    Parameters
    ----------
    leads : mapping of str to (n, C) float ndarray
        As :func:`plan_scales`'s.
    scales : mapping of str to float
        Per map, its declared scale.
    pairs : int
        New pairs per map.
    alpha : float
        The level the hypothesis's p is held to (its Holm step).
    replicates : int
    rng : numpy.random.Generator
    effect : float

    Returns
    -------
    float
        The share of replicates that confirm.
    """
    if pairs < 2 or replicates < 1:
        raise ParameterError(f"pairs, replicates: got {pairs} and {replicates}, expected at least 2 and 1")
    shifted = []
    for name, values in leads.items():
        values = np.asarray(values, np.float64) / scales[name]
        shifted.append(values - (1.0 - effect) * values.mean(axis=0))
    strata = np.repeat(np.arange(len(shifted)), pairs)
    confirmed = 0
    for _ in range(replicates):
        drawn = np.concatenate([values[rng.integers(0, values.shape[0], pairs)] for values in shifted])  # (M pairs, C)
        largest = max(stratified_t(Stratified.of(drawn[:, c], strata)).p_value for c in range(drawn.shape[1]))
        confirmed += bool(largest <= alpha)
    return confirmed / replicates
