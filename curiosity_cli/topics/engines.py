"""The engines that hold a block of labelling chains on a device and advance them
(:class:`~curiosity_cli.topics.chains.FrozenChains` drives one; the interface and what each
step does on each device: ``topics/chains.py``'s docstring).

:class:`CpuEngine` runs the numba kernels of ``_chain_kernels.py``; :class:`CudaEngine`
those of ``_chain_kernels_cuda.py`` (numba-cuda, the optional extra). Each device of
:data:`curiosity_cli.topics.devices.DEVICES` names its engine.
"""

from __future__ import annotations

import numpy as np


def _phiw(counts: np.ndarray, inv: np.ndarray, allowed: np.ndarray, beta: float) -> np.ndarray:
    """eq. 5's fixed factors (V, K, R) float32: ``(float32(counts) + beta) * inv``, one rounding each, where
    ``allowed`` (V, K, R) bool; 0 where not (that word never takes that topic)."""
    return np.where(allowed, (counts.astype(np.float32) + np.float32(beta)) * inv, np.float32(0))


class CpuEngine:
    """The chains' state in numpy arrays, advanced by ``_chain_kernels.py`` (the interface: module docstring)."""

    def __init__(self, order, colour_starts, cell_first, cell_count, words, table, alpha, beta):
        self._fixed = (order, cell_first, cell_count, words)
        self._table = table
        self._alpha = alpha  # float64 in the ML weights, float32 in the sweeps'
        self._beta = beta
        self._state = None  # [topics, ncz, ng]

    def set_counts(self, counts, inv, allowed) -> None:
        self._counts = counts
        self._allowed = allowed
        self._phiw = _phiw(counts, inv, allowed, self._beta)

    def start(self, counts, inv, allowed, keys, placed) -> None:
        self.set_counts(counts, inv, allowed)
        self._keys = tuple(keys)
        self._state = _start_on_cpu(
            self._phiw, keys, placed, self._fixed[1], self._fixed[2], self._fixed[3], self._table, self._alpha
        )

    def keep(self, index, keys) -> None:
        self._state = [np.ascontiguousarray(a[..., index]) for a in self._state]
        self._counts = np.ascontiguousarray(self._counts[:, :, index])
        self._allowed = np.ascontiguousarray(self._allowed[:, :, index])
        self._phiw = np.ascontiguousarray(self._phiw[:, :, index])
        self._keys = tuple(keys)

    def get(self) -> tuple:
        return tuple(self._state)

    def sweep(self, counter) -> None:
        from curiosity_cli.topics._chain_kernels import sweep_chains_kernel

        topics, ncz, ng = self._state
        order, cell_first, cell_count, words = self._fixed
        sweep_chains_kernel(
            order, cell_first, cell_count, words, topics, self._phiw, ncz, ng, self._table, np.float32(self._alpha),
            self._keys, counter,
        )

    def ml_topics(self, norm) -> np.ndarray:
        from curiosity_cli.topics._chain_kernels import ml_chains_kernel

        _, cell_first, cell_count, words = self._fixed
        out = np.empty((words.size, len(self._keys)), np.int16)
        cells = np.arange(cell_first.size, dtype=np.int64)
        phid = np.where(self._allowed, (self._counts + self._beta) * norm, 0.0)
        ml_chains_kernel(cells, cell_first, cell_count, words, phid, self._state[2], self._alpha, self._keys, out)
        return out


def _start_on_cpu(phiw, keys, placed, cell_first, cell_count, words, table, alpha) -> list[np.ndarray]:
    """``[topics, ncz, ng]`` of chains started by the CPU start kernel, chain ``r`` with ``keys[r]`` and ``placed[r]``."""
    from curiosity_cli.topics._chain_kernels import start_chain_kernel

    n_cells, n_topics, held = table.shape[0], phiw.shape[1], phiw.shape[2]
    topics = np.zeros((words.size, held), np.int8)
    ncz = np.zeros((n_cells, n_topics, held), np.int32)
    ng = np.zeros((n_cells, n_topics, held), np.int32)
    cells = np.arange(n_cells, dtype=np.int64)
    for r in range(held):
        start_chain_kernel(
            r, placed[r], cells, cell_first, cell_count, words, topics, phiw, ncz, ng, table, np.float32(alpha), keys[r]
        )
    return [topics, ncz, ng]


class CudaEngine:
    """The chains' state on a CUDA GPU, advanced by ``_chain_kernels_cuda.py`` (the interface: module docstring).

    The frozen counts go to the GPU once per :meth:`set_counts`; eq. 5's factors and the
    ML weights are computed there, as numpy computes them for the CPU.
    """

    def __init__(self, order, colour_starts, cell_first, cell_count, words, table, alpha, beta):
        from numba import cuda

        self._cuda = cuda
        self._colours = [
            cuda.to_device(np.ascontiguousarray(order[a:b])) for a, b in zip(colour_starts[:-1], colour_starts[1:])
        ]
        self._host = (cell_first, cell_count, words, table)  # for the placed starts, made on the CPU
        self._cell_first = cuda.to_device(cell_first)
        self._cell_count = cuda.to_device(cell_count)
        self._words = cuda.to_device(words)
        self._table = cuda.to_device(table)
        self._n_words = words.size
        self._alpha = alpha
        self._beta = beta
        self._state = None  # [topics, ncz, ng] on the GPU

    def set_counts(self, counts, inv, allowed) -> None:
        from curiosity_cli.topics._chain_kernels_cuda import launch, phiw_kernel

        self._counts = self._cuda.to_device(counts)
        self._allowed = self._cuda.to_device(allowed)
        self._phiw = self._cuda.device_array(counts.shape, np.float32)
        launch(
            phiw_kernel, counts.size, self._counts, self._allowed, np.float32(self._beta), self._cuda.to_device(inv),
            self._phiw,
        )

    def start(self, counts, inv, allowed, keys, placed) -> None:
        """Uniform starts on the GPU; placed ones on the CPU (they are sequential over the cells), put in their columns."""
        from curiosity_cli.topics._chain_kernels_cuda import launch, neighbour_sums_kernel, start_uniform_kernel

        cuda = self._cuda
        self.set_counts(counts, inv, allowed)
        self._keys = cuda.to_device(np.ascontiguousarray(keys, np.uint64))
        n_cells, n_topics, held = self._table.shape[0], counts.shape[1], counts.shape[2]
        topics = cuda.to_device(np.zeros((self._n_words, held), np.int8))
        ncz = cuda.to_device(np.zeros((n_cells, n_topics, held), np.int32))
        ng = cuda.device_array((n_cells, n_topics, held), np.int32)
        launch(start_uniform_kernel, n_cells * held, held, n_topics, self._cell_first, self._cell_count, topics, ncz,
               self._keys)
        launch(neighbour_sums_kernel, n_cells * held, held, ncz, self._table, ng)
        self._state = [topics, ncz, ng]
        columns = np.flatnonzero(placed)
        if columns.size:
            cell_first, cell_count, words, table = self._host
            started = _start_on_cpu(
                _phiw(counts[:, :, columns], inv[:, columns], allowed[:, :, columns], self._beta), keys[columns],
                placed[columns],
                cell_first, cell_count, words, table, self._alpha,
            )
            self._put_columns(columns, started)

    def _put_columns(self, columns, host_arrays) -> None:
        """Put the host arrays' chains (each (..., P)) into the GPU state's ``columns``."""
        from curiosity_cli.topics._chain_kernels_cuda import launch, put_columns_kernel

        to = self._cuda.to_device
        where = to(columns.astype(np.int64))
        held = self._keys.shape[0]
        for target, source in zip(self._state, host_arrays):
            source = np.ascontiguousarray(source.reshape(-1, columns.size))
            launch(put_columns_kernel, source.size, where, to(source), target.reshape(source.shape[0], held))

    def keep(self, index, keys) -> None:
        to = self._cuda.to_device
        self._state = [to(np.ascontiguousarray(a.copy_to_host()[..., index])) for a in self._state]
        self._counts = to(np.ascontiguousarray(self._counts.copy_to_host()[:, :, index]))
        self._allowed = to(np.ascontiguousarray(self._allowed.copy_to_host()[:, :, index]))
        self._phiw = to(np.ascontiguousarray(self._phiw.copy_to_host()[:, :, index]))
        self._keys = to(np.ascontiguousarray(keys, np.uint64))

    def get(self) -> tuple:
        return tuple(a.copy_to_host() for a in self._state)

    def sweep(self, counter) -> None:
        from curiosity_cli.topics._chain_kernels_cuda import launch, sweep_colour_kernel

        topics, ncz, ng = self._state
        n_chains = self._keys.shape[0]
        for cells in self._colours:
            launch(
                sweep_colour_kernel, cells.shape[0] * n_chains, cells, n_chains, self._cell_first, self._cell_count,
                self._words, topics, self._phiw, ncz, ng, self._table, np.float32(self._alpha), self._keys, counter,
            )
        self._cuda.synchronize()

    def ml_topics(self, norm) -> np.ndarray:
        from curiosity_cli.topics._chain_kernels_cuda import launch, ml_kernel

        n_chains = self._keys.shape[0]
        out = self._cuda.device_array((self._n_words, n_chains), np.int16)
        launch(
            ml_kernel, self._cell_first.shape[0] * n_chains, n_chains, self._cell_first, self._cell_count, self._words,
            self._counts, self._allowed, float(self._beta), self._cuda.to_device(np.ascontiguousarray(norm)), self._state[2],
            float(self._alpha), out,
        )
        return out.copy_to_host()
