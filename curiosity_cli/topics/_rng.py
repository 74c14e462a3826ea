"""Inline counter-based random numbers for the topic kernels (splitmix64).

Every piece of random work (adding one cell, refining one cell in one sweep, one
realtime refinement's cell picks, one temporary labelling) draws from its own stream,
whose start is a hash of the model's seed, the model's event counter and a cell id. A
stream therefore does not depend on which thread runs it or on what ran before it, and
the model's whole random state is its seed and one 64-bit counter.

splitmix64 (Steele, Lea & Flood 2014): the state advances by a fixed odd constant and
each output is a bijective mix of the state; it passes BigCrush and costs a few
multiplications, which is what the hot loop can afford. Private: ``tests/naive.py``
holds a pure-Python twin.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli._numba import njit

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_S30 = np.uint64(30)
_S27 = np.uint64(27)
_S31 = np.uint64(31)
_S32 = np.uint64(32)
_S40 = np.uint64(40)
_S11 = np.uint64(11)
_TWO_M24 = np.float32(2.0**-24)
_TWO_M53 = 2.0**-53


@njit
def mix(z):
    """splitmix64's output function: a bijection of uint64 that scrambles every bit."""
    z = np.uint64(z)
    z = (z ^ (z >> _S30)) * _MIX1
    z = (z ^ (z >> _S27)) * _MIX2
    return z ^ (z >> _S31)


@njit
def stream_start(key, counter, cell):
    """Start state of the stream of ``(counter, cell)`` for a model whose key is ``key``.

    ``key`` is ``mix(seed)``; ``counter`` (uint64) numbers the model's random events;
    ``cell`` (int, >= 0) tells apart the streams of one event.
    """
    return mix(np.uint64(key) ^ mix(np.uint64(counter) ^ (np.uint64(cell) * _GOLDEN)))


@njit
def next_state(state):
    """``(new state, 64 random bits)``."""
    state = np.uint64(state) + _GOLDEN
    return state, mix(state)


@njit
def unit32(bits):
    """float32 uniform on [0, 1) from the top 24 bits (exact: 24 bits fit the mantissa)."""
    return np.float32(bits >> _S40) * _TWO_M24


@njit
def unit64(bits):
    """float64 uniform on [0, 1) from the top 53 bits."""
    return np.float64(bits >> _S11) * _TWO_M53


@njit
def below(bits, n):
    """Integer in ``[0, n)`` from the top 32 bits (multiply-shift; bias below n / 2**32)."""
    return np.int64(((bits >> _S32) * np.uint64(n)) >> _S32)
