"""The table of measures: what a path found and how well its model labels the map, each declared once.

A measure is a value per run and checkpoint, one ``mi.csv`` column for each labelling it
is taken against (``human``: the map's human labels; ``batch``: Z_b), or one column
against no labelling (:data:`WORDS`: the held-out log-likelihood of the map's words). Its entry in
:data:`MEASURES` says how a checkpoint gives it (:class:`Checkpoint`), whether walkers
are compared on it beside MI, whose headline has tables of its own, and how the report
writes it. Every consumer loops over the table: the rows (:mod:`~curiosity_cli.evaluate.rows`),
the per-walker summary and the paired comparisons
(:mod:`~curiosity_cli.evaluate.found`), the report's "What each walker found"
(:mod:`~curiosity_cli.evaluate.report`), pooled replicates
(:mod:`~curiosity_cli.evaluate.replicates`) and a study's curve (``--measure``). A
study records ``mi.csv`` whole, so every measure of a recorded seed is pooled; a
recorded table from before a measure existed lacks its columns, and the pooled tables
say so rather than invent it.

Adding a measure is a function of a :class:`Checkpoint`, an entry here and its tests.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from curiosity_cli.errors import ParameterError
from curiosity_cli.evaluate.information import (
    adjusted_mutual_information,
    classes_found,
    mean_recall,
    mutual_information,
    normalised_mutual_information,
)

#: The labellings a measure is taken against, in the order of ``mi.csv``'s columns.
AGAINST = ("human", "batch")
#: What a measure of no labelling is taken against, in a table's ``against``: the map's words held out of the
#: chains that score them (:mod:`curiosity_cli.label.heldout`).
WORDS = "words"


@dataclass(frozen=True)
class Checkpoint:
    """What a label file holds of one run at one path length.

    Attributes
    ----------
    length : int
        The path length.
    batch : (K, K) int ndarray
        Contingency table of Z_p's topics against Z_b's.
    human : (K, C) int ndarray or None
        Against the human classes; None for a map without labels.
    first_step : (C,) int ndarray or None
        The step each human class was first reached (-1: never), as
        :func:`~curiosity_cli.maps.cell_classes.first_steps` records it; None for label files without it.
    visited_batch, visited_human : ndarray or None
        ``batch`` and ``human`` of only the pixels whose word lies in a cell the path had
        visited (None where the label file has no such tables, or the map no labels).
    heldout_bits : (2,) float64 ndarray or None
        The sum of log2 of each held-out word's probability under Φ_p, over every cell and
        over the cells the path had not visited (:mod:`curiosity_cli.label.heldout`); None
        where the label file has none.
    heldout_words : (2,) int ndarray or None
        The held-out words of those sums.
    """

    length: int
    batch: np.ndarray
    human: np.ndarray | None
    first_step: np.ndarray | None
    visited_batch: np.ndarray | None = None
    visited_human: np.ndarray | None = None
    heldout_bits: np.ndarray | None = None
    heldout_words: np.ndarray | None = None

    def part(self, against: str, visited: bool) -> np.ndarray | None:
        """The table against ``against`` ("human" or "batch") of the pixels the path visited, or of those it did not."""
        whole, seen = getattr(self, against), getattr(self, f"visited_{against}")
        if whole is None or seen is None:
            return None
        return seen if visited else whole - seen


@dataclass(frozen=True)
class Measure:
    """One measure of a run at a checkpoint.

    Attributes
    ----------
    name : str
        What ``--measure`` and the tables call it.
    title : str
        What the report calls it.
    unit : str
        Of its values ("" for a share or an index).
    columns : mapping of str to str
        Per labelling it is taken against (:data:`AGAINST`), or :data:`WORDS` for a measure
        of none, its ``mi.csv`` column.
    values : callable
        ``values(checkpoint)``: the row's values of ``columns`` (NaN where the checkpoint
        lacks what it needs), and of any column that says what they are out of.
    found : bool
        Compared between walkers in ``found_effects.csv`` and the report's "What each walker
        found"; MI, the paper's measure, has its own tables (``summary.csv``, ``effects.csv``,
        ``headline.csv``).
    digits : int
        Decimals the report writes.
    lower_is_better : bool
        A walker leads by a lower value (a time), not a higher one.
    """

    name: str
    title: str
    unit: str
    columns: Mapping[str, str]
    values: Callable[[Checkpoint], dict]
    found: bool
    digits: int
    lower_is_better: bool = False

    def ahead(self, ours, theirs):
        """Whether ``ours`` is better than ``theirs`` (elementwise for arrays)."""
        return ours < theirs if self.lower_is_better else ours > theirs


def _per_labelling(function: Callable[[np.ndarray], float], prefix: str) -> Callable[[Checkpoint], dict]:
    """``values`` of a measure of a contingency table, taken against each labelling."""

    def values(point: Checkpoint) -> dict:
        return {
            f"{prefix}_human": function(point.human) if point.human is not None else np.nan,
            f"{prefix}_batch": function(point.batch),
        }

    return values


def _present(point: Checkpoint) -> np.ndarray:
    """The human classes with pixels at a checkpoint."""
    return np.flatnonzero(point.human.sum(axis=0) > 0)


def _classes_found(point: Checkpoint) -> dict:
    if point.human is None:
        return {"classes_found": np.nan, "classes": np.nan}
    present = _present(point)
    found = classes_found(point.first_step[present], point.length) if point.first_step is not None else np.nan
    return {"classes_found": found, "classes": present.size}


def _mean_recall(point: Checkpoint) -> dict:
    return {"mean_recall": mean_recall(point.human) if point.human is not None else np.nan}


def _time_to_find(point: Checkpoint) -> dict:
    # a class not found by the checkpoint is censored there: it counts the whole length, never more
    if point.human is None or point.first_step is None:
        return {"time_to_find": np.nan}
    return {"time_to_find": float(restricted_steps(point.first_step[_present(point)], point.length).mean())}


def restricted_steps(first_step: np.ndarray, length: int) -> np.ndarray:
    """The steps a path took to first reach each class, censored at ``length``: ``first_step`` where
    ``0 <= first_step < length``, ``length`` for a class not reached by then (-1, or later).

    Parameters
    ----------
    first_step : (C,) int ndarray
        As :func:`~curiosity_cli.maps.cell_classes.first_steps` records them (step 0 is the start cell).
    length : int

    Returns
    -------
    (C,) float64 ndarray
    """
    first_step = np.asarray(first_step)
    return np.where((first_step >= 0) & (first_step < length), first_step, length).astype(np.float64)


def _mi_of_part(visited: bool) -> Callable[[Checkpoint], dict]:
    """``values`` of MI over the pixels the path visited (or those it did not); NaN where there are none."""
    prefix = "mi_visited" if visited else "mi_unvisited"

    def values(point: Checkpoint) -> dict:
        row = {}
        for against in AGAINST:
            table = point.part(against, visited)
            row[f"{prefix}_{against}"] = mutual_information(table) if table is not None and table.sum() else np.nan
        return row

    return values


def _heldout(unvisited: bool) -> Callable[[Checkpoint], dict]:
    """``values`` of the held-out log-likelihood per word, over every cell or the cells the path did not visit;
    NaN where no word is held out there."""
    name, part = ("heldout_unvisited", 1) if unvisited else ("heldout", 0)

    def values(point: Checkpoint) -> dict:
        if point.heldout_words is None or not point.heldout_words[part]:
            return {name: np.nan}
        return {name: float(point.heldout_bits[part] / point.heldout_words[part])}

    return values


def _adjusted(point: Checkpoint) -> dict:
    # the topics Z_p gives some pixel: the chance correction counts those, not the model's K
    return {**_per_labelling(adjusted_mutual_information, "ami")(point), "topics_used": int((point.batch.sum(axis=1) > 0).sum())}


MI = Measure("mi", "MI", "bits", {"human": "mi_human", "batch": "mi_batch"},
             _per_labelling(mutual_information, "mi"), found=False, digits=3)
NMI = Measure("nmi", "NMI", "", {"human": "nmi_human", "batch": "nmi_batch"},
              _per_labelling(normalised_mutual_information, "nmi"), found=True, digits=3)
AMI = Measure("ami", "AMI", "", {"human": "ami_human", "batch": "ami_batch"}, _adjusted, found=True, digits=3)
CLASSES_FOUND = Measure("classes_found", "classes found", "classes", {"human": "classes_found"}, _classes_found,
                        found=True, digits=2)
MEAN_RECALL = Measure("mean_recall", "mean recall", "", {"human": "mean_recall"}, _mean_recall, found=True, digits=3)
#: The restricted mean time to first find: over the map's classes, the step each was first reached, a class not
#: reached by the checkpoint counting the checkpoint's length (censored there), so that walkers are compared on one
#: scale however many classes they miss.
TIME_TO_FIND = Measure("time_to_find", "time to first find", "steps", {"human": "time_to_find"}, _time_to_find,
                       found=True, digits=1, lower_is_better=True)
#: MI over the pixels whose word lies in a cell the path visited (words Φ_p holds), and over the rest: a walker
#: whose model labels well only what it saw is told apart from one whose model carries to terrain it never saw.
#: Each part has its own classes' entropy, so a part holding fewer classes bounds its MI lower.
MI_VISITED = Measure("mi_visited", "MI where the path went", "bits",
                     {"human": "mi_visited_human", "batch": "mi_visited_batch"}, _mi_of_part(True), found=True, digits=3)
MI_UNVISITED = Measure("mi_unvisited", "MI where the path did not go", "bits",
                       {"human": "mi_unvisited_human", "batch": "mi_unvisited_batch"}, _mi_of_part(False),
                       found=True, digits=3)
#: The held-out log-likelihood by document completion: how well Φ_p predicts half of each cell's words given the
#: other half, against no labelling; over every cell, and over the cells the path did not visit, whose words Φ_p
#: never held. Every walker of a map is scored on the same held-out words.
HELDOUT = Measure("heldout", "held-out log-likelihood", "bits/word", {WORDS: "heldout"}, _heldout(False),
                  found=True, digits=3)
HELDOUT_UNVISITED = Measure("heldout_unvisited", "held-out log-likelihood where the path did not go", "bits/word",
                            {WORDS: "heldout_unvisited"}, _heldout(True), found=True, digits=3)
#: Every measure, in the order of their ``mi.csv`` columns.
MEASURES = (MI, NMI, AMI, CLASSES_FOUND, MEAN_RECALL, TIME_TO_FIND, MI_VISITED, MI_UNVISITED, HELDOUT, HELDOUT_UNVISITED)


def measure_values(point: Checkpoint) -> dict:
    """Every measure's ``mi.csv`` values at a checkpoint, in :data:`MEASURES`' order."""
    row = {}
    for measure in MEASURES:
        row.update(measure.values(point))
    return row


def read_against(present) -> str:
    """The ``against`` a map's account of the measures reads, of those ``present`` in its rows: human labels where
    the map has them, else Z_b, else :data:`WORDS` (a measure of no labelling alone)."""
    present = set(present)
    return next(against for against in (*AGAINST, WORDS) if against in present)


def measure_named(name: str) -> Measure:
    """The measure called ``name``.

    Raises
    ------
    ParameterError
        No measure is called that, naming those there are.
    """
    for measure in MEASURES:
        if measure.name == name:
            return measure
    raise ParameterError(f"measure: got {name!r}, expected one of {', '.join(m.name for m in MEASURES)}")
