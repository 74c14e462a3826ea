"""Walkers: how a run chooses its next cell (paper section 4, and our baselines).

Most walkers are **weight functions**: a pure function of a :class:`Candidates` record,
the facts about the in-bounds candidate cells ``g_i`` around the walker's cell (its 4
neighbours, or 8 with ``explore.candidates: 8``), returning one
weight per candidate; the walker steps to ``g_i`` with probability ``weight_i / Σ weight``.
The facts are computed once per step for every weight function alike (so every run logs
them), which keeps each function a one-liner that is easy to check against the paper:

- ``random-walk``: 1 (eq. 7);
- ``stochastic-coverage``: ``1 / U(g_i)`` (eq. 8), with the coverage potential
  ``U(g) = Σ_j n_j / d²(g, c_j)`` over the visited cells ``c_j`` with visit counts
  ``n_j``; ``d`` is the Euclidean distance in cell units. A visited candidate's own term
  has ``d = 0``, which eq. 8 leaves undefined; ``explore.coverage`` names how it is read
  (:func:`coverage_potential`):

  - ``literal`` (the default): ``n / 0 = ∞``, so ``U = ∞`` and weight 0, as the formula
    is written: the walker never steps back while an unvisited neighbour is open. When
    every neighbour is visited the walker is *boxed in* and the step is drawn by the
    limit of eq. 8 as a visited cell's own ``d²`` shrinks to 0 alike for every
    candidate: ``U(g_i)`` becomes ``n(g_i)``, the candidate's own visit count, so the
    least visited neighbours are preferred.
  - ``clamp``: ``d²`` clamped from below at ``explore.min_d2``, what an implementation
    does to avoid dividing by zero (our own earlier code did): with ``min_d2 = 0.25`` a
    visited cell repels as if half a cell away, so a walker may step back onto it.
  - ``others``: a candidate's own visits are left out of its sum, the reading of a
    potential meant to push away from *other* places: a visited neighbour repels only
    through the visited cells around it, like an unvisited one.

  Under every reading a step whose neighbours are all visited is counted as boxed in.
- ``word-perplexity``: ``WordPerplexity(g_i) / U(g_i)`` (eqs. 9 and 11);
- ``topic-perplexity``: ``TopicPerplexity(g_i) / U(g_i)`` (eqs. 10 and 12).

The others are **plans** (:class:`Plan`, :mod:`curiosity_cli.explore.plans`), whose
cells are fixed when the run starts: ``lawnmower``, the pre-programmed boustrophedon
mission, a path compared with the weight functions; and the two **ceilings**
``scattered-cells`` and ``compact-block``, models learned from cells chosen without
walking, which say what any walker could hope for and are reported apart (:data:`CEILINGS`).

Last, the **validation walkers** (:data:`~curiosity_cli.config.VALIDATION_WALKERS`), which
test whether a measure sees an effect where one must exist and none where none does
(issue 58). They are run beside the paper's walkers and compared with stochastic coverage,
never in the paper's verdict (:func:`in_verdict`):

- ``oracle-P`` (:class:`Oracle`, P = 0.1, 0.2, 0.3): stochastic coverage's walk, on its
  streams (the same model and moves), with a planted advantage: at each step, with
  probability P it moves uniformly among the candidates that hold a class the path has
  not yet seen (a human class on at least 10 % of a cell's pixels, the rule that counts a
  class found), when there is one. It reads the map's truth, so it runs only on maps with
  human labels.
- ``sham`` (:class:`Sham`): steers as hard as topic perplexity, on scores that carry no
  information about the candidate. Each candidate ``g`` takes the topic perplexity, under
  the run's model, of the cell ``τ(g)`` that a translation of the map puts in its place
  (drawn when the run starts, wrapping at the edges, at least a quarter of the map's
  larger side away: :meth:`Sham.stand_ins`), and weighs ``TopicPerplexity(τ(g))^γ / U(g)``.
  The exponent ``γ >= 0`` is chosen at each step so that the move's total-variation
  distance from stochastic coverage's (what ``steering.csv`` measures) is the one topic
  perplexity's own weights would have on these candidates: the sham steers exactly as
  hard, at every step, in a direction that says nothing about the candidates. (Without
  the exponent, scores of stand-ins steered about twice as hard as topic perplexity on
  the generated maps and rare-patches, 0.20-0.22 against 0.08-0.12, and scores of cells
  from a permutation of the map three times, 0.35 against 0.11.)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.config import COVERAGE_READINGS, READS_TRUTH, VALIDATION_WALKERS, WALKER_NAMES
from curiosity_cli.errors import ParameterError
from curiosity_cli.explore import plans


@dataclass(frozen=True)
class Candidates:
    """What the walker knows about its neighbouring cells at one step.

    Attributes
    ----------
    cells : (n,) int64 ndarray
        Row-major indices of the in-bounds neighbours: the walker's cell's row of
        :meth:`~curiosity_cli.maps.cell_grid.SquareGrid.neighbour_table` without its ``-1``
        (up, down, left, right, and with 8 candidates the diagonals: those that exist).
    coverage : (n,) float64 ndarray
        The coverage potential ``U(g_i)`` (module docstring), > 0: infinite for a visited
        candidate under the literal reading, and its visit count when the walker is boxed
        in under that reading.
    word_perplexity, topic_perplexity : (n,) float64 ndarrays
        Eqs. 11 and 12 of each candidate's words under the model learned so far (the
        words are seen, not added to the model); 1.0 for a cell without words.
    """

    cells: np.ndarray
    coverage: np.ndarray
    word_perplexity: np.ndarray
    topic_perplexity: np.ndarray


WeightFunction = Callable[[Candidates], np.ndarray]


def random_walk_weights(candidates: Candidates) -> np.ndarray:
    """Every neighbour equally likely (eq. 7)."""
    return np.ones(candidates.cells.shape[0])


def stochastic_coverage_weights(candidates: Candidates) -> np.ndarray:
    """Repelled by visited cells (eq. 8)."""
    return 1.0 / candidates.coverage


def word_perplexity_weights(candidates: Candidates) -> np.ndarray:
    """Drawn to cells whose words the model finds surprising, repelled by visited ones (eq. 9)."""
    return repelled(candidates.word_perplexity, candidates.coverage)


def topic_perplexity_weights(candidates: Candidates) -> np.ndarray:
    """Drawn to cells whose topics are rare on the path so far, repelled by visited ones (eq. 10)."""
    return repelled(candidates.topic_perplexity, candidates.coverage)


def repelled(surprise: np.ndarray, coverage: np.ndarray) -> np.ndarray:
    """``surprise / U``, and 0 where ``U`` is infinite (a visited candidate under the literal
    reading), however surprising the candidate: even an infinite perplexity (counts-only
    P(k | path)) does not undo the literal reading's ban on stepping back."""
    return np.divide(surprise, coverage, out=np.zeros(coverage.shape), where=np.isfinite(coverage))


@dataclass(frozen=True)
class Plan:
    """A walker whose cells are fixed when it starts (:mod:`curiosity_cli.explore.plans`).

    Attributes
    ----------
    cells : callable
        ``cells(start_cell, grid, length, rng)`` -> (length,) int64 ndarray of
        row-major cells of the :class:`~curiosity_cli.maps.cell_grid.SquareGrid` ``grid``.
    ceiling : bool
        True for a reference that is not a path (reported apart from the walkers).
    """

    cells: Callable[[int, SquareGrid, int, np.random.Generator], np.ndarray]
    ceiling: bool = False


lawnmower = Plan(plans.lawnmower)
scattered_cells = Plan(plans.scattered_cells, ceiling=True)
compact_block = Plan(plans.compact_block, ceiling=True)


@dataclass(frozen=True)
class Oracle:
    """A validation walker with a planted advantage (module docstring).

    Attributes
    ----------
    share : float
        P, the chance at each step of moving to a candidate holding a class new to the path.
    """

    share: float

    #: The walker whose streams and moves it takes: with no new class in reach, it is this walker.
    base = "stochastic-coverage"


@dataclass(frozen=True)
class Sham:
    """A validation walker that steers on information-free scores (module docstring)."""

    #: The shortest translation, as a share of the map's larger side: a near one would put a neighbour,
    #: whose terrain is much like the candidate's, in its place.
    min_shift = 0.25
    #: The largest exponent of the stand-ins' scores: enough to put nearly every chance on the highest.
    max_exponent = 64.0

    def stand_ins(self, grid: SquareGrid, rng: np.random.Generator) -> np.ndarray:
        """(n_cells,) int64 ndarray: the cell whose score each cell takes, under one translation of the grid.

        The offset ``(dr, dc)`` is drawn uniformly among those whose distance on the torus,
        ``hypot(min(dr, rows - dr), min(dc, cols - dc))``, is at least :attr:`min_shift`
        of the larger side (the farthest offsets when none is that far); cell ``(r, c)``
        takes the score of ``((r + dr) mod rows, (c + dc) mod cols)``.
        """
        dr, dc = np.meshgrid(np.arange(grid.rows), np.arange(grid.cols), indexing="ij")
        far = np.hypot(np.minimum(dr, grid.rows - dr), np.minimum(dc, grid.cols - dc))
        offsets = np.flatnonzero(far.ravel() >= min(self.min_shift * max(grid.rows, grid.cols), far.max()))
        pick = int(rng.choice(offsets))
        rows, cols = np.divmod(np.arange(grid.n_cells), grid.cols)
        return ((rows + dr.ravel()[pick]) % grid.rows) * grid.cols + (cols + dc.ravel()[pick]) % grid.cols

#: Every walker by the name configs use, in the order of :data:`curiosity_cli.config.WALKER_NAMES`
#: (the paper's four weight functions, the lawnmower baseline, the ceilings, the validation walkers).
WEIGHT_FUNCTIONS: dict[str, WeightFunction | Plan | Oracle | Sham] = {
    "random-walk": random_walk_weights,
    "stochastic-coverage": stochastic_coverage_weights,
    "word-perplexity": word_perplexity_weights,
    "topic-perplexity": topic_perplexity_weights,
    "lawnmower": lawnmower,
    "scattered-cells": scattered_cells,
    "compact-block": compact_block,
    "oracle-0.1": Oracle(0.1),
    "oracle-0.2": Oracle(0.2),
    "oracle-0.3": Oracle(0.3),
    "sham": Sham(),
}
if tuple(WEIGHT_FUNCTIONS) != WALKER_NAMES:  # the config's vocabulary and the walkers are one list
    raise ImportError(f"explore.weights: walkers {tuple(WEIGHT_FUNCTIONS)} are not config.WALKER_NAMES {WALKER_NAMES}")
if tuple(n for n, w in WEIGHT_FUNCTIONS.items() if isinstance(w, (Oracle, Sham))) != VALIDATION_WALKERS:
    raise ImportError(f"explore.weights: the validation walkers are not config.VALIDATION_WALKERS {VALIDATION_WALKERS}")

#: Names of the runs that are ceilings, not walkers: reported apart, never the "next best".
CEILINGS: tuple[str, ...] = tuple(n for n, w in WEIGHT_FUNCTIONS.items() if isinstance(w, Plan) and w.ceiling)
if tuple(n for n, w in WEIGHT_FUNCTIONS.items() if isinstance(w, Oracle)) != READS_TRUTH:
    raise ImportError(f"explore.weights: the oracles are not config.READS_TRUTH {READS_TRUTH}")


def in_verdict(name: str) -> bool:
    """Whether topic perplexity is compared with this walker in the paper's verdict (its next best, its
    leads): every walker but the ceilings and the validation walkers."""
    return name not in CEILINGS and name not in VALIDATION_WALKERS


def stream_name(name: str) -> str:
    """The walker whose random streams a run of ``name`` draws from: an oracle's base walker's, else its own."""
    walker = WEIGHT_FUNCTIONS.get(name)
    return walker.base if isinstance(walker, Oracle) else name


def _literal(n: np.ndarray, d2: np.ndarray, min_d2: float | None) -> np.ndarray:
    """``n / 0 = ∞``: a visited candidate's potential is ``∞``, the others' as under ``others``."""
    return np.where((d2 == 0).any(axis=1), np.inf, _others(n, d2, min_d2))


def _clamp(n: np.ndarray, d2: np.ndarray, min_d2: float | None) -> np.ndarray:
    """``d²`` clamped from below at ``min_d2``: a visited candidate's own term is ``n / min_d2``."""
    return (n / np.maximum(d2, min_d2)).sum(axis=1)


def _others(n: np.ndarray, d2: np.ndarray, min_d2: float | None) -> np.ndarray:
    """A candidate's own visits left out of its sum."""
    own = d2 == 0
    return (np.where(own, 0.0, n) / np.where(own, 1, d2)).sum(axis=1)


#: How :func:`coverage_potential` computes each reading of :data:`curiosity_cli.config.COVERAGE_READINGS`,
#: by its name: ``f(n, d2, min_d2)`` of the visit counts ``n_j`` as a (1, m) row and the candidates'
#: (k, m) squared distances ``d²`` to the visited cells.
_POTENTIALS: dict[str, Callable[[np.ndarray, np.ndarray, float | None], np.ndarray]] = {
    "literal": _literal, "clamp": _clamp, "others": _others,
}


def coverage_potential(
    candidates: np.ndarray, visited: np.ndarray, visits: np.ndarray, grid: SquareGrid, reading: str,
    min_d2: float | None = None,
) -> np.ndarray:
    """``U(g) = Σ_j n_j / d²(g, c_j)`` for each candidate cell ``g`` (eq. 8) under a reading.

    Parameters
    ----------
    candidates : (n,) int ndarray
        Row-major cell indices.
    visited : (m,) int ndarray
        The distinct visited cells ``c_j``.
    visits : (m,) int ndarray
        ``n_j``, how often each was visited.
    grid : SquareGrid
        The map's cells, whose distances ``d`` are.
    reading : {'literal', 'clamp', 'others'}
        A name in :data:`curiosity_cli.config.COVERAGE_READINGS`: what a visited
        candidate's own term (``d = 0``) is (module docstring): ``∞`` (``U = ∞``),
        ``n / min_d2``, or left out.
    min_d2 : float, optional
        The clamp's floor on ``d²``, > 0; read by a reading whose ``reads_min_d2`` says so
        (``clamp``) only.

    Returns
    -------
    (n,) float64 ndarray
        ``∞`` for a visited candidate under a reading whose ``infinite_when_visited``
        says so (``literal``); finite otherwise.

    Raises
    ------
    ParameterError
        An unknown ``reading``, or ``clamp`` without ``min_d2``.
    """
    d2 = grid.squared_distances(candidates, visited)
    n = np.asarray(visits, np.float64)[None, :]
    if reading not in COVERAGE_READINGS:
        raise ParameterError(f"reading: got {reading!r}, expected one of {', '.join(COVERAGE_READINGS)}")
    if COVERAGE_READINGS[reading].reads_min_d2 and min_d2 is None:
        raise ParameterError("min_d2: got None, expected the clamp's floor on d^2 (> 0)")
    return _POTENTIALS[reading](n, d2, min_d2)
