"""Weight functions: how much a walker wants to step into each neighbouring cell (paper section 4).

A weight function is a pure function of a :class:`Candidates` record, the facts about the
in-bounds 4-neighbours ``g_i`` of the walker's cell, and returns one weight per
candidate; the walker steps to ``g_i`` with probability ``weight_i / Σ weight``. The
facts are computed once per step for every weight function alike (so every run logs
them), which keeps each function a one-liner that is easy to check against the paper:

- ``random-walk``: 1 (eq. 7);
- ``stochastic-coverage``: ``1 / U(g_i)`` (eq. 8), with the coverage potential
  ``U(g) = Σ_j n_j / max(d²(g, c_j), min_d2)`` over the visited cells ``c_j`` with visit
  counts ``n_j``. ``d`` is the Euclidean distance in cell units. The clamp is ours: an
  already visited candidate has ``d = 0`` and, unclamped, weight 0 for ever; with the
  default ``min_d2 = 0.25`` a visited cell repels as if it were half a cell away;
- ``word-perplexity``: ``WordPerplexity(g_i) / U(g_i)`` (eqs. 9 and 11);
- ``topic-perplexity``: ``TopicPerplexity(g_i) / U(g_i)`` (eqs. 10 and 12).

To add a weight function, write ``def mine(candidates: Candidates) -> np.ndarray`` and
add it to :data:`WEIGHT_FUNCTIONS` under a name; configs can then name it in
``explore.weight_functions``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Candidates:
    """What the walker knows about its neighbouring cells at one step.

    Attributes
    ----------
    cells : (n,) int64 ndarray
        Row-major indices of the in-bounds 4-neighbours, in the order up, down, left,
        right (those that exist).
    coverage : (n,) float64 ndarray
        The coverage potential ``U(g_i)`` (module docstring), > 0.
    word_perplexity, topic_perplexity : (n,) float64 ndarrays
        Eqs. 11 and 12 of each candidate's words under the model learned so far (the
        words are seen, not added to the model); 1.0 for a cell without words.
    """

    cells: np.ndarray
    coverage: np.ndarray
    word_perplexity: np.ndarray
    topic_perplexity: np.ndarray


WeightFunction = Callable[[Candidates], np.ndarray]


def random_walk(candidates: Candidates) -> np.ndarray:
    """Every neighbour equally likely (eq. 7)."""
    return np.ones(candidates.cells.shape[0])


def stochastic_coverage(candidates: Candidates) -> np.ndarray:
    """Repelled by visited cells (eq. 8)."""
    return 1.0 / candidates.coverage


def word_perplexity(candidates: Candidates) -> np.ndarray:
    """Drawn to cells whose words the model finds surprising, repelled by visited ones (eq. 9)."""
    return candidates.word_perplexity / candidates.coverage


def topic_perplexity(candidates: Candidates) -> np.ndarray:
    """Drawn to cells whose topics are rare on the path so far, repelled by visited ones (eq. 10)."""
    return candidates.topic_perplexity / candidates.coverage


#: Every weight function by the name configs use; the paper's four first, in its order.
WEIGHT_FUNCTIONS: dict[str, WeightFunction] = {
    "random-walk": random_walk,
    "stochastic-coverage": stochastic_coverage,
    "word-perplexity": word_perplexity,
    "topic-perplexity": topic_perplexity,
}


def coverage_potential(candidates: np.ndarray, visited: np.ndarray, visits: np.ndarray, grid_cols: int, min_d2: float) -> np.ndarray:
    """``U(g) = Σ_j n_j / max(d²(g, c_j), min_d2)`` for each candidate cell ``g``.

    Parameters
    ----------
    candidates : (n,) int ndarray
        Row-major cell indices.
    visited : (m,) int ndarray
        The distinct visited cells ``c_j``.
    visits : (m,) int ndarray
        ``n_j``, how often each was visited.
    grid_cols : int
        Cells per row of the grid (to turn indices into rows and columns).
    min_d2 : float
        Lower clamp on the squared distance, > 0.

    Returns
    -------
    (n,) float64 ndarray
    """
    c_rows, c_cols = np.divmod(np.asarray(candidates, np.int64), grid_cols)
    v_rows, v_cols = np.divmod(np.asarray(visited, np.int64), grid_cols)
    d2 = (c_rows[:, None] - v_rows[None, :]) ** 2 + (c_cols[:, None] - v_cols[None, :]) ** 2
    return (np.asarray(visits, np.float64)[None, :] / np.maximum(d2, min_d2)).sum(axis=1)
