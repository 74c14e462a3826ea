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

The sweep keeps every count in ``ncz`` and ``ng`` as an integer (a cell's pass holds its
copy of ``ng[cell]`` as float32 holding the same integers, exact below 2**24, far more words
than a neighbourhood holds) and relies on ``ng[c] = ncz[c] + the sum of ncz over c's
neighbours`` holding between cells (the start kernel makes it so, and every cell's pass
keeps it): while a cell is resampled only its own words change its neighbourhood sum, so
the change of ``ng[c]`` over the pass is its own counts' change.
``scripts/bench_chain_kernel.py`` times the sweep against an earlier commit's, on the
same inputs, and checks that the two leave the same bytes.

Two cells of one colour could be resampled side by side, word by word, each with its own
streams and its own copy of its sums (issue 55's "locality"): the same bytes, but slower at
R = 16 on the 2-core machine (27 against 19 ns a word-sample per chain on aerial-mosaic,
23 against 19 on reef-mosaic), although the pair's topic pass compiled to clean vector code.
That pass waits on loading Φ rows and the tables, not on its chain of additions (splitting
the chain in two made it slower too). Grouping words by id would not pay either: 44 % of
words already repeat the word before, and 87 % find their row of ``phiw`` among the last 32
distinct ones; merging 8 or 32 cells' words by id, each cell's in order, adds under 2 points.

Where a word's time goes (aerial-mosaic, R = 16, about 560 cycles a word for the 16 chains,
variants timed beside the kernel and dropped): the running sum is a chain of 64 dependent
float32 additions per vector (about 190 cycles, which no byte-keeping change shortens); the
rest is the draw after it (the search, the count changes, and the next word waiting on them).
Misses are small: one fixed row of ``phiw`` for every word saves 15 %; prefetching the next
cell's rows of ``ng`` and ``ncz`` (the ``_settle`` traffic), or ``_settle`` on one cached row,
saves nothing, nor does a prefetch of the next words' ``phiw`` rows (6 % slower). The random
numbers are vector code already; drawing a whole cell's uniforms before its words saves nothing.
The table of counts in float32 (one table, no separate factors, each change one addition) with
unsigned topic indices is 1.10x to 1.17x (11.4 to 11.5 against 12.6 to 13.4 ns a word-sample
per chain, CPU time, interleaved against 5073e36; reef-mosaic 1.09x), the same bytes.
Tried and left: the search without its early stop, or summing each block's eight comparisons as
a tree or into two accumulators (the search waits on a chain of 64 integer additions): LLVM
then vectorises across topics or relinks the sums into one chain, 1.2x to 3x slower; taking the
next word out of the counts before the search instead of after the draw: no change.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli._numba import njit
from curiosity_cli.topics._intrinsics import stack_array, stack_table
from curiosity_cli.topics._rng import below, next_state, stream_start, unit32

#: The most topics :func:`sweep_chains_kernel` holds (its stack tables' rows; ``FrozenChains`` allows K <= 127).
MAX_TOPICS = 128


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
def _last_positive(phiw, w, r, counts, alpha):
    """The last topic whose weight ``phiw[w, k, r] * (float32(counts[k, r]) + alpha)`` is positive in chain ``r``
    (``counts``: (K, R) neighbourhood sums, the word left out, integers or float32 holding integers): the draw
    when rounding left the target at or past the total."""
    k = phiw.shape[1] - 1
    while k > 0 and phiw[w, k, r] * (np.float32(counts[k, r]) + alpha) <= 0:
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
                    k = _last_positive(phiw, w, r, ng[cell], alpha)
            else:
                k = below(bits, n_topics)
            topics[i, r] = k
            _count(cell, k, r, ncz, ng, table)


@njit
def sweep_chains_kernel(cells, cell_first, cell_count, words, topics, phiw, ncz, ng, table, alpha, keys, counter):
    """One Gibbs sweep of every chain over ``cells`` in order, each chain's cell ``c`` from stream ``(counter, c)``.

    :class:`~curiosity_cli.topics.chains.FrozenChains` passes the cells colour by colour
    (module docstring). ``phiw.shape[1]`` (K) must be at most :data:`MAX_TOPICS`.

    ``keys`` is a tuple, so the number of chains is known when compiling: the loops over
    chains become vector code, and the per-chain sums live in registers (stack arrays).
    A cell's pass works on its own copy of the cell's neighbourhood sums ``ng[cell]``
    (the only counts it reads: its neighbours are of other colours) in a stack table
    (:func:`~curiosity_cli.topics._intrinsics.stack_table`) of float32 holding the
    integers exactly (below 2**24, so ``n - 1`` and ``n + 1`` are exact too): a weight's
    factor ``n + alpha`` is then the same float32 as ``float32(n) + alpha``, and each
    count change is one float addition to one table. Each word is taken out of the
    counts before its weights and counted at its new topic after the draw (exact
    leave-one-out); the topics index the table as unsigned integers, which numba does
    not check for negative (wrapped) indices. One pass over the topics makes the running
    sums and keeps them; the draw counts, per chain, the sums at or below its target, eight topics at a time,
    and stops once every chain's sum has passed its target (the sums never decrease).
    After the cell, :func:`_settle` writes its counts back.
    """
    n_topics = phiw.shape[1]
    n_chains = len(keys)
    if n_topics > MAX_TOPICS:
        raise ValueError("more topics than the stack tables hold")
    states = stack_array(keys, np.uint64)
    total = stack_array(keys, np.float32)
    targets = stack_array(keys, np.float32)
    chosen = stack_array(keys, np.int32)
    counts = stack_table(MAX_TOPICS, keys, np.float32)  # ng[cell] as exact float32 integers, the drawn word left out
    running = stack_table(MAX_TOPICS, keys, np.float32)  # the running sums of the weights
    for j in range(cells.shape[0]):
        cell = cells[j]
        for k in range(n_topics):
            for r in range(n_chains):
                counts[k, r] = np.float32(ng[cell, k, r])
        for r in range(n_chains):
            states[r] = stream_start(keys[r], counter, cell)
        for i in range(cell_first[cell], cell_first[cell] + cell_count[cell]):
            w = words[i]
            for r in range(n_chains):
                counts[np.uint64(topics[i, r]), r] -= 1  # unsigned: an index never negative, never wrapped
                total[r] = 0
            for k in range(n_topics):
                for r in range(n_chains):
                    total[r] += phiw[w, k, r] * (counts[k, r] + alpha)
                    running[k, r] = total[r]
            for r in range(n_chains):
                states[r], bits = next_state(states[r])
                targets[r] = unit32(bits) * total[r]
                chosen[r] = 0
            _count_at_or_below(running, targets, chosen, n_topics, n_chains)
            past = 0
            for r in range(n_chains):
                past |= np.int32(chosen[r] == n_topics)
            if past:  # rounding left some target at or past its total
                for r in range(n_chains):
                    if chosen[r] == n_topics:
                        chosen[r] = _last_positive(phiw, w, r, counts, alpha)
            for r in range(n_chains):
                topics[i, r] = chosen[r]
            for r in range(n_chains):
                counts[np.uint64(chosen[r]), r] += 1
        _settle(cell, counts, ncz, ng, table, n_topics, n_chains)


@njit(inline="always")
def _count_at_or_below(running, targets, chosen, n_topics, n_chains):
    """Add to ``chosen[r]`` the number of ``running[:n_topics, r]`` at or below ``targets[r]``: the first topic
    whose running sum exceeds the target. Eight topics at a time, stopping once no chain's sum is still at or
    below its target (the sums never decrease, so none after is); the check also keeps the compiler from
    turning the loop over topics, instead of the one over chains, into vector code."""
    below_any = 1
    k = 0
    while k + 8 <= n_topics:
        below_any = 0
        for q in range(8):
            for r in range(n_chains):
                below = np.int32(running[k + q, r] <= targets[r])
                chosen[r] += below
                if q == 7:
                    below_any |= below
        k += 8
        if below_any == 0:
            return
    while k < n_topics:
        for r in range(n_chains):
            chosen[r] += np.int32(running[k, r] <= targets[r])
        k += 1


@njit(inline="always")
def _settle(cell, counts, ncz, ng, table, n_topics, n_chains):
    """After a pass over ``cell`` that kept only its copy ``counts`` of ``ng[cell]`` current (float32 holding
    integers): the change is the cell's own words' (its neighbours are of other colours, unchanged meanwhile),
    so it goes to ``ng[cell]``, to the cell's own counts ``ncz[cell]`` and to every neighbour's sum.
    ``counts`` is left holding the change."""
    for k in range(n_topics):
        for r in range(n_chains):
            change = np.int32(counts[k, r]) - ng[cell, k, r]
            counts[k, r] = change
            ng[cell, k, r] += change
            ncz[cell, k, r] += change
    for j in range(table.shape[1]):
        d = table[cell, j]
        if d >= 0:
            for k in range(n_topics):
                for r in range(n_chains):
                    ng[d, k, r] += np.int32(counts[k, r])


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
