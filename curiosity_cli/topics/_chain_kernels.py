"""Numba kernels of frozen-Φ labelling with many chains in lock-step.

Private: call :class:`curiosity_cli.topics.chains.FrozenChains`, which validates inputs
and owns the arrays. Every kernel has a slow twin in ``tests/naive.py`` (section
"chains in lock-step"), which follows one chain at a time.

``R`` chains label the same words (the same cells, word order and neighbour table) with
their own word-topic counts Φ_r and their own random streams. The chain index is the
innermost, contiguous dimension of every per-chain array, so each step over topics is one
vector operation across chains, and the chains hide each other's latency (a single
chain's draw waits for the count change of the word before it):

- ``topics`` (N, R) int8: each word's topic in each chain (K <= 127).
- ``phiw`` (V, K, R) float32: ``(float32(n_kw) + beta) * float32(1 / (n_k + V beta))``,
  the factors of eq. 5 that frozen counts fix.
- ``ncz``, ``ng`` (n_cells, K, R) int32: each chain's cell topic counts and neighbourhood
  sums (a cell's counts plus its neighbours').
- ``keys``: a tuple of R uint64, ``mix(seed)`` of each chain; a tuple, so that the
  number of chains is known when compiling (one compilation per R, cached on disk).

The draw, per chain, for word ``i`` of cell ``c`` with word id ``w`` and topic ``old``::

    p[k] = phiw[w, k] * (float32(ng[c, k] - (k == old)) + alpha)    # the word left out

in float32; an inverse-CDF search over the float32 running sum ``s[k] = s[k-1] + p[k]``
(from ``s[-1] = 0``): ``target = unit32(bits) * s[K-1]`` and the topic is the first
``k`` with ``s[k] > target`` (rounding can leave none; then the last topic with
``p[k] > 0``). Every
operation is per chain, so a chain's draws do not depend on which chains share its block.

A sweep visits the cells colour by colour (:func:`neighbour_colouring`: all cells of
colour 0 in index order, then colour 1, ...). Cells of one colour are never neighbours, so
none of them reads a count another one changes: the GPU kernels
(``_chain_kernels_cuda.py``) resample all cells of a colour at once and give these
kernels' bytes.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli._numba import njit
from curiosity_cli.topics._intrinsics import stack_array
from curiosity_cli.topics._rng import below, next_state, stream_start, unit32


@njit
def neighbour_colouring(table):
    """Greedy proper colouring of the neighbour graph: neighbours get different colours.

    Cells are coloured in index order, each with the smallest colour that none of its
    already-coloured neighbours has (a 4-neighbour grid gets the checkerboard
    ``(row + col) % 2``). Returns (n_cells,) int32 colours. A cell's neighbourhood sum
    holds its own counts and its neighbours', so while the cells of one colour are
    resampled each one's sum changes only by its own words.
    """
    n_cells, width = table.shape
    colour = np.full(n_cells, -1, np.int32)
    taken = np.full(width + 1, -1, np.int64)  # a cell has at most width neighbours
    for c in range(n_cells):
        for j in range(width):
            d = table[c, j]
            if d >= 0 and colour[d] >= 0:
                taken[colour[d]] = c
        pick = 0
        while taken[pick] == c:
            pick += 1
        colour[c] = pick
    return colour


@njit(inline="always")
def _count(cell, k, r, ncz, ng, table):
    """Count one more word of ``cell`` at topic ``k`` in chain ``r``: in its cell counts and
    the neighbourhood sums of the cell and of every neighbour."""
    ncz[cell, k, r] += 1
    ng[cell, k, r] += 1
    for j in range(table.shape[1]):
        d = table[cell, j]
        if d >= 0:
            ng[d, k, r] += 1


@njit
def _last_positive(phiw, ng, cell, w, r, alpha):
    """The last topic whose weight is positive in chain ``r`` (the word not in ``ng[cell]``):
    the draw when rounding left the target at or past the total."""
    k = phiw.shape[1] - 1
    while k > 0 and phiw[w, k, r] * (np.float32(ng[cell, k, r]) + alpha) <= 0:
        k -= 1
    return k


@njit
def start_chain_kernel(r, placed, cells, cell_first, cell_count, words, topics, phiw, ncz, ng, table, alpha, key):
    """Give chain ``r`` its starting topics; its counts ``ncz[:, :, r]``, ``ng[:, :, r]`` must be zero.

    Uniform (``placed`` False): the ``j``-th of ``cells`` draws each word's topic
    uniformly from stream ``(j, cell)``, as ``TopicModel.restart`` does. Placed: cells in
    the order given, each word drawn from eq. 5 given the words placed before it (its
    cell's and its neighbours'), from stream ``(0, cell)``, then counted.
    """
    n_topics = phiw.shape[1]
    running = np.empty(n_topics, np.float32)
    for j in range(cells.shape[0]):
        cell = cells[j]
        state = stream_start(key, np.uint64(0) if placed else np.uint64(j), cell)
        for i in range(cell_first[cell], cell_first[cell] + cell_count[cell]):
            state, bits = next_state(state)
            if placed:
                w = words[i]
                total = np.float32(0.0)
                for k in range(n_topics):
                    total += phiw[w, k, r] * (np.float32(ng[cell, k, r]) + alpha)
                    running[k] = total
                target = unit32(bits) * total
                k = 0
                while k < n_topics and running[k] <= target:
                    k += 1
                if k == n_topics:
                    k = _last_positive(phiw, ng, cell, w, r, alpha)
            else:
                k = below(bits, n_topics)
            topics[i, r] = k
            _count(cell, k, r, ncz, ng, table)


@njit
def sweep_chains_kernel(cells, cell_first, cell_count, words, topics, phiw, ncz, ng, table, alpha, keys, counter):
    """One Gibbs sweep of every chain over ``cells`` in order, each chain's cell ``c`` from stream ``(counter, c)``.

    :class:`~curiosity_cli.topics.chains.FrozenChains` passes the cells colour by colour
    (module docstring).

    ``keys`` is a tuple, so the number of chains is known when compiling: the loops over
    chains become vector code, and the per-chain sums live in registers (stack arrays).
    Each word is taken out of ``ng[cell]`` before its weights and counted at its new
    topic after the draw (exact leave-one-out); the cell's own counts and its
    neighbours' sums are brought up to date once, after the cell. The weights are
    computed twice, once for the total and once for the search, which costs less than
    keeping them: a stored weight table makes the compiler guard every load against it.
    """
    n_topics = phiw.shape[1]
    n_chains = len(keys)
    states = stack_array(keys, np.uint64)
    old = stack_array(keys, np.int32)
    total = stack_array(keys, np.float32)
    targets = stack_array(keys, np.float32)
    running = stack_array(keys, np.float32)
    chosen = stack_array(keys, np.int32)
    for j in range(cells.shape[0]):
        cell = cells[j]
        for r in range(n_chains):
            states[r] = stream_start(keys[r], counter, cell)
        for i in range(cell_first[cell], cell_first[cell] + cell_count[cell]):
            w = words[i]
            for r in range(n_chains):
                old[r] = topics[i, r]
                ng[cell, old[r], r] -= 1
                total[r] = 0
            for k in range(n_topics):
                for r in range(n_chains):
                    total[r] += phiw[w, k, r] * (np.float32(ng[cell, k, r]) + alpha)
            for r in range(n_chains):
                states[r], bits = next_state(states[r])
                targets[r] = unit32(bits) * total[r]
                running[r] = 0
                chosen[r] = 0
            # the number of running sums at or below the target is the first topic whose sum exceeds it
            for k in range(n_topics):
                for r in range(n_chains):
                    running[r] += phiw[w, k, r] * (np.float32(ng[cell, k, r]) + alpha)
                    chosen[r] += np.int32(running[r] <= targets[r])
            for r in range(n_chains):
                new = chosen[r]
                if new == n_topics:  # rounding left the target at or past the total
                    new = _last_positive(phiw, ng, cell, w, r, alpha)
                topics[i, r] = new
                ng[cell, new, r] += 1
        _settle(cell, ncz, ng, table)


@njit(inline="always")
def _settle(cell, ncz, ng, table):
    """After a pass over ``cell`` that kept only ``ng[cell]`` current: its own counts are
    its neighbourhood sum less its neighbours' own counts, and the change goes to every
    neighbour's sum."""
    width = table.shape[1]
    for k in range(ng.shape[1]):
        for r in range(ng.shape[2]):
            now = ng[cell, k, r]
            for j in range(width):
                d = table[cell, j]
                if d >= 0:
                    now -= ncz[d, k, r]
            change = now - ncz[cell, k, r]
            ncz[cell, k, r] = now
            for j in range(width):
                d = table[cell, j]
                if d >= 0:
                    ng[d, k, r] += change


@njit
def ml_chains_kernel(cells, cell_first, cell_count, words, phid, ng, alpha, keys, out):
    """Each chain's most probable topic of every word of ``cells``, the word included.

    ``phid`` (V, K, R) float64 holds ``(n_kw + beta) * (1 / (n_k + V beta))``; the
    weight ``phid[w, k, r] * (ng[c, k, r] + alpha)`` in float64 is
    ``TopicModel.ml_topics``'s, ties to the lowest ``k``. ``keys`` is a tuple of R
    (only its length is used, as in :func:`sweep_chains_kernel`); ``out`` (N, R), in
    the order of ``cells``.
    """
    n_topics = phid.shape[1]
    n_chains = len(keys)
    best = stack_array(keys, np.float64)
    best_k = stack_array(keys, np.int32)
    at = 0
    for j in range(cells.shape[0]):
        cell = cells[j]
        for i in range(cell_first[cell], cell_first[cell] + cell_count[cell]):
            w = words[i]
            for r in range(n_chains):
                best[r] = -1.0
                best_k[r] = 0
            for k in range(n_topics):
                for r in range(n_chains):
                    v = phid[w, k, r] * (ng[cell, k, r] + alpha)
                    better = v > best[r]
                    best[r] = v if better else best[r]
                    best_k[r] = np.int32(k) if better else best_k[r]
            for r in range(n_chains):
                out[at, r] = best_k[r]
            at += 1
