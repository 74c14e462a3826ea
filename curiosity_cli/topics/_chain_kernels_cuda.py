"""CUDA kernels of frozen-Φ labelling: the GPU twins of ``_chain_kernels.py``, the same bytes.

Private: :class:`curiosity_cli.topics.chains.FrozenChains` (``device="cuda"``) validates
inputs, owns the arrays and calls these. Their slow twins are the CPU kernels themselves
(``tests/topics/test_chains_cuda.py`` compares them byte for byte, under numba's CUDA
simulator on any machine and on a real GPU by ``scripts/device_check.sh``), whose own
twins are in ``tests/naive.py``.

The arrays are the CPU kernels' (``_chain_kernels.py``): ``topics`` (N, R) int8, ``phiw``
(V, K, R) float32, ``ncz``, ``ng`` (n_cells, K, R) int32, the chain index innermost, so
the threads of one cell read consecutive addresses. ``keys`` is an (R,) uint64 array
here (R is a launch size, not a compile-time constant).

One thread per (cell, chain) of one colour (``_chain_kernels.neighbour_colouring``):
the cells of a colour are never neighbours, so a thread reads no count another thread of
the launch writes. It copies its cell's neighbourhood sums ``ng[cell, :, r]`` into local
memory, resamples the cell's words in order exactly as ``sweep_chains_kernel`` does (the
same stream ``(counter, cell)``, the same float32 operations in the same order), then
writes the cell's sums and counts back and adds the change to each neighbour's sums with
integer atomics, whose order does not change the result. Launching the colours one after
the other is therefore the CPU's sweep, colour by colour, cell by cell.

**The same bytes.** Every float32 sum and product is written as ``fadd`` / ``fmul``,
which on a GPU are libdevice's ``fadd_rn`` / ``fmul_rn``: correctly rounded and never
contracted, whereas plain ``a * b + c`` is fused into one multiply-add by NVVM even
without fast-math, and rounds differently from the CPU (``docs/PERFORMANCE.md``).
numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``) has no libdevice; there the same
names are numpy float32 scalar operations (one rounding each, no fusion), and the
unsigned 64-bit products and sums of the random streams are wrapped explicitly (numpy
would warn on their overflow).
"""

from __future__ import annotations

import math

import numpy as np

from curiosity_cli._numba import import_cuda
from curiosity_cli.topics._rng import _GOLDEN, _MIX1, _MIX2, _S27, _S30, _S31, _S32, _S40, _TWO_M24

cuda = import_cuda()
try:
    from numba.cuda import config as cuda_config  # noqa: E402  (numba-cuda's own settings)
except ImportError:  # older numba-cuda read numba's
    from numba.core import config as cuda_config

#: Whether these kernels run on numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``).
SIMULATED = bool(getattr(cuda_config, "ENABLE_CUDASIM", 0))
#: Threads per CUDA block of the sweep and ML kernels.
THREADS_PER_BLOCK = 128
#: The most topics a thread's local copy of its neighbourhood sums holds (K <= 127).
MAX_TOPICS = 128

if SIMULATED:
    _MASK64 = (1 << 64) - 1

    def fadd(a, b):
        """float32 ``a + b``, one rounding (numpy scalars)."""
        return np.float32(a) + np.float32(b)

    def fmul(a, b):
        """float32 ``a * b``, one rounding (numpy scalars)."""
        return np.float32(a) * np.float32(b)

    def dadd(a, b):
        return np.float64(a) + np.float64(b)

    def dmul(a, b):
        return np.float64(a) * np.float64(b)

    def umul(a, b):
        """uint64 ``a * b`` modulo 2**64."""
        return np.uint64((int(a) * int(b)) & _MASK64)

    def uadd(a, b):
        """uint64 ``a + b`` modulo 2**64."""
        return np.uint64((int(a) + int(b)) & _MASK64)

else:
    from numba.cuda import libdevice

    fadd, fmul = libdevice.fadd_rn, libdevice.fmul_rn
    dadd, dmul = libdevice.dadd_rn, libdevice.dmul_rn

    @cuda.jit(device=True, inline=True)
    def umul(a, b):
        return a * b

    @cuda.jit(device=True, inline=True)
    def uadd(a, b):
        return a + b


@cuda.jit(device=True, inline=True)
def _mix(z):
    """``_rng.mix``."""
    z = umul(z ^ (z >> _S30), _MIX1)
    z = umul(z ^ (z >> _S27), _MIX2)
    return z ^ (z >> _S31)


@cuda.jit(device=True, inline=True)
def _stream_start(key, counter, cell):
    """``_rng.stream_start``."""
    return _mix(key ^ _mix(counter ^ umul(np.uint64(cell), _GOLDEN)))


@cuda.jit(device=True, inline=True)
def _weight(phiw, w, k, r, count, alpha):
    """``phiw[w, k, r] * (float32(count) + alpha)``, never fused."""
    return fmul(phiw[w, k, r], fadd(np.float32(count), alpha))


@cuda.jit(cache=True)
def sweep_colour_kernel(colour_cells, n_chains, cell_first, cell_count, words, topics, phiw, ncz, ng, table, alpha, keys,
                        counter):
    """Resample every word of every chain in the cells of one colour (``colour_cells``): one thread per (cell, chain).

    ``sweep_chains_kernel`` restricted to these cells, with the cells in parallel (module docstring).
    """
    t = cuda.grid(1)
    if t >= colour_cells.shape[0] * n_chains:
        return
    r = t % n_chains
    cell = colour_cells[t // n_chains]
    n_topics = phiw.shape[1]
    sums = cuda.local.array(MAX_TOPICS, np.int32)
    for k in range(n_topics):
        sums[k] = ng[cell, k, r]
    state = _stream_start(keys[r], counter, cell)
    first = cell_first[cell]
    for i in range(first, first + cell_count[cell]):
        w = words[i]
        old = np.int32(topics[i, r])
        sums[old] -= 1
        total = np.float32(0.0)
        for k in range(n_topics):
            total = fadd(total, _weight(phiw, w, k, r, sums[k], alpha))
        state = uadd(state, _GOLDEN)
        bits = _mix(state)
        target = fmul(fmul(np.float32(bits >> _S40), _TWO_M24), total)
        # the first topic whose running sum exceeds the target: the CPU counts the sums at or
        # below it, the same number since a float32 sum of non-negative terms never decreases
        running = np.float32(0.0)
        new = np.int32(0)
        while new < n_topics:
            running = fadd(running, _weight(phiw, w, new, r, sums[new], alpha))
            if running > target:
                break
            new += 1
        if new == n_topics:  # rounding left the target at or past the total: the last positive weight
            new = n_topics - 1
            while new > 0 and _weight(phiw, w, new, r, sums[new], alpha) <= np.float32(0.0):
                new -= 1
        topics[i, r] = new
        sums[new] += 1
    width = table.shape[1]
    for k in range(n_topics):
        change = sums[k] - ng[cell, k, r]
        if change != 0:
            ng[cell, k, r] = sums[k]
            ncz[cell, k, r] += change
            for j in range(width):
                d = table[cell, j]
                if d >= 0:
                    cuda.atomic.add(ng, (d, k, r), change)


@cuda.jit(cache=True)
def ml_kernel(n_chains, cell_first, cell_count, words, counts, allowed, beta, norm, ng, alpha, out):
    """``ml_chains_kernel`` over every cell in index order: one thread per (cell, chain), ``out`` (N, R) int16.

    The weight ``phid * (float64(ng[cell, k, r]) + alpha)`` in float64, ties to the lowest
    topic, with ``phid = (float64(counts[w, k, r]) + beta) * norm[k, r]`` computed here
    as :class:`~curiosity_cli.topics.chains.FrozenChains` computes it in numpy for the CPU, 0 where
    ``allowed[w, k, r]`` is False.
    """
    t = cuda.grid(1)
    if t >= cell_first.shape[0] * n_chains:
        return
    r = t % n_chains
    cell = t // n_chains
    n_topics = counts.shape[1]
    first = cell_first[cell]
    for i in range(first, first + cell_count[cell]):
        w = words[i]
        best = np.float64(-1.0)
        best_k = 0
        for k in range(n_topics):
            phid = dmul(dadd(np.float64(counts[w, k, r]), beta), norm[k, r]) if allowed[w, k, r] else np.float64(0.0)
            v = dmul(phid, dadd(np.float64(ng[cell, k, r]), alpha))
            if v > best:
                best = v
                best_k = k
        out[i, r] = best_k


@cuda.jit(cache=True)
def phiw_kernel(counts, allowed, beta, inv, phiw):
    """eq. 5's fixed factors, as numpy computes them for the CPU: ``phiw = (float32(counts) + beta) * inv[k, r]``
    in float32 where ``allowed``, else 0, one thread per element of the (V, K, R) arrays."""
    t = cuda.grid(1)
    n_topics, n_chains = counts.shape[1], counts.shape[2]
    if t >= counts.shape[0] * n_topics * n_chains:
        return
    r = t % n_chains
    k = (t // n_chains) % n_topics
    w = t // (n_chains * n_topics)
    phiw[w, k, r] = fmul(fadd(np.float32(counts[w, k, r]), beta), inv[k, r]) if allowed[w, k, r] else np.float32(0.0)


@cuda.jit(cache=True)
def start_uniform_kernel(n_chains, n_topics, cell_first, cell_count, topics, ncz, keys):
    """``start_chain_kernel``'s uniform start of every chain, one thread per (cell, chain), cells in index order:
    cell ``c`` draws its words' topics from stream ``(c, c)`` and counts them in ``ncz`` (zero before);
    the neighbourhood sums follow (:func:`neighbour_sums_kernel`)."""
    t = cuda.grid(1)
    if t >= cell_first.shape[0] * n_chains:
        return
    r = t % n_chains
    cell = t // n_chains
    state = _stream_start(keys[r], np.uint64(cell), cell)
    first = cell_first[cell]
    for i in range(first, first + cell_count[cell]):
        state = uadd(state, _GOLDEN)
        k = np.int32(((_mix(state) >> _S32) * np.uint64(n_topics)) >> _S32)
        topics[i, r] = k
        ncz[cell, k, r] += 1


@cuda.jit(cache=True)
def neighbour_sums_kernel(n_chains, ncz, table, ng):
    """``ng[c] = ncz[c] + the sum of ncz over c's neighbours``, one thread per (cell, chain): the sums the CPU
    builds word by word, the same integers."""
    t = cuda.grid(1)
    if t >= ncz.shape[0] * n_chains:
        return
    r = t % n_chains
    cell = t // n_chains
    for k in range(ncz.shape[1]):
        total = ncz[cell, k, r]
        for j in range(table.shape[1]):
            d = table[cell, j]
            if d >= 0:
                total += ncz[d, k, r]
        ng[cell, k, r] = total


@cuda.jit(cache=True)
def put_columns_kernel(columns, source, target):
    """``target[:, columns[p]] = source[:, p]`` for (rows, R) ``target`` and (rows, P) ``source``, a thread per element of ``source``."""
    t = cuda.grid(1)
    if t >= source.shape[0] * source.shape[1]:
        return
    p = t % source.shape[1]
    row = t // source.shape[1]
    target[row, columns[p]] = source[row, p]


def launch(kernel, threads: int, *args) -> None:
    """Run ``kernel`` over ``threads`` threads in blocks of :data:`THREADS_PER_BLOCK`."""
    if threads > 0:
        kernel[math.ceil(threads / THREADS_PER_BLOCK), THREADS_PER_BLOCK](*args)


def gpu_available() -> tuple[bool, str]:
    """Whether numba sees a CUDA GPU it can use, and if not, why (numba's own words)."""
    try:
        if cuda.is_available():
            return True, ""
        return False, "numba.cuda.is_available() is False (no CUDA driver or no GPU)"
    except Exception as exc:  # noqa: BLE001  (a broken driver raises its own types)
        return False, f"{type(exc).__name__}: {exc}"
