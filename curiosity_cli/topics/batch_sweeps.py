"""Algorithm 1 on threads: the phases of a batch sweep, and the threads that refine them.

:meth:`TopicModel.refine_batch <curiosity_cli.topics.model.TopicModel.refine_batch>`
checks its arguments and owns the arrays; this module cuts the observed cells into
phases (:func:`batch_phases`) and runs the sweeps on the kernels' shared arguments
(:func:`sweep_phases`), with the model's log-likelihood after each sweep on the same
threads when asked (:func:`mean_log_likelihood`). It also owns the cache-line alignment
of the count arrays those threads write (:func:`aligned_zeros`).
"""

from __future__ import annotations

import itertools

import numpy as np

_CACHE_LINE = 64
# a batch phase holds at most 1/_PHASES of the observed cells
_PHASES = 16
# the log-likelihood is summed over runs of this many cells, in order, whatever the threads
_LIKELIHOOD_CELLS = 256


def aligned_zeros(shape, dtype) -> np.ndarray:
    """Zeros starting on a 64-byte cache line (numpy only promises 16 bytes).

    Count rows of 64 topics are 256 bytes: aligned, each is 4 cache lines, not 5 shared
    with its neighbours, which matters for speed and, when threads refine cells whose
    rows are adjacent, for false sharing.
    """
    dtype = np.dtype(dtype)
    size = int(np.prod(shape))
    buffer = np.zeros(size * dtype.itemsize + _CACHE_LINE, np.uint8)
    start = -buffer.ctypes.data % _CACHE_LINE
    return buffer[start : start + size * dtype.itemsize].view(dtype).reshape(shape)


def batch_phases(cells: np.ndarray, colour: np.ndarray) -> list[np.ndarray]:
    """The phases of a batch sweep over the observed ``cells``.

    For each colour in increasing order (two cells of one colour share no cell count
    and no neighbourhood sum), the ``n_c`` cells of that colour in cell order, cut into
    ``ceil(n_c / m)`` runs of consecutive cells as equal in size as can be (the first
    ``n_c mod runs`` one cell longer), ``m = ceil(n / 16)``. So no phase holds more than
    1/16 of the cells, even without neighbours (one colour).

    Parameters
    ----------
    cells : (n,) int64 ndarray
        The observed cells, by cell index.
    colour : (n_cells,) int ndarray
        A distance-2 colouring of the neighbour table (``_gibbs_kernels.distance2_colouring``).

    Returns
    -------
    list of (m_i,) int64 ndarray
        The phases, in the order a sweep visits them.
    """
    colour = colour[cells]
    most = -(-cells.size // _PHASES)
    phases = []
    for c in np.unique(colour):
        group = cells[colour == c]
        parts = -(-group.size // most)
        phases += np.array_split(group, parts)
    return phases


def mean_log_likelihood(cells: np.ndarray, likelihood_arrays: tuple, threads: int = 1, pool=None) -> float:
    """The mean over the words of ``cells`` of the model's per-word log-likelihood (``log_likelihood_sum_kernel``).

    Summed over runs of :data:`_LIKELIHOOD_CELLS` consecutive cells, on ``threads``
    threads (this one and ``threads - 1`` of ``pool``), then the runs' sums in order:
    the same float64 for any number of threads.

    Parameters
    ----------
    cells : (n,) int64 ndarray
    likelihood_arrays : tuple
        The kernel's arguments after ``cells``: from ``cell_first`` to ``vbeta``.
    threads : int
    pool : ThreadPoolExecutor, optional
        With at least ``threads - 1`` workers; needed when ``threads`` > 1.
    """
    from curiosity_cli.topics._gibbs_kernels import log_likelihood_sum_kernel

    runs = [cells[start : start + _LIKELIHOOD_CELLS] for start in range(0, cells.size, _LIKELIHOOD_CELLS)]
    sums = [(0.0, 0)] * len(runs)
    taken = itertools.count()  # each thread takes the next run (next() of a count is atomic)

    def work() -> None:
        while (index := next(taken)) < len(runs):
            sums[index] = log_likelihood_sum_kernel(runs[index], *likelihood_arrays)

    others = [pool.submit(work) for _ in range(min(threads, len(runs)) - 1)]
    work()
    for other in others:
        other.result()
    words = sum(n for _, n in sums)
    return sum(total for total, _ in sums) / words if words else 0.0


def sweep_phases(
    phases: list[np.ndarray], sampler_arrays: tuple, n_topics: int, counter: int, sweeps: int, threads: int,
    *, frozen: bool, trace: tuple | None = None,
) -> np.ndarray | None:
    """``sweeps`` batch sweeps through ``phases``, changing the model's arrays in place.

    Parameters
    ----------
    phases : list of (m_i,) int64 ndarray
        From :func:`batch_phases`.
    sampler_arrays : tuple
        The model's ``_sampler_arrays()``: the kernels' shared arguments, from
        ``cell_first`` to ``key``.
    n_topics : int
        K.
    counter : int
        The model's random state: sweep ``s`` draws from the streams ``(counter + s, cell)``.
    sweeps, threads : int
        >= 1 each.
    frozen : bool
        The model's word-topic counts are frozen (only read).
    trace : tuple, optional
        With a model whose counts are not frozen: the arguments ``(cells,
        likelihood_arrays)`` of :func:`mean_log_likelihood`, taken after each sweep on the
        same threads.

    Returns
    -------
    (sweeps,) float64 ndarray or None
        The log-likelihood after each sweep, when ``trace`` is given.
    """
    if frozen:
        _sweep_frozen(phases, sampler_arrays, counter, sweeps, threads)
        return

    from concurrent.futures import ThreadPoolExecutor

    from curiosity_cli.topics._gibbs_kernels import merge_phase, refine_phase_share

    if len(phases) == 1:
        # one observed cell: the threads would merge the one phase into their copies
        # while it is being refined, and only one of them would have work
        threads = 1
    (cell_first, cell_count, words, topics, nwk, nk, inv, ncz, ng, table, alpha, beta, vbeta,
     key) = sampler_arrays  # fmt: skip
    kp = nwk.shape[1]
    own = (nwk, nk, inv)
    copies = [own] + [tuple(_aligned_copy(a) for a in own) for _ in range(threads - 1)]
    # each thread's scratch, and the shared chunk counter, on cache lines of their own:
    # two threads writing one line (false sharing) halved the speed
    scratch = [(*copy, aligned_zeros(kp, np.int32), aligned_zeros(kp, np.float32)) for copy in copies]
    taken = aligned_zeros(1, np.int64)
    before = np.empty_like(topics)

    def refine(mine: tuple, phase: np.ndarray, previous: np.ndarray, stream: np.uint64) -> None:
        refine_phase_share(
            taken, phase, previous, before, *mine, cell_first, cell_count, words, topics, ncz, ng, table,
            n_topics, alpha, beta, vbeta, key, stream,
        )

    # the phase whose changes are not yet in the counts: every thread merges it into
    # its copy when the next phase starts, and this thread into the model's at the end
    previous = np.zeros(0, np.int64)
    trace_out = None if trace is None else np.empty(sweeps)
    # this thread refines too, on the model's own counts; the pool starts no thread for threads == 1
    with ThreadPoolExecutor(max(threads - 1, 1)) as pool:
        for sweep in range(sweeps):
            stream = np.uint64(counter + sweep)
            for phase in phases:
                taken[0] = 0
                others = [pool.submit(refine, mine, phase, previous, stream) for mine in scratch[1:]]
                refine(scratch[0], phase, previous, stream)
                for other in others:
                    other.result()  # waits, and re-raises an error of that thread
                previous = phase
            if trace_out is not None:
                # the sweep's last phase into every copy now, not when the next sweep starts: the
                # model's counts are then whole, and the next sweep's first phase has nothing to merge
                merges = [pool.submit(merge_phase, previous, cell_first, cell_count, words, before, topics, *mine[:3],
                                      n_topics, vbeta) for mine in scratch[1:]]
                merge_phase(previous, cell_first, cell_count, words, before, topics, *own, n_topics, vbeta)
                for merge in merges:
                    merge.result()
                previous = np.zeros(0, np.int64)
                trace_out[sweep] = mean_log_likelihood(*trace, threads, pool)
    merge_phase(previous, cell_first, cell_count, words, before, topics, *own, n_topics, vbeta)
    return trace_out


def _sweep_frozen(phases: list[np.ndarray], sampler_arrays: tuple, counter: int, sweeps: int, threads: int) -> None:
    """:func:`sweep_phases` of a frozen model: the same draws, on shared read-only weights.

    With Φ fixed, ``(n_kw + β) / (n_k + Vβ)`` is computed once per call, and the
    threads of a phase share it: no copies of the counts, nothing to merge.
    """
    from concurrent.futures import ThreadPoolExecutor

    from curiosity_cli.topics._gibbs_kernels import refine_frozen_phase

    (cell_first, cell_count, words, topics, nwk, _, inv, ncz, ng, table, alpha, beta, _,
     key) = sampler_arrays  # fmt: skip
    # (float32(n_kw) + β) * inv[k], the factors of eq. 5 that frozen counts fix
    phiw = aligned_zeros(nwk.shape, np.float32)
    np.multiply(nwk.astype(np.float32) + beta, inv, out=phiw)
    taken = aligned_zeros(1, np.int64)

    def refine(phase: np.ndarray, stream: np.uint64) -> None:
        refine_frozen_phase(
            taken, phase, phiw, cell_first, cell_count, words, topics, ncz, ng, table, alpha, key, stream,
        )

    with ThreadPoolExecutor(max(threads - 1, 1)) as pool:
        for sweep in range(sweeps):
            stream = np.uint64(counter + sweep)
            for phase in phases:
                taken[0] = 0
                others = [pool.submit(refine, phase, stream) for _ in range(threads - 1)]
                refine(phase, stream)
                for other in others:
                    other.result()


def _aligned_copy(array: np.ndarray) -> np.ndarray:
    """A copy of ``array`` starting on a cache line (see :func:`aligned_zeros`)."""
    copy = aligned_zeros(array.shape, array.dtype)
    copy[...] = array
    return copy
