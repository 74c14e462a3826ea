"""Numba kernels of the spatial topic model: initial topics, refinement, ML topics.

Private: call the methods of :class:`curiosity_cli.topics.model.TopicModel`, which
validate inputs and own the arrays (their layout and the sampler: ``_sampler.py``).
Every kernel has a slow reference twin in ``tests/naive.py`` (section "topic model").
"""

from __future__ import annotations

import numpy as np

from curiosity_cli._numba import njit
from curiosity_cli.topics._intrinsics import fetch_add
from curiosity_cli.topics._rng import below, next_state, stream_start, unit64
from curiosity_cli.topics._sampler import (
    gibbs_cell, gibbs_cell_frozen, refresh_inverse, row_dot, weights_scratch,
)

# threads refining a batch phase take cells in chunks of this many
_CHUNK = 4


@njit(inline="always")
def count_word(cell, k, ncz, ng, table):
    """Count one more word of ``cell`` at topic ``k``: in its cell counts and in the
    neighbourhood sums of the cell and of every neighbour."""
    ncz[cell, k] += 1
    ng[cell, k] += 1
    for j in range(table.shape[1]):
        d = table[cell, j]
        if d >= 0:
            ng[d, k] += 1


@njit
def add_cell_kernel(
    cell, first, count, words, topics, nwk, nk, inv, ncz, ng, table, n_topics, vbeta, key, counter, update_phi
):
    """Give the words of a new cell uniformly random topics and count them.

    Draws from the stream ``(counter, cell)``. ``update_phi`` False leaves ``nwk``,
    ``nk`` and ``inv`` alone (a model whose word-topic counts are frozen).
    """
    state = stream_start(key, counter, cell)
    for i in range(first, first + count):
        state, bits = next_state(state)
        k = below(bits, n_topics)
        topics[i] = k
        count_word(cell, k, ncz, ng, table)
        if update_phi:
            nwk[words[i], k] += 1
            nk[k] += 1
    if update_phi:
        refresh_inverse(nk, inv, n_topics, vbeta)


@njit
def remove_cells_kernel(cells, cell_first, cell_count, words, topics, nwk, nk, inv, ncz, ng, table, n_topics, vbeta, update_phi):
    """Take every word of ``cells`` out of the counts: what :func:`add_cell_kernel` and
    refinement counted, undone (``nwk``, ``nk`` and ``inv`` only when ``update_phi``)."""
    for j in range(cells.shape[0]):
        cell = cells[j]
        first = cell_first[cell]
        for i in range(first, first + cell_count[cell]):
            k = topics[i]
            ncz[cell, k] -= 1
            ng[cell, k] -= 1
            for column in range(table.shape[1]):
                d = table[cell, column]
                if d >= 0:
                    ng[d, k] -= 1
            if update_phi:
                nwk[words[i], k] -= 1
                nk[k] -= 1
    if update_phi:
        refresh_inverse(nk, inv, n_topics, vbeta)


@njit
def redraw_topics_kernel(cells, cell_first, cell_count, words, topics, nwk, nk, inv, ncz, ng, table, n_topics, vbeta, key, update_phi):
    """Draw every word's topic anew, the ``j``-th of ``cells`` from stream ``(j, cell)``,
    as :func:`add_cell_kernel` did when the cells were added in that order. The counts
    must be zero (``nwk``, ``nk`` only when ``update_phi``)."""
    for j in range(cells.shape[0]):
        cell = cells[j]
        add_cell_kernel(
            cell, cell_first[cell], cell_count[cell], words, topics, nwk, nk, inv, ncz, ng, table, n_topics, vbeta,
            key, np.uint64(j), update_phi,
        )


@njit
def refine_cells_kernel(
    cells, cell_first, cell_count, words, topics, nwk, nk, inv, ncz, ng, table, alpha, beta, vbeta, key, counter,
    update_phi,
):
    """Refine ``cells`` one after the other; the ``j``-th uses stream ``(counter + j, cell)``."""
    p = weights_scratch(inv)
    for j in range(cells.shape[0]):
        cell = cells[j]
        state = stream_start(key, counter + np.uint64(j), cell)
        gibbs_cell(
            cell, cell_first[cell], cell_count[cell], words, topics, nwk, nk, inv, ncz, ng, table, p,
            alpha, beta, vbeta, state, update_phi,
        )


@njit
def refine_phase_share(
    taken, cells, previous, before, nwk, nk, inv, work_nk, work_inv,
    cell_first, cell_count, words, topics, ncz, ng, table, n_topics, alpha, beta, vbeta, key, counter,
):
    """Refine cells of one batch phase until none is left; several threads run this at once.

    A batch sweep (``TopicModel.refine_batch``) visits the observed cells in phases: no
    two cells of a phase are within graph distance 2, so they share no cell count or
    neighbourhood sum and may be refined at the same time. Each caller takes chunks of
    ``_CHUNK`` cells from the shared counter ``taken[0]`` (atomically), so a thread on a
    busier core simply takes fewer.

    Each caller has its own copy ``nwk``, ``nk``, ``inv`` of the word-topic counts, equal
    to the counts at the end of the phase before once it has merged that phase's changes
    (``previous``, empty for the first phase) into it; every caller merges the same
    changes, in parallel. Each cell is then refined on that copy, with totals reset from
    it (``work_nk``, ``work_inv``), and its changes are taken back out of the copy. So
    every cell sees the counts of the phase's start plus its own changes and draws from
    stream ``(counter, cell)``, whichever caller refines it and however many there are.
    A model with frozen counts uses :func:`refine_frozen_phase` instead.

    Parameters
    ----------
    taken : (1,) int64 ndarray
        Cells of ``cells`` handed out so far; 0 at the start of the phase.
    cells, previous : (n,) int64 ndarrays
        The phase's cells and the phase before's.
    before : (capacity,) ndarray of the topic type
        Receives the phase-start topics of the words refined; holds those of
        ``previous``.
    nwk, nk, inv : (V, Kp) int32, (Kp,) int32, (Kp,) float32 ndarrays
        The caller's copy of the counts.
    work_nk, work_inv : (Kp,) int32, float32 ndarrays
        The caller's scratch, each on cache lines of its own.
    """
    if previous.shape[0]:
        merge_phase(previous, cell_first, cell_count, words, before, topics, nwk, nk, inv, n_topics, vbeta)
    p = weights_scratch(work_inv)
    n = cells.shape[0]
    while True:
        start = fetch_add(taken, 0, _CHUNK)
        if start >= n:
            break
        for index in range(start, min(start + _CHUNK, n)):
            cell = cells[index]
            first = cell_first[cell]
            last = first + cell_count[cell]
            for i in range(first, last):
                before[i] = topics[i]
            for k in range(nk.shape[0]):
                work_nk[k] = nk[k]
                work_inv[k] = inv[k]
            gibbs_cell(
                cell, first, cell_count[cell], words, topics, nwk, work_nk, work_inv, ncz, ng, table, p,
                alpha, beta, vbeta, stream_start(key, counter, cell), True,
            )
            # take the cell's changes back out, the next cell must not see them
            # (unconditionally: a no-op for an unchanged word, and no branch to mispredict)
            for i in range(first, last):
                w = words[i]
                nwk[w, topics[i]] -= 1
                nwk[w, before[i]] += 1


@njit
def refine_frozen_phase(taken, cells, phiw, cell_first, cell_count, words, topics, ncz, ng, table, alpha, key, counter):
    """:func:`refine_phase_share` for a model with frozen word-topic counts.

    Nothing any cell writes is read by another cell of the phase, so the callers share
    everything but their weights scratch: no copies, no merge. ``phiw`` is
    :func:`~curiosity_cli.topics._sampler.gibbs_cell_frozen`'s.
    """
    p = np.zeros(phiw.shape[1], np.float32)
    n = cells.shape[0]
    while True:
        start = fetch_add(taken, 0, _CHUNK)
        if start >= n:
            break
        for index in range(start, min(start + _CHUNK, n)):
            cell = cells[index]
            gibbs_cell_frozen(
                cell, cell_first[cell], cell_count[cell], words, topics, phiw, ncz, ng, table, p, alpha,
                stream_start(key, counter, cell),
            )


@njit
def merge_phase(cells, cell_first, cell_count, words, before, topics, nwk, nk, inv, n_topics, vbeta):
    """Move each word of ``cells`` from topic ``before[i]`` to ``topics[i]`` in ``nwk``, ``nk``, ``inv``.

    Every word, changed or not: skipping the unchanged ones cost more in mispredicted
    branches than their no-op updates.
    """
    for index in range(cells.shape[0]):
        cell = cells[index]
        first = cell_first[cell]
        for i in range(first, first + cell_count[cell]):
            a = before[i]
            b = topics[i]
            w = words[i]
            nwk[w, a] -= 1
            nwk[w, b] += 1
            nk[a] -= 1
            nk[b] += 1
    refresh_inverse(nk, inv, n_topics, vbeta)


@njit
def refine_realtime_kernel(
    limit, eta, order, group_start,
    cell_first, cell_count, words, topics, nwk, nk, inv, ncz, ng, table, alpha, beta, vbeta, key, counter,
    update_phi, recent, window, tau, carry,
):
    """Algorithm 2 of the paper: refine picked observation times until ``limit`` of the budget is spent.

    A budget is spent over one or more calls, each resuming where the last stopped, so
    that a large budget returns to Python often enough for a signal to stop it; the picks
    are the same however it is cut.

    Parameters
    ----------
    limit : int
        Pick until ``done + idle`` reaches it (at most the budget).
    order : (n_observed,) int32 ndarray
        Observed cells in the order they were added.
    group_start : (T + 1,) int64 ndarray, T >= 1
        Observation time ``t`` holds ``order[group_start[t]:group_start[t + 1]]``.
    carry : (5,) uint64 ndarray
        The picks' stream state (``stream_start(key, counter, pick_stream)`` before the
        first call), words sampled (``done``), picks without words (``idle``), picks, and
        words sampled at the newest time; read, and updated in place.

    Notes
    -----
    Picks draw from stream ``(counter, pick_stream)``: with probability ``eta`` (or
    always, with one time) the newest time, else a uniform earlier one (eq. 6); or, when
    ``recent``, with probability ``eta`` a uniform one of the newest ``window`` times,
    else time ``floor(T u^(1 / tau))`` for a uniform ``u`` (a Beta(tau, 1) draw by age:
    recent times more often). Pick ``j`` refines each cell of its time with stream
    ``(counter + 1 + j, cell)``. Each word sampled spends one unit of the budget, and so
    does a pick that finds no words, so the loop ends after at most ``limit`` picks even
    if every reachable cell is empty.
    """
    n_times = group_start.shape[0] - 1
    p = weights_scratch(inv)
    picker = carry[0]
    done = np.int64(carry[1])
    idle = np.int64(carry[2])
    picks = np.int64(carry[3])
    newest_done = np.int64(carry[4])
    while done + idle < limit:
        picker, bits = next_state(picker)
        if recent:
            newest = unit64(bits) < eta
            picker, bits = next_state(picker)
            if newest:
                last = min(window, n_times)
                t = n_times - last + below(bits, last)
            else:
                t = min(np.int64(np.floor(unit64(bits) ** (1.0 / tau) * n_times)), n_times - 1)
        elif n_times == 1 or unit64(bits) < eta:
            t = n_times - 1
        else:
            picker, bits = next_state(picker)
            t = below(bits, n_times - 1)
        pick_counter = counter + np.uint64(1 + picks)
        sampled = 0
        for index in range(group_start[t], group_start[t + 1]):
            cell = order[index]
            state = stream_start(key, pick_counter, cell)
            gibbs_cell(
                cell, cell_first[cell], cell_count[cell], words, topics, nwk, nk, inv, ncz, ng, table, p,
                alpha, beta, vbeta, state, update_phi,
            )
            sampled += cell_count[cell]
        done += sampled
        if t == n_times - 1:
            newest_done += sampled
        if sampled == 0:
            idle += 1
        picks += 1
    carry[0] = picker
    carry[1] = done
    carry[2] = idle
    carry[3] = picks
    carry[4] = newest_done


@njit
def ml_topics_kernel(cells, cell_first, cell_count, words, nwk, nk, ng, n_topics, alpha, beta, vbeta, out):
    """Most probable topic of every word of ``cells`` (in that order), the word included.

    ``argmax_k (nwk[w, k] + beta) * (1 / (nk[k] + V beta)) * (ng[c, k] + alpha)`` in
    float64 (``alpha``, ``beta`` float64), ties to the lowest ``k``; written to ``out``.
    """
    norm = np.empty(n_topics)
    for k in range(n_topics):
        norm[k] = 1.0 / (nk[k] + vbeta)
    at = 0
    for j in range(cells.shape[0]):
        cell = cells[j]
        first = cell_first[cell]
        for i in range(first, first + cell_count[cell]):
            w = words[i]
            best = -1.0
            best_k = 0
            for k in range(n_topics):
                v = (nwk[w, k] + beta) * norm[k] * (ng[cell, k] + alpha)
                if v > best:
                    best = v
                    best_k = k
            out[at] = best_k
            at += 1


@njit
def log_likelihood_sum_kernel(cells, cell_first, cell_count, words, nwk, nk, ng, n_topics, alpha, beta, vbeta):
    """``(total, n)``: the sum over the ``n`` words of ``cells`` of ``log sum_k phi_k(w) theta_c(k)``, float64.

    ``phi_k(w) = (nwk[w, k] + beta) / (nk[k] + V beta)`` and ``theta_c(k) = (ng[c, k] +
    alpha) / (sum_k ng[c, k] + K alpha)``, every count including the word itself. A word
    id repeated in a cell (aerial cells hold ~260 words of ~25 ids) has the same term each
    time: it is computed once per cell and added as often, in word order, so the sum is
    the same to the last bit as term by term.
    """
    kp = nk.shape[0]
    norm = np.zeros(kp)
    for k in range(n_topics):
        norm[k] = 1.0 / (nk[k] + vbeta)
    mixture = np.zeros(kp)
    term = np.zeros(nwk.shape[0])
    seen = np.full(nwk.shape[0], -1, np.int64)  # the cell whose term `term[w]` holds
    total = 0.0
    n = 0
    for j in range(cells.shape[0]):
        cell = cells[j]
        first = cell_first[cell]
        size = 0.0
        for k in range(n_topics):
            size += ng[cell, k]
        scale = 1.0 / (size + n_topics * alpha)
        for k in range(n_topics):
            mixture[k] = norm[k] * (ng[cell, k] + alpha) * scale
        for i in range(first, first + cell_count[cell]):
            w = words[i]
            if seen[w] != cell:
                term[w] = np.log(row_dot(nwk, w, beta, mixture))
                seen[w] = cell
            total += term[w]
            n += 1
    return total, n


@njit
def distance2_colouring(table):
    """Greedy colouring in which cells within graph distance 2 get different colours.

    Cells are coloured in index order, each with the smallest colour that no
    already-coloured cell within distance 2 has. Returns (n_cells,) int32 colours.
    """
    n_cells, width = table.shape
    colour = np.full(n_cells, -1, np.int32)
    # a cell has at most width + width * width cells within distance 2
    taken = np.full(width * width + width + 1, -1, np.int64)
    for c in range(n_cells):
        for j in range(width):
            d = table[c, j]
            if d < 0:
                continue
            if colour[d] >= 0:
                taken[colour[d]] = c
            for jj in range(width):
                e = table[d, jj]
                if e >= 0 and e != c and colour[e] >= 0:
                    taken[colour[e]] = c
        pick = 0
        while taken[pick] == c:
            pick += 1
        colour[c] = pick
    return colour
