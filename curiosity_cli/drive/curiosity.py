"""Cell curiosity: topic perplexity of each image cell, decayed over frames (paper 5.2).

Perplexity of an image cell ``c`` at frame ``t`` is eq. 12 of the paper on the topics
the words of ``c`` hold in the stream model after the frame's refinement::

    p_c(t) = exp(-(1/W_c) Σ_i log P(z_i | path)),   P(k | path) = (n_k + α) / (N + Kα)

with ``n_k`` the words of topic ``k`` among the frames in memory (``N = Σ n_k``) and
``W_c`` the words of the cell; a cell without words has perplexity 1 (no surprise), as
in :mod:`curiosity_cli.topics.perplexity`. The paper draws temporary topics for a cell
not yet in the model; here the cell is in the model, so its refined topics are used.

Every image cell (a fixed place in the camera's view, not in the world) keeps a score::

    s_c(1) = p_c(1)
    s_c(t) = γ · s_c(t-1) + (1 - γ) · p_c(t)        t > 1

applied once per frame, after refinement. The target is the cell with the highest
score (ties: the first in row-major order).
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.errors import ParameterError


def cell_perplexity(cell_counts: np.ndarray, topic_totals: np.ndarray, alpha: float) -> np.ndarray:
    """Topic perplexity of each cell from its topic counts (module docstring).

    Parameters
    ----------
    cell_counts : (n_cells, K) int ndarray
        Words of each topic in each cell.
    topic_totals : (K,) int ndarray
        ``n_k`` over the memory (includes the cells' own words).
    alpha : float
        Dirichlet prior on topics, > 0.

    Returns
    -------
    (n_cells,) float64 ndarray
        >= 1; 1.0 for a cell without words.
    """
    cell_counts = np.asarray(cell_counts, np.float64)
    totals = np.asarray(topic_totals, np.float64)
    if cell_counts.ndim != 2 or totals.shape != (cell_counts.shape[1],):
        raise ParameterError(
            f"cell_counts, topic_totals: got shapes {cell_counts.shape} and {totals.shape}, expected (n, K) and (K,)"
        )
    log_p = np.log((totals + alpha) / (totals.sum() + totals.size * alpha))
    words = cell_counts.sum(axis=1)
    mean_log = (cell_counts @ log_p) / np.maximum(words, 1)
    return np.where(words > 0, np.exp(-mean_log), 1.0)


class CuriosityScores:
    """Per-cell scores decayed with ``gamma`` (module docstring), and the target cell.

    Parameters
    ----------
    gamma : float
        0 <= gamma < 1: the weight of the past.
    grid : (int, int)
        Image cells per column and per row.
    """

    def __init__(self, gamma: float, grid: tuple[int, int]):
        if not 0 <= gamma < 1:
            raise ParameterError(f"gamma: got {gamma}, expected 0 <= gamma < 1")
        self.gamma = float(gamma)
        self.grid = grid
        self.scores: np.ndarray | None = None

    def update(self, perplexity: np.ndarray) -> np.ndarray:
        """Fold one frame's perplexities in; return the (rows, cols) float64 scores."""
        perplexity = np.asarray(perplexity, np.float64).reshape(self.grid)
        if self.scores is None:
            self.scores = perplexity.copy()
        else:
            self.scores = self.gamma * self.scores + (1 - self.gamma) * perplexity
        return self.scores

    def target(self) -> tuple[int, int]:
        """(row, col) of the highest score."""
        if self.scores is None:
            raise ParameterError("target: no frame scored yet")
        flat = int(np.argmax(self.scores))
        return flat // self.grid[1], flat % self.grid[1]
