"""Does a measure see an effect where one must exist, and none where none does (issue 58)?

The validation walkers (:mod:`curiosity_cli.explore.weights`) run beside stochastic coverage,
whose streams the oracles share: each oracle-P has a planted advantage that grows with P,
the sham steers as hard as topic perplexity on scores that say nothing. A measure is
**validated** on a map when, at the path length read:

1. **the oracles' lead rises with P**: each restart's least-squares slope of
   ``oracle-P - stochastic coverage`` over P (its pairs at P = 0.1, 0.2, 0.3: one restart,
   one start cell and stream, so the slope is paired), and the one-sided Wilcoxon
   signed-rank test that those slopes lie above 0, p < :data:`ALPHA`;
2. **the largest oracle leads**: the one-sided Wilcoxon test of ``oracle-0.3 - stochastic
   coverage`` above 0, p < :data:`ALPHA`;
3. **the sham does not**: the restarts are cut into replications of :data:`BLOCK` pairs (in
   restart order within each seed), each tested one-sided as the verdict tests a lead
   (sham above stochastic coverage); the share of replications with p < :data:`ALPHA` has a
   Clopper-Pearson 95 % interval whose lower end is at most :data:`ALPHA` (a rate not above
   the nominal one). Fewer than :data:`MIN_REPLICATIONS` replications decide nothing.

"Above" is "below" for a measure where lower is better (a time). Topic perplexity is placed
on the oracles' scale: its mean lead over stochastic coverage, and the P at which the
oracles' mean slope would give that lead (NaN when their slope is not positive).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from curiosity_cli.evaluate.measures import MEASURES, Measure
from curiosity_cli.evaluate.statistics import ALPHA, PAIR_KEYS, mean_interval
from curiosity_cli.explore.weights import WEIGHT_FUNCTIONS, Oracle

if TYPE_CHECKING:
    import pandas as pd

#: The walker every validation walker is compared with: the oracles' base, the sham's unsteered twin.
BASE = Oracle.base
#: The oracles by their P.
ORACLES = {name: walker.share for name, walker in WEIGHT_FUNCTIONS.items() if isinstance(walker, Oracle)}
SHAM = "sham"
OURS = "topic-perplexity"
#: Pairs a sham replication holds: few enough for many replications, enough for a Wilcoxon p below 0.05
#: (5 pairs all of one sign give one-sided p = 1/32).
BLOCK = 5
#: The fewest sham replications whose rate is read (issue 58).
MIN_REPLICATIONS = 40

#: ``validation.csv``'s columns.
COLUMNS = [
    "dataset", "measure", "against", "path_length", "n",
    *[f"lead_{p:g}{end}" for p in ORACLES.values() for end in ("", "_low", "_high")],
    "slope", "slope_p", "top_p", "sham_lead", "sham_replications", "sham_rate", "sham_rate_low", "sham_rate_high",
    "ours_lead", "ours_low", "ours_high", "ours_p_equivalent", "graded", "sham_null", "validated",
]


#: What tells one run of a pooled table from another.
RUN_KEYS = ["dataset", "weight_function", "replicate", "restart", "path_length"]


def pooled_runs(folders) -> pd.DataFrame:
    """The ``mi.csv`` rows of evaluated experiment folders, each run once.

    Experiments of one seed share their runs of a walker on a map (the same start cells and
    streams): ``validation`` and ``validation-sham`` both run stochastic coverage's restarts
    0-39. A run found in two folders is kept once, and only when both give it the same values.

    Parameters
    ----------
    folders : sequence of Path
        Evaluated experiment folders (``curiosity evaluate``).

    Raises
    ------
    StaleTablesError
        A folder whose tables are not one current set.
    EvaluationError
        A run two folders give different values, naming both and the run.
    """
    from curiosity_cli.evaluate.tables import read_table
    from curiosity_cli.experiment.experiment import Experiment
    from curiosity_cli.files import display_path

    parts = {}
    for folder in folders:
        experiment = Experiment.open(folder)
        experiment.check_tables()
        parts[display_path(folder)] = read_table(experiment.folder.table("mi"))
    return merge_runs(parts)


def pooled_readings(folders) -> dict:
    """:func:`pooled_runs` of evaluated experiment folders, apart for each labelling reading their configs name.

    Returns
    -------
    dict of str to pandas.DataFrame
        By reading (:attr:`~curiosity_cli.label.readings.Reading.title`, in the order first met), the runs of
        the folders labelled under it, each run once.
    """
    from curiosity_cli.experiment.experiment import Experiment
    from curiosity_cli.label.readings import Reading

    groups = {}
    for folder in folders:
        groups.setdefault(Reading.of(Experiment.open(folder).config.label).title, []).append(folder)
    return {title: pooled_runs(group) for title, group in groups.items()}


def readings_table(groups: dict, path_length: int, measures: tuple[Measure, ...] = MEASURES) -> pd.DataFrame:
    """:func:`validation_table` under each labelling reading: ``groups`` maps a reading's title to its runs (as
    :func:`pooled_readings` gives them); the rows of each, a ``reading`` column first. A measure that reads no
    labels (the time to a first find, the classes found, the held-out words) has the same row under every reading."""
    import pandas as pd

    tables = [validation_table(mi, path_length, measures).assign(reading=title) for title, mi in groups.items()]
    return pd.concat(tables, ignore_index=True)[["reading", *COLUMNS]]


def merge_runs(parts: dict) -> pd.DataFrame:
    """:func:`pooled_runs` of tables already read: ``parts`` maps where each came from to its rows.

    Raises
    ------
    EvaluationError
        A run two tables give different values, naming both and the run.
    """
    import pandas as pd

    from curiosity_cli.evaluate.tables import EvaluationError

    rows = pd.concat([table.assign(_folder=name) for name, table in parts.items()], ignore_index=True)
    values = [c for c in rows.columns if c not in (*RUN_KEYS, "_folder") and pd.api.types.is_numeric_dtype(rows[c])]
    for _, same in rows[rows.duplicated(RUN_KEYS, keep=False)].groupby(RUN_KEYS, sort=False):
        first = same[values].iloc[0].to_numpy(float)
        for _, other in same.iloc[1:].iterrows():
            if not np.allclose(other[values].to_numpy(float), first, rtol=0, atol=0, equal_nan=True):
                run = "/".join(str(same.iloc[0][key]) for key in RUN_KEYS[:4])
                raise EvaluationError(
                    f"{same.iloc[0]['_folder']} and {other['_folder']}: run {run} has other values in each; "
                    "expected the same run, made the same way"
                )
    return rows.drop_duplicates(RUN_KEYS).drop(columns="_folder").reset_index(drop=True)


def validation_table(mi: pd.DataFrame, path_length: int, measures: tuple[Measure, ...] = MEASURES) -> pd.DataFrame:
    """The validation of each measure on each map (module docstring): a row per dataset, measure and labelling.

    Parameters
    ----------
    mi : pandas.DataFrame
        ``mi.csv`` rows of one or more experiments (seeds told apart by ``replicate``) that
        ran stochastic coverage and the oracles, and the sham and topic perplexity where
        they are to be judged.
    path_length : int
        The checkpoint read.
    measures : tuple of Measure
        Those whose columns ``mi`` has are validated.

    Returns
    -------
    pandas.DataFrame
        :data:`COLUMNS`: per oracle its mean lead over stochastic coverage (``lead_P``, with its 95 %
        Student-t interval ``lead_P_low``, ``lead_P_high``),
        the mean per-restart ``slope`` of the lead over P and its one-sided ``slope_p``,
        ``top_p`` of the largest oracle, the sham's mean lead, its replications, their rate
        of p < :data:`ALPHA` with its interval, topic perplexity's lead with its 95 % CI and
        its P on the oracles' scale, and the three criteria with ``validated`` (all three;
        False, not NaN, when a part is missing).
    """
    import pandas as pd

    rows = []
    at = mi[mi["path_length"] == path_length]
    for measure in measures:
        for against, column in measure.columns.items():
            if column not in at:
                continue
            wide = at.dropna(subset=[column]).pivot_table(
                index=["dataset", *PAIR_KEYS], columns="weight_function", values=column,
            )
            for dataset, block in wide.groupby(level="dataset", sort=False):
                if BASE in block:
                    rows.append(_validate(block.droplevel("dataset"), measure, dataset, against, path_length))
    return pd.DataFrame(rows, columns=COLUMNS)


def _validate(block: pd.DataFrame, measure: Measure, dataset: str, against: str, length: int) -> dict:
    """One row of :func:`validation_table`: ``block`` has a row per (replicate, restart) and a column per walker."""
    sign = -1.0 if measure.lower_is_better else 1.0
    leads = {name: sign * (block[name] - block[BASE]) for name in (*ORACLES, SHAM, OURS) if name in block}
    row = {"dataset": dataset, "measure": measure.name, "against": against, "path_length": length}
    # the restarts every oracle has, a column each: what the paired slope over P needs
    complete = block[list(ORACLES)].sub(block[BASE], axis=0).mul(sign).dropna() if set(ORACLES) <= set(leads) else None
    row["n"] = 0 if complete is None else len(complete)
    for name, share in ORACLES.items():
        values = leads[name].dropna().to_numpy() if name in leads else np.zeros(0)
        row[f"lead_{share:g}"], row[f"lead_{share:g}_low"], row[f"lead_{share:g}_high"] = mean_interval(values)
    slope = slope_p = np.nan
    if complete is not None and len(complete) >= 2:
        shares = np.array(list(ORACLES.values()))
        centred = shares - shares.mean()
        # the leads centred too, elementwise: equal leads give a slope of exactly 0 (a tie Wilcoxon drops), and
        # no matrix product whose rounding follows the array's layout
        leads_centred = complete.to_numpy() - complete.to_numpy().mean(axis=1, keepdims=True)
        slopes = (leads_centred * centred).sum(axis=1) / (centred * centred).sum()
        slope, slope_p = float(slopes.mean()), _greater_p(slopes)
    top = max(ORACLES, key=ORACLES.get)
    top_p = _greater_p(leads[top].dropna().to_numpy()) if top in leads and leads[top].notna().any() else np.nan
    row.update(slope=slope, slope_p=slope_p, top_p=top_p)
    row.update(_sham(leads.get(SHAM)))
    ours = leads.get(OURS)
    mean, low, high = mean_interval(ours.dropna().to_numpy()) if ours is not None else (np.nan,) * 3
    row.update(ours_lead=mean, ours_low=low, ours_high=high, ours_p_equivalent=mean / slope if slope > 0 else np.nan)
    row["graded"] = bool(slope_p < ALPHA and top_p < ALPHA)
    row["sham_null"] = bool(row["sham_replications"] >= MIN_REPLICATIONS and row["sham_rate_low"] <= ALPHA)
    row["validated"] = row["graded"] and row["sham_null"]
    return row


def _sham(leads) -> dict:
    """The sham's mean lead and its rate of one-sided p < ALPHA over replications of :data:`BLOCK` pairs."""
    from scipy import stats

    empty = {"sham_lead": np.nan, "sham_replications": 0, "sham_rate": np.nan, "sham_rate_low": np.nan,
             "sham_rate_high": np.nan}
    if leads is None:
        return empty
    leads = leads.dropna()
    p_values = []
    for _, seed in leads.groupby(level="replicate", sort=True):
        values = seed.sort_index(level="restart").to_numpy()
        for start in range(0, len(values) - BLOCK + 1, BLOCK):
            p_values.append(_greater_p(values[start : start + BLOCK]))
    if not p_values:
        return {**empty, "sham_lead": float(leads.mean())}
    hits = int(np.count_nonzero(np.array(p_values) < ALPHA))
    interval = stats.binomtest(hits, len(p_values)).proportion_ci(confidence_level=0.95, method="exact")
    return {
        "sham_lead": float(leads.mean()), "sham_replications": len(p_values), "sham_rate": hits / len(p_values),
        "sham_rate_low": float(interval.low), "sham_rate_high": float(interval.high),
    }


def _greater_p(values: np.ndarray) -> float:
    """One-sided Wilcoxon signed-rank p that ``values`` lie above 0 (scipy's; 1.0 when every value is 0)."""
    from scipy import stats

    values = np.asarray(values, np.float64)
    if not np.any(values != 0):
        return 1.0
    return float(stats.wilcoxon(values, alternative="greater").pvalue)
