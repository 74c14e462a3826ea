"""Numba kernel of the held-out words' scores under a path's model.

Private: call :func:`curiosity_cli.label.heldout.word_log2`; twin in ``tests/naive.py``
(``heldout_log2_naive``).
"""

from __future__ import annotations

import numpy as np

from curiosity_cli._numba import njit


@njit
def word_log2_kernel(mixture, topic_words, words, cells, out):
    """``out[i] = log2 Σ_k mixture[cells[i], k] * topic_words[words[i], k]``, the sum in topic order, in float64.

    ``mixture`` (n_cells, K) and ``topic_words`` (V, K) float64: θ_c and φ_k(w); ``words``,
    ``cells`` (H,) int: each scored word's id and cell; ``out`` (H,) float64.
    """
    for i in range(words.shape[0]):
        c = cells[i]
        w = words[i]
        total = 0.0
        for k in range(mixture.shape[1]):
            total += mixture[c, k] * topic_words[w, k]
        out[i] = np.log2(total)


@njit
def heldout_sums_kernel(scores, unvisited, out):
    """``out[0] = Σ_i scores[i]`` and ``out[1] = Σ_i scores[i]`` over the ``i`` with ``unvisited[i]``, each added
    in index order in float64 (no reordering: the same bits on every machine).

    ``scores`` (H,) float64; ``unvisited`` (H,) bool; ``out`` (2,) float64.
    """
    total = 0.0
    part = 0.0
    for i in range(scores.shape[0]):
        total += scores[i]
        if unvisited[i]:
            part += scores[i]
    out[0] = total
    out[1] = part
