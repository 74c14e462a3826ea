"""Numba kernel of the mutual information two labelings share by chance.

Private: call :func:`curiosity_cli.evaluate.information.expected_mutual_information`.
Twin in ``tests/naive.py`` (section "chance").
"""

from __future__ import annotations

import math

from curiosity_cli._numba import njit

#: Terms of a cell's hypergeometric sum whose probability is below this share of its mode's are
#: left out: e^-50 (about 2e-22), far below what a float64 sum of probabilities near one keeps.
_TAIL_LOG = -50.0


@njit
def _log_pmf(n, a, b, total):
    """log P(n) of the hypergeometric law: ``n`` of ``b`` draws from ``total`` items of which ``a`` are marked."""
    return (
        math.lgamma(a + 1) + math.lgamma(b + 1) + math.lgamma(total - a + 1) + math.lgamma(total - b + 1)
        - math.lgamma(total + 1) - math.lgamma(n + 1) - math.lgamma(a - n + 1) - math.lgamma(b - n + 1)
        - math.lgamma(total - a - b + n + 1)
    )


@njit
def _cell_expectation(a, b, total, logs):
    """``E[(n / N) log(N n / (a b))]`` in nats over the hypergeometric law of one cell's count ``n``,
    walked out from its mode both ways until the probabilities fall below :data:`_TAIL_LOG` of the mode's;
    ``logs[n]`` is ``log(n)``."""
    low = max(1, a + b - total)  # n = 0 adds nothing
    high = min(a, b)
    if low > high:
        return 0.0
    mode = min(max((a + 1) * (b + 1) // (total + 2), low), high)
    log_mode = _log_pmf(mode, a, b, total)
    scale = math.log(total / (a * b))
    p_mode = math.exp(log_mode)
    floor = math.exp(log_mode + _TAIL_LOG)
    result = p_mode * mode / total * (scale + logs[mode])
    p = p_mode
    n = mode
    while n < high:
        p *= (a - n) * (b - n) / ((n + 1.0) * (total - a - b + n + 1.0))
        n += 1
        if p < floor:
            break
        result += p * n / total * (scale + logs[n])
    p = p_mode
    n = mode
    while n > low:
        p *= n * (total - a - b + n) / ((a - n + 1.0) * (b - n + 1.0))
        n -= 1
        if p < floor:
            break
        result += p * n / total * (scale + logs[n])
    return result


@njit
def expected_mi_kernel(rows, columns, total, logs):
    """Expected MI in nats of two labelings with marginal counts ``rows`` and ``columns`` (int64,
    each summing to ``total``) under the hypergeometric (permutation) model (Vinh, Epps & Bailey 2010);
    ``logs[n]`` is ``log(n)`` for ``n`` up to the largest count (a table: the sum takes one per term)."""
    result = 0.0
    for i in range(rows.shape[0]):
        if rows[i] == 0:
            continue
        for j in range(columns.shape[0]):
            if columns[j] > 0:
                result += _cell_expectation(rows[i], columns[j], total, logs)
    return result
