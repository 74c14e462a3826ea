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
(:func:`~curiosity_cli.label.classes.classes_present`, as the label stage has it).

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
- ``opportunity`` (M2), how often there was anything new to point at: the share of the
  scored moves (``moves``) with at least one candidate holding a new class. A score can
  only make a difference at such moves; a map whose classes lie in large patches gives few.
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
- ``infinite_share`` and ``infinite_unseen`` (M5), what the score sees. The share of the
  scored candidates (``candidates``, of moves ``0 .. L - 2``) whose topic perplexity is
  infinite, and of those, the share holding at least one word id that none of
  ``path[0 .. t]``'s cells holds (at the candidate's move ``t``). Under counts-only
  P(k | path) a candidate is infinitely surprising when its words' topics have never been
  seen on the path; if most infinite candidates are those with unseen words, topic
  perplexity's pointing is word novelty, which need not be class novelty.

Rows as :mod:`~curiosity_cli.evaluate.steering`'s: one per run and checkpoint length,
none for a run that scored nothing (the planned walkers). :func:`summarise_mechanism`
averages them over runs per map, walker and length.
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
    "moves", "pairs", "auc", "opportunity", "gain", "new_class_cells", "classes_found", "candidates",
    "infinite_share", "infinite_unseen",
)
#: A mechanism table's columns (:func:`mechanism_rows`).
MECHANISM_COLUMNS = (*RUN_COLUMNS, "path_length", *MEASURES)
#: :func:`summarise_mechanism`'s columns: the means of :data:`MEASURES` over ``n`` runs.
MECHANISM_SUMMARY_COLUMNS = ("dataset", "weight_function", "path_length", "n", *MEASURES)
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
        Pixels of each class in each cell (:func:`~curiosity_cli.label.classes.cell_class_pixels`).

    Returns
    -------
    (n_cells, C) bool ndarray
        :func:`~curiosity_cli.label.classes.classes_present` at
        :data:`~curiosity_cli.experiment.recipes.CLASS_SHARE_PERCENT`.
    """
    from curiosity_cli.experiment.recipes import CLASS_SHARE_PERCENT
    from curiosity_cli.label.classes import classes_present

    return classes_present(cell_pixels, CLASS_SHARE_PERCENT)


@dataclass(frozen=True)
class _Moves:
    """Per scored move and per candidate, what the measures add up over a path's moves.

    Attributes
    ----------
    step : (S,) int64
        The scored moves, increasing.
    wins, pairs : (S,) float64, (S,) int64
        M1's wins and pairs of each move.
    opportunity : (S,) bool
        Whether a candidate of the move holds a new class.
    gain : (S,) float64
        The walker's chance on those candidates less coverage's (NaN without an opportunity).
    candidate_step : (M,) int64
    infinite, unseen : (M,) bool
        Whether each candidate's topic perplexity is infinite, and (for those) whether it
        holds a word id unseen on the path.
    """

    step: np.ndarray
    wins: np.ndarray
    pairs: np.ndarray
    opportunity: np.ndarray
    gain: np.ndarray
    candidate_step: np.ndarray
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
        docstring); ``moves``, ``pairs``, ``new_class_cells``, ``classes_found`` and
        ``candidates`` ints, the rest floats (NaN where undefined).

    Raises
    ------
    ParameterError
        A bad argument, named: a key missing from ``run_info``, a path or candidate cell
        outside ``present``'s cells, a step outside the path's moves, a length outside
        ``1 .. L``, a NaN score, ``cell_words`` not giving integer arrays.
    """
    from curiosity_cli.evaluate.information import classes_found
    from curiosity_cli.label.classes import first_steps

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
        pairs = int(moves.pairs[made].sum())
        chances = made & moves.opportunity
        infinite = scored & moves.infinite
        reached = class_first[(class_first >= 0) & (class_first < length)]
        rows.append({
            **{key: run_info[key] for key in RUN_COLUMNS}, "path_length": length, "moves": n_moves, "pairs": pairs,
            "auc": float(moves.wins[made].sum() / pairs) if pairs else np.nan,
            "opportunity": float(chances.sum() / n_moves) if n_moves else np.nan,
            "gain": float(moves.gain[chances].mean()) if chances.any() else np.nan,
            "new_class_cells": int(np.unique(reached).size), "classes_found": classes_found(class_first, length),
            "candidates": n_candidates,
            "infinite_share": float(infinite.sum() / n_candidates) if n_candidates else np.nan,
            "infinite_unseen": float((infinite & moves.unseen).sum() / infinite.sum()) if infinite.any() else np.nan,
        })
    return rows


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
    steps, wins, pairs = step_auc(step, table[score_column], positive, negative)

    opportunity = np.zeros(steps.size, bool)
    gain = np.full(steps.size, np.nan)
    with np.errstate(divide="ignore"):  # U = 0 (a lone visited cell under `others`): weight +inf, as the walker had it
        inverse = 1.0 / table["coverage"]
    rows_of = np.searchsorted(steps, step)
    for i in np.unique(rows_of[positive]):
        at = np.flatnonzero(rows_of == i)
        new = positive[at]
        walker, _ = move_probabilities(table["weight"][at])
        coverage, _ = move_probabilities(inverse[at])
        opportunity[i] = True
        gain[i] = float(walker[new].sum() - coverage[new].sum())

    infinite = table["topic_perplexity"] == np.inf
    unseen = np.zeros(step.size, bool)
    if infinite.any():
        word_ids, word_first = _first_word_steps(path, cell_words)
        for m in np.flatnonzero(infinite):
            words = _words(cell_words, int(cell[m]))
            first = np.full(words.size, path.size)  # a word on no cell of the path: never seen
            if word_ids.size:
                at = np.minimum(np.searchsorted(word_ids, words), word_ids.size - 1)
                first = np.where(word_ids[at] == words, word_first[at], first)
            unseen[m] = bool(np.any(first > step[m]))
    return _Moves(steps, wins, pairs, opportunity, gain, step, infinite, unseen)


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
    """The measures averaged over runs, per map, walker and path length.

    Parameters
    ----------
    table : pandas.DataFrame
        Rows of :func:`mechanism_rows` (columns :data:`MECHANISM_COLUMNS`).

    Returns
    -------
    pandas.DataFrame
        Columns :data:`MECHANISM_SUMMARY_COLUMNS`: a row per ``dataset``,
        ``weight_function`` and ``path_length`` in the order they first come (lengths
        increasing); ``n`` the runs, each measure the mean of the runs where it is
        defined (NaN where it is in none).

    Raises
    ------
    ParameterError
        ``table`` not a DataFrame, or without one of the columns.
    """
    import pandas as pd

    if not isinstance(table, pd.DataFrame):
        raise ParameterError(f"table: got {type(table).__name__}, expected a pandas DataFrame", parameter="table")
    missing = [c for c in MECHANISM_COLUMNS if c != "restart" and c != "replicate" and c not in table.columns]
    if missing:
        raise ParameterError(f"table: no column {missing[0]!r}; expected {', '.join(MECHANISM_COLUMNS)}", parameter="table")
    keys = ["dataset", "weight_function", "path_length"]
    if table.empty:
        return pd.DataFrame({c: [] for c in MECHANISM_SUMMARY_COLUMNS})
    measures = table[keys + list(MEASURES)].astype({m: np.float64 for m in MEASURES})
    order = {k: list(dict.fromkeys(table[k])) for k in keys[:2]}
    grouped = measures.groupby(keys, sort=False)
    out = grouped[list(MEASURES)].mean().reset_index()  # NaN skipped: the mean of the runs that define it
    out.insert(3, "n", grouped.size().to_numpy().astype(np.int64))
    rank = [out[k].map({v: i for i, v in enumerate(order[k])}) for k in keys[:2]]
    out = out.assign(_d=rank[0], _w=rank[1]).sort_values(["_d", "_w", "path_length"], kind="stable")
    return out.drop(columns=["_d", "_w"]).reset_index(drop=True)[list(MECHANISM_SUMMARY_COLUMNS)]
