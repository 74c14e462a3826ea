"""The ROST spatial topic model (paper section 3): state, refinement, Φ.

A :class:`TopicModel` holds the words of the cells observed so far, one topic label per
word, and the counts the Gibbs sampler needs. A word's topic is resampled from eq. 5::

    p(z = k) ∝ (n_kw + β) / (n_k + Vβ) · (n_Gk + α)

with every count excluding the word itself; ``n_Gk`` is the number of topic-``k`` words
in the word's cell and its neighbours (the neighbour table; only observed cells hold
words). With a table without columns this is the collapsed Gibbs sampler of LDA with
cells as documents.

Randomness: the model's seed and a 64-bit event counter determine every draw (see
``_rng.py``); the same seed and the same calls give bit-identical states.

Layouts: word-topic counts are stored ``(V, Kp)`` (``Kp`` = K rounded up to a multiple
of 8), so one word's counts over topics are contiguous for the sampler's dense loop;
public accessors return ``(V, K)``, topics in columns.

Snapshots (:mod:`~curiosity_cli.topics.persistence`) read and restore the state through
:meth:`TopicModel.full_state` and :meth:`TopicModel.set_full_state`; model files keep
the compact form built on them (:mod:`~curiosity_cli.topics.compact_state`). What the
model is given is checked by :mod:`~curiosity_cli.topics.model_checks`; how its cells grow
and are forgotten after it is made is :mod:`~curiosity_cli.topics.model_memory`.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.checks import check_choice, check_float, check_int
from curiosity_cli.config import EXPLORE_READINGS, RECENT_NEWEST
from curiosity_cli.errors import ParameterError
from curiosity_cli.topics.batch_sweeps import aligned_zeros, batch_phases, mean_log_likelihood, sweep_phases
from curiosity_cli.topics.model_checks import (
    check_frozen_counts,
    check_model_cells,
    check_vocabulary_hashes,
    check_word_ids,
)
from curiosity_cli.topics.model_memory import CellMemory
from curiosity_cli.topics.neighbours import check_neighbours

_MIN_CAPACITY = 1024
#: The authors' ROST refinery (rost_topics/include/rost/refinery.hpp, ``parallel_refine_online2``,
#: with rost_txy_image_node.cpp's defaults): a cell of the last observation with probability
#: ``p_refine_last_observation`` (0.5, the paper's η), else a cell drawn by age from Beta(``tau``
#: = 2, 1). :meth:`TopicModel.refine_realtime` with ``picks="recent"`` (or ``"recent-64-ours"``).
RECENT_TAU = 2.0
#: Word samples of realtime refinement per kernel call: a tenth of a second or so (20-50 ns a
#: sample), so that a signal stops a step or frame of up to 10^8 samples promptly; the picks
#: are the same however a budget is cut (``refine_realtime_kernel`` resumes them).
RESPONSIVE_SAMPLES = 1 << 22


class TopicModel(CellMemory):
    """Spatial topic model over cells with a fixed neighbour table.

    Parameters
    ----------
    n_topics : int
        K >= 1. Topic labels are stored as int8 for K <= 127 (int16, int32 above).
    vocabulary_size : int
        V >= 1; word ids are ``0 .. V - 1``.
    neighbours : (n_cells, width) int ndarray
        Neighbour table (see :mod:`curiosity_cli.topics.neighbours`): symmetric, ``-1``
        padded, no self-loops. Its row count fixes the cells ``0 .. n_cells - 1``.
    alpha, beta : float
        Dirichlet hyper-parameters, > 0.
    seed : int
        0 .. 2**64 - 1; with the same calls, the same seed gives the same state.
    vocabulary_hashes : mapping of str to str, or sequence of str, optional
        Identifies the vocabularies the word ids come from; stored and saved verbatim.
    frozen_counts : (V, K) int ndarray, optional
        Fix the word-topic counts (Φ) to these, e.g. another model's
        :meth:`topic_word_counts`: words added to this model then count only in their
        cell and neighbourhood, refinement changes only topics, cell counts and
        neighbourhood sums, and the sampler uses ``(frozen_kw + β) / (frozen_k + Vβ)``
        for Φ (the word is not in the frozen counts, so there is nothing to leave out).
        This is how a whole map is labelled with a model learned on a path.

    Raises
    ------
    ParameterError
        Naming the first invalid parameter.
    """

    def __init__(
        self,
        n_topics: int,
        vocabulary_size: int,
        neighbours,
        *,
        alpha: float,
        beta: float,
        seed: int,
        vocabulary_hashes=None,
        frozen_counts=None,
    ):
        self._k = check_int("n_topics", n_topics, 1)
        self._v = check_int("vocabulary_size", vocabulary_size, 1)
        self._table = check_neighbours(neighbours).copy()  # a copy: the caller's stays writeable
        self._table.flags.writeable = False
        self._alpha = check_float("alpha", alpha, 0, low_open=True)
        self._beta = check_float("beta", beta, 0, low_open=True)
        self._seed = check_int("seed", seed, 0, 2**64 - 1)
        self._hashes = check_vocabulary_hashes(vocabulary_hashes)
        self._kp = -(-self._k // 8) * 8
        self._topic_dtype = np.dtype(np.int8 if self._k <= 127 else np.int16 if self._k <= 32767 else np.int32)
        self._colours = None

        n_cells = self._table.shape[0]
        # streams from this id on are no cell's: the picks' and the perplexity draws'. Kept
        # when the model grows, so that growing changes no draw.
        self._free_stream = np.uint64(n_cells)
        self._words = np.zeros(0, np.int32)
        self._topics = np.zeros(0, self._topic_dtype)
        self._n_words = 0  # the end of the stored words, which hold removed cells' until compacted
        self._n_dead = 0
        self._cell_first = np.full(n_cells, -1, np.int64)
        self._cell_count = np.zeros(n_cells, np.int64)
        self._order = np.zeros(n_cells, np.int32)
        self._times = np.zeros(n_cells, np.int64)
        self._n_observed = 0
        # where each observation time's cells start in `_order`, for the first `_grouped` cells:
        # adding cells extends it, anything that reorders them sets `_grouped` back to 0
        self._groups = np.zeros(_MIN_CAPACITY, np.int64)
        self._n_groups = self._grouped = 0
        self._nwk = aligned_zeros((self._v, self._kp), np.int32)
        self._nk = aligned_zeros(self._kp, np.int32)
        self._inv = aligned_zeros(self._kp, np.float32)
        self._ncz = aligned_zeros((n_cells, self._kp), np.int32)
        self._ng = aligned_zeros((n_cells, self._kp), np.int32)
        self._counter = 0
        self._frozen = frozen_counts is not None
        if self._frozen:
            self._nwk[:, : self._k] = check_frozen_counts(frozen_counts, self._v, self._k)
            self._nk[:] = self._nwk.sum(axis=0, dtype=np.int64)
        self._refresh_inverse()

    # ------------------------------------------------------------------ properties

    @property
    def n_topics(self) -> int:
        return self._k

    @property
    def vocabulary_size(self) -> int:
        return self._v

    @property
    def n_cells(self) -> int:
        return self._table.shape[0]

    @property
    def neighbours(self) -> np.ndarray:
        """The (n_cells, width) int32 neighbour table (read-only)."""
        return self._table

    @property
    def alpha(self) -> float:
        return self._alpha

    @property
    def beta(self) -> float:
        return self._beta

    @property
    def seed(self) -> int:
        return self._seed

    @property
    def vocabulary_hashes(self):
        return self._hashes

    @property
    def frozen(self) -> bool:
        """True if the word-topic counts are fixed (``frozen_counts`` was given)."""
        return self._frozen

    @property
    def topic_dtype(self) -> np.dtype:
        return self._topic_dtype

    @property
    def n_words(self) -> int:
        """Number of words in the model."""
        return self._n_words - self._n_dead

    @property
    def n_observed(self) -> int:
        """Number of cells added."""
        return self._n_observed

    # ------------------------------------------------------------------ reading the state

    def observed_cells(self) -> np.ndarray:
        """(n_observed,) int32 ndarray of the cells added, in the order they were added."""
        return self._order[: self._n_observed].copy()

    def observation_times(self) -> np.ndarray:
        """(n_observed,) int64 ndarray: the time of each cell of :meth:`observed_cells`."""
        return self._times[: self._n_observed].copy()

    def is_observed(self, cell: int) -> bool:
        cell = check_int("cell", cell, 0, self.n_cells - 1)
        return bool(self._cell_first[cell] >= 0)

    def cell_words(self, cell: int) -> np.ndarray:
        """(n,) int32 word ids of an observed cell, in the order they were added."""
        cell = check_model_cells([cell], "cell", self._cell_first)[0]
        first = self._cell_first[cell]
        return self._words[first : first + self._cell_count[cell]].copy()

    def topics(self, cells=None) -> np.ndarray:
        """Current topic of every word of ``cells`` (default: all observed, by cell index).

        Returns
        -------
        (n,) ndarray of :attr:`topic_dtype`
            Cell after cell in the order given, each cell's words in the order added
            (for cells added from a word store: store order).
        """
        return self._in_order(self._topics, self._cells_or_all(cells))

    def set_topics(self, topics) -> None:
        """Put every observed word at the topic given and recount from them: the start of a chain from given labels.

        Parameters
        ----------
        topics : (n,) int ndarray
            ``0 .. K - 1``, in the order of :meth:`topics` (every observed cell by cell
            index, each cell's words in the order added). The counts (``n_kw`` and ``n_k``
            unless the model is frozen, each cell's and each neighbourhood's) are made
            from them; the random state is kept.

        Raises
        ------
        ParameterError
            ``topics`` is not one topic per observed word in ``0 .. K - 1``.
        """
        cells = self._cells_or_all(None)
        index = self._in_order(np.arange(self._topics.size), cells)
        topics = np.asarray(topics)
        if topics.shape != index.shape or (topics.size and not np.issubdtype(topics.dtype, np.integer)):
            raise ParameterError(f"topics: got {topics.dtype} of shape {topics.shape}, expected ({index.size},) integers")
        if topics.size and (topics.min() < 0 or topics.max() >= self._k):
            raise ParameterError(f"topics: got {topics.min()} .. {topics.max()}, expected 0 .. {self._k - 1}")
        self._topics[index] = topics
        kp = self._nwk.shape[1]
        word_cells = np.repeat(cells, self._cell_count[cells])
        self._ncz[:] = np.bincount(word_cells * kp + topics, minlength=self._ncz.size).reshape(self._ncz.shape)
        self._ng[:] = self._ncz
        for j in range(self._table.shape[1]):
            around = self._table[:, j]
            has = around >= 0
            self._ng[has] += self._ncz[around[has]]
        if not self._frozen:
            words = self._words[index].astype(np.int64)
            self._nwk[:] = np.bincount(words * kp + topics, minlength=self._nwk.size).reshape(self._nwk.shape)
            self._nk[:] = self._nwk.sum(axis=0)
            self._refresh_inverse()

    def topic_word_counts(self) -> np.ndarray:
        """(V, K) int32 ndarray: ``n_kw``, how often word ``w`` has topic ``k`` (Φ as counts)."""
        return self._nwk[:, : self._k].copy()

    def topic_totals(self) -> np.ndarray:
        """(K,) int32 ndarray: ``n_k``, the words with topic ``k`` (columns of Φ summed)."""
        return self._nk[: self._k].copy()

    def cell_topic_counts(self, cells=None) -> np.ndarray:
        """(n_cells, K) int32 ndarray: topic counts of each cell (zeros if not observed); of ``cells`` only, in their
        order, if given."""
        return self._ncz[:, : self._k].copy() if cells is None else self._ncz[np.asarray(cells, np.int64), : self._k]

    def neighbourhood_counts(self, cells=None) -> np.ndarray:
        """(n_cells, K) int32 ndarray: ``n_Gk``, topic counts of each cell plus its neighbours; of ``cells`` only, in
        their order, if given."""
        return self._ng[:, : self._k].copy() if cells is None else self._ng[np.asarray(cells, np.int64), : self._k]

    def phi(self, words=None) -> np.ndarray:
        """(V, K) float64 ndarray: ``φ_k(w) = (n_kw + β) / (n_k + Vβ)``; each column sums to 1. Of ``words`` only, a
        row per word in their order, if given."""
        rows = self._nwk[:, : self._k] if words is None else self._nwk[np.asarray(words, np.int64), : self._k]
        return (rows.astype(np.float64) + self._beta) / (self._nk[: self._k] + self._v * self._beta)

    def ml_topics(self, cells=None) -> np.ndarray:
        """Maximum-likelihood topic of every word of ``cells`` (default: all observed, by cell index).

        ``argmax_k (n_kw + β) / (n_k + Vβ) · (n_Gk + α)`` with the word *included* in
        every count (eq. 5 of the current state), in float64, ties to the lowest topic.

        Returns
        -------
        (n,) ndarray of :attr:`topic_dtype`
            In the order of :meth:`topics`.
        """
        from curiosity_cli.topics._gibbs_kernels import ml_topics_kernel

        cells = self._cells_or_all(cells)
        out = np.empty(int(self._cell_count[cells].sum()), self._topic_dtype)
        ml_topics_kernel(
            cells, self._cell_first, self._cell_count, self._words, self._nwk, self._nk, self._ng,
            self._k, self._alpha, self._beta, self._v * self._beta, out,
        )
        return out

    def log_likelihood(self) -> float:
        """Mean per-word log-likelihood of the observed words under the current state (nats).

        ``(1/N) Σ_i log Σ_k φ_k(w_i) θ_{c_i}(k)`` with ``φ_k(w) = (n_kw + β) / (n_k + Vβ)``
        and ``θ_c(k) = (n_Gk + α) / (Σ_k n_Gk + Kα)`` the topic distribution of the
        word's neighbourhood (eq. 3), counts including the word itself: the plug-in
        predictive probability of each word, so ``exp(-log_likelihood())`` is the model's
        perplexity on its own words. 0.0 for a model without words. Not the collapsed
        joint ``log p(w, z)``: the spatial prior has no normalised joint to compare with.
        """
        return mean_log_likelihood(self._cells_or_all(None), self._likelihood_arrays())

    def _likelihood_arrays(self) -> tuple:
        """The arguments of ``log_likelihood_sum_kernel`` after its cells (the counts themselves, not copies)."""
        return (
            self._cell_first, self._cell_count, self._words, self._nwk, self._nk, self._ng, self._k, self._alpha,
            self._beta, self._v * self._beta,
        )

    # ------------------------------------------------------------------ changing the state

    def add_cell(self, cell: int, words, *, time: int | None = None) -> None:
        """Add an observed cell's words, each with a uniformly random topic.

        Parameters
        ----------
        cell : int
            A cell not yet in the model, ``0 .. n_cells - 1``.
        words : (n,) int array_like
            Word ids in ``0 .. V - 1``; may be empty.
        time : int, optional
            Observation time, at least the latest time so far; cells with one time are
            one observation for :meth:`refine_realtime` (the cells of one camera frame).
            Default: a new time, one after the latest (each cell its own observation).

        Raises
        ------
        ParameterError
            Naming ``cell``, ``words`` or ``time``.
        """
        cell = check_int("cell", cell, 0, self.n_cells - 1)
        if self._cell_first[cell] >= 0:
            raise ParameterError(f"cell: cell {cell} is already in the model")
        words = check_word_ids(words, self._v)
        latest = int(self._times[self._n_observed - 1]) if self._n_observed else -1
        time = latest + 1 if time is None else check_int("time", time, max(latest, 0))

        first = self._n_words
        self._reserve(first + words.size)
        self._words[first : first + words.size] = words
        self._n_words += words.size
        self._cell_first[cell] = first
        self._cell_count[cell] = words.size
        self._order[self._n_observed] = cell
        self._times[self._n_observed] = time
        self._n_observed += 1
        self._draw_new_topics(cell, first, words.size)

    def add_words(self, cell: int, words, *, time: int | None = None) -> None:
        """Add more words to an observed cell, each with a uniformly random topic.

        A cell observed again (a walker back on it) holds its old words and topics and
        these too, as the authors' ROST ``add_observation`` appends a pose's words to its
        cell. The cell becomes the newest observation, at ``time``, so that realtime
        refinement treats what was just seen as new (in the authors' code a cell keeps
        its place in the refinement order).

        Parameters
        ----------
        cell : int
            A cell already in the model.
        words : (n,) int array_like
            Word ids in ``0 .. V - 1``; may be empty.
        time : int, optional
            As for :meth:`add_cell`.

        Raises
        ------
        ParameterError
            Naming ``cell`` (not in the model), ``words`` or ``time``.
        """
        cell = check_int("cell", cell, 0, self.n_cells - 1)
        if self._cell_first[cell] < 0:
            raise ParameterError(f"cell: cell {cell} is not in the model yet; add_cell adds it")
        words = check_word_ids(words, self._v)
        latest = int(self._times[self._n_observed - 1])
        time = latest + 1 if time is None else check_int("time", time, latest)

        # the new words go right after the cell's, so that its words stay one run
        end = int(self._cell_first[cell] + self._cell_count[cell])
        n_new = words.size
        self._reserve(self._n_words + n_new)
        for array in (self._words, self._topics):
            array[end + n_new : self._n_words + n_new] = array[end : self._n_words].copy()
        self._words[end : end + n_new] = words
        later = self._cell_first >= end
        later[cell] = False
        self._cell_first[later] += n_new
        self._cell_count[cell] += n_new
        self._n_words += n_new
        n = self._n_observed
        self._grouped = 0
        at = int(np.flatnonzero(self._order[:n] == cell)[0])
        self._order[at : n - 1] = self._order[at + 1 : n].copy()
        self._times[at : n - 1] = self._times[at + 1 : n].copy()
        self._order[n - 1] = cell
        self._times[n - 1] = time
        self._draw_new_topics(cell, end, n_new)

    def _draw_new_topics(self, cell: int, first: int, count: int) -> None:
        """Give words ``first .. first + count - 1`` of ``cell`` uniformly random topics from the
        stream of this event, count them, and advance the event counter."""
        from curiosity_cli.topics._gibbs_kernels import add_cell_kernel

        add_cell_kernel(
            cell, first, count, self._words, self._topics, self._nwk, self._nk, self._inv,
            self._ncz, self._ng, self._table, self._k, self._v * self._beta,
            self._key(), np.uint64(self._counter), not self._frozen,
        )
        self._counter += 1

    def restart(self, seed: int) -> None:
        """Every word back to a uniformly random topic, with a new seed.

        The state becomes exactly that of a new model with ``seed`` (and this one's other
        parameters and frozen counts) to which the observed cells were added in cell
        order: a labelling can reuse one whole-map model for many runs instead of
        building it again for each.

        Raises
        ------
        ParameterError
            ``seed`` outside 0 .. 2**64 - 1.
        """
        from curiosity_cli.topics._gibbs_kernels import redraw_topics_kernel

        cells = self._forget_topics(seed)
        if not self._frozen:
            self._nwk[:] = 0
            self._nk[:] = 0
            self._refresh_inverse()
        redraw_topics_kernel(
            cells, self._cell_first, self._cell_count, self._words, self._topics, self._nwk, self._nk, self._inv,
            self._ncz, self._ng, self._table, self._k, self._v * self._beta, self._key(), not self._frozen,
        )
        self._counter = cells.size

    def _forget_topics(self, seed: int) -> np.ndarray:
        """Take a new seed, reorder the observed cells by cell with times 0, 1, ..., and zero
        the cell counts; returns the cells, (n_observed,) int64, in that order."""
        self._seed = check_int("seed", seed, 0, 2**64 - 1)
        cells = self._cells_in_order()
        self._grouped = 0
        self._order[: self._n_observed] = cells
        self._times[: self._n_observed] = np.arange(cells.size)
        self._ncz[:] = 0
        self._ng[:] = 0
        return cells

    def refine_cells(self, cells) -> int:
        """One Gibbs pass over the words of each listed cell, in the order given.

        Exactly sequential (each word sees every earlier change). The ``j``-th listed
        cell draws from its own stream, so a cell may be listed more than once.

        Returns
        -------
        int
            Words sampled.
        """
        from curiosity_cli.topics._gibbs_kernels import refine_cells_kernel

        cells = check_model_cells(cells, "cells", self._cell_first)
        refine_cells_kernel(cells, *self._sampler_arrays(), np.uint64(self._counter), not self._frozen)
        self._counter += cells.size
        return int(self._cell_count[cells].sum())

    def refine_batch(self, sweeps: int, *, threads: int = 1, trace: bool = False) -> np.ndarray | None:
        """Algorithm 1: ``sweeps`` Gibbs sweeps over every observed cell, in parallel phases.

        A sweep visits the observed cells in phases of at most ``m = ceil(n_observed / 16)``
        cells, no two of which share a cell count or a neighbourhood sum, whatever
        ``threads`` is (:func:`~curiosity_cli.topics.batch_sweeps.batch_phases`), and the
        cells of a phase at once on ``threads`` threads.

        Within a phase every cell sees the word-topic counts (``n_kw``, ``n_k``) as at
        the start of the phase plus its own changes, and in sweep ``s`` draws from the
        stream ``(counter + s, cell)``; cell counts and neighbourhood sums are exact. So
        the result is the same for every ``threads``, and differs from an exactly
        sequential sweep (:meth:`refine_cells`) only in that staleness, of at most ``m``
        cells.

        Parameters
        ----------
        sweeps : int
            >= 0.
        threads : int
            >= 1. Each thread past the first refines on its own copy of the word-topic
            counts, (V, Kp) int32 (``Kp`` = K rounded up to a multiple of 8), made for
            the call; none for a frozen model, whose counts are only read.
        trace : bool
            Also take :meth:`log_likelihood` after each sweep, on the same threads (the
            same value as calling it then). Not for a frozen model.

        Returns
        -------
        (sweeps,) float64 ndarray or None
            With ``trace``, the log-likelihood after each sweep.
        """
        sweeps = check_int("sweeps", sweeps, 0)
        threads = check_int("threads", threads, 1)
        if trace and self._frozen:
            raise ParameterError("trace: a frozen model's log-likelihood is not traced (its counts do not change)")
        if sweeps == 0 or self._n_observed == 0:
            return np.full(sweeps, self.log_likelihood()) if trace else None
        phases = batch_phases(self._cells_in_order(), self._colouring())
        out = sweep_phases(
            phases, self._sampler_arrays(), self._k, self._counter, sweeps, threads, frozen=self._frozen,
            trace=(self._cells_or_all(None), self._likelihood_arrays()) if trace else None,
        )
        self._counter += sweeps
        return out

    def refine_realtime(self, word_budget: int, *, eta: float, picks: str = "uniform", return_newest: bool = False):
        """Algorithm 2: refine picked observations until ``word_budget`` words are sampled.

        Each pick refines every cell observed at one observation time
        (:meth:`refine_cells`), chosen by ``picks``:

        - ``uniform``: the newest time with probability ``eta``, else a uniformly random
          earlier one (eq. 6; with a single time, always that one);
        - ``recent``: as the authors' ROST refinery (``parallel_refine_online2``), with
          probability ``eta`` the newest time (the last observation), else one drawn by
          age from Beta(:data:`RECENT_TAU`, 1) over all ``T`` times (time
          ``floor(T u^(1/τ))``, ``u`` uniform), so recent observations are refined more
          often and old ones still now and then;
        - ``recent-64-ours``: as ``recent``, but with probability ``eta`` a uniform one
          of the newest 64 times (our earlier translation of the refinery's
          ``observation_size``; :data:`~curiosity_cli.config.RECENT_NEWEST`).

        Deterministic.

        Parameters
        ----------
        word_budget : int
            >= 0. Each word sampled spends one unit, and so does a pick whose cells hold
            no words (so the call ends even if every cell it can pick is empty).
        eta : float
            Refinement bias, 0 <= eta <= 1.
        picks : {'uniform', 'recent', 'recent-64-ours'}
        return_newest : bool
            Also return the words sampled at the newest observation time: 0 when no pick
            chose it, and its words keep the topics they were given (a camera frame whose
            perplexity then reads random topics).

        Returns
        -------
        int, or (int, int) with ``return_newest``
            Words sampled: at least ``word_budget`` (the last pick overshoots by less
            than the words of one observation) unless some picks found no words.
        """
        from curiosity_cli.topics._gibbs_kernels import refine_realtime_kernel
        from curiosity_cli.topics._rng import stream_start

        word_budget = check_int("word_budget", word_budget, 0)
        eta = check_float("eta", eta, 0, 1)
        picks = check_choice("picks", picks, EXPLORE_READINGS["refine_picks"])
        if word_budget == 0 or self._n_observed == 0:
            return (0, 0) if return_newest else 0
        counter = np.uint64(self._counter)
        # picks' stream state, words sampled, idle picks, picks, newest time's words
        carry = np.zeros(5, np.uint64)
        carry[0] = stream_start(self._key(), counter, self._free_stream)
        arrays = (self._order[: self._n_observed], self._time_groups(), *self._sampler_arrays())
        while (spent := int(carry[1]) + int(carry[2])) < word_budget:
            refine_realtime_kernel(
                min(word_budget, spent + RESPONSIVE_SAMPLES), eta, *arrays, counter, not self._frozen,
                picks in RECENT_NEWEST, RECENT_NEWEST.get(picks, 0), RECENT_TAU, carry,
            )
        done, n_picks, newest = int(carry[1]), int(carry[3]), int(carry[4])
        self._counter += 1 + n_picks
        return (done, newest) if return_newest else done

    # ------------------------------------------------------------------ the whole state (persistence.py, compact_state.py)

    def full_state(self) -> dict:
        """A copy of the whole mutable state in the model's own layout, random state included.

        What a snapshot (:func:`~curiosity_cli.topics.persistence.take_snapshot`) keeps;
        :meth:`set_full_state` puts it back. A model file's compact form is made from it
        and put back through its setter (:mod:`~curiosity_cli.topics.compact_state`).

        Returns
        -------
        dict
            ``words``, ``topics``: (n_words,) int32 and :attr:`topic_dtype`, in storage
            order; ``cell_first``, ``cell_count``: (n_cells,) int64, where each cell's
            words sit; ``order``: (n_observed,) int32, the cells in the order added;
            ``times``: (n_observed,) int64; ``nwk``: (V, Kp), ``nk``: (Kp,), ``ncz`` and
            ``ng``: (n_cells, Kp), the int32 counts (``Kp`` = K rounded up to a multiple
            of 8); ``counter``: int, the random state.
        """
        n = self._n_observed
        return {
            "words": self._words[: self._n_words].copy(),
            "topics": self._topics[: self._n_words].copy(),
            "cell_first": self._cell_first.copy(),
            "cell_count": self._cell_count.copy(),
            "order": self._order[:n].copy(),
            "times": self._times[:n].copy(),
            "nwk": self._nwk.copy(),
            "nk": self._nk.copy(),
            "ncz": self._ncz.copy(),
            "ng": self._ng.copy(),
            "counter": self._counter,
        }

    def set_full_state(self, *, words, topics, cell_first, cell_count, order, times, nwk, nk, ncz, ng, counter) -> None:
        """Return to a state :meth:`full_state` gave, random state included.

        The state must come from a model with the same K, V, neighbour table and
        frozenness (and, for one that grew, made with as many cells: its later draws
        depend on that); that is not checked here (the caller knows where it came from).
        The arrays are copied.
        """
        self._words = words.copy()
        self._topics = topics.copy()
        self._n_words = words.size
        self._n_dead = words.size - int(cell_count.sum())
        self._cell_first[:] = cell_first
        self._cell_count[:] = cell_count
        self._n_observed = order.size
        self._grouped = 0
        self._order[: self._n_observed] = order
        self._times[: self._n_observed] = times
        self._nwk[:] = nwk
        self._nk[:] = nk
        self._ncz[:] = ncz
        self._ng[:] = ng
        self._counter = counter
        self._refresh_inverse()

    # ------------------------------------------------------------------ internals

    def _key(self) -> np.uint64:
        from curiosity_cli.topics._rng import mix

        return np.uint64(mix(np.uint64(self._seed)))

    def _sampler_arrays(self) -> tuple:
        """The kernels' shared arguments, from ``cell_first`` to ``key``."""
        return (
            self._cell_first, self._cell_count, self._words, self._topics, self._nwk, self._nk, self._inv,
            self._ncz, self._ng, self._table, np.float32(self._alpha), np.float32(self._beta),
            self._v * self._beta, self._key(),
        )

    def _time_groups(self) -> np.ndarray:
        """(T + 1,) int64: where each of the T observation times' cells start in the order
        added, then ``n_observed`` (at least 1). Extended over the cells added since the last
        call, so that a stream's refinement per frame costs no more as its frames accumulate."""
        n, known = self._n_observed, self._grouped
        times = self._times
        if known == 0:
            self._n_groups = 0
            starts = np.concatenate([[0], np.flatnonzero(np.diff(times[:n])) + 1])
        else:
            starts = np.flatnonzero(times[known:n] != times[known - 1 : n - 1]) + known
        end = self._n_groups + starts.size
        if end + 1 > self._groups.size:
            self._groups = np.concatenate([self._groups, np.zeros(max(end + 1, self._groups.size), np.int64)])
        self._groups[self._n_groups : end] = starts
        self._groups[end] = n
        self._n_groups, self._grouped = end, n
        return self._groups[: end + 1]

    def _refresh_inverse(self) -> None:
        self._inv[:] = 0
        self._inv[: self._k] = (1.0 / (self._nk[: self._k] + self._v * self._beta)).astype(np.float32)

    def _colouring(self) -> np.ndarray:
        if self._colours is None:
            from curiosity_cli.topics._gibbs_kernels import distance2_colouring

            self._colours = distance2_colouring(self._table)
        return self._colours

    def _reserve(self, size: int) -> None:
        if size <= self._words.size:
            return
        capacity = max(size, 2 * self._words.size, _MIN_CAPACITY)
        words = np.zeros(capacity, np.int32)
        topics = np.zeros(capacity, self._topic_dtype)
        words[: self._n_words] = self._words[: self._n_words]
        topics[: self._n_words] = self._topics[: self._n_words]
        self._words, self._topics = words, topics

    def _cells_or_all(self, cells) -> np.ndarray:
        if cells is None:
            return self._cells_in_order()
        return check_model_cells(cells, "cells", self._cell_first)

    def _cells_in_order(self) -> np.ndarray:
        """(n_observed,) int64: the observed cells, by cell index."""
        return np.sort(self._order[: self._n_observed]).astype(np.int64)

    def _in_order(self, per_word: np.ndarray, cells: np.ndarray) -> np.ndarray:
        """The entries of a per-word array for ``cells`` (observed), cell after cell."""
        if not len(cells):
            return per_word[:0].copy()
        first, count = self._cell_first, self._cell_count
        return np.concatenate([per_word[first[c] : first[c] + count[c]] for c in cells])

