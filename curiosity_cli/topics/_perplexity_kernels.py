"""Numba kernels of the perplexities of words outside the model (paper eqs. 11 and 12).

Private: call :mod:`curiosity_cli.topics.perplexity`. Arrays as in ``_sampler``;
twins in ``tests/naive.py`` (section "topic model").
"""

from __future__ import annotations

import numpy as np

from curiosity_cli._numba import njit
from curiosity_cli.topics._rng import next_state, stream_start
from curiosity_cli.topics._sampler import lane_draw, row_dot, weight


@njit
def word_perplexity_kernel(words, nwk, nk, n_topics, alpha, beta, vbeta):
    """``exp(-mean_i log sum_k phi_k(w_i) P(k | path))`` in float64, for >= 1 word.

    ``phi_k(w) = (nwk[w, k] + beta) / (nk[k] + V beta)``, ``P(k | path) = (nk[k] +
    alpha) / (N + K alpha)`` with ``N = sum_k nk[k]``.
    """
    total = 0.0
    for k in range(n_topics):
        total += nk[k]
    mixture = np.zeros(nk.shape[0])
    for k in range(n_topics):
        mixture[k] = (nk[k] + alpha) / (total + n_topics * alpha) / (nk[k] + vbeta)
    log_sum = 0.0
    for i in range(words.shape[0]):
        log_sum += np.log(row_dot(nwk, words[i], beta, mixture))
    return np.exp(-log_sum / words.shape[0])


@njit
def topic_perplexity_kernel(
    words, cell, nwk, nk, inv, ng, n_topics, alpha, alpha32, beta32, key, counter, own, sweeps, smoothed, free_stream
):
    """Draw temporary topics for ``words`` at ``cell``; ``exp(-mean_i log P(z_i | path))``.

    Word ``i`` (in order) gets a topic drawn as the sampler does (eq. 5, float32, lane
    order; see ``_sampler``) with neighbourhood counts ``ng[cell]`` (none when ``own``)
    plus the temporary topics of words ``0 .. i - 1``; each of ``sweeps - 1`` further
    passes draws every word again, in order, against the others' temporary topics. All
    draws come from one stream, ``(counter, free_stream + 1 + cell)``. Nothing of the model
    changes. ``P(k | path)`` in float64 is ``(nk[k] + alpha) / (N + K alpha)`` when
    ``smoothed``, else ``nk[k] / N`` (``N = sum_k nk[k]``), and a topic the path has
    not seen makes the perplexity infinite. Returns ``(perplexity, topics)``.
    """
    kp = nk.shape[0]
    # one row of neighbourhood counts: the model's (or none), plus the temporary topics
    local = np.zeros((1, kp), ng.dtype) if own else ng[cell : cell + 1].copy()
    p = np.zeros(kp, np.float32)
    topics = np.empty(words.shape[0], np.int32)
    state = stream_start(key, counter, free_stream + 1 + cell)
    for sweep in range(sweeps):
        for i in range(words.shape[0]):
            if sweep:
                local[0, topics[i]] -= 1
            w = words[i]
            for k in range(kp):
                p[k] = weight(nwk, inv, local, w, 0, k, alpha32, beta32)
            state, bits = next_state(state)
            z = lane_draw(p, bits)
            topics[i] = z
            local[0, z] += 1
    total = 0.0
    for k in range(n_topics):
        total += nk[k]
    log_sum = 0.0
    for i in range(words.shape[0]):
        z = topics[i]
        if smoothed:
            log_sum += np.log((nk[z] + alpha) / (total + n_topics * alpha))
        elif nk[z] == 0:
            return np.inf, topics
        else:
            log_sum += np.log(nk[z] / total)
    return np.exp(-log_sum / words.shape[0]), topics
