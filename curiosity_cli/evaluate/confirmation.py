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
