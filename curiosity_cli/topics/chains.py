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
(0, 1, ...) draws cell ``c`` from stream ``(n_cells + s, c)``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from curiosity_cli.checks import check_float, check_int
from curiosity_cli.errors import ParameterError
from curiosity_cli.topics.neighbours import check_neighbours

#: Chains are held in multiples of this many (float32 lanes of a 256-bit vector): the
#: kernels compile for the number of chains held, and a remainder past a multiple of 8
#: runs as scalar code, at twice the time per chain. The padding chains repeat the last
#: real one and are never reported.
LANES = 8


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

    Raises
    ------
    ParameterError
        Naming the first invalid parameter.
    """

    def __init__(self, words, cells, neighbours, *, n_topics: int, vocabulary_size: int, alpha: float, beta: float):
        self._k = check_int("n_topics", n_topics, 1, 127)
        self._v = check_int("vocabulary_size", vocabulary_size, 1)
        self._alpha = check_float("alpha", alpha, 0, low_open=True)
        self._beta = check_float("beta", beta, 0, low_open=True)
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
        self._cells = np.arange(n_cells, dtype=np.int64)
        self._counts = None  # (V, K, R) int32 frozen word-topic counts
        self._phiw = None
        self._keys = None  # (R padded,) uint64
        self._n = 0  # real chains
        self._sweeps = 0
        self._topics = self._ncz = self._ng = None

    @property
    def n_chains(self) -> int:
        """R, the chains started (0 before :meth:`start`)."""
        return self._n

    @property
    def n_words(self) -> int:
        return self._words.size

    def start(self, phis: Sequence[np.ndarray], seeds: Sequence[int], placed: Sequence[bool] | None = None) -> None:
        """Start ``R = len(phis)`` chains: chain ``r`` with Φ ``phis[r]`` and seed ``seeds[r]``.

        Parameters
        ----------
        phis : sequence of R (V, K) int ndarrays
            Each chain's frozen word-topic counts.
        seeds : sequence of R ints
            0 .. 2**64 - 1.
        placed : sequence of R bools, optional
            Per chain, start from placed topics (each word drawn from eq. 5 given the
            words drawn before it) instead of uniformly random ones (the default).
        """
        from curiosity_cli.topics._chain_kernels import start_chain_kernel
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
        self._set_phis(phis)
        self._n = n
        held = self._phiw.shape[2]
        self._keys = np.array(_padded(keys, held), np.uint64)
        placed = _padded(placed, held)
        n_cells = self._table.shape[0]
        self._topics = np.zeros((self._words.size, held), np.int8)
        self._ncz = np.zeros((n_cells, self._k, held), np.int32)
        self._ng = np.zeros((n_cells, self._k, held), np.int32)
        for r in range(held):
            start_chain_kernel(
                r, placed[r], self._cells, self._cell_first, self._cell_count, self._words, self._topics, self._phiw,
                self._ncz, self._ng, self._table, np.float32(self._alpha), self._keys[r],
            )
        self._sweeps = 0

    def switch(self, phis: Sequence[np.ndarray]) -> None:
        """Freeze each chain's Φ to ``phis[r]``, keeping every topic (a warm start)."""
        self._started("switch")
        if len(phis) != self.n_chains:
            raise ParameterError(f"phis: got {len(phis)}, expected one per chain ({self.n_chains})")
        self._set_phis(phis)

    def keep(self, chains: Sequence[int]) -> None:
        """Keep only the listed chains, in that order (the others have no more checkpoints)."""
        self._started("keep")
        index = np.asarray(chains, np.int64)
        if index.ndim != 1 or index.size == 0 or index.min() < 0 or index.max() >= self.n_chains:
            raise ParameterError(f"chains: expected a non-empty list of chains in 0..{self.n_chains - 1}")
        self._n = index.size
        index = np.array(_padded(list(index), _held(index.size)), np.int64)
        self._counts = np.ascontiguousarray(self._counts[:, :, index])
        self._phiw = np.ascontiguousarray(self._phiw[:, :, index])
        self._keys = self._keys[index]
        self._topics = np.ascontiguousarray(self._topics[:, index])
        self._ncz = np.ascontiguousarray(self._ncz[:, :, index])
        self._ng = np.ascontiguousarray(self._ng[:, :, index])

    def sweep(self, sweeps: int) -> None:
        """``sweeps`` Gibbs sweeps of every chain over every word, cells in order."""
        from curiosity_cli.topics._chain_kernels import sweep_chains_kernel

        self._started("sweep")
        sweeps = check_int("sweeps", sweeps, 0)
        n_cells = self._table.shape[0]
        for _ in range(sweeps):
            sweep_chains_kernel(
                self._cells, self._cell_first, self._cell_count, self._words, self._topics, self._phiw, self._ncz,
                self._ng, self._table, np.float32(self._alpha), tuple(self._keys), np.uint64(n_cells + self._sweeps),
            )
            self._sweeps += 1

    def topics(self) -> np.ndarray:
        """(N, R) int8: each word's current topic in each chain."""
        self._started("topics")
        return self._topics[:, : self._n].copy()

    def ml_topics(self) -> np.ndarray:
        """(N, R) int16: each word's maximum-likelihood topic in each chain, the word included.

        ``argmax_k (n_kw + β) / (n_k + Vβ) · (n_Gk + α)`` in float64, ties to the lowest
        topic: :meth:`~curiosity_cli.topics.model.TopicModel.ml_topics` of each chain.
        """
        from curiosity_cli.topics._chain_kernels import ml_chains_kernel

        self._started("ml_topics")
        norm = 1.0 / (self._counts.sum(axis=0, dtype=np.int64) + self._v * self._beta)  # (K, R)
        phid = (self._counts + self._beta) * norm
        out = np.empty((self._words.size, self._keys.size), np.int16)
        ml_chains_kernel(
            self._cells, self._cell_first, self._cell_count, self._words, phid, self._ng, self._alpha, tuple(self._keys), out
        )
        return out[:, : self._n]

    def _set_phis(self, phis: Sequence[np.ndarray]) -> None:
        """Each chain's frozen counts and eq. 5's fixed factors, padded (:data:`LANES`)."""
        phis = _padded(list(phis), _held(len(phis)))
        counts = np.empty((self._v, self._k, len(phis)), np.int32)
        for r, phi in enumerate(phis):
            phi = np.asarray(phi)
            if phi.shape != (self._v, self._k):
                raise ParameterError(f"phis: chain {r} has shape {phi.shape}, expected (V, K) = {(self._v, self._k)}")
            if phi.dtype == np.bool_ or not np.issubdtype(phi.dtype, np.integer):
                raise ParameterError(f"phis: chain {r} has dtype {phi.dtype}, expected integer counts")
            if phi.size and (phi.min() < 0 or phi.sum(axis=0, dtype=np.int64).max() > np.iinfo(np.int32).max):
                raise ParameterError(f"phis: chain {r}'s counts must be >= 0 and each topic's total fit in int32")
            counts[:, :, r] = phi
        inv = (1.0 / (counts.sum(axis=0, dtype=np.int64) + self._v * self._beta)).astype(np.float32)  # (K, R)
        self._counts = counts
        self._phiw = (counts.astype(np.float32) + np.float32(self._beta)) * inv

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
