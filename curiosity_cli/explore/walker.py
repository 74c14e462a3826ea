"""One exploration run: a walker on a map's cell grid, learning a topic model as it goes.

Each step ``t`` (0-based) of a run of ``path_length`` steps, with the walker in cell ``p_t``:

1. **Observe**: on the first visit, the words of ``p_t`` enter the topic model with
   observation time ``t``; on a later visit they enter again when ``explore.revisits``
   is ``again`` (the authors' ROST), and the cell becomes the newest observation.
2. **Refine**: realtime refinement (Algorithm 2, bias η; the picks of
   ``explore.refine_picks``) for a fixed budget of word samples, or for a wall-clock
   budget when ``explore.step_seconds`` is set. The fixed budget stands in for the
   paper's 200 ms per step, so results do not depend on how fast the machine is.
3. **Score** the in-bounds candidates (the cell's row of the grid's neighbour table,
   :meth:`~curiosity_cli.maps.cell_grid.SquareGrid.neighbour_table`: up, down, left, right,
   and with ``explore.candidates`` 8 the diagonals, those that exist) with the run's
   weight function (:mod:`curiosity_cli.explore.weights`), under the run's reading of
   eq. 8; topic perplexity (eq. 12) under the readings ``explore.candidate_context``,
   ``candidate_sweeps``, ``candidate_labels``, ``candidate_words`` and ``path_topics``
   (:func:`~curiosity_cli.topics.perplexity.topic_perplexity`). A step
   whose neighbours are all visited is counted as boxed in; under the literal reading,
   which leaves them all weight 0, they are scored again by that module's boxed-in rule.
4. **Move** to a neighbour drawn with probability proportional to its weight
   (:func:`move_probabilities`: NaN counts as 0, infinite weights take every chance
   among themselves); if no weight is left positive the draw is uniform, and the step
   is counted as a fallback. A validation walker (:mod:`curiosity_cli.explore.weights`) moves
   by its own rule: an oracle may replace its base walker's move by one to a candidate
   holding a class the path has not seen; the sham weighs candidates by other cells' scores.

A planned walker (:class:`~curiosity_cli.explore.weights.Plan`: the lawnmower and the
ceilings) skips steps 3 and 4: its cells are drawn when it starts, from the same move
stream, and nothing is scored.

After ``L`` steps the path has length ``L`` (``p_0 .. p_{L-1}`` observed); at each
checkpoint length the model's word-topic counts Φ_p are kept. The last step only
observes and refines: nothing scores a move that would never be observed.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from curiosity_cli.config import COVERAGE_READINGS, ExploreConfig, ModelConfig
from curiosity_cli.errors import ParameterError
from curiosity_cli.explore.weights import (
    WEIGHT_FUNCTIONS, Candidates, Oracle, Plan, Sham, coverage_potential, repelled, stochastic_coverage_weights,
    topic_perplexity_weights,
)
from curiosity_cli.topics.map_model import map_topic_model
from curiosity_cli.words.store import WordStore

# word samples per call when refining against the clock: small enough to stop on time
_CLOCK_CHUNK = 5000


@dataclass(frozen=True)
class SparseCounts:
    """Non-zero entries of a (V, K) word-topic count matrix, for compact checkpoints.

    Attributes
    ----------
    words, topics : (nnz,) int ndarrays
        Row (word id) and column (topic) of each non-zero count.
    counts : (nnz,) int32 ndarray
    shape : (int, int)
        ``(V, K)``.
    """

    words: np.ndarray
    topics: np.ndarray
    counts: np.ndarray
    shape: tuple[int, int]

    @classmethod
    def of(cls, dense: np.ndarray) -> SparseCounts:
        words, topics = np.nonzero(dense)
        return cls(
            words.astype(np.min_scalar_type(dense.shape[0] - 1)),
            topics.astype(np.min_scalar_type(dense.shape[1] - 1)),
            dense[words, topics].astype(np.int32),
            (int(dense.shape[0]), int(dense.shape[1])),
        )

    def dense(self) -> np.ndarray:
        """(V, K) int32 ndarray."""
        out = np.zeros(self.shape, np.int32)
        out[self.words, self.topics] = self.counts
        return out

    def hash_into(self, digest) -> None:
        """Feed the counts to a ``hashlib`` digest: words, topics and counts as int64, then the shape.

        One spelling for every content key of Φ_p: a label file's key
        (:func:`~curiosity_cli.label.shared_items.label_key`) and a study record's runs
        (:mod:`~curiosity_cli.study.record`) read the same bytes, whatever integer types a
        checkpoint was stored in.
        """
        for array in (self.words, self.topics, self.counts):
            digest.update(np.ascontiguousarray(array, np.int64).tobytes())
        digest.update(np.asarray(self.shape, np.int64).tobytes())


@dataclass(frozen=True)
class Exploration:
    """What one run did and learned.

    Attributes
    ----------
    path : (L,) int64 ndarray
        Row-major cell of each step.
    first_visit : (L,) bool ndarray
        Whether the step observed a new cell.
    words_sampled : (L,) int64 ndarray
        Word samples of refinement at each step.
    log_likelihood : (L,) float64 ndarray
        The model's mean per-word log-likelihood after each step's refinement (nats).
    fallback : (L,) bool ndarray
        Steps whose move was drawn uniformly because no weight was positive (always
        False on the last step, which does not move).
    boxed_in : (L,) bool ndarray
        Steps whose neighbours were all visited (under the literal reading of eq. 8, the
        steps the boxed-in rule scored).
    candidate_step, candidate_cell : (M,) int64 ndarrays
        For every scored neighbour: the step and the neighbour's cell.
    coverage, word_perplexity, topic_perplexity, weight : (M,) float64 ndarrays
        The facts the weight function saw and the weight it gave.
    chosen : (M,) bool ndarray
        Whether the walker moved there.
    checkpoints : dict of int to SparseCounts
        Word-topic counts Φ_p at each checkpoint path length.
    """

    path: np.ndarray
    first_visit: np.ndarray
    words_sampled: np.ndarray
    log_likelihood: np.ndarray
    fallback: np.ndarray
    boxed_in: np.ndarray
    candidate_step: np.ndarray
    candidate_cell: np.ndarray
    coverage: np.ndarray
    word_perplexity: np.ndarray
    topic_perplexity: np.ndarray
    weight: np.ndarray
    chosen: np.ndarray
    checkpoints: dict[int, SparseCounts]


def move_probabilities(weights: np.ndarray) -> tuple[np.ndarray, bool]:
    """The walker's chance of stepping to each candidate; ``(probabilities, fell back to uniform)``.

    Proportional to ``weights``, with two limits: NaN and ``-inf`` count as 0, and when
    some weights are ``+inf`` (a candidate infinitely surprising, e.g. a topic the path
    has never seen under counts-only P(k | path)) the walker steps to one of those,
    uniformly, which is the limit of proportional weights as theirs grow without bound.
    When no weight is left positive the step is uniform and counted as a fallback.
    Negative weights are a bug in the weight function: the caller checks.

    Parameters
    ----------
    weights : (n,) float ndarray, n >= 1

    Returns
    -------
    (n,) float64 ndarray, bool
    """
    weights = np.asarray(weights, np.float64)
    infinite = weights == np.inf
    if infinite.any():
        return infinite / np.count_nonzero(infinite), False
    usable = np.where(np.isfinite(weights), weights, 0.0)
    total = usable.sum()
    if not total > 0:
        return np.full(weights.shape[0], 1.0 / weights.shape[0]), True
    return usable / total, False


def draw_move(weights: np.ndarray, rng: np.random.Generator) -> tuple[int, bool]:
    """Index drawn from :func:`move_probabilities` of ``weights``; ``(index, fell back to uniform)``."""
    probabilities, fell_back = move_probabilities(weights)
    if fell_back:
        return int(rng.integers(weights.shape[0])), True
    return int(rng.choice(weights.shape[0], p=probabilities)), False


def explore(
    store: WordStore,
    weight_function: str,
    start_cell: int,
    *,
    model: ModelConfig,
    settings: ExploreConfig,
    seed,
    truth: np.ndarray | None = None,
) -> Exploration:
    """Run one exploration path (module docstring) and return its records and checkpoints.

    Parameters
    ----------
    store : WordStore
        The map's words by cell.
    weight_function : str
        A name in :data:`~curiosity_cli.explore.weights.WEIGHT_FUNCTIONS`: a weight
        function or a plan.
    start_cell : int
        Row-major cell of the first step.
    model : ModelConfig
        Topics, α, β, η and the spatial neighbourhood of the topic model.
    settings : ExploreConfig
        Path length, checkpoints, refinement budget and the reading of eq. 8.
    seed : int or sequence of int
        Entropy for :class:`numpy.random.SeedSequence`; the topic model and the moves
        draw from two streams spawned from it, a validation walker's own draws from a
        third (an oracle's coins; the sham's translation).
    truth : (n_cells, C) bool ndarray, optional
        The classes present in each cell (:func:`~curiosity_cli.maps.cell_classes.classes_present`):
        what an oracle (:class:`~curiosity_cli.explore.weights.Oracle`) reads; required for one.

    Returns
    -------
    Exploration

    Raises
    ------
    ParameterError
        An unknown weight function, a start cell off the grid, a single-cell map, an oracle
        without ``truth`` of a row per cell, or a weight function returning the wrong shape
        or negative weights.
    """
    from curiosity_cli.topics.perplexity import word_perplexity

    if weight_function not in WEIGHT_FUNCTIONS:
        raise ParameterError(
            f"weight_function: got {weight_function!r}, expected one of {', '.join(WEIGHT_FUNCTIONS)}"
        )
    walker = WEIGHT_FUNCTIONS[weight_function]
    n_cells = store.n_cells
    if n_cells < 2:
        raise ParameterError("store: the map has a single cell, so there is nowhere to move")
    if not 0 <= int(start_cell) < n_cells:
        raise ParameterError(f"start_cell: got {start_cell}, expected 0 .. {n_cells - 1}")
    if isinstance(walker, Oracle) and (truth is None or np.shape(truth)[0] != n_cells):
        raise ParameterError(
            f"truth: expected the classes present in each of the map's {n_cells} cells for {weight_function!r}, "
            "which reads the map's human labels"
        )
    # spawn(3)'s first two children are spawn(2)'s: the paper's walkers draw as they always did
    model_seed, move_seed, own_seed = np.random.SeedSequence(seed).spawn(3)
    rng = np.random.default_rng(move_seed)
    own = np.random.default_rng(own_seed)
    seen = np.zeros(np.shape(truth)[1], bool) if isinstance(walker, Oracle) else None
    stand_in = walker.stand_ins(store.grid, own) if isinstance(walker, Sham) else None
    topic_model = map_topic_model(store, model, int(model_seed.generate_state(1, np.uint64)[0]))
    neighbours = store.grid.neighbour_table(settings.candidates)

    length = settings.path_length
    path = np.empty(length, np.int64)
    first_visit = np.zeros(length, bool)
    words_sampled = np.zeros(length, np.int64)
    log_likelihood = np.empty(length)
    fallback = np.zeros(length, bool)
    boxed_in = np.zeros(length, bool)
    visits = np.zeros(n_cells, np.int64)
    scored: list[tuple] = []
    checkpoints: dict[int, SparseCounts] = {}
    keep = set(settings.checkpoints)

    planned = walker.cells(int(start_cell), store.grid, length, rng) if isinstance(walker, Plan) else None
    cell = int(start_cell) if planned is None else int(planned[0])
    for step in range(length):
        path[step] = cell
        if seen is not None:
            seen |= truth[cell]
        if visits[cell] == 0:
            first_visit[step] = True
            topic_model.add_cell(cell, store.cell_words(cell), time=step)
        elif settings.revisits == "again":
            topic_model.add_words(cell, store.cell_words(cell), time=step)
        visits[cell] += 1
        words_sampled[step] = _refine(topic_model, model.eta, settings)
        log_likelihood[step] = topic_model.log_likelihood()
        if step + 1 in keep:
            checkpoints[step + 1] = SparseCounts.of(topic_model.topic_word_counts())
        if step + 1 == length:
            break
        if planned is not None:
            cell = int(planned[step + 1])
            continue

        around = neighbours[cell]
        cells = around[around >= 0].astype(np.int64)
        visited = np.flatnonzero(visits)
        candidates = Candidates(
            cells=cells,
            coverage=coverage_potential(
                cells, visited, visits[visited], store.grid, settings.coverage, settings.min_d2
            ),
            word_perplexity=np.array([word_perplexity(topic_model, store.cell_words(g)) for g in cells]),
            topic_perplexity=_perplexities(topic_model, store, cells, settings),
        )
        boxed_in[step] = bool(np.all(visits[cells] > 0))
        # every candidate's potential is then ∞, leaving nothing to weigh: eq. 8's limit is their own visit counts
        if boxed_in[step] and COVERAGE_READINGS[settings.coverage].infinite_when_visited:
            candidates = dataclasses.replace(candidates, coverage=visits[cells].astype(np.float64))
        if isinstance(walker, Oracle):
            weights, choice, fallback[step] = _oracle_move(walker, candidates, truth[cells] & ~seen, rng, own)
        else:
            if isinstance(walker, Sham):
                weights = _sham_weights(walker, candidates, _perplexities(topic_model, store, stand_in[cells], settings))
            else:
                weights = _weights(walker, weight_function, candidates)
            choice, fallback[step] = draw_move(weights, rng)
        scored.append((step, candidates, weights, choice))
        cell = int(cells[choice])

    return _records(path, first_visit, words_sampled, log_likelihood, fallback, boxed_in, scored, checkpoints)


def _perplexities(topic_model, store: WordStore, cells: np.ndarray, settings: ExploreConfig) -> np.ndarray:
    """(n,) float64 ndarray: eq. 12 of each of ``cells``' words under the model, under the run's readings."""
    from curiosity_cli.topics.perplexity import topic_perplexity

    return np.array([
        topic_perplexity(
            topic_model, store.cell_words(g), g, context=settings.candidate_context, sweeps=settings.candidate_sweeps,
            labels=settings.candidate_labels, words_in_model=settings.candidate_words, path_topics=settings.path_topics,
        )
        for g in cells
    ])


def _oracle_move(oracle: Oracle, candidates: Candidates, new: np.ndarray, rng, own) -> tuple[np.ndarray, int, bool]:
    """An oracle's step: ``(weights, choice, fell back)``.

    Its base walker's move is drawn first from the move stream, so that the stream
    advances as the base walker's does; then one coin from the oracle's own stream, and
    when it falls below P and some candidate holds a new class (``new``: (n, C) bool, the
    classes each candidate holds that the path has not seen), a move uniform among those
    candidates replaces it. The weights recorded are the ones the move was drawn from.
    """
    weights = _weights(WEIGHT_FUNCTIONS[oracle.base], oracle.base, candidates)
    choice, fell_back = draw_move(weights, rng)
    holds_new = new.any(axis=1)
    if own.random() < oracle.share and holds_new.any():
        return holds_new.astype(np.float64), int(own.choice(np.flatnonzero(holds_new))), False
    return weights, choice, fell_back


def _sham_weights(sham: Sham, candidates: Candidates, scores: np.ndarray) -> np.ndarray:
    """The sham's weights ``scores^γ / U``: ``scores`` are its stand-ins' topic perplexities, and ``γ`` in
    ``[0, max_exponent]`` is found by bisection so that the move's total-variation distance from stochastic
    coverage's is topic perplexity's on these candidates (or as near as the largest exponent comes)."""
    coverage_only, _ = move_probabilities(stochastic_coverage_weights(candidates))

    def distance(weights: np.ndarray) -> float:
        return 0.5 * float(np.abs(move_probabilities(weights)[0] - coverage_only).sum())

    def steered(exponent: float) -> np.ndarray:
        with np.errstate(over="ignore"):  # an overflow is +inf: every chance among the highest, as its limit
            return repelled(scores**exponent, candidates.coverage)

    target = distance(topic_perplexity_weights(candidates))
    low, high = 0.0, sham.max_exponent
    if distance(steered(high)) > target:
        for _ in range(40):  # the exponent to 64 / 2^40: far below any change of a step's chances that matters
            middle = 0.5 * (low + high)
            low, high = (middle, high) if distance(steered(middle)) < target else (low, middle)
    return steered(high)


def _weights(weight_function, name: str, candidates: Candidates) -> np.ndarray:
    weights = np.asarray(weight_function(candidates), np.float64)
    if weights.shape != candidates.cells.shape or np.any(weights < 0):
        raise ParameterError(
            f"weight function {name!r}: returned {weights!r}, expected {candidates.cells.size} weights >= 0"
        )
    return weights


def _refine(topic_model, eta: float, settings: ExploreConfig) -> int:
    if settings.step_seconds is None:
        return topic_model.refine_realtime(settings.samples_per_step, eta=eta, picks=settings.refine_picks)
    deadline = time.perf_counter() + settings.step_seconds
    done = 0
    while time.perf_counter() < deadline:
        done += topic_model.refine_realtime(_CLOCK_CHUNK, eta=eta, picks=settings.refine_picks)
    return done


def _records(path, first_visit, words_sampled, log_likelihood, fallback, boxed_in, scored, checkpoints) -> Exploration:
    def column(get, dtype) -> np.ndarray:
        parts = [np.asarray(get(*entry), dtype) for entry in scored]
        return np.concatenate(parts) if parts else np.zeros(0, dtype)

    return Exploration(
        path=path,
        first_visit=first_visit,
        words_sampled=words_sampled,
        log_likelihood=log_likelihood,
        fallback=fallback,
        boxed_in=boxed_in,
        candidate_step=column(lambda step, c, w, i: np.full(c.cells.size, step), np.int64),
        candidate_cell=column(lambda step, c, w, i: c.cells, np.int64),
        coverage=column(lambda step, c, w, i: c.coverage, np.float64),
        word_perplexity=column(lambda step, c, w, i: c.word_perplexity, np.float64),
        topic_perplexity=column(lambda step, c, w, i: c.topic_perplexity, np.float64),
        weight=column(lambda step, c, w, i: w, np.float64),
        chosen=column(lambda step, c, w, i: np.arange(c.cells.size) == i, bool),
        checkpoints=checkpoints,
    )
