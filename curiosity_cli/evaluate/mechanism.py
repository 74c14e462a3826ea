"""Mechanism: does topic perplexity point the walker at what is new, and is that why it would gather more MI?

The paper's claim is that a walker weighing stochastic coverage's ``1 / U`` (eq. 8) by
topic perplexity gathers more mutual information with the human labels than the other
walkers, because the cells it finds surprising are those that hold what the path has not
seen yet. MI with the human labels (:mod:`~curiosity_cli.evaluate.information`) grows
when the path reaches classes it had not reached; these measures take the claim apart
into its links, each from what a run recorded (``candidates.csv``: every scored
neighbour's coverage potential ``U``, word and topic perplexity, the walker's weight; every
walker records both perplexities, even one that does not use them) and the map's human
labels. A human class is *present* in a cell when it covers at least
:data:`~curiosity_cli.experiment.recipes.CLASS_SHARE_PERCENT` % of its pixels
(:func:`~curiosity_cli.maps.cell_classes.classes_present`, as the label stage has it).

A path of length ``L`` visits ``path[0 .. L - 1]``; its move ``t`` goes from ``path[t]`` to
``path[t + 1]``, and the candidates of that move are the rows with ``step == t``
(moves ``0 .. L - 2``). At move ``t`` a class is *new to the path* when it is present in a
candidate cell but in none of ``path[0 .. t]``; a candidate is *unvisited* when its cell
is none of ``path[0 .. t]`` (a candidate holding a new class always is).

- ``auc`` (M1), does the score point at what is new? The within-step AUC of the walker's
  score (its own perplexity; topic perplexity's for walkers without one: random walk,
  stochastic coverage, which gives a reference for what an uninformed walker's candidates
  look like under topic perplexity) for the candidates holding a new class (positives)
  against the other unvisited candidates of the same move (negatives): each pair within a
  move counts 1 when the positive scores higher, ½ on a tie, 0 below; the run's AUC is the
  wins over the pairs pooled over its moves (``pairs``; NaN without any). An infinite
  score is above any finite one, and two infinities tie. 0.5: the score does not tell
  what is new from what is merely unvisited; 1: it always ranks the new above the rest.
  Visited candidates are left out, since coverage already turns the walker away from them.
  ``infinite_ties`` is the share of those pairs in which both scores are ``+inf`` (NaN
  without pairs): each is counted ½, so an AUC near 0.5 made of them says the score could
  not rank the pair at all, not that it ranked it at random.
- ``auc_mixed`` (M1 against mixed texture): the same AUC, the same positives, with the
  negatives restricted to the unvisited candidates of *mixed texture* whose classes the
  path has all seen: at least two classes present and none of them new (``pairs_mixed``
  its pairs; NaN without any). A candidate holding a new class lies mostly on a boundary
  between classes, so it holds two textures, while most of ``auc``'s negatives hold one:
  a score high on any heterogeneous cell, blind to what the path has seen, gets ``auc``
  above 0.5. Against negatives as heterogeneous as the positives that score gets about
  0.5, and only one that ranks the new first stays above it.
- ``opportunity`` (M2), how often there was anything new to point at: the share of the
  scored moves (``moves``) with at least one candidate holding a new class. A score can
  only make a difference at such moves; a map whose classes lie in large patches gives few.
  ``new_share`` is the same per candidate: the share of the scored candidates
  (``candidates``, of moves ``0 .. L - 2``) holding a new class (NaN without any), which
  does not grow with the candidates a move offers, so experiments with 8 and with 4
  candidates per move compare on it.
- ``gain`` (M3), did the walker act on it? At those moves, the chance the walker gave the
  candidates holding a new class (:func:`~curiosity_cli.explore.walker.move_probabilities`
  of its weights) less the chance stochastic coverage would have given them
  (``move_probabilities(1 / U)``), averaged over the moves (NaN without one). A score that
  points at the new (M1) moves the walker towards it only as much as the weights let it
  stray from coverage (:mod:`~curiosity_cli.evaluate.steering`); stochastic coverage's own
  gain is 0.
- ``new_class_cells`` and ``classes_found`` (M4), did it reach more? The steps ``0 .. L - 1``
  at which the walker entered a cell holding a class new to the path (the start cell
  counts when it holds any class), and the classes present in ``path[0 .. L - 1]``
  (:func:`~curiosity_cli.evaluate.information.classes_found`), the quantity that MI
  against the human labels rewards.
- ``infinite_share``, ``infinite_unseen`` and ``finite_unseen`` (M5), what the score sees.
  The share of the scored candidates whose topic perplexity is infinite; of those, the
  share holding at least one word id that none of ``path[0 .. t]``'s cells holds (at the
  candidate's move ``t``); and the same share among the candidates whose topic perplexity
  is finite, its base rate (each NaN without candidates to count). Under counts-only
  P(k | path) a candidate is infinitely surprising when its words' topics have never been
  seen on the path; if infinite candidates hold unseen words much more often than finite
  ones do, topic perplexity's pointing is word novelty, which need not be class novelty.
  ``infinite_unseen`` alone cannot say so: next to a short path most cells hold a word it
  has not seen.

Rows as :mod:`~curiosity_cli.evaluate.steering`'s: one per run and checkpoint length,
none for a run that scored nothing (the planned walkers). :func:`summarise_mechanism`
pools them over runs per map, walker and length, each with a 95 % interval over runs.
Tables written before ``infinite_ties``, ``pairs_mixed``, ``auc_mixed``, ``new_share`` and
``finite_unseen`` existed (:data:`ADDED_MEASURES`) are still summarised, without those.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from curiosity_cli.errors import ParameterError

if TYPE_CHECKING:
    import pandas as pd

#: The columns naming a run, as ``steering.csv``'s.
RUN_COLUMNS = ("dataset", "weight_function", "restart", "replicate")
#: The measures of a row (module docstring), in the order of its columns.
MEASURES = (
    "moves", "pairs", "auc", "infinite_ties", "pairs_mixed", "auc_mixed", "opportunity", "new_share", "gain",
    "new_class_cells", "classes_found", "candidates", "infinite_share", "infinite_unseen", "finite_unseen",
)
#: The measures that tables written before them lack (issue 57): :func:`summarise_mechanism` gives them NaN there.
ADDED_MEASURES = ("infinite_ties", "pairs_mixed", "auc_mixed", "new_share", "finite_unseen")
#: The shares of pairs that :func:`summarise_mechanism` pools over every run's pairs, each with the column counting them.
PAIR_WEIGHTED = {"auc": "pairs", "infinite_ties": "pairs", "auc_mixed": "pairs_mixed"}
#: A mechanism table's columns (:func:`mechanism_rows`).
MECHANISM_COLUMNS = (*RUN_COLUMNS, "path_length", *MEASURES)
#: :func:`summarise_mechanism`'s columns: each of :data:`MEASURES` over ``n`` runs, then its 95 % interval.
MECHANISM_SUMMARY_COLUMNS = (
    "dataset", "weight_function", "path_length", "n", *(c for m in MEASURES for c in (m, f"{m}_low", f"{m}_high")),
)
#: The walkers whose own score is a column of ``candidates.csv``; any other is read under topic perplexity's.
OWN_SCORES = {"topic-perplexity": "topic_perplexity", "word-perplexity": "word_perplexity"}
#: The score of the walkers without one of their own.
DEFAULT_SCORE = "topic_perplexity"


def walker_score(weight_function: str) -> str:
    """The ``candidates.csv`` column whose value is the walker's score (M1).

    Parameters
    ----------
    weight_function : str

    Returns
    -------
    str
        ``topic_perplexity`` or ``word_perplexity`` for the perplexity walkers, and
        ``topic_perplexity`` for any other (random walk, stochastic coverage).
    """
    if not isinstance(weight_function, str):
        raise ParameterError(f"weight_function: got {weight_function!r}, expected a walker's name", parameter="weight_function")
    return OWN_SCORES.get(weight_function, DEFAULT_SCORE)


def class_presence(cell_pixels: np.ndarray) -> np.ndarray:
    """Which human classes are present in each cell, at the label stage's share.

    Parameters
    ----------
    cell_pixels : (n_cells, C) integer ndarray
        Pixels of each class in each cell (:func:`~curiosity_cli.maps.cell_classes.cell_class_pixels`).

    Returns
    -------
    (n_cells, C) bool ndarray
        :func:`~curiosity_cli.maps.cell_classes.classes_present` at
        :data:`~curiosity_cli.experiment.recipes.CLASS_SHARE_PERCENT`.
    """
    from curiosity_cli.experiment.recipes import CLASS_SHARE_PERCENT
    from curiosity_cli.maps.cell_classes import classes_present

    return classes_present(cell_pixels, CLASS_SHARE_PERCENT)


@dataclass(frozen=True)
class _Moves:
    """Per scored move and per candidate, what the measures add up over a path's moves.

    Attributes
    ----------
    step : (S,) int64
        The scored moves, increasing.
    wins, pairs, infinite_ties : (S,) float64, (S,) int64, (S,) int64
        M1's wins and pairs of each move, and its pairs whose two scores are ``+inf``.
    wins_mixed, pairs_mixed : (S,) float64, (S,) int64
        The same against the negatives of mixed texture.
    opportunity : (S,) bool
        Whether a candidate of the move holds a new class.
    gain : (S,) float64
        The walker's chance on those candidates less coverage's (NaN without an opportunity).
    candidate_step : (M,) int64
    new, infinite, unseen : (M,) bool
        Whether each candidate holds a new class, whether its topic perplexity is
        infinite, and whether it holds a word id unseen on the path.
    """

    step: np.ndarray
    wins: np.ndarray
    pairs: np.ndarray
    infinite_ties: np.ndarray
    wins_mixed: np.ndarray
    pairs_mixed: np.ndarray
    opportunity: np.ndarray
    gain: np.ndarray
    candidate_step: np.ndarray
    new: np.ndarray
    infinite: np.ndarray
    unseen: np.ndarray


def step_auc(
    step: np.ndarray, score: np.ndarray, positive: np.ndarray, negative: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """M1's wins and pairs of each move: positives against negatives of the same step.

    Parameters
    ----------
    step : (M,) integer ndarray
        Each candidate's move; the rows of a move need not be together.
    score : (M,) float ndarray
        The walker's score of each candidate; ``+inf`` is above every finite score and
        ties another ``+inf``. NaN only where neither ``positive`` nor ``negative``.
    positive, negative : (M,) bool ndarray
        The candidates holding a new class, and the other unvisited ones (disjoint).

    Returns
    -------
    (S,) int64 ndarray, (S,) float64 ndarray, (S,) int64 ndarray
        The moves in increasing order; each one's wins (1 per pair whose positive scores
        higher, ½ per tie) and its number of pairs (positives × negatives). The pooled
        AUC is ``wins.sum() / pairs.sum()``.

    Raises
    ------
    ParameterError
        Arrays of different lengths, a NaN score to compare, or a candidate both positive
        and negative.
    """
    step = np.asarray(step)
    score = np.asarray(score, np.float64)
    positive = np.asarray(positive, bool)
    negative = np.asarray(negative, bool)
    for name, array in (("score", score), ("positive", positive), ("negative", negative)):
        if array.shape != step.shape or array.ndim != 1:
            raise ParameterError(f"{name}: got shape {array.shape}, expected ({step.size},), one per candidate of step", parameter=name)
    if step.size and step.dtype.kind not in "iu":
        raise ParameterError(f"step: got dtype {step.dtype}, expected whole numbers", parameter="step")
    if np.any(positive & negative):
        raise ParameterError("negative: a candidate is also positive; expected the two disjoint", parameter="negative")
    if np.any(np.isnan(score) & (positive | negative)):
        raise ParameterError("score: NaN for a candidate to compare", parameter="score")
    steps, rows, cols, width = _pad(step.astype(np.int64))
    padded = np.full((steps.size, width), np.nan)
    pos = np.zeros((steps.size, width), bool)
    neg = np.zeros((steps.size, width), bool)
    padded[rows, cols], pos[rows, cols], neg[rows, cols] = score, positive, negative
    pair = pos[:, :, None] & neg[:, None, :]  # (S, K, K): positive i against negative j of a step
    above = padded[:, :, None] > padded[:, None, :]
    tie = padded[:, :, None] == padded[:, None, :]  # inf == inf: a tie
    wins = np.where(pair, above + 0.5 * tie, 0.0).sum(axis=(1, 2))
    return steps, wins, pair.sum(axis=(1, 2)).astype(np.int64)


def _pad(step: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The distinct steps, and each candidate's row (its step's index) and column (its place in its step)."""
    steps, inverse, counts = np.unique(step, return_inverse=True, return_counts=True)
    order = np.argsort(inverse, kind="stable")
    cols = np.empty(step.size, np.int64)
    starts = np.cumsum(counts) - counts  # each step's first place in the order
    cols[order] = np.arange(step.size) - np.repeat(starts, counts)
    return steps, inverse.astype(np.int64), cols, int(counts.max()) if counts.size else 0


def mechanism_rows(
    run_info: dict,
    path: np.ndarray,
    candidates,
    present: np.ndarray,
    cell_words: Callable[[int], np.ndarray],
    lengths: Iterable[int],
) -> list[dict]:
    """The mechanism table's rows of one run: one per checkpoint length, none for a run that scored nothing.

    Parameters
    ----------
    run_info : dict
        ``dataset``, ``weight_function``, ``restart`` and ``replicate`` of the run.
    path : (L,) integer ndarray
        Row-major cell of each step.
    candidates : pandas.DataFrame
        Its ``candidates.csv`` (:meth:`~curiosity_cli.explore.runs.Run.candidates`): ``step``, ``cell``, ``coverage``,
        ``weight``, ``topic_perplexity`` and the walker's score (:func:`walker_score`).
    present : (n_cells, C) bool ndarray
        Which human classes are present in each cell (:func:`class_presence`).
    cell_words : callable
        Cell -> (W,) integer ndarray, its word ids
        (:meth:`~curiosity_cli.words.store.WordStore.cell_words`).
    lengths : iterable of int
        The checkpoint lengths, each 1 .. L.

    Returns
    -------
    list of dict
        Keys :data:`MECHANISM_COLUMNS`, a row per length in the order given (module
        docstring); ``moves``, ``pairs``, ``pairs_mixed``, ``new_class_cells``,
        ``classes_found`` and ``candidates`` ints, the rest floats (NaN where undefined).

    Raises
    ------
    ParameterError
        A bad argument, named: a key missing from ``run_info``, a path or candidate cell
        outside ``present``'s cells, a step outside the path's moves, a length outside
        ``1 .. L``, a NaN score, ``cell_words`` not giving integer arrays.
    """
    from curiosity_cli.evaluate.information import classes_found
    from curiosity_cli.maps.cell_classes import first_steps

    run_info = _check_run_info(run_info)
    present = _check_present(present)
    path = _check_path(path, present.shape[0])
    lengths = _check_lengths(lengths, path.size)
    if not callable(cell_words):
        raise ParameterError(f"cell_words: got {type(cell_words).__name__}, expected a callable cell -> word ids", parameter="cell_words")
    score_column = walker_score(run_info["weight_function"])
    table = _check_candidates(candidates, path.size, present.shape[0], score_column)
    if table is None:
        return []
    class_first = first_steps(path, present)  # (C,): the step each class was first present on the path
    moves = _moves(path, table, present, class_first, cell_words, score_column)
    rows = []
    for length in lengths:
        made = moves.step <= length - 2
        scored = moves.candidate_step <= length - 2
        n_moves, n_candidates = int(made.sum()), int(scored.sum())
        pairs, pairs_mixed = int(moves.pairs[made].sum()), int(moves.pairs_mixed[made].sum())
        chances = made & moves.opportunity
        infinite, finite = scored & moves.infinite, scored & ~moves.infinite
        reached = class_first[(class_first >= 0) & (class_first < length)]
        rows.append({
            **{key: run_info[key] for key in RUN_COLUMNS}, "path_length": length, "moves": n_moves, "pairs": pairs,
            "auc": _share(moves.wins[made].sum(), pairs),
            "infinite_ties": _share(moves.infinite_ties[made].sum(), pairs),
            "pairs_mixed": pairs_mixed, "auc_mixed": _share(moves.wins_mixed[made].sum(), pairs_mixed),
            "opportunity": _share(chances.sum(), n_moves), "new_share": _share((scored & moves.new).sum(), n_candidates),
            "gain": float(moves.gain[chances].mean()) if chances.any() else np.nan,
            "new_class_cells": int(np.unique(reached).size), "classes_found": classes_found(class_first, length),
            "candidates": n_candidates, "infinite_share": _share(infinite.sum(), n_candidates),
            "infinite_unseen": _share((infinite & moves.unseen).sum(), infinite.sum()),
            "finite_unseen": _share((finite & moves.unseen).sum(), finite.sum()),
        })
    return rows


def _share(part, whole) -> float:
    """``part / whole`` as a float, NaN when ``whole`` is 0."""
    return float(part / whole) if whole else np.nan


def _moves(
    path: np.ndarray, table: dict, present: np.ndarray, class_first: np.ndarray,
    cell_words: Callable[[int], np.ndarray], score_column: str,
) -> _Moves:
    """Each scored move's M1-M3 terms and each candidate's M5 flags (:class:`_Moves`)."""
    from curiosity_cli.explore.walker import move_probabilities

    step, cell = table["step"], table["cell"]
    first_visit = np.full(present.shape[0], path.size, np.int64)
    np.minimum.at(first_visit, path, np.arange(path.size))
    unvisited = first_visit[cell] > step
    seen = (class_first >= 0)[None, :] & (class_first[None, :] <= step[:, None])  # (M, C): on path[0 .. t]
    positive = (present[cell] & ~seen).any(axis=1)  # a class new to the path: never in a visited cell
    negative = unvisited & ~positive
    score = table[score_column]
    steps, wins, pairs = step_auc(step, score, positive, negative)
    # not positive, so each of its two or more classes has been seen: as heterogeneous as a boundary, yet nothing new
    mixed = negative & (present[cell].sum(axis=1) >= 2)
    _, wins_mixed, pairs_mixed = step_auc(step, score, positive, mixed)
    rows_of = np.searchsorted(steps, step)
    at_infinity = score == np.inf
    ties = [np.bincount(rows_of[at_infinity & side], minlength=steps.size) for side in (positive, negative)]

    opportunity = np.zeros(steps.size, bool)
    gain = np.full(steps.size, np.nan)
    with np.errstate(divide="ignore"):  # U = 0 (a lone visited cell under `others`): weight +inf, as the walker had it
        inverse = 1.0 / table["coverage"]
    for i in np.unique(rows_of[positive]):
        at = np.flatnonzero(rows_of == i)
        new = positive[at]
        walker, _ = move_probabilities(table["weight"][at])
        coverage, _ = move_probabilities(inverse[at])
        opportunity[i] = True
        gain[i] = float(walker[new].sum() - coverage[new].sum())

    # a candidate holds a word unseen at its move t when its cell's last word to reach the path came after t
    word_ids, word_first = _first_word_steps(path, cell_words)
    last_seen = np.full(present.shape[0], -1, np.int64)  # a cell without words holds nothing unseen
    for c in np.unique(cell):
        words = _words(cell_words, int(c))
        first = np.full(words.size, path.size)  # a word on no cell of the path: never seen
        if word_ids.size:
            at = np.minimum(np.searchsorted(word_ids, words), word_ids.size - 1)
            first = np.where(word_ids[at] == words, word_first[at], first)
        last_seen[c] = first.max(initial=-1)
    return _Moves(
        steps, wins, pairs, ties[0] * ties[1], wins_mixed, pairs_mixed, opportunity, gain, step, positive,
        table["topic_perplexity"] == np.inf, last_seen[cell] > step,
    )


def _first_word_steps(path: np.ndarray, cell_words: Callable[[int], np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The word ids on the path, sorted, and the first step whose cell holds each."""
    words = {int(c): _words(cell_words, int(c)) for c in np.unique(path)}
    ids = np.concatenate([words[int(c)] for c in path]) if path.size else np.zeros(0, np.int64)
    at = np.repeat(np.arange(path.size), [words[int(c)].size for c in path])
    order = np.lexsort((at, ids))  # by word, then step: a word's first row is its first step
    ids, at = ids[order], at[order]
    word_ids, first = np.unique(ids, return_index=True)
    return word_ids, at[first]


def _words(cell_words: Callable[[int], np.ndarray], cell: int) -> np.ndarray:
    words = np.asarray(cell_words(cell))
    if words.ndim != 1 or (words.size and words.dtype.kind not in "iu"):
        raise ParameterError(
            f"cell_words: gave shape {words.shape} of dtype {words.dtype} for cell {cell}, expected (W,) integer word ids",
            parameter="cell_words",
        )
    return words.astype(np.int64)


def _check_run_info(run_info) -> dict:
    if not isinstance(run_info, dict):
        raise ParameterError(f"run_info: got {type(run_info).__name__}, expected a dict of {', '.join(RUN_COLUMNS)}", parameter="run_info")
    missing = [key for key in RUN_COLUMNS if key not in run_info]
    if missing:
        raise ParameterError(f"run_info: no key {missing[0]!r}; expected {', '.join(RUN_COLUMNS)}", parameter="run_info")
    return run_info


def _check_present(present) -> np.ndarray:
    present = np.asarray(present)
    if present.ndim != 2 or present.dtype != bool:
        raise ParameterError(
            f"present: got shape {present.shape} of dtype {present.dtype}, expected an (n_cells, C) bool ndarray",
            parameter="present",
        )
    return present


def _check_path(path, n_cells: int) -> np.ndarray:
    path = np.asarray(path)
    if path.ndim != 1 or path.size == 0 or path.dtype.kind not in "iu":
        raise ParameterError(f"path: got shape {path.shape} of dtype {path.dtype}, expected (L,) cells, L >= 1", parameter="path")
    if path.min() < 0 or path.max() >= n_cells:
        raise ParameterError(f"path: cells {path.min()} .. {path.max()}, expected 0 .. {n_cells - 1}", parameter="path")
    return path.astype(np.int64)


def _check_lengths(lengths, steps: int) -> list[int]:
    from curiosity_cli.checks import check_int

    if isinstance(lengths, (str, bytes)) or not isinstance(lengths, Iterable):
        raise ParameterError(f"lengths: got {lengths!r}, expected checkpoint lengths", parameter="lengths")
    out = []
    for length in lengths:
        try:
            out.append(check_int("lengths", length, 1, steps))
        except ParameterError as exc:
            raise ParameterError(f"{exc} (the path has {steps} steps)", parameter="lengths") from None
    return out


def _check_candidates(candidates, steps: int, n_cells: int, score_column: str) -> dict | None:
    """``candidates``' columns as arrays, checked; ``None`` for a run that scored nothing."""
    import pandas as pd

    if not isinstance(candidates, pd.DataFrame):
        raise ParameterError(f"candidates: got {type(candidates).__name__}, expected a pandas DataFrame", parameter="candidates")
    if candidates.empty:
        return None
    needed = list(dict.fromkeys(["step", "cell", "coverage", "weight", "topic_perplexity", score_column]))
    missing = [c for c in needed if c not in candidates.columns]
    if missing:
        raise ParameterError(f"candidates: no column {missing[0]!r}; expected {', '.join(needed)}", parameter="candidates")
    table = {}
    for column in ("step", "cell"):
        values = candidates[column].to_numpy()
        if values.dtype.kind not in "iu":
            raise ParameterError(f"candidates: {column}: got dtype {values.dtype}, expected whole numbers", parameter="candidates")
        table[column] = values.astype(np.int64)
    if table["step"].min() < 0 or table["step"].max() > steps - 2:
        raise ParameterError(
            f"candidates: step: {table['step'].min()} .. {table['step'].max()}, expected 0 .. {steps - 2}, the moves "
            f"of a path of {steps} steps", parameter="candidates",
        )
    if table["cell"].min() < 0 or table["cell"].max() >= n_cells:
        raise ParameterError(
            f"candidates: cell: {table['cell'].min()} .. {table['cell'].max()}, expected 0 .. {n_cells - 1}",
            parameter="candidates",
        )
    for column in needed[2:]:
        try:
            table[column] = candidates[column].to_numpy(np.float64)
        except (TypeError, ValueError):
            raise ParameterError(f"candidates: {column}: expected numbers", parameter="candidates") from None
    for column in dict.fromkeys(["topic_perplexity", score_column]):
        if np.isnan(table[column]).any():
            raise ParameterError(f"candidates: {column}: NaN; expected a perplexity for every candidate", parameter="candidates")
    return table


def summarise_mechanism(table):
    """The measures pooled over runs, per map, walker and path length, each with a 95 % interval over runs.

    ``auc``, ``infinite_ties`` and ``auc_mixed`` (:data:`PAIR_WEIGHTED`) are shares of
    pairs, pooled over the runs' pairs: the wins (ties at infinity) of every run over the
    pairs of every run, ``R = sum(w_i) / sum(p_i)`` with ``w_i`` the run's share times its
    ``p_i`` pairs (``pairs``, or ``pairs_mixed`` for ``auc_mixed``), which is the mean of the
    per-run shares weighted by their pairs, so that a run with 2 pairs counts 1/25 of one
    with 50. Over the ``m`` runs with pairs, their interval is the linearised (delta-method)
    interval of that ratio of means, clustered by run: ``R ± t * se`` with ``t`` the
    97.5 % quantile of Student's t with ``m - 1`` degrees of freedom and
    ``se = sqrt(sum((w_i - R p_i) ** 2) / (m (m - 1))) / mean(p_i)``, clipped to [0, 1].
    Every other measure is the plain mean of the runs where it is defined, with the
    Student-t interval of that mean over those ``m`` runs, ``mean ± t * s / sqrt(m)``
    (``s`` their standard deviation, ``m - 1`` degrees of freedom). An interval is NaN
    where fewer than 2 runs define the measure.

    Parameters
    ----------
    table : pandas.DataFrame
        Rows of :func:`mechanism_rows` (columns :data:`MECHANISM_COLUMNS`; ``restart`` and
        ``replicate`` may be absent). A table written before :data:`ADDED_MEASURES`
        existed may lack them, and so may some of its rows (NaN ``pairs_mixed``, which a
        later table always counts), as when such a table is pooled with later ones.

    Returns
    -------
    pandas.DataFrame
        Columns :data:`MECHANISM_SUMMARY_COLUMNS`: a row per ``dataset``,
        ``weight_function`` and ``path_length`` in the order they first come (lengths
        increasing); ``n`` the runs, each measure as above (NaN where no run defines it)
        and its interval in ``<measure>_low`` and ``<measure>_high``. The measures of
        :data:`ADDED_MEASURES` are NaN in a group where any run lacks them: a pool of the
        runs that have them would be another set of runs than the other measures'.

    Raises
    ------
    ParameterError
        ``table`` not a DataFrame, without one of the columns other than
        :data:`ADDED_MEASURES`, or with a measure that is not a number.
    """
    import pandas as pd

    from curiosity_cli.evaluate.statistics import mean_interval

    if not isinstance(table, pd.DataFrame):
        raise ParameterError(f"table: got {type(table).__name__}, expected a pandas DataFrame", parameter="table")
    needed = [c for c in MECHANISM_COLUMNS if c not in ("restart", "replicate", *ADDED_MEASURES)]
    missing = [c for c in needed if c not in table.columns]
    if missing:
        raise ParameterError(f"table: no column {missing[0]!r}; expected {', '.join(MECHANISM_COLUMNS)}", parameter="table")
    keys = ["dataset", "weight_function", "path_length"]
    if table.empty:
        return pd.DataFrame({c: [] for c in MECHANISM_SUMMARY_COLUMNS})
    values = {}
    for m in MEASURES:
        try:
            values[m] = table[m].to_numpy(np.float64) if m in table.columns else np.full(len(table), np.nan)
        except (TypeError, ValueError):
            raise ParameterError(f"table: {m}: expected numbers", parameter="table") from None
    recorded = ~np.isnan(values["pairs_mixed"])
    order = {k: list(dict.fromkeys(table[k])) for k in keys[:2]}
    rows = []
    for key, at in table.reset_index(drop=True).groupby(keys, sort=False).indices.items():
        row = {**dict(zip(keys, key)), "n": at.size}
        for m in MEASURES:
            if m in ADDED_MEASURES and not recorded[at].all():
                row.update({m: np.nan, f"{m}_low": np.nan, f"{m}_high": np.nan})
            elif m in PAIR_WEIGHTED:
                row[m], row[f"{m}_low"], row[f"{m}_high"] = _pooled_share(values[m][at], values[PAIR_WEIGHTED[m]][at])
            else:
                defined = values[m][at]
                row[m], row[f"{m}_low"], row[f"{m}_high"] = mean_interval(defined[~np.isnan(defined)])
        rows.append(row)
    out = pd.DataFrame(rows, columns=list(MECHANISM_SUMMARY_COLUMNS)).astype({"n": np.int64})
    rank = [out[k].map({v: i for i, v in enumerate(order[k])}) for k in keys[:2]]
    out = out.assign(_d=rank[0], _w=rank[1]).sort_values(["_d", "_w", "path_length"], kind="stable")
    return out.drop(columns=["_d", "_w"]).reset_index(drop=True)


def _t_quantile(runs: int) -> float:
    """Student's t quantile of a two-sided 95 % interval over ``runs`` runs."""
    from scipy import stats

    from curiosity_cli.evaluate.statistics import CONFIDENCE

    return float(stats.t.ppf(0.5 + CONFIDENCE / 2, runs - 1))


def _pooled_share(shares: np.ndarray, pairs: np.ndarray) -> tuple[float, float, float]:
    """A share of pairs pooled over the runs with pairs (NaN none), and its delta-method interval (NaN under 2)."""
    with_pairs = pairs > 0  # a run without pairs has no share, and adds nothing to either sum
    pairs, wins = pairs[with_pairs], shares[with_pairs] * pairs[with_pairs]
    if pairs.size == 0:
        return np.nan, np.nan, np.nan
    share = float(wins.sum() / pairs.sum())
    if pairs.size < 2:
        return share, np.nan, np.nan
    runs = pairs.size
    se = np.sqrt(np.sum((wins - share * pairs) ** 2) / (runs * (runs - 1))) / pairs.mean()
    half = _t_quantile(runs) * float(se)
    return share, max(share - half, 0.0), min(share + half, 1.0)
