"""The Gibbs sampler of the spatial topic model: one cell's words, the draw, its weights.

Private: used by ``_gibbs_kernels`` and ``_perplexity_kernels``; twins in
``tests/naive.py`` (section "topic model").

The arrays, for ``n_cells`` cells, vocabulary ``V``, ``K`` topics padded to
``Kp = 8 * ceil(K / 8)`` columns (padding columns stay zero, and ``inv`` is zero there,
so padded topics get probability exactly 0 and the dense loops need no remainder):

- ``words`` (capacity,) int32, ``topics`` (capacity,) int8/int16/int32: the words of
  observed cell ``c`` are ``[cell_first[c], cell_first[c] + cell_count[c])``.
- ``nwk`` (V, Kp) int32 word-topic counts: one word's counts over topics are contiguous,
  which is the inner loop of the sampler.
- ``nk`` (Kp,) int32 topic totals; ``inv`` (Kp,) float32, ``inv[k] = float32(1 /
  (nk[k] + V beta))`` computed in float64, kept in step with ``nk``.
- ``ncz`` (n_cells, Kp) int32 topic counts of each cell.
- ``ng`` (n_cells, Kp) int32 neighbourhood sums: ``ncz[c]`` plus ``ncz[d]`` for every
  ``d`` in ``table[c]``, for every cell, observed or not (an unobserved cell counts
  nothing itself, and its sum is the prior a candidate cell there would see).
- ``table`` (n_cells, width) int32 neighbours, -1 padded, symmetric.

The sampler (eq. 5 of the paper), for word ``i`` of cell ``c`` with word id ``w``, with
the word removed from every count::

    p[k] = (float32(nwk[w, k]) + beta) * inv[k] * (float32(ng[c, k]) + alpha)

in float32, left to right. The draw is an inverse-CDF search over topics in *lane
order*: lane ``j`` (0..7) holds topics ``j, j + 8, j + 16, ...``; lane sums are
accumulated in float32 in that order, the total is ``lane[0] + lane[1] + ... + lane[7]``,
``target = u * total`` with ``u`` a float32 uniform, the lane is the first whose running
sum exceeds ``target``, and within it the topic is the first whose running sum (from 0)
exceeds ``target - (sum of the earlier lanes)``. Rounding can leave ``target`` past the
last running sum; then the last lane (topic) with positive mass is taken. Lanes make the
sums 8 independent chains of additions instead of one, and the search 16 steps, not 64.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli._numba import njit
from curiosity_cli.topics._rng import next_state, unit32

LANES = 8


@njit
def inverse(count, vbeta):
    """``float32(1 / (count + V beta))``, the cached topic normaliser."""
    return np.float32(1.0 / (count + vbeta))


@njit(inline="always")
def weight(nwk, inv, ng, w, cell, k, alpha, beta):
    """Eq. 5's unnormalised weight of topic ``k`` for word ``w`` of ``cell``, in float32."""
    return (np.float32(nwk[w, k]) + beta) * inv[k] * (np.float32(ng[cell, k]) + alpha)


@njit
def refresh_inverse(nk, inv, n_topics, vbeta):
    """Recompute ``inv`` from ``nk`` for the real topics (padding stays 0)."""
    for k in range(n_topics):
        inv[k] = inverse(nk[k], vbeta)


@njit(inline="always")
def lane_draw(p, bits):
    """Topic drawn with probability proportional to ``p`` (length a multiple of 8), in lane order.

    Both searches count the running sums at or below the target rather than break out of
    a loop: the same topic as a first-exceeding search (running sums never decrease),
    without unpredictable branches. Written without indexing tuples by a variable or
    storing partial sums, both of which numba makes slow here.
    """
    n_blocks = p.shape[0] // LANES
    l0 = l1 = l2 = l3 = l4 = l5 = l6 = l7 = np.float32(0.0)
    for b in range(n_blocks):
        o = b * LANES
        l0 += p[o]
        l1 += p[o + 1]
        l2 += p[o + 2]
        l3 += p[o + 3]
        l4 += p[o + 4]
        l5 += p[o + 5]
        l6 += p[o + 6]
        l7 += p[o + 7]
    c0 = l0
    c1 = c0 + l1
    c2 = c1 + l2
    c3 = c2 + l3
    c4 = c3 + l4
    c5 = c4 + l5
    c6 = c5 + l6
    c7 = c6 + l7
    target = unit32(bits) * c7
    lane = (
        int(c0 <= target) + int(c1 <= target) + int(c2 <= target) + int(c3 <= target)
        + int(c4 <= target) + int(c5 <= target) + int(c6 <= target) + int(c7 <= target)
    )
    # the sum of the lanes before the chosen one: the last running sum at or below target
    below_lane = np.float32(0.0)
    below_lane = c0 if c0 <= target else below_lane
    below_lane = c1 if c1 <= target else below_lane
    below_lane = c2 if c2 <= target else below_lane
    below_lane = c3 if c3 <= target else below_lane
    below_lane = c4 if c4 <= target else below_lane
    below_lane = c5 if c5 <= target else below_lane
    below_lane = c6 if c6 <= target else below_lane
    below_lane = c7 if c7 <= target else below_lane
    if lane == LANES:
        # rounding left the target at or past the total: the last lane with mass
        lane = (
            7 if l7 > 0 else 6 if l6 > 0 else 5 if l5 > 0 else 4 if l4 > 0
            else 3 if l3 > 0 else 2 if l2 > 0 else 1 if l1 > 0 else 0
        )
    rest = target - below_lane
    running = np.float32(0.0)
    block = 0
    for b in range(n_blocks):
        running += p[b * LANES + lane]
        block += int(running <= rest)
    if block == n_blocks:
        block = n_blocks - 1
        while p[block * LANES + lane] == 0:
            block -= 1
    return block * LANES + lane


@njit(inline="always")
def row_dot(nwk, w, beta, weights):
    """``sum_k (nwk[w, k] + beta) * weights[k]`` in float64, over 8 partial sums.

    ``weights`` has ``Kp`` entries, zero for padding topics. Eight partial sums break
    the chain of dependent additions a single running sum would be.
    """
    s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = 0.0
    for b in range(weights.shape[0] // LANES):
        o = b * LANES
        s0 += (nwk[w, o] + beta) * weights[o]
        s1 += (nwk[w, o + 1] + beta) * weights[o + 1]
        s2 += (nwk[w, o + 2] + beta) * weights[o + 2]
        s3 += (nwk[w, o + 3] + beta) * weights[o + 3]
        s4 += (nwk[w, o + 4] + beta) * weights[o + 4]
        s5 += (nwk[w, o + 5] + beta) * weights[o + 5]
        s6 += (nwk[w, o + 6] + beta) * weights[o + 6]
        s7 += (nwk[w, o + 7] + beta) * weights[o + 7]
    return ((s0 + s1) + (s2 + s3)) + ((s4 + s5) + (s6 + s7))


@njit
def weights_scratch(inv):
    """(Kp,) float32 zeros for :func:`gibbs_cell`'s weights ``p``, 2 KiB from ``inv`` modulo 4 KiB.

    The dense loop stores ``p`` and loads ``inv``; where the two lie a multiple of 4 KiB
    apart, the processor takes each load for a reload of a store (4K aliasing) and
    waits: up to 12 % per word, depending on where the allocator happened to put ``p``.
    """
    kp = inv.shape[0]
    buffer = np.zeros(kp + 1024, np.float32)
    gap = ((inv.ctypes.data + 2048 - buffer.ctypes.data) % 4096) // 4
    return buffer[gap : gap + kp]


@njit(inline="always")
def settle_cell(cell, ncz, ng, table):
    """After a pass over ``cell`` that kept only ``ng[cell]`` current: its own counts are
    its neighbourhood sum less its neighbours' own counts (which no pass over this cell
    changes), and the change goes to every neighbour's sum."""
    width = table.shape[1]
    for k in range(ng.shape[1]):
        now = ng[cell, k]
        for j in range(width):
            d = table[cell, j]
            if d >= 0:
                now -= ncz[d, k]
        change = now - ncz[cell, k]
        ncz[cell, k] = now
        if change != 0:
            for j in range(width):
                d = table[cell, j]
                if d >= 0:
                    ng[d, k] += change


@njit
def gibbs_cell(
    cell, first, count, words, topics, nwk, nk, inv, ncz, ng, table, p, alpha, beta, vbeta, state, update_phi
):
    """One Gibbs pass over the words of ``cell`` in order (eq. 5, exact leave-one-out).

    ``p`` is (Kp,) float32 scratch whose padding entries are 0, best from
    :func:`weights_scratch`. Returns the new state.

    The weights, so the draws, are those of removing each word from the counts, drawing,
    and counting it at its new topic before the next word. But the counts the pass reads
    (``nwk``, ``nk``, ``inv``, ``ng[cell]``) change only after the next word's dense
    loop, and only if the topic changed; the next word's weights at the two topics
    involved, and a word's own weight at its old topic (from its counts minus one), are
    then computed one by one. The counts the pass does not read (``ncz[cell]``, the
    neighbours' ``ng``) are brought up to date once, at the end. Why: the dense loop
    reads ``inv``, ``ng[cell]`` and a row of ``nwk`` as vectors, and a vector load soon
    after a scalar store into it waits for the store to retire, as does a load from an
    address a multiple of 4 KiB from a recent store (``ncz[cell]`` and ``ng[cell]`` of
    arrays allocated alike; on a 64-column grid, ``ng`` rows of neighbours above and
    below). Against updating every count at once, a word took 8 % less time on the
    synthetic benchmark corpus and 15 % less on the aerial one, where fewer words change
    topic. Written as one loop with a last pass that only moves the last word: with the
    move in a helper function, or its flag in a boolean, numba generated code 20-50 %
    slower.
    """
    kp = p.shape[0]
    last = first + count
    # the previous word: id (-1: none), old and new topic, and the normaliser of its old
    # topic without it; still counted at its old topic
    held_w = -1
    held_old = held_new = 0
    held_inv = np.float32(0.0)
    for i in range(first, last + 1):
        if i < last:
            w = words[i]
            for k in range(kp):
                p[k] = weight(nwk, inv, ng, w, cell, k, alpha, beta)
        moved = held_w >= 0 and held_new != held_old
        if moved:
            ng[cell, held_old] -= 1
            ng[cell, held_new] += 1
            if update_phi:
                nwk[held_w, held_old] -= 1
                nwk[held_w, held_new] += 1
                nk[held_old] -= 1
                nk[held_new] += 1
                inv[held_old] = held_inv
                inv[held_new] = inverse(nk[held_new], vbeta)
        if i == last:
            break
        if moved:
            p[held_old] = weight(nwk, inv, ng, w, cell, held_old, alpha, beta)
            p[held_new] = weight(nwk, inv, ng, w, cell, held_new, alpha, beta)
        # this word's weight at its old topic, with the word removed (eq. 5's weight of
        # the counts minus one, in the same float32 operations)
        old = topics[i]
        own_nwk = nwk[w, old]
        own_inv = inv[old]
        if update_phi:
            own_nwk -= 1
            own_inv = inverse(nk[old] - 1, vbeta)
        p[old] = (np.float32(own_nwk) + beta) * own_inv * (np.float32(ng[cell, old] - 1) + alpha)
        state, bits = next_state(state)
        new = lane_draw(p, bits)
        topics[i] = new
        held_w, held_old, held_new, held_inv = w, old, new, own_inv
    settle_cell(cell, ncz, ng, table)
    return state


@njit
def gibbs_cell_frozen(cell, first, count, words, topics, phiw, ncz, ng, table, p, alpha, state):
    """:func:`gibbs_cell` for a model whose word-topic counts are frozen, the same draws.

    ``phiw`` (V, Kp) float32 holds ``(float32(nwk[w, k]) + beta) * inv[k]``, the first two
    factors of every weight, which frozen counts never change: each weight is then one
    product, ``phiw[w, k] * (float32(ng[cell, k]) + alpha)``, the same float32 value as
    :func:`weight` computes left to right. The deferred neighbourhood update is that of
    :func:`gibbs_cell`, for the same reason.
    """
    kp = p.shape[0]
    last = first + count
    held = False  # whether the previous word moved and ng[cell] does not show it yet
    held_old = held_new = 0
    for i in range(first, last + 1):
        if i < last:
            w = words[i]
            for k in range(kp):
                p[k] = phiw[w, k] * (np.float32(ng[cell, k]) + alpha)
        if held:
            ng[cell, held_old] -= 1
            ng[cell, held_new] += 1
        if i == last:
            break
        if held:
            p[held_old] = phiw[w, held_old] * (np.float32(ng[cell, held_old]) + alpha)
            p[held_new] = phiw[w, held_new] * (np.float32(ng[cell, held_new]) + alpha)
        old = topics[i]
        p[old] = phiw[w, old] * (np.float32(ng[cell, old] - 1) + alpha)
        state, bits = next_state(state)
        new = lane_draw(p, bits)
        topics[i] = new
        held, held_old, held_new = new != old, old, new
    settle_cell(cell, ncz, ng, table)
    return state
