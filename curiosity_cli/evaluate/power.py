"""What an experiment could detect: the power of its paired comparison.

A ratio of mean MI (topic perplexity over another walker) from 10 or 20 paired
restarts is noisy; a verdict of "no lead" means little unless it says how large a lead
the same experiment would have found (the ratio's intervals and its null reference:
:mod:`~curiosity_cli.evaluate.comparisons`). These functions answer that from the observed
paired differences, under a two-sided paired Student-t test (the Wilcoxon test the
report uses needs about 5 % more pairs for normally distributed differences).
"""

from __future__ import annotations

import numpy as np

#: The chance of detecting a lead that a power figure is quoted at.
POWER = 0.8
#: The lead whose pairs a headline says it would need: 10 % above the next best.
TARGET_LEAD = 0.10
_MOST_PAIRS = 1_000_000
# scipy's non-central t is NaN far in the tail at one degree of freedom; two pairs say
# too little to quote a power anyway
_FEWEST_PAIRS = 3


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
