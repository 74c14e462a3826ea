"""Seeds as replicates: one headline from the paired restarts of several experiments.

An experiment's seed draws its start cells and every random stream, so experiments that
differ only in their seed are replicates of one treatment, not treatments of their own.
Pooling their pairs (a restart of one seed is paired with the same restart of the same
seed, never across seeds) gives one ratio with one interval and one p, from as many
pairs as the replicates hold together. A sweep over ``seed`` pools this way
(:func:`curiosity_cli.sweep.write_sweep_report`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from curiosity_cli.errors import RERUN
from curiosity_cli.evaluate.tables import (
    EvaluationError,
    headline,
    paired_effects,
    paired_tests,
    summarise,
    summarise_revisits,
    with_power,
)
from curiosity_cli.experiment.experiment import Experiment
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
        :func:`~curiosity_cli.evaluate.tables.headline` with
        :func:`~curiosity_cli.evaluate.tables.with_power`'s columns, over every pair.
    revisits : pandas.DataFrame
        :func:`~curiosity_cli.evaluate.tables.summarise_revisits` over every run.
    seeds : tuple of int
        The replicates pooled.
    """

    headline: pd.DataFrame
    revisits: pd.DataFrame
    seeds: tuple[int, ...]


def pool(folders: Sequence[Path]) -> Pooled:
    """Pool the ``mi.csv`` of experiment folders that differ only in their seed.

    Parameters
    ----------
    folders : sequence of Path
        Evaluated experiment folders (``curiosity evaluate``), one per seed.

    Raises
    ------
    EvaluationError
        A folder without ``mi.csv`` or from before ``mi.csv`` named its replicate, or two
        folders of the same seed (their pairs would count twice).
    """
    import pandas as pd

    tables = []
    for folder in folders:
        path = ExperimentFolder(folder).table("mi")
        try:
            mi = pd.read_csv(path)
        except (OSError, ValueError) as exc:
            raise EvaluationError(
                f"{display_path(path)}: cannot read it ({exc}); {RERUN} makes it", rerun="evaluate", force=False
            ) from None
        if "replicate" not in mi or mi["replicate"].nunique() != 1:
            raise EvaluationError(
                f"{display_path(path)}: replicate: expected one seed per experiment; {RERUN} makes the table again",
                rerun="evaluate", force=False,
            )
        tables.append(mi)
    seeds = [int(mi["replicate"].iloc[0]) for mi in tables]
    if len(set(seeds)) != len(seeds):
        raise EvaluationError(f"seeds {seeds}: two experiments of the same seed cannot be pooled as replicates")
    mi = pd.concat(tables, ignore_index=True)
    tests = paired_tests(mi)
    paper_maps = Experiment.open(folders[0]).paper_maps()
    top = with_power(headline(summarise(mi), tests, paper_maps, paired_effects(mi, tests)), mi)
    return Pooled(top, summarise_revisits(mi), tuple(sorted(seeds)))
