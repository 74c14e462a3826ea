"""How sure a headline is: the ratio's bootstrap interval, and what the experiment could detect.

A ratio of mean MI (topic perplexity over the next best walker) from 10 or 20 paired
restarts is noisy; a verdict of "no lead" means little unless it says how large a lead
the same experiment would have found. These functions answer that from the observed
paired differences, under a two-sided paired Student-t test (the Wilcoxon test the
report uses needs about 5 % more pairs for normally distributed differences).
"""

from __future__ import annotations

import numpy as np

#: The chance of detecting a lead that a power figure is quoted at.
POWER = 0.8
#: The lead whose pairs a headline says it would need: 10 % above the next best.
TARGET_LEAD = 0.10
#: Bootstrap resamples of the ratio's interval; fixed, with a fixed seed, so a report is
#: the same every time it is written.
RESAMPLES = 10_000
_MOST_PAIRS = 1_000_000
# scipy's non-central t is NaN far in the tail at one degree of freedom; two pairs say
# too little to quote a power anyway
_FEWEST_PAIRS = 3


def ratio_interval(a: np.ndarray, b: np.ndarray, confidence: float = 0.95, resamples: int = RESAMPLES) -> tuple[float, float]:
    """Percentile bootstrap interval of ``mean(a) / mean(b)``, resampling pairs.

    Parameters
    ----------
    a, b : (n,) float ndarrays
        Paired values: the same restart of two walkers.
    confidence : float
        Of the interval, in (0, 1).
    resamples : int
        Bootstrap resamples, drawn from a fixed seed.

    Returns
    -------
    (float, float)
        Lower and upper bound; NaN for fewer than two pairs, or when a resample's
        ``b`` has mean 0.
    """
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    if a.shape != b.shape or a.ndim != 1:
        raise ValueError(f"a, b: got shapes {a.shape} and {b.shape}, expected two (n,) arrays of pairs")
    if a.size < 2:
        return np.nan, np.nan
    picks = np.random.default_rng(0).integers(0, a.size, (resamples, a.size))
    with np.errstate(divide="ignore", invalid="ignore"):  # a resample whose b is all 0 has no ratio
        ratios = a[picks].mean(axis=1) / b[picks].mean(axis=1)
    if not np.isfinite(ratios).all():
        return np.nan, np.nan
    low, high = np.quantile(ratios, [(1 - confidence) / 2, (1 + confidence) / 2])
    return float(low), float(high)


def t_test_power(difference: float, sd: float, pairs: int, alpha: float = 0.05) -> float:
    """The chance a two-sided paired t-test at ``alpha`` finds a true mean difference.

    Parameters
    ----------
    difference : float
        The true mean paired difference.
    sd : float
        Standard deviation of the paired differences, > 0.
    pairs : int
        Number of pairs, >= 3.
    alpha : float
        Significance level.
    """
    from scipy import stats

    df = pairs - 1
    critical = stats.t.ppf(1 - alpha / 2, df)
    shift = difference * np.sqrt(pairs) / sd
    return float(stats.nct.sf(critical, df, shift) + stats.nct.cdf(-critical, df, shift))


def detectable_difference(sd: float, pairs: int, power: float = POWER, alpha: float = 0.05) -> float:
    """The smallest true mean paired difference found with chance ``power`` from ``pairs`` pairs.

    NaN for fewer than three pairs or no spread.
    """
    from scipy import optimize

    if pairs < _FEWEST_PAIRS or not sd > 0:
        return np.nan
    high = sd
    while t_test_power(high, sd, pairs, alpha) < power:
        high *= 2
    return float(optimize.brentq(lambda d: t_test_power(d, sd, pairs, alpha) - power, 0.0, high, xtol=1e-12 * sd))


def pairs_needed(difference: float, sd: float, power: float = POWER, alpha: float = 0.05) -> int | None:
    """The fewest pairs, at least three, with which a paired t-test finds ``difference`` with chance ``power``.

    None when there is no spread to go by, or more than a million pairs would be needed.
    """
    if not sd > 0 or not difference > 0:
        return None
    if t_test_power(difference, sd, _MOST_PAIRS, alpha) < power:
        return None
    low = high = _FEWEST_PAIRS
    while t_test_power(difference, sd, high, alpha) < power:
        low, high = high, high * 2
    while low < high:  # the fewest pairs with enough power; power grows with pairs
        middle = (low + high) // 2
        low, high = (middle + 1, high) if t_test_power(difference, sd, middle, alpha) < power else (low, middle)
    return low
