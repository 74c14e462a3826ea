"""Many frozen-Φ Gibbs chains over one map's words, advanced in lock-step.

Labelling a map with a path's model (Z_p) runs a Gibbs chain over every word of the map
with the word-topic counts frozen to the path's Φ. Every run of a map labels the same
words in the same order with the same neighbour table; only Φ and the random stream
differ. :class:`FrozenChains` holds ``R`` such chains and advances them together, the
chain index innermost (``_chain_kernels.py``), so that each step over topics is one vector
operation across chains instead of a dependent chain of additions in one.

Each chain is the exact collapsed sampler of eq. 5 with Φ frozen, and its state depends
only on its own Φ, its own seed and the calls made: never on which other chains share
the object, nor on their number.

Random streams, per chain, from ``key = mix(seed)``: a uniform start draws cell ``c``
from stream ``(c, c)`` (as :meth:`~curiosity_cli.topics.model.TopicModel.restart` of a
model holding every cell), a placed start from ``(0, c)``; sweep ``s`` after a start
(0, 1, ...) draws cell ``c`` from stream ``(n_cells + s, c)``. A sweep visits the cells
colour by colour (:func:`sweep_order`): every cell of colour 0 in index order, then
colour 1, ... (label format 3; before it, cells in index order). Every order is the
exact sampler; this one lets a GPU resample a colour's cells at once.

**Devices.** The chains run on the CPU (``device="cpu"``, :class:`~curiosity_cli.topics.engines.CpuEngine`, the numba
kernels of ``_chain_kernels.py``) or on a CUDA GPU (``device="cuda"``, :class:`~curiosity_cli.topics.engines.CudaEngine`,
``_chain_kernels_cuda.py``, the optional extra ``curiosity-cli[cuda]``), behind one interface,
with the same bytes on both: the same streams, the same float32 operations in the same
order, never fused. :data:`curiosity_cli.topics.devices.DEVICES` names each device's engine.
What a device does for each step of the interface:

==============  ==============================================================================
step            CPU / CUDA
==============  ==============================================================================
``start``       CPU: the start kernel, per chain. CUDA: uniform starts on the GPU, a thread per
                (cell, chain), then the neighbourhood sums from the cell counts (the same
                integers); a placed start, sequential over the cells, on the CPU, its
                chain then put in its column on the GPU
``switch``      the frozen counts and allowed topics to the device; eq. 5's fixed factors ``phiw``
                computed there, 0 for a topic not allowed (CPU: numpy float32; CUDA: a thread
                per element, the same roundings)
``keep``        CPU: indexing; CUDA: to the host, indexing, back
``sweep``       CPU: one kernel call over the cells in colour order, every chain in
                lock-step; CUDA: one launch per colour, a thread per (cell, chain)
``topics``      CPU: a copy; CUDA: a copy from the GPU
``ml_topics``   CPU: the ML kernel; CUDA: its twin on the GPU, one thread per (cell, chain),
                the float64 factors computed in the kernel from the counts already there
==============  ==============================================================================

Chains per block, each device's (:attr:`~curiosity_cli.topics.devices.Device.block_chains`):
the CPU holds chains in multiples of :data:`LANES` and gains nothing past a few of them in
one block, so a map's chains are cut into blocks that keep every core busy; a GPU wants
every chain of a map in one block.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from curiosity_cli.checks import check_float, check_int
from curiosity_cli.errors import ParameterError
from curiosity_cli.topics.devices import DEVICES
from curiosity_cli.topics.neighbours import check_neighbours

#: Chains are held in multiples of this many (float32 lanes of a 256-bit vector): the
#: kernels compile for the number of chains held, and a remainder past a multiple of 8
#: runs as scalar code, at twice the time per chain. The padding chains repeat the last
#: real one and are never reported.
LANES = 8


def sweep_order(table: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cells in sweep order and where each colour starts in it.

    Parameters
    ----------
    table : (n_cells, width) int32 ndarray
        A checked neighbour table.

    Returns
    -------
    order : (n_cells,) int64 ndarray
        Cells of colour 0 in index order, then colour 1, ...
        (``_chain_kernels.neighbour_colouring``: neighbours never share a colour).
    starts : (n_colours + 1,) int64 ndarray
        Colour ``c``'s cells are ``order[starts[c]:starts[c + 1]]``.
    """
    from curiosity_cli.topics._chain_kernels import neighbour_colouring

    colour = neighbour_colouring(table)
    order = np.argsort(colour, kind="stable").astype(np.int64)
    starts = np.concatenate([[0], np.cumsum(np.bincount(colour))]).astype(np.int64)
    return order, starts


class FrozenChains:
    """``R`` frozen-Φ Gibbs chains over the same words, advanced in lock-step.

    Parameters
    ----------
    words : (N,) int ndarray
        Word ids, ``0 .. vocabulary_size - 1``, grouped by cell.
    cells : (N,) int ndarray
        The cell of each word, non-decreasing, ``0 .. n_cells - 1``.
    neighbours : (n_cells, width) int ndarray
        The neighbour table (:mod:`curiosity_cli.topics.neighbours`).
    n_topics : int
        K, 1 .. 127.
    vocabulary_size : int
        V >= 1.
    alpha, beta : float
        Dirichlet hyper-parameters, > 0.
    device : str
        Where the chains run: a name in :data:`curiosity_cli.topics.devices.DEVICES`, whose
        engine runs them (module docstring); the same bytes on each. ``"cuda"`` needs
        numba-cuda and a GPU (:func:`curiosity_cli.topics.devices.resolve_device` says
        which is missing).

    Raises
    ------
    ParameterError
        Naming the first invalid parameter.
    """

    def __init__(
        self, words, cells, neighbours, *, n_topics: int, vocabulary_size: int, alpha: float, beta: float,
        device: str = "cpu",
    ):
        self._k = check_int("n_topics", n_topics, 1, 127)
        self._v = check_int("vocabulary_size", vocabulary_size, 1)
        self._alpha = check_float("alpha", alpha, 0, low_open=True)
        self._beta = check_float("beta", beta, 0, low_open=True)
        if device not in DEVICES:
            raise ParameterError(f"device: got {device!r}, expected one of {', '.join(DEVICES)}")
        self._table = check_neighbours(neighbours)
        n_cells = self._table.shape[0]
        self._words = _check_ids("words", words, self._v)
        word_cells = _check_ids("cells", cells, n_cells)
        if word_cells.shape != self._words.shape:
            raise ParameterError(f"cells: got shape {word_cells.shape}, expected one cell per word {self._words.shape}")
        if np.any(np.diff(word_cells) < 0):
            raise ParameterError("cells: must be non-decreasing (words grouped by cell)")
        self._cell_count = np.bincount(word_cells, minlength=n_cells).astype(np.int64)
        self._cell_first = np.concatenate([[0], np.cumsum(self._cell_count)[:-1]]).astype(np.int64)
        self._order, self._colour_starts = sweep_order(self._table)
        self.device = device
        self._engine = DEVICES[device].engine(
            self._order, self._colour_starts, self._cell_first, self._cell_count, self._words, self._table, self._alpha,
            self._beta,
        )
        self._totals = None  # (K, R held) int64: each chain's frozen words per topic (its counts are the engine's)
        self._keys = None  # (R padded,) uint64
        self._n = 0  # real chains
        self._sweeps = 0

    @property
    def n_chains(self) -> int:
        """R, the chains started (0 before :meth:`start`)."""
        return self._n

    @property
    def n_words(self) -> int:
        return self._words.size

    def start(
        self, phis: Sequence[np.ndarray], seeds: Sequence[int], placed: Sequence[bool] | None = None,
        allowed: Sequence[np.ndarray | None] | None = None,
    ) -> None:
        """Start ``R = len(phis)`` chains: chain ``r`` with Φ ``phis[r]`` and seed ``seeds[r]``.

        Parameters
        ----------
        phis : sequence of R (V, K) int ndarrays
            Each chain's frozen word-topic counts.
        seeds : sequence of R ints
            0 .. 2**64 - 1.
        placed : sequence of R bools, optional
            Per chain, start from placed topics (each word drawn from eq. 5 given the
            words drawn before it, cells in index order) instead of uniformly random
            ones (the default).
        allowed : sequence of R (V, K) bool ndarrays or None, optional
            Per chain, the topics each word may take (a labelling reading,
            :mod:`curiosity_cli.label.readings`): eq. 5's weight of the others is 0, in
            the sweeps and the ML labels (a uniform start may still put a word there,
            which its first sweep moves). None: every topic, for every word. Each word
            must be allowed a topic.
        """
        from curiosity_cli.topics._rng import mix

        n = len(phis)
        if n == 0:
            raise ParameterError("phis: expected at least one chain")
        if len(seeds) != n:
            raise ParameterError(f"seeds: got {len(seeds)}, expected one per chain ({n})")
        placed = [False] * n if placed is None else [bool(p) for p in placed]
        if len(placed) != n:
            raise ParameterError(f"placed: got {len(placed)}, expected one per chain ({n})")
        keys = [mix(np.uint64(check_int("seeds", s, 0, 2**64 - 1))) for s in seeds]
        counts, inv, allowed = self._set_phis(phis, allowed)
        self._n = n
        held = counts.shape[2]
        self._keys = np.array(_padded(keys, held), np.uint64)
        self._engine.start(counts, inv, allowed, self._keys, np.array(_padded(placed, held), bool))
        self._sweeps = 0

    def switch(self, phis: Sequence[np.ndarray], allowed: Sequence[np.ndarray | None] | None = None) -> None:
        """Freeze each chain's Φ to ``phis[r]`` and its topics to ``allowed[r]`` (as :meth:`start`), keeping every
        topic (a warm start)."""
        self._started("switch")
        if len(phis) != self.n_chains:
            raise ParameterError(f"phis: got {len(phis)}, expected one per chain ({self.n_chains})")
        self._engine.set_counts(*self._set_phis(phis, allowed))

    def keep(self, chains: Sequence[int]) -> None:
        """Keep only the listed chains, in that order (the others have no more checkpoints)."""
        self._started("keep")
        index = np.asarray(chains, np.int64)
        if index.ndim != 1 or index.size == 0 or index.min() < 0 or index.max() >= self.n_chains:
            raise ParameterError(f"chains: expected a non-empty list of chains in 0..{self.n_chains - 1}")
        self._n = index.size
        index = np.array(_padded(list(index), _held(index.size)), np.int64)
        self._totals = self._totals[:, index]
        self._keys = self._keys[index]
        self._engine.keep(index, self._keys)

    def sweep(self, sweeps: int, on_sweep=None) -> None:
        """``sweeps`` Gibbs sweeps of every chain over every word, cells in colour order (:func:`sweep_order`);
        ``on_sweep(chains)`` after each, for a display of progress."""
        self._started("sweep")
        sweeps = check_int("sweeps", sweeps, 0)
        n_cells = self._table.shape[0]
        for _ in range(sweeps):
            self._engine.sweep(np.uint64(n_cells + self._sweeps))
            self._sweeps += 1
            if on_sweep is not None:
                on_sweep(self._n)

    def topics(self) -> np.ndarray:
        """(N, R) int8: each word's current topic in each chain."""
        self._started("topics")
        return self._engine.get()[0][:, : self._n].copy()

    def counts(self) -> tuple[np.ndarray, np.ndarray]:
        """``(ncz, ng)``, each (n_cells, K, R) int32: each chain's cell topic counts and neighbourhood sums."""
        self._started("counts")
        _, ncz, ng = self._engine.get()
        return ncz[:, :, : self._n].copy(), ng[:, :, : self._n].copy()

    def ml_topics(self) -> np.ndarray:
        """(N, R) int16: each word's maximum-likelihood topic in each chain, the word included.

        ``argmax_k (n_kw + β) / (n_k + Vβ) · (n_Gk + α)`` in float64, ties to the lowest
        topic: :meth:`~curiosity_cli.topics.model.TopicModel.ml_topics` of each chain.
        """
        self._started("ml_topics")
        norm = 1.0 / (self._totals + self._v * self._beta)  # (K, R)
        return self._engine.ml_topics(norm)[:, : self._n]

    def _set_phis(
        self, phis: Sequence[np.ndarray], allowed: Sequence[np.ndarray | None] | None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Each chain's frozen counts and allowed topics, kept, padded (:data:`LANES`): ``(counts, inv, allowed)``,
        (V, K, R held) int32, ``1 / (n_k + V beta)`` (K, R held) float32 and (V, K, R held) bool, from which a device
        makes eq. 5's fixed factors (:func:`_phiw`)."""
        if allowed is None:
            allowed = [None] * len(phis)
        if len(allowed) != len(phis):
            raise ParameterError(f"allowed: got {len(allowed)}, expected one per chain ({len(phis)})")
        phis = _padded(list(phis), _held(len(phis)))
        allowed = _padded(list(allowed), len(phis))
        counts = np.empty((self._v, self._k, len(phis)), np.int32)
        opened = np.ones((self._v, self._k, len(phis)), bool)
        for r, (phi, mask) in enumerate(zip(phis, allowed)):
            phi = np.asarray(phi)
            if phi.shape != (self._v, self._k):
                raise ParameterError(f"phis: chain {r} has shape {phi.shape}, expected (V, K) = {(self._v, self._k)}")
            if phi.dtype == np.bool_ or not np.issubdtype(phi.dtype, np.integer):
                raise ParameterError(f"phis: chain {r} has dtype {phi.dtype}, expected integer counts")
            if phi.size and (phi.min() < 0 or phi.sum(axis=0, dtype=np.int64).max() > np.iinfo(np.int32).max):
                raise ParameterError(f"phis: chain {r}'s counts must be >= 0 and each topic's total fit in int32")
            counts[:, :, r] = phi
            if mask is not None:
                mask = np.asarray(mask)
                if mask.shape != (self._v, self._k) or mask.dtype != np.bool_:
                    raise ParameterError(
                        f"allowed: chain {r} is {mask.dtype} of shape {mask.shape}, expected bool (V, K) = "
                        f"{(self._v, self._k)}"
                    )
                if not mask.any(axis=1).all():
                    raise ParameterError(f"allowed: chain {r} allows no topic to word {int(np.argmin(mask.any(axis=1)))}")
                opened[:, :, r] = mask
        self._totals = counts.sum(axis=0, dtype=np.int64)
        return counts, (1.0 / (self._totals + self._v * self._beta)).astype(np.float32), opened

    def _started(self, name: str) -> None:
        if self._keys is None:
            raise ParameterError(f"{name}: no chains yet; start() them first")


def _held(n: int) -> int:
    """The chains held for ``n`` real ones: the next multiple of :data:`LANES`."""
    return -(-n // LANES) * LANES


def _padded(values: list, size: int) -> list:
    """``values`` to ``size`` items, the last repeated."""
    return values + values[-1:] * (size - len(values))


def _check_ids(name: str, values, size: int) -> np.ndarray:
    values = np.asarray(values)
    if values.ndim != 1:
        raise ParameterError(f"{name}: got shape {values.shape}, expected (N,)")
    if values.size and (values.dtype == np.bool_ or not np.issubdtype(values.dtype, np.integer)):
        raise ParameterError(f"{name}: got dtype {values.dtype}, expected integers")
    if values.size and (values.min() < 0 or values.max() >= size):
        raise ParameterError(f"{name}: values must be in 0..{size - 1}, got {values.min()}..{values.max()}")
    return values.astype(np.int32 if name == "words" else np.int64)
