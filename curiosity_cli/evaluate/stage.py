"""``curiosity evaluate``: mutual information per run and checkpoint, its summary and tests, and evidence beyond MI.


Written under ``results/<experiment>/``:

- ``mi.csv`` and ``mi.parquet``: one row per (dataset, weight function, restart, path
  length): every measure of :data:`~curiosity_cli.evaluate.measures.MEASURES`:
  ``mi_human``, ``mi_batch`` (bits), ``nmi_human``, ``nmi_batch``, ``ami_human``,
  ``ami_batch`` (chance-corrected, with ``topics_used``: the topics Z_p gives some pixel);
  ``classes_found`` (human classes the path's cells reached within the length, see
  :data:`~curiosity_cli.experiment.recipes.CLASS_SHARE_PERCENT`) of ``classes`` (the map's
  classes with pixels); ``mean_recall`` (mean per-class recall of Z_p under the best
  one-to-one topic-to-class matching, :func:`~curiosity_cli.evaluate.information.matched_recall`);
  ``heldout`` and ``heldout_unvisited`` (bits per word: the held-out log-likelihood of the map's words
  under Φ_p, over every cell and over the cells the path did not visit, :mod:`~curiosity_cli.label.heldout`);
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
  interval, and the Wilcoxon p of ``tests.csv`` (:func:`~curiosity_cli.evaluate.headline.paired_effects`): the
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
  and 1.05); then how sure the ratio is (:func:`~curiosity_cli.evaluate.headline.with_uncertainty`): its bootstrap
  interval with the next best chosen in every resample, its null reference (median,
  interval and p with the walkers exchangeable, and with the random walk left out of them,
  :mod:`~curiosity_cli.evaluate.comparisons`), the smallest ratio detectable at 80 % power
  and the pairs a 10 % lead would need; and the p of the lead and of the null reference
  adjusted for the number of maps (:func:`~curiosity_cli.evaluate.headline.with_adjusted`).
- ``found_summary.csv``, ``found_effects.csv``, ``found_leads.csv``: every measure beside MI
  (NMI, AMI, classes found, mean recall, time to first find, MI where the path went and where it did not,
  held-out log-likelihood) per walker, topic perplexity against each other
  walker on it, and whether it leads each, with MI's statistics; ``found_classes.csv``: how
  soon it first reached each human class against each walker (:mod:`~curiosity_cli.evaluate.found`).
- ``tables.json``: each table's size and SHA-256 and those of every file and map fact the
  tables were made from (:meth:`~curiosity_cli.experiment.experiment.Experiment.record_tables`),
  written last with the others: ``plot`` and the report draw only a set whose record holds.

Every run of the grid needs usable labels; ``partial`` evaluates the others and lists the
runs left out in ``skipped.json``.

The rows come from :mod:`~curiosity_cli.evaluate.rows`, the headline's statistics from
:mod:`~curiosity_cli.evaluate.headline`; :mod:`~curiosity_cli.evaluate.tables` reads a table back.
"""

from __future__ import annotations

import contextlib
import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from curiosity_cli.errors import RERUN
from curiosity_cli.evaluate.found import class_times, found_effects, found_leads, summarise_found
from curiosity_cli.evaluate.headline import (
    ADJUSTED_COLUMNS, HEADLINE_COLUMNS, UNCERTAINTY_COLUMNS, headline, paired_effects, with_adjusted, with_uncertainty,
)
from curiosity_cli.evaluate.rows import label_rows
from curiosity_cli.evaluate.statistics import (
    KEYS, label_convergence, paired_tests, summarise, summarise_classes, summarise_revisits,
)
from curiosity_cli.evaluate.tables import EvaluationError, read_maps, read_table
from curiosity_cli.experiment.experiment import Experiment
from curiosity_cli.experiment.recipes import first_of
from curiosity_cli.files import atomic_path, display_path

if TYPE_CHECKING:
    import pandas as pd


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
    found_summary: pd.DataFrame | None = None
    found_effects: pd.DataFrame | None = None
    found_leads: pd.DataFrame | None = None
    found_classes: pd.DataFrame | None = None


#: The tables ``evaluate`` writes as CSV, each under its name in ``results/<experiment>/`` and as the
#: :class:`Evaluation` field of that name.
TABLES = (
    "mi", "classes", "summary", "classes_summary", "tests", "effects", "headline", "convergence", "revisits",
    "steering", "mechanism", "found_summary", "found_effects", "found_leads", "found_classes",
)


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
        found = found_effects(mi)
        tables = {
            "mi": mi, "classes": classes, "summary": summary, "classes_summary": classes_summary, "tests": tests,
            "effects": effects, "headline": top, "convergence": label_convergence(mi), "revisits": summarise_revisits(mi),
            "steering": steering, "mechanism": mechanism, "found_summary": summarise_found(mi), "found_effects": found,
            "found_leads": found_leads(found), "found_classes": class_times(classes),
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
        return Evaluation(skipped=skipped, maps=maps, **tables)


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
    try:
        skipped = json.loads(layout.skipped.read_text())
    except (OSError, ValueError) as exc:
        raise EvaluationError(f"{display_path(layout.skipped)}: cannot read it ({exc}); {RERUN} makes it again",
                              rerun="evaluate", force=False) from None
    headline_columns = [*HEADLINE_COLUMNS, *UNCERTAINTY_COLUMNS, *ADJUSTED_COLUMNS]
    tables = {name: read_table(layout.table(name), headline_columns if name == "headline" else ()) for name in TABLES}
    return Evaluation(skipped=skipped, maps=read_maps(layout.root), **tables)
