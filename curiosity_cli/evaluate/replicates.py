"""Seeds as replicates: one headline from the paired restarts of several experiments.

An experiment's seed draws its start cells and every random stream, so experiments that
differ only in their seed are replicates of one treatment, not treatments of their own.
Pooling their pairs (a restart of one seed is paired with the same restart of the same
seed, never across seeds) gives one ratio with one interval and one p, from as many
pairs as the replicates hold together. A sweep over ``seed`` pools this way
(:func:`curiosity_cli.study.report.pool_treatments`), and so does a study's specification
curve (:mod:`curiosity_cli.evaluate.specification_curve`).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from curiosity_cli.errors import RERUN
from curiosity_cli.evaluate.found import found_effects, found_leads, missing_measures
from curiosity_cli.evaluate.headline import headline, headline_length, paired_effects, with_adjusted, with_uncertainty
from curiosity_cli.evaluate.measures import MEASURES
from curiosity_cli.evaluate.statistics import paired_blocks, paired_tests, summarise, summarise_revisits, summarise_steering
from curiosity_cli.evaluate.tables import EvaluationError, read_table
from curiosity_cli.experiment.experiment import Experiment
from curiosity_cli.explore.weights import CEILINGS
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.files import display_path

if TYPE_CHECKING:
    import pandas as pd


@dataclass(frozen=True)
class Pooled:
    """The pooled evidence of some replicates.

    Attributes
    ----------
    headline : pandas.DataFrame
        :func:`~curiosity_cli.evaluate.headline.headline` with
        :func:`~curiosity_cli.evaluate.headline.with_uncertainty`'s columns, over every pair:
        against human labels (against Z_b on a map without them).
    batch_headline : pandas.DataFrame
        The same against Z_b, on every map.
    effects : pandas.DataFrame
        :func:`~curiosity_cli.evaluate.headline.paired_effects` over every pair: topic
        perplexity against each other walker.
    revisits : pandas.DataFrame
        :func:`~curiosity_cli.evaluate.statistics.summarise_revisits` over every run.
    seeds : tuple of int
        The replicates pooled.
    steering : pandas.DataFrame
        :func:`~curiosity_cli.evaluate.statistics.summarise_steering` over every run's ``steering.csv``.
    mechanism : pandas.DataFrame
        :func:`~curiosity_cli.evaluate.mechanism.summarise_mechanism` over every run's ``mechanism.csv``.
    blocks : dict
        The pooled MI itself, for tests that redraw it (a study's joint null,
        :mod:`~curiosity_cli.evaluate.joint_null`): per (against, dataset, path length), a
        row per (``replicate``, ``restart``) and a column per walker
        (:func:`~curiosity_cli.evaluate.statistics.paired_blocks`).
    found_effects, found_leads : pandas.DataFrame
        Every measure beside MI over every pair (:mod:`~curiosity_cli.evaluate.found`).
    missing : tuple of str
        The measures beside MI that some folder's ``mi.csv`` lacks (recorded before they
        existed): pooled from none, so that no seed's pairs stand in for another's.
    """

    headline: pd.DataFrame
    batch_headline: pd.DataFrame
    effects: pd.DataFrame
    revisits: pd.DataFrame
    seeds: tuple[int, ...]
    steering: pd.DataFrame
    mechanism: pd.DataFrame
    blocks: dict
    found_effects: pd.DataFrame
    found_leads: pd.DataFrame
    missing: tuple[str, ...]

    def versus(self, dataset: str, against: str) -> pd.DataFrame:
        """Topic perplexity against each other walker on ``dataset`` at the headline's length
        (``effects.csv``'s rows, indexed by ``other``)."""
        rows = self.effects[(self.effects["dataset"] == dataset) & (self.effects["against"] == against)]
        rows = rows[rows["path_length"] == headline_length(rows["path_length"].unique())]
        return rows.set_index("other")

    def mean_distinct_cells(self, dataset: str, walker: str) -> float:
        """The walker's mean distinct cells in 80 steps (the headline length) over every pooled run; NaN without."""
        revisits = self.revisits[self.revisits["measure"] == "distinct_cells"]
        return _at_headline(revisits, dataset, walker)

    def mean_mechanism(self, dataset: str, walker: str, measure: str) -> float:
        """The walker's ``mechanism.csv`` measure at 80 steps (the headline length) over every pooled run, as
        :func:`~curiosity_cli.evaluate.mechanism.summarise_mechanism` pools it (an AUC over every run's pairs,
        the rest means); NaN without."""
        return _at_headline(self.mechanism, dataset, walker, measure)

    def mean_steering(self, dataset: str, walker: str) -> float:
        """The walker's mean steering at 80 steps (the headline length) over every pooled run
        (:mod:`~curiosity_cli.evaluate.steering`); NaN without."""
        return _at_headline(self.steering, dataset, walker)


def _at_headline(summary, dataset: str, walker: str, column: str = "mean") -> float:
    """``column`` of a summary's row for ``dataset``, ``walker`` and the headline's length; NaN if none."""
    rows = summary[(summary["dataset"] == dataset) & (summary["weight_function"] == walker)]
    match = rows[rows["path_length"] == headline_length(rows["path_length"].unique())][column]
    return float(match.iloc[0]) if len(match) else float("nan")


def pool(folders: Sequence[Path], walkers: Collection[str] | None = None) -> Pooled:
    """Pool the ``mi.csv``, ``steering.csv`` and ``mechanism.csv`` of experiment folders that differ only in their seed.

    Parameters
    ----------
    folders : sequence of Path
        Evaluated experiment folders (``curiosity evaluate``), one per seed.
    walkers : collection of str, optional
        Only these walkers' runs (and ceilings') take part, e.g. the paper's four
        (:data:`curiosity_cli.config.PAPER_WALKERS`), so the next best is one of them;
        default every walker the folders ran.

    Raises
    ------
    EvaluationError
        A folder without ``mi.csv``, ``steering.csv`` or ``mechanism.csv``, or from before ``mi.csv`` named
        its replicate, or two folders of the same seed (their pairs would count twice).
    """
    import pandas as pd

    from curiosity_cli.evaluate.mechanism import summarise_mechanism

    tables, steering, mechanism = [], [], []
    for folder in folders:
        mi = read_table(ExperimentFolder(folder).table("mi"))
        if "replicate" not in mi or mi["replicate"].nunique() != 1:
            raise EvaluationError(
                f"{display_path(ExperimentFolder(folder).table('mi'))}: replicate: expected one seed per experiment; "
                f"{RERUN} makes the table again", rerun="evaluate", force=False,
            )
        tables.append(mi)
        steering.append(read_table(ExperimentFolder(folder).table("steering")))
        mechanism.append(read_table(ExperimentFolder(folder).table("mechanism")))
    seeds = [int(mi["replicate"].iloc[0]) for mi in tables]
    if len(set(seeds)) != len(seeds):
        raise EvaluationError(f"seeds {seeds}: two experiments of the same seed cannot be pooled as replicates")
    # a measure one seed lacks is left out of all: a mean over the seeds that have it would be another treatment's
    missing = tuple(dict.fromkeys(m.name for mi in tables for m in missing_measures(mi)))
    lacking = [column for m in MEASURES if m.name in missing for column in m.columns.values()]
    mi = pd.concat([mi.drop(columns=lacking, errors="ignore") for mi in tables], ignore_index=True)
    steering = pd.concat(steering, ignore_index=True)
    mechanism = pd.concat(mechanism, ignore_index=True)
    if walkers is not None:
        mi = mi[mi["weight_function"].isin(walkers) | mi["weight_function"].isin(CEILINGS)]
        steering = steering[steering["weight_function"].isin(walkers)]
        mechanism = mechanism[mechanism["weight_function"].isin(walkers)]
    tests = paired_tests(mi)
    paper_maps = Experiment.open(folders[0]).paper_maps()
    summary, effects, found = summarise(mi), paired_effects(mi, tests), found_effects(mi)
    top = with_adjusted(with_uncertainty(headline(summary, tests, paper_maps, effects), mi))
    batch = with_adjusted(with_uncertainty(headline(summary, tests, paper_maps, effects, against="batch"), mi))
    return Pooled(
        top, batch, effects, summarise_revisits(mi), tuple(sorted(seeds)), summarise_steering(steering),
        summarise_mechanism(mechanism),
        {(against, dataset, length): block.droplevel(["dataset", "path_length"])
         for against, dataset, length, block in paired_blocks(mi)},
        found, found_leads(found), missing,
    )
