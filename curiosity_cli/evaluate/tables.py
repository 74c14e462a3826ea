"""``curiosity evaluate``: mutual information per run and checkpoint, its summary and tests, and evidence beyond MI.

Written under ``results/<experiment>/``:

- ``mi.csv`` and ``mi.parquet``: one row per (dataset, weight function, restart, path
  length): ``mi_human``, ``mi_batch`` (bits), ``nmi_human``, ``nmi_batch``;
  ``classes_found`` (human classes the path's cells reached within the length, see
  :data:`~curiosity_cli.experiment.recipes.CLASS_SHARE_PERCENT`) of ``classes`` (the map's
  classes with pixels); ``mean_recall`` (mean per-class recall of Z_p under the best
  one-to-one topic-to-class matching, :func:`~curiosity_cli.evaluate.information.matched_recall`);
  the run's ``seed`` and ``replicate`` (the experiment's seed, whose runs are paired by
  restart: :data:`~curiosity_cli.evaluate.statistics.PAIR_KEYS`); and the revisits of the path so far
  (:mod:`~curiosity_cli.evaluate.revisits`): ``distinct_cells``, ``revisit_steps``,
  ``boxed_in_steps``. The human columns are NaN for a map without labels. A run
  labelled twice (``label.check_restarts``) has ``placed_mi_human`` and
  ``placed_mi_batch``: the MI of its second chain, from a placed start (NaN for the
  others).
- ``classes.csv``: one row per run, length and human class with pixels: the class's
  ``pixels``, whether the path ``found`` it, the ``first_step`` it did (NaN if never),
  its matched ``topic`` (-1 if none) and ``recall``; ``class_name`` from the map's legend
  when it can be read.
- ``summary.csv``: per (dataset, weight function, path length, against): ``n``, ``mean``,
  ``std``, and the 95 % confidence interval of the mean MI (Student's t).
- ``classes_summary.csv``: the same for ``classes_found`` and ``mean_recall``
  (``measure``), with the map's ``classes``.
- ``tests.csv``: per (dataset, path length, against) and pair of walkers, the Wilcoxon
  signed-rank test over the restarts both have (paired by restart, which share start
  cells). Ceilings (:data:`~curiosity_cli.explore.weights.CEILINGS`) are not walkers
  and take no part.
- ``effects.csv``: per (dataset, path length, against), topic perplexity against each
  other walker, paired by restart: the mean difference with its 95 % Student-t
  confidence interval, the ratio of the means with its 95 % studentized bootstrap
  interval, and the Wilcoxon p of ``tests.csv`` (:func:`paired_effects`): the
  pre-specified comparisons a lead is decided by.
- ``convergence.csv``: per (dataset, path length, against), over the runs labelled
  twice: ``n``, the mean MI of each chain (``uniform``, ``placed``), their mean
  difference with its standard error, and whether it is within
  :data:`~curiosity_cli.evaluate.statistics.CONVERGENCE_TOLERANCE` bits or twice its standard error (``converged``): the
  check that Z_p has forgotten how its chain started (:func:`~curiosity_cli.evaluate.statistics.label_convergence`).
- ``revisits.csv``: the same as ``summary.csv`` for each revisit column (``measure``), per
  (dataset, weight function, path length).
- ``steering.csv``: per run (``replicate`` and ``restart``) of a walker that scores its
  moves and checkpoint length: the moves scored (``steps``) and the mean total-variation
  distance of the walker's step distribution from stochastic coverage's on the same
  candidates (``steering``, :mod:`~curiosity_cli.evaluate.steering`); none for planned walkers.
- ``mechanism.csv``: per run of a walker that scores its moves and checkpoint length,
  whether surprise points at what is new (:mod:`~curiosity_cli.evaluate.mechanism`): the
  within-step AUC of the walker's score for candidates holding a class new to the path
  (M1, ``auc``), the share of moves with such a candidate (M2, ``opportunity``), the
  chance the walker put on them beyond stochastic coverage's (M3, ``gain``), new-class
  cells entered and classes found (M4), and the share of candidates with infinite topic
  perplexity and of those holding a word unseen on the path (M5). The word store is read
  from ``cache_dir`` (extracted again if it is not there).
- ``headline.csv``: per dataset, topic-perplexity MI at 80 steps (against human labels,
  or against Z_b on a map without them: ``against``) divided by the next best walker's,
  the paired difference to it with its CI and Wilcoxon p, whether topic perplexity beats
  every other walker (higher mean and p < 0.05 against each), its share of the better
  ceiling's MI, and the paper's ratio for the map the dataset stands in for (1.51, 1.20
  and 1.05); then how sure the ratio is (:func:`with_uncertainty`): its bootstrap
  interval with the next best chosen in every resample, its null reference (median,
  interval and p with the walkers exchangeable, and with the random walk left out of them,
  :mod:`~curiosity_cli.evaluate.comparisons`), the smallest ratio detectable at 80 % power
  and the pairs a 10 % lead would need; and the p of the lead and of the null reference
  adjusted for the number of maps (:func:`with_adjusted`).
- ``tables.json``: each table's size and SHA-256 and those of every file and map fact the
  tables were made from (:meth:`~curiosity_cli.experiment.experiment.Experiment.record_tables`),
  written last with the others: ``plot`` and the report draw only a set whose record holds.

Every run of the grid needs usable labels; ``partial`` evaluates the others and lists the
runs left out in ``skipped.json``.
"""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from curiosity_cli.errors import RERUN, CuriosityError
from curiosity_cli.experiment.experiment import Experiment
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.experiment.recipes import first_of
from curiosity_cli.evaluate.statistics import (
    ALPHA, KEYS, label_convergence, paired_blocks, paired_difference, paired_tests, summarise, summarise_classes,
    summarise_revisits, wilcoxon_p,
)
from curiosity_cli.evaluate.multiplicity import intersection_union_p
from curiosity_cli.explore.weights import CEILINGS
from curiosity_cli.files import CorruptFileError, atomic_path, display_path, open_npz

if TYPE_CHECKING:
    import pandas as pd

    from curiosity_cli.config import ExperimentConfig

#: The path length the paper reads its headline at (about a map's width); a map without
#: that checkpoint is read at its longest one below it (:func:`headline_length`).
HEADLINE_LENGTH = 80
HEADLINE_WEIGHT = "topic-perplexity"


def headline_length(lengths) -> int | None:
    """The path length a map's headline is read at: :data:`HEADLINE_LENGTH`, or the longest of ``lengths``
    below it; None when every length is longer."""
    below = [int(n) for n in lengths if n <= HEADLINE_LENGTH]
    return max(below) if below else None


class EvaluationError(CuriosityError):
    """Results that cannot be evaluated: missing, corrupt, or not from the same maps."""


class IncompleteLabelsError(EvaluationError):
    """Runs of the grid without usable labels: tables without them would not be the experiment's.

    Attributes
    ----------
    left_out : list of str
        One line per run, naming the file at fault and why.
    """

    def __init__(self, left_out: list[str]):
        super().__init__(
            f"{len(left_out)} runs of the grid have no usable labels ({first_of(left_out)}); {RERUN} makes them "
            "once their runs are explored, or evaluating with `partial` leaves them out", rerun="label", force=False,
        )
        self.left_out = left_out


#: :func:`read_table`'s ``absent`` when a missing table is an error.
_RAISE = object()


def read_table(path: Path, columns: Sequence[str] = (), *, absent=_RAISE, error: type = EvaluationError, **options):
    """An evaluation table, the one way every reader reads one back.

    Parameters
    ----------
    path : Path
        The CSV file ``evaluate`` wrote.
    columns : sequence of str
        Columns it must have (others are kept).
    absent : optional
        What a missing file gives; without it, a missing file is an error.
    error : type
        The :class:`~curiosity_cli.errors.CuriosityError` to raise (a figure's reader raises its own).
    **options
        For :func:`pandas.read_csv` (a table whose empty cells mean "" rather than missing).

    Returns
    -------
    pandas.DataFrame
        Empty, without columns, for a table written without any (no run was labelled twice).

    Raises
    ------
    error
        Missing, unreadable, or without one of ``columns``; naming the file and that ``evaluate``
        makes it.
    """
    import pandas as pd

    path = Path(path)
    again = {"rerun": "evaluate", "force": False}
    if not path.is_file():
        if absent is not _RAISE:
            return absent
        raise error(f"{display_path(path)}: not found; {RERUN} makes it", **again)
    try:
        table = pd.read_csv(path, **options)
    except pd.errors.EmptyDataError:
        table = pd.DataFrame()
    except (OSError, ValueError) as exc:  # pandas' parser errors are ValueErrors, a bad encoding a UnicodeDecodeError
        raise error(f"{display_path(path)}: not a readable CSV table ({exc}); {RERUN} makes it again", **again) from None
    missing = [c for c in columns if c not in table.columns]
    if missing:
        raise error(
            f"{display_path(path)}: no column {missing[0]!r}; expected {', '.join(columns)} ({RERUN} makes it again)",
            **again,
        )
    return table


@dataclass(frozen=True)
class Evaluation:
    """The tables of an experiment, and the notes on what had to be left out (each with why)."""

    mi: pd.DataFrame
    summary: pd.DataFrame
    tests: pd.DataFrame
    headline: pd.DataFrame
    skipped: list[str]
    maps: pd.DataFrame | None  # maps.csv, None for folders from before it existed
    effects: pd.DataFrame | None = None
    classes: pd.DataFrame | None = None
    classes_summary: pd.DataFrame | None = None
    convergence: pd.DataFrame | None = None
    revisits: pd.DataFrame | None = None
    steering: pd.DataFrame | None = None
    mechanism: pd.DataFrame | None = None


@dataclass(frozen=True)
class LabelRows:
    """What the label files hold, as table rows (:func:`label_rows`)."""

    mi: list[dict]  # one per run and checkpoint
    classes: list[dict]  # one per run, checkpoint and class with pixels
    left_out: list[str]  # runs of the grid without usable labels, each naming the file at fault and why
    notes: list[str]  # label files of runs outside the grid, which change no number
    steering: list[dict]  # one per run that scored its moves and checkpoint (steering.csv)
    mechanism: list[dict]  # likewise (mechanism.csv)


def run_rows(
    meta: dict, arrays: dict, class_names: dict[int, str] | None = None, steps: tuple | None = None,
) -> tuple[list[dict], list[dict]]:
    """The mi.csv rows (one per checkpoint) and classes.csv rows of one run's label file.

    Parameters
    ----------
    meta : dict
        The label file's ``meta``.
    arrays : dict of str to ndarray
        ``lengths`` (n,), ``batch`` (n, K, K), optionally ``human`` (n, K, C),
        ``class_first_step`` (C,) and the second chain's ``placed_batch`` and
        ``placed_human``, as :func:`~curiosity_cli.label.stage.label_block` writes them.
    class_names : dict of int to str, optional
        The map's legend.
    steps : ((L,) int ndarray, (L,) bool ndarray), optional
        The run's path and ``boxed_in`` flags, for the revisit columns
        (:func:`~curiosity_cli.evaluate.revisits.revisit_counts`); NaN without.

    Returns
    -------
    (list of dict, list of dict)
    """
    from curiosity_cli.evaluate.information import (
        classes_found,
        matched_recall,
        mutual_information,
        normalised_mutual_information,
    )
    from curiosity_cli.label.label_files import SECOND_PREFIX
    from curiosity_cli.evaluate.revisits import REVISIT_COLUMNS, revisit_counts

    human, batch = arrays.get("human"), arrays["batch"]
    first = arrays.get("class_first_step")
    run = {"dataset": meta["dataset"], "weight_function": meta["weight_function"], "restart": meta["restart"]}
    rows, class_rows = [], []
    for i, length in enumerate(arrays["lengths"].tolist()):
        row = {
            **run, "path_length": length,
            "mi_human": np.nan, "mi_batch": mutual_information(batch[i]),
            "nmi_human": np.nan, "nmi_batch": normalised_mutual_information(batch[i]),
            "classes_found": np.nan, "classes": np.nan, "mean_recall": np.nan,
            "seed": " ".join(map(str, meta["run_seed"])), "replicate": meta["run_seed"][0],
            "placed_mi_human": np.nan, "placed_mi_batch": np.nan,
            **(revisit_counts(*steps, length) if steps is not None else dict.fromkeys(REVISIT_COLUMNS, np.nan)),
        }
        for against in ("human", "batch"):
            if SECOND_PREFIX + against in arrays:
                row[f"placed_mi_{against}"] = mutual_information(arrays[SECOND_PREFIX + against][i])
        if human is not None:
            pixels = human[i].sum(axis=0)
            present = np.flatnonzero(pixels > 0)
            recall, topic = matched_recall(human[i])
            row.update({
                "mi_human": mutual_information(human[i]), "nmi_human": normalised_mutual_information(human[i]),
                "classes": present.size, "mean_recall": float(recall[present].mean()) if present.size else np.nan,
            })
            if first is not None:
                row["classes_found"] = classes_found(first[present], length)
            for h in present.tolist():
                reached = first is not None and 0 <= first[h] < length
                class_rows.append({
                    **run, "path_length": length, "class_id": h, "class_name": (class_names or {}).get(h, ""),
                    "pixels": int(pixels[h]), "found": bool(reached) if first is not None else np.nan,
                    "first_step": float(first[h]) if reached else np.nan,
                    "topic": int(topic[h]), "recall": float(recall[h]),
                })
        rows.append(row)
    return rows, class_rows


def label_rows(experiment: Experiment, cache_dir: Path | None = None) -> LabelRows:
    """The table rows of every label file of an experiment, and the files left out, with why.

    Every label file must have been made from its run and its map's batch reference as
    the experiment's ``config.yaml`` and its maps as they are now make them, human labels
    included, and every run likewise (:meth:`~curiosity_cli.experiment.experiment.Experiment.run_recipe`);
    their files and example maps must be as they were written.

    Parameters
    ----------
    experiment : Experiment
    cache_dir : Path, optional
        Where the maps' word stores are cached (for ``mechanism.csv``); default the user cache.

    Raises
    ------
    EvaluationError
        No label files at all, or label files or runs made otherwise or altered since
        (naming them and what changed).
    CuriosityError
        A map of the config that cannot be loaded, naming it.
    """
    from curiosity_cli.label.label_files import examples_changed, read_label_file
    from curiosity_cli.evaluate.mechanism import mechanism_rows
    from curiosity_cli.evaluate.steering import steering_rows
    from curiosity_cli.explore.runs import RunError, read_run

    layout = experiment.folder
    files = layout.label_files()
    if not files:
        raise EvaluationError(f"{display_path(layout.labels)}: no label files; {RERUN} makes them", rerun="label", force=False)
    class_names = read_class_names(experiment.config)
    planned = _planned_label_files(experiment)
    files, notes = _in_grid(layout, files, planned)
    skipped = []
    rows, class_rows, steering, mechanism, otherwise = [], [], [], [], []
    batches = {}  # per map: what is wrong with its batch reference, None if nothing
    surroundings = {}  # per map: its classes per cell and its words per cell, for mechanism.csv
    for path in files:
        try:
            meta, arrays = read_label_file(path)
        except CorruptFileError as exc:
            skipped.append(f"{exc}; label the experiment again to redo it")
            continue
        if layout.label_file(meta["dataset"], meta["weight_function"], meta["restart"]) != path:
            # a file copied or moved over another run's: it would count its own run twice
            skipped.append(
                f"{display_path(path)}: holds the labels of {meta['dataset']} / {meta['weight_function']} / restart "
                f"{meta['restart']}, not of the run it is named after; label the experiment again to redo it"
            )
            continue
        if meta["dataset"] not in experiment.maps:
            skipped.append(f"{display_path(path)}: {meta['dataset']} is not a map of {display_path(layout.config)}")
            continue
        run_path = layout.run(meta["dataset"], meta["weight_function"], meta["restart"])
        try:
            run = read_run(run_path)
        except RunError as exc:
            skipped.append(str(exc))
            continue
        run_change = experiment.run_recipe(meta["dataset"], meta["weight_function"], meta["restart"]).changes(run.meta)
        if run_change is not None:
            otherwise.append(f"{display_path(run_path / 'run.json')}: {run_change}")
            continue
        if meta["dataset"] not in batches:
            batches[meta["dataset"]] = _batch_change(layout.batch(meta["dataset"]), experiment.batch_recipe(meta["dataset"]))
        if batches[meta["dataset"]] is not None:
            otherwise.append(batches[meta["dataset"]])
            continue
        change = experiment.label_recipe(run.meta).changes(meta)
        if change is not None:
            otherwise.append(f"{display_path(path)}: {change}")
            continue
        if (change := examples_changed(path, meta)) is not None:
            otherwise.append(change)
            continue
        try:
            steps = (run.path, run.boxed_in())
            candidates = run.candidates()
        except RunError as exc:
            skipped.append(str(exc))
            continue
        mi, classes = run_rows(meta, arrays, class_names.get(meta["dataset"]), steps)
        rows += mi
        class_rows += classes
        if mi:
            lengths = arrays["lengths"].tolist()
            steering += steering_rows(mi[0], candidates, lengths)
            if meta["dataset"] not in surroundings:
                surroundings[meta["dataset"]] = _surroundings(experiment, meta["dataset"], cache_dir)
            mechanism += mechanism_rows(mi[0], run.path, candidates, *surroundings[meta["dataset"]], lengths)
    if otherwise:
        raise EvaluationError(
            f"{len(otherwise)} label files or runs were made otherwise than {display_path(layout.config)} "
            f"and the maps make them now, or changed since ({first_of(otherwise)}); {RERUN} makes the label files "
            "again (explore first, for runs made otherwise)",
            rerun="label", force=False,
        )
    skipped += _unlabelled_runs(layout, files, planned)
    return LabelRows(rows, class_rows, skipped, notes, steering, mechanism)


def _surroundings(experiment: Experiment, dataset: str, cache_dir: Path | None) -> tuple:
    """A map's human classes present per cell ((n_cells, C) bool, C = 0 without labels) and
    its words per cell (the word store's ``cell_words``), for :func:`~curiosity_cli.evaluate.mechanism.mechanism_rows`."""
    from curiosity_cli.evaluate.mechanism import class_presence
    from curiosity_cli.label.classes import map_class_pixels
    from curiosity_cli.maps.map_data import load_map
    from curiosity_cli.paths import DEFAULT_CACHE
    from curiosity_cli.words.extract import extract_words

    map_data = load_map(experiment.maps[dataset].entry)
    store = extract_words(map_data, experiment.config.words, cache_dir=cache_dir or DEFAULT_CACHE).store
    cell_classes = map_class_pixels(map_data)
    if cell_classes is None:
        return np.zeros((store.n_cells, 0), bool), store.cell_words
    return class_presence(cell_classes), store.cell_words


def _batch_change(path: Path, recipe) -> str | None:
    """What is wrong with a map's batch reference (missing, corrupt, or made otherwise than
    ``recipe``), in words; None if nothing. Its label files were compared with it, and the
    figures draw it."""
    from curiosity_cli.files import read_meta

    try:
        with open_npz(path) as npz:
            change = recipe.changes(read_meta(npz))
    except FileNotFoundError:
        return f"{display_path(path)}: not found"
    except CorruptFileError as exc:
        return str(exc)
    return None if change is None else f"{display_path(path)}: {change}"


def _planned_label_files(experiment: Experiment) -> list[Path]:
    """The label file of each run of the grid."""
    return [experiment.folder.label_file(r.dataset, r.weight_function, r.restart) for r in experiment.planned()]


def _in_grid(layout: ExperimentFolder, files: list[Path], planned: list[Path]) -> tuple[list[Path], list[str]]:
    """``files`` of runs in the grid (``planned``: :func:`_planned_label_files`), and a line
    for those of runs outside it (a config narrowed since)."""
    keep = set(planned)
    outside = [path for path in files if path not in keep]
    if not outside:
        return files, []
    note = (
        f"{len(outside)} label files of runs outside the grid of {display_path(layout.config)} "
        f"(explore.weight_functions or explore.restarts narrowed since), e.g. {display_path(outside[0])}"
    )
    return [path for path in files if path in keep], [note]


def _unlabelled_runs(layout: ExperimentFolder, files: list[Path], planned: list[Path]) -> list[str]:
    """A line for each run of the grid (``planned``) that has no label file, naming the file it lacks, or the run
    folder when the run is not explored (as ``label`` names it)."""
    from curiosity_cli.label.stage import unexplored

    lines = []
    for path in planned:
        if path not in files:
            run = layout.run(*layout.run_of_label_file(path))
            if (run / ExperimentFolder.RUN_META).is_file():
                lines.append(f"{display_path(path)}: not found; label the experiment to make it")
            else:
                lines.append(unexplored(run, layout))
    return lines


def paired_effects(mi, tests=None):
    """Topic perplexity against each other walker, paired by restart (ceilings left out).

    Per (dataset, path length, against, other walker): ``n`` pairs, the two means over
    those pairs, the mean paired difference with its 95 % Student-t CI
    (:func:`~curiosity_cli.evaluate.statistics.paired_difference`), the ratio of the
    means with its 95 % studentized paired-bootstrap interval
    (:func:`~curiosity_cli.evaluate.comparisons.ratio_interval`) and the Wilcoxon p of
    the same pairs from ``tests`` (computed with
    :func:`~curiosity_cli.evaluate.statistics.paired_tests` when not given): each walker
    a pre-specified comparison (:mod:`~curiosity_cli.evaluate.comparisons`).
    """
    import pandas as pd

    from curiosity_cli.evaluate.comparisons import ratio_interval

    tests = paired_tests(mi) if tests is None else tests
    rows = []
    for against, dataset, length, block in paired_blocks(mi):
        if HEADLINE_WEIGHT not in block.columns:
            continue
        for other in block.columns.drop(HEADLINE_WEIGHT):
            pair = block[[HEADLINE_WEIGHT, other]].dropna()
            if pair.empty:
                continue
            ours, theirs = pair[HEADLINE_WEIGHT].to_numpy(), pair[other].to_numpy()
            mean, low, high = paired_difference(ours, theirs)
            ratio_low, ratio_high = ratio_interval(ours, theirs)
            rows.append({
                "dataset": dataset, "path_length": length, "against": against, "other": other, "n": len(pair),
                "topic_perplexity": float(ours.mean()), "other_mean": float(theirs.mean()),
                "mean_difference": mean, "ci_low": low, "ci_high": high,
                "ratio": float(ours.mean() / theirs.mean()) if theirs.mean() > 0 else np.nan,
                "ratio_ci_low": ratio_low, "ratio_ci_high": ratio_high,
                "p_value": wilcoxon_p(tests, dataset, length, against, HEADLINE_WEIGHT, other)[0],
            })
    return pd.DataFrame(rows, columns=EFFECT_COLUMNS)


#: ``effects.csv``'s columns (:func:`paired_effects`).
EFFECT_COLUMNS = [
    "dataset", "path_length", "against", "other", "n", "topic_perplexity", "other_mean", "mean_difference", "ci_low",
    "ci_high", "ratio", "ratio_ci_low", "ratio_ci_high", "p_value",
]
HEADLINE_COLUMNS = [
    "dataset", "path_length", "against", "topic_perplexity", "next_best", "next_best_mi", "ratio", "mean_difference", "ci_low",
    "ci_high", "p_value", "pairs", "beats_all", "not_beaten", "p_each", "best_ceiling", "ceiling_mi", "ceiling_share",
    "paper_map", "paper_ratio",
]
#: The columns :func:`with_uncertainty` adds to the headline.
UNCERTAINTY_COLUMNS = [
    "ratio_ci_low", "ratio_ci_high", "null_median", "null_low", "null_high", "null_p", "null_no_rw_median",
    "null_no_rw_low", "null_no_rw_high", "null_no_rw_p", "detectable_ratio", "pairs_for_lead",
]
#: The p-values :func:`with_adjusted` corrects for the family of maps (and a study's curve for its points), and the
#: columns it adds: each one Holm- and Benjamini-Hochberg-adjusted.
ADJUSTED_P = ("p_each", "null_no_rw_p", "null_p")
ADJUSTED_COLUMNS = [f"{p}_{method}" for p in ADJUSTED_P for method in ("holm", "bh")]
#: The walker left out of the stricter null reference's exchangeable set (``null_no_rw_*``): the random walk
#: ignores eq. 8's coverage and sees about half the cells the others see in 80 steps, so no reading makes it
#: exchangeable with topic perplexity, and permuting it in puts the null ratios too low (the null p too small).
NOT_EXCHANGEABLE = "random-walk"


def headline(summary, tests, stands_in_for: dict[str, str], effects=None, against: str | None = None):
    """Per dataset: topic perplexity's mean MI at 80 steps (``path_length``: or the map's longest
    checkpoint below 80, :func:`headline_length`) over the next best walker's.

    Against human labels, or against Z_b on a map without them (``against`` None); or
    against the labels ``against`` names (``"human"`` or ``"batch"``: a map without
    them gets no row). The next best is chosen after seeing the data: the ratio is a
    summary, read against its null reference (:func:`with_uncertainty`). With the
    paired Wilcoxon p of topic perplexity against that next best; the mean paired
    difference to it and its 95 % CI (from ``effects``, NaN without); ``beats_all``:
    topic perplexity's mean is above every other walker's with a paired Wilcoxon p below
    :data:`~curiosity_cli.evaluate.statistics.ALPHA` against each, and ``not_beaten``: the walkers (``;``-separated) for
    which that fails; ``p_each``, the p of that lead
    (:func:`~curiosity_cli.evaluate.multiplicity.intersection_union_p`: ``beats_all`` is ``p_each`` below the level,
    for one map alone; :func:`with_adjusted` corrects it for the family of maps); the better ceiling, its MI and topic perplexity's share of it (no
    ceiling runs: empty and NaN); and the paper's ratio for the map the dataset stands
    in for (``stands_in_for``: dataset name to paper map name; datasets without one get
    no paper ratio). Ceilings are never the next best.
    """
    import pandas as pd

    from curiosity_cli.paper import PAPER_MAPS

    rows = []
    for dataset, every in summary.groupby("dataset", sort=False):
        length = headline_length(every["path_length"].unique())
        block = every[every["path_length"] == length]
        if block.empty:
            continue
        read = against or ("human" if (block["against"] == "human").any() else "batch")
        means = block[block["against"] == read].set_index("weight_function")["mean"]
        ceilings = means[means.index.isin(CEILINGS)]
        walkers = means[~means.index.isin(CEILINGS)]
        if HEADLINE_WEIGHT not in walkers or len(walkers) < 2:
            continue
        ours = walkers[HEADLINE_WEIGHT]
        others = walkers.drop(HEADLINE_WEIGHT).sort_values(ascending=False, kind="stable")
        next_best = others.index[0]
        p_values = {o: wilcoxon_p(tests, dataset, length, read, HEADLINE_WEIGHT, o) for o in others.index}
        not_beaten = [o for o in others.index if not (ours > others[o] and p_values[o][0] < ALPHA)]
        p_each = intersection_union_p(ours, others.to_numpy(), [p_values[o][0] for o in others.index])
        effect = None
        if effects is not None:
            match = effects[
                (effects["dataset"] == dataset) & (effects["path_length"] == length)
                & (effects["against"] == read) & (effects["other"] == next_best)
            ]
            effect = match.iloc[0] if len(match) else None
        best_ceiling = ceilings.idxmax() if len(ceilings) and ceilings.notna().any() else ""
        ceiling_mi = ceilings[best_ceiling] if best_ceiling else np.nan
        paper = PAPER_MAPS.get(stands_in_for.get(dataset, ""))
        rows.append({
            "dataset": dataset, "path_length": length, "against": read, "topic_perplexity": ours, "next_best": next_best,
            "next_best_mi": others.iloc[0], "ratio": ours / others.iloc[0] if others.iloc[0] > 0 else np.nan,
            "mean_difference": effect["mean_difference"] if effect is not None else np.nan,
            "ci_low": effect["ci_low"] if effect is not None else np.nan,
            "ci_high": effect["ci_high"] if effect is not None else np.nan,
            "p_value": p_values[next_best][0], "pairs": p_values[next_best][1],
            "beats_all": not not_beaten, "not_beaten": ";".join(not_beaten), "p_each": p_each,
            "best_ceiling": best_ceiling, "ceiling_mi": ceiling_mi,
            "ceiling_share": ours / ceiling_mi if best_ceiling and ceiling_mi > 0 else np.nan,
            "paper_map": paper.name if paper else "", "paper_ratio": paper.headline_ratio if paper else np.nan,
        })
    return pd.DataFrame(rows, columns=HEADLINE_COLUMNS)


def with_uncertainty(top, mi):
    """``top`` (:func:`headline`) with how sure each ratio is, and where "no difference" lies.

    From the restarts at the headline's length where every walker has an MI (the
    walkers' mean MI per restart, ceilings left out):

    - ``ratio_ci_low``, ``ratio_ci_high``: the next-best ratio's 95 % paired-bootstrap
      interval, the next best chosen again in every resample
      (:func:`~curiosity_cli.evaluate.comparisons.next_best_interval`);
    - ``null_median``, ``null_low``, ``null_high``, ``null_p``: the ratio's null
      reference, the walkers' labels permuted within each restart
      (:func:`~curiosity_cli.evaluate.comparisons.next_best_null`): its median and 95 %
      interval, and the share of permutations at least as high as the observed ratio;
    - ``null_no_rw_median``, ``null_no_rw_low``, ``null_no_rw_high``, ``null_no_rw_p``: the
      same with the random walk left out of the permuted walkers
      (:data:`NOT_EXCHANGEABLE`): "topic perplexity does not differ from the walkers that
      could equal it", the null the verdicts read;
    - ``detectable_ratio``: the smallest ratio the experiment could have detected at 80 %
      power against the observed next best, and ``pairs_for_lead``: the pairs a 10 % lead
      would need (NaN beyond a million) (:mod:`~curiosity_cli.evaluate.power`).
    """
    from curiosity_cli.evaluate.comparisons import next_best_interval, next_best_null
    from curiosity_cli.evaluate.power import TARGET_LEAD, detectable_difference, pairs_needed

    columns = {name: [] for name in UNCERTAINTY_COLUMNS}
    blocks = {(against, dataset, length): block for against, dataset, length, block in paired_blocks(mi)}
    for row in top.itertuples():
        block = blocks[(row.against, row.dataset, row.path_length)]
        complete = block.dropna()
        ours, others = complete[HEADLINE_WEIGHT].to_numpy(), complete.drop(columns=HEADLINE_WEIGHT).to_numpy()
        low, high = next_best_interval(ours, others)
        null = next_best_null(ours, others)
        strict = next_best_null(ours, others, exchangeable=complete.columns.drop(HEADLINE_WEIGHT) != NOT_EXCHANGEABLE)
        pair = block[[HEADLINE_WEIGHT, row.next_best]].dropna().to_numpy()
        ours_nb, theirs = pair[:, 0], pair[:, 1]
        sd = float(np.std(ours_nb - theirs, ddof=1)) if len(pair) > 1 else np.nan
        baseline = float(theirs.mean())
        needed = pairs_needed(TARGET_LEAD * baseline, sd)
        values = {
            "ratio_ci_low": low, "ratio_ci_high": high, "null_median": null.median, "null_low": null.low,
            "null_high": null.high, "null_p": null.p_value, "null_no_rw_median": strict.median,
            "null_no_rw_low": strict.low, "null_no_rw_high": strict.high, "null_no_rw_p": strict.p_value,
            "detectable_ratio": 1 + detectable_difference(sd, len(pair)) / baseline if baseline > 0 else np.nan,
            "pairs_for_lead": np.nan if needed is None else needed,
        }
        for name in UNCERTAINTY_COLUMNS:
            columns[name].append(values[name])
    return top.assign(**columns)


def with_adjusted(top):
    """``top`` (:func:`with_uncertainty`) with :data:`ADJUSTED_P` corrected for its family of maps.

    Each of ``p_each``, ``null_no_rw_p`` and ``null_p`` gains its Holm (``_holm``) and
    Benjamini-Hochberg (``_bh``) adjusted value over the rows measured against the same
    labels (:mod:`~curiosity_cli.evaluate.multiplicity`): an experiment on five maps asks
    five questions, and "leads on one of them" needs the adjusted p.
    """
    from curiosity_cli.evaluate.multiplicity import benjamini_hochberg, holm

    top = top.copy()
    for column in ADJUSTED_COLUMNS:
        top[column] = np.nan
    for _, rows in top.groupby("against", sort=False):
        for p in ADJUSTED_P:
            values = rows[p].to_numpy(float)
            top.loc[rows.index, f"{p}_holm"] = holm(values)
            top.loc[rows.index, f"{p}_bh"] = benjamini_hochberg(values)
    return top


def read_class_names(config: ExperimentConfig) -> dict[str, dict[int, str]]:
    """Per dataset of an experiment, its legend's class names by id; none for a map whose legend cannot be read.

    Best effort from the datasets' YAML and legend files (no images): the names only
    label ``classes.csv`` rows.
    """
    from curiosity_cli.maps.datasets import dataset_path, load_dataset_config
    from curiosity_cli.maps.map_data import load_legend

    names = {}
    for entry in config.datasets:
        try:
            dataset = load_dataset_config(dataset_path(entry))
            if dataset.legend is not None:
                names[dataset.name] = {c.id: c.name for c in load_legend(dataset.legend)}
        except (CuriosityError, OSError):
            continue
    return names


def read_maps(folder: Path):
    """``maps.csv`` of an experiment (each map's words and the paper map it stands in
    for, written by ``explore``), or None for a folder from before it existed.

    Raises
    ------
    EvaluationError
        It is not as ``explore`` wrote it (``provenance.yaml`` records its size and digest), or cannot be read.
    """
    import pandas as pd

    import yaml

    from curiosity_cli.experiment.wholeness import FILES_KEY, changed

    layout = ExperimentFolder(folder)
    path = layout.maps_csv
    if not path.is_file():
        return None
    try:  # what explore recorded of it (nothing in a folder from before it did)
        written = yaml.safe_load(layout.provenance.read_text()).get(FILES_KEY, {})
    except (OSError, yaml.YAMLError, AttributeError):
        written = {}
    if path.name in written and (change := changed(layout.root, {path.name: written[path.name]})) is not None:
        raise EvaluationError(
            f"{display_path(path)}: {change[1]} (explore wrote it); {RERUN} writes it again, keeping the runs",
            rerun="explore", force=False,
        )
    try:
        return pd.read_csv(path, keep_default_na=False, na_values=[""])
    except (ValueError, OSError) as exc:
        raise EvaluationError(f"{display_path(path)}: cannot read the table of maps: {exc}") from None


def evaluate_experiment(folder: Path, *, partial: bool = False, cache_dir: Path | None = None) -> Evaluation:
    """Compute and write every table of an experiment folder (module docstring), and
    ``tables.json``: the tables' sizes and digests and what they were made from
    (:meth:`~curiosity_cli.experiment.experiment.Experiment.record_tables`).

    Parameters
    ----------
    folder : Path
    partial : bool
        Evaluate the runs that have usable labels and leave out those that do not
        (missing, corrupt or misplaced label files, broken runs), listing them in
        ``skipped.json`` and the ``skipped`` of the result. Without it such runs are an
        error: tables without them are not the experiment's.
    cache_dir : Path, optional
        Where the maps' word stores are cached (``mechanism.csv`` reads each cell's
        words); default the user cache. A store that is not there is extracted again.

    Raises
    ------
    ConfigError
        No ``config.yaml``, or one that does not validate.
    IncompleteLabelsError
        Without ``partial``, runs of the grid without usable labels, naming each.
    EvaluationError
        No usable label files, or labels or runs made otherwise than the experiment
        makes them now.
    FolderInUseError
        Another process works in the folder (:mod:`~curiosity_cli.experiment.lock`).
    """
    import pandas as pd

    from curiosity_cli.experiment.lock import working_in
    from curiosity_cli.experiment.stage_seconds import record_stage_seconds

    started = time.perf_counter()
    with working_in(folder, "evaluate"):
        experiment = Experiment.open(folder)
        layout = experiment.folder
        inputs = experiment.inputs()  # before reading: a file changed meanwhile makes the record stale, never wrong
        found = label_rows(experiment, cache_dir)
        if found.left_out and not partial:
            raise IncompleteLabelsError(found.left_out)
        skipped = [*found.notes, *found.left_out]
        if not found.mi:
            raise EvaluationError(f"{display_path(layout.labels)}: every label file was left out: " + "; ".join(skipped))
        from curiosity_cli.evaluate.mechanism import MECHANISM_COLUMNS
        from curiosity_cli.evaluate.steering import STEERING_COLUMNS

        mi = pd.DataFrame(found.mi).sort_values(KEYS, ignore_index=True)
        steering = pd.DataFrame(found.steering, columns=list(STEERING_COLUMNS)).sort_values(KEYS, ignore_index=True)
        mechanism = pd.DataFrame(found.mechanism, columns=list(MECHANISM_COLUMNS)).sort_values(KEYS, ignore_index=True)
        class_columns = [*KEYS, "class_id", "class_name", "pixels", "found", "first_step", "topic", "recall"]
        classes = pd.DataFrame(found.classes, columns=class_columns).sort_values([*KEYS, "class_id"], ignore_index=True)
        summary = summarise(mi)
        classes_summary = summarise_classes(mi)
        tests = paired_tests(mi)
        effects = paired_effects(mi, tests)
        maps = read_maps(folder)
        top = with_adjusted(with_uncertainty(headline(summary, tests, experiment.paper_maps(), effects), mi))
        revisits = summarise_revisits(mi)
        convergence = label_convergence(mi)
        tables = {
            "mi": mi, "classes": classes, "summary": summary, "classes_summary": classes_summary, "tests": tests,
            "effects": effects, "headline": top, "convergence": convergence, "revisits": revisits, "steering": steering,
            "mechanism": mechanism,
        }
        # every file is written whole before any replaces its old self, and tables.json
        # records each one's digest: a failure (a full disk) leaves the old set or a mix that
        # plot refuses, never a mix taken as one set
        with contextlib.ExitStack() as stack:
            written = {}  # each file's name in the folder, and the temporary file that will replace it

            def temporary(path: Path) -> Path:
                tmp = written[str(path.relative_to(layout.root))] = stack.enter_context(atomic_path(path))
                return tmp

            for name, table in tables.items():
                table.to_csv(temporary(layout.table(name)), index=False)
            mi.to_parquet(temporary(layout.table("mi", ".parquet")), index=False)
            temporary(layout.skipped).write_text(json.dumps(skipped, indent=2) + "\n")
            record = experiment.record_tables(written, inputs)
            temporary(layout.tables_record).write_text(record)
        record_stage_seconds(folder, "evaluate", time.perf_counter() - started, add=False)
        return Evaluation(
            mi, summary, tests, top, skipped, maps, effects, classes, classes_summary, convergence, revisits, steering,
            mechanism,
        )


def read_evaluation(experiment: Experiment) -> Evaluation:
    """The tables ``evaluate`` wrote in an experiment folder, read back as it returned them.

    The caller has checked that they are one set made from the folder's files as they are
    now (:meth:`~curiosity_cli.experiment.experiment.Experiment.check_tables`), which
    digests every input: ``plot`` does so once, for its figures and this report.

    Raises
    ------
    EvaluationError
        A table that cannot be read, naming it.
    """
    layout = experiment.folder

    def read(name: str):
        return read_table(layout.table(name))

    try:
        skipped = json.loads(layout.skipped.read_text())
    except (OSError, ValueError) as exc:
        raise EvaluationError(f"{display_path(layout.skipped)}: cannot read it ({exc}); {RERUN} makes it again",
                              rerun="evaluate", force=False) from None
    return Evaluation(
        read("mi"), read("summary"), read("tests"),
        read_table(layout.table("headline"), [*HEADLINE_COLUMNS, *UNCERTAINTY_COLUMNS, *ADJUSTED_COLUMNS]), skipped, read_maps(layout.root), read("effects"),
        read("classes"), read("classes_summary"), read("convergence"), read("revisits"), read("steering"),
        read("mechanism"),
    )
