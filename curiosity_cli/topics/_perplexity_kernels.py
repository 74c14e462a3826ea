"""Numba kernels of the perplexities of words outside the model (paper eqs. 11 and 12).

Private: call :mod:`curiosity_cli.topics.perplexity`. Arrays as in ``_sampler``;
twins in ``tests/naive.py`` (section "topic model").
"""

from __future__ import annotations

import numpy as np

from curiosity_cli._numba import njit
from curiosity_cli.topics._rng import next_state, stream_start
from curiosity_cli.topics._sampler import inverse, lane_draw, row_dot


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
    words, cell, nwk, nk, inv, ng, n_topics, alpha, alpha32, beta32, vbeta, key, counter, own, sweeps, argmax, added,
    update_phi, smoothed, free_stream,
):
    """Give ``words`` at ``cell`` temporary topics; ``exp(-mean_i log P(z_i | path))``.

    Word ``i`` (in order) gets the topic of eq. 5's weights (float32, as the sampler forms
    them; see ``_sampler``): drawn in lane order when not ``argmax``, else the largest
    weight, the lowest topic of a tie. The weights count, as neighbourhood, ``ng[cell]``
    (none when ``own``) plus the temporary topics of words ``0 .. i - 1``; when ``added``
    (and ``update_phi``: a frozen model's Φ stays), those topics count in ``nwk`` and
    ``nk`` as well. Each of ``sweeps - 1`` further passes takes every word's topic out of
    those counts, chooses it again and counts it back. Draws come from one stream,
    ``(counter, free_stream + 1 + cell)``. Nothing of the model changes. ``P(k | path)``
    in float64 is ``(n[k] + alpha) / (N + K alpha)`` when ``smoothed``, else ``n[k] / N``,
    with ``n[k]`` the model's ``nk[k]``, plus the temporary topics at ``k`` when they
    count in ``nk`` (``N = sum_k n[k]``); a topic of ``n[k] = 0`` makes the perplexity
    infinite. Returns ``(perplexity, topics)``.
    """
    kp = nk.shape[0]
    n_words = words.shape[0]
    local = np.zeros(kp, ng.dtype) if own else ng[cell].copy()
    # the temporary topics' counts in Φ, when they count there: a row per distinct word id
    # (row[i]), their topic totals and the normalisers of those. The rows are float32:
    # float32(nwk) + row is exact below 2^24, so the weights are float32(nwk + row)'s, and
    # the dense loop converts no int64 sum (which made it about twice as slow)
    counted = added and update_phi
    row = np.zeros(n_words, np.int64)
    n_rows = 1
    if counted:
        order = np.argsort(words, kind="mergesort")
        n_rows = 0
        for j in range(n_words):
            if j == 0 or words[order[j]] != words[order[j - 1]]:
                n_rows += 1
            row[order[j]] = n_rows - 1
    extra_wk = np.zeros((n_rows, kp), np.float32)
    extra_k = np.zeros(kp, np.int32)
    scale = inv.copy()
    p = np.zeros(kp, np.float32)
    topics = np.empty(n_words, np.int32)
    state = stream_start(key, counter, free_stream + 1 + cell)
    for sweep in range(sweeps):
        for i in range(n_words):
            w = words[i]
            r = row[i]
            if sweep:
                z = topics[i]
                local[z] -= 1
                if counted:
                    extra_wk[r, z] -= 1
                    extra_k[z] -= 1
                    scale[z] = inverse(nk[z] + extra_k[z], vbeta)
            for k in range(kp):
                p[k] = (np.float32(nwk[w, k]) + extra_wk[r, k] + beta32) * scale[k] * (np.float32(local[k]) + alpha32)
            if argmax:
                z = 0
                for k in range(1, kp):
                    if p[k] > p[z]:
                        z = k
            else:
                state, bits = next_state(state)
                z = lane_draw(p, bits)
            topics[i] = z
            local[z] += 1
            if counted:
                extra_wk[r, z] += 1
                extra_k[z] += 1
                scale[z] = inverse(nk[z] + extra_k[z], vbeta)
    total = 0.0
    for k in range(n_topics):
        total += nk[k] + extra_k[k]
    log_sum = 0.0
    for i in range(n_words):
        z = topics[i]
        n = nk[z] + extra_k[z]
        if smoothed:
            log_sum += np.log((n + alpha) / (total + n_topics * alpha))
        elif n == 0:
            return np.inf, topics
        else:
            log_sum += np.log(n / total)
    return np.exp(-log_sum / n_words), topics
