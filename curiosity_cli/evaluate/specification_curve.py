"""The specification curve of a study: the headline under every specification, side by side.

Simonsohn, Simmons & Nelson's specification-curve analysis (Nature Human Behaviour 4,
2020) reports a finding under every defensible specification at once instead of under
one chosen: here a specification is a set of config overrides (one reading of the
paper's open choices), run on every map with several seeds, and the finding is topic
perplexity's lead at 80 steps. Per specification and map, from the seeds pooled as
replicates (:func:`~curiosity_cli.evaluate.replicates.pool`, over the paper's walkers),
against human labels (or, as a second curve, against Z_b):

- topic perplexity against **each** of the paper's other walkers, pre-specified: the
  ratio of mean MI with its 95 % studentized bootstrap interval and the paired Wilcoxon
  p (``ratio_<walker>``, ``ratio_<walker>_low``, ``ratio_<walker>_high``,
  ``p_<walker>``), and whether topic perplexity leads every one of them at p < 0.05
  (``beats_all``, an intersection-union test): the decision;
- the ratio to the next best of them, a summary only (the next best is chosen after
  seeing the data, which biases it toward "no lead"): its bootstrap interval with the
  next best chosen in every resample, and its null reference with the walkers
  exchangeable (``null_median``, ``null_low``, ``null_high``, ``null_p``;
  :mod:`~curiosity_cli.evaluate.comparisons`), so a reader sees where "no difference"
  lies; the paired Wilcoxon p against that walker, the pairs, the smallest lead
  detectable at 80 % power and whether the paper's ratio for the map lies inside the
  interval (``paper_inside``);
- the distinct cells of topic perplexity and stochastic coverage in 80 steps, topic
  perplexity's steering (:mod:`~curiosity_cli.evaluate.steering`), and whether its
  surprise points at what is new (:mod:`~curiosity_cli.evaluate.mechanism`): M1 the AUC
  of its score for candidates holding a class new to the path, M2 the share of moves with
  such a candidate, M3 the chance it put on them beyond stochastic coverage, M5 the share
  of candidates with infinite perplexity (``auc``, ``opportunity``, ``gain``,
  ``infinite_share``; means over the pooled runs). Every number is the pooled headline's
(:func:`~curiosity_cli.evaluate.tables.headline`, :func:`~curiosity_cli.evaluate.tables.with_power`);
this module only puts them in rows, sorted by ratio, and counts.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from curiosity_cli.config import PAPER_WALKERS
from curiosity_cli.evaluate.statistics import ALPHA, CONFIDENCE
from curiosity_cli.evaluate.tables import HEADLINE_LENGTH, HEADLINE_WEIGHT

if TYPE_CHECKING:
    import pandas as pd

    from curiosity_cli.evaluate.replicates import Pooled

#: The walkers whose distinct cells a curve's row gives, and the one whose steering it gives.
DISTINCT_WALKERS = (HEADLINE_WEIGHT, "stochastic-coverage")
STEERING_WALKER = HEADLINE_WEIGHT
#: The mechanism's measures a curve's row gives, topic perplexity's (:mod:`~curiosity_cli.evaluate.mechanism`).
MECHANISM_MEASURES = ("auc", "opportunity", "gain", "infinite_share")
#: The walkers topic perplexity is compared with one by one, named before any run.
VERSUS = tuple(w for w in PAPER_WALKERS if w != HEADLINE_WEIGHT)


def _versus_names(walker: str) -> tuple[str, str, str, str]:
    """A curve row's columns of topic perplexity against ``walker``: ratio, its interval, Wilcoxon p."""
    return f"ratio_{walker}", f"ratio_{walker}_low", f"ratio_{walker}_high", f"p_{walker}"


#: A curve row's columns after those naming its specification (:func:`curve_table`).
CURVE_COLUMNS = (
    "dataset", "against", "seeds", "beats_all", "not_beaten",
    *(name for w in VERSUS for name in _versus_names(w)),
    "ratio", "ratio_ci_low", "ratio_ci_high", "null_median", "null_low", "null_high", "null_p", "p_value", "pairs",
    "next_best", "detectable_ratio", "pairs_for_lead", "paper_map", "paper_ratio", "paper_inside",
    *(f"distinct_{w}" for w in DISTINCT_WALKERS), f"steering_{STEERING_WALKER}", *MECHANISM_MEASURES,
)


def curve_table(specifications: Sequence[tuple[Mapping[str, str], Pooled]], against: str = "human"):
    """A row per specification and map, sorted by ratio (module docstring).

    Parameters
    ----------
    specifications : sequence of (mapping of str to str, Pooled)
        Per specification: the columns that name it (``specification`` and any other
        swept key but the seed, to their values), and its seeds pooled.
    against : {'human', 'batch'}
        The labels MI is measured against: human labels (a map without them is read
        against Z_b, as its headline is) or Z_b on every map.

    Returns
    -------
    pandas.DataFrame
        The naming columns, then :data:`CURVE_COLUMNS`; rows in increasing ratio (a row
        without one last), ties in the order given.
    """
    import pandas as pd

    rows, names = [], []
    for labels, pooled in specifications:
        names += [k for k in labels if k not in names]
        seeds = " ".join(map(str, pooled.seeds))
        for r in (pooled.headline if against == "human" else pooled.batch_headline).to_dict("records"):
            dataset = r["dataset"]
            versus = pooled.versus(dataset, r["against"])
            rows.append({
                **labels, "dataset": dataset, "seeds": seeds, **{k: r[k] for k in CURVE_COLUMNS if k in r},
                **_versus_columns(versus),
                "paper_inside": _inside(r["paper_ratio"], r["ratio_ci_low"], r["ratio_ci_high"]),
                **{f"distinct_{w}": pooled.mean_distinct_cells(dataset, w) for w in DISTINCT_WALKERS},
                f"steering_{STEERING_WALKER}": pooled.mean_steering(dataset, STEERING_WALKER),
                **{m: pooled.mean_mechanism(dataset, STEERING_WALKER, m) for m in MECHANISM_MEASURES},
            })
    table = pd.DataFrame(rows, columns=[*names, *CURVE_COLUMNS])
    return table.sort_values("ratio", kind="stable", na_position="last", ignore_index=True)


def _versus_columns(versus) -> dict:
    """Topic perplexity against each walker of :data:`VERSUS` (NaN for one that did not run)."""
    columns = {}
    for walker in VERSUS:
        row = versus.loc[walker] if walker in versus.index else None
        for column, source in zip(_versus_names(walker), ("ratio", "ratio_ci_low", "ratio_ci_high", "p_value")):
            columns[column] = float(row[source]) if row is not None else np.nan
    return columns


def _inside(paper: float, low: float, high: float):
    """Whether the paper's ratio is inside the interval; None when either is unknown."""
    if not (np.isfinite(paper) and np.isfinite(low) and np.isfinite(high)):
        return None
    return bool(low <= paper <= high)


def curve_sentence(table) -> str:
    """In how many specifications topic perplexity leads every walker at p < 0.05, and in how many
    the paper's ratio lies inside the interval: per map, and over every (specification, map) row.

    Parameters
    ----------
    table : pandas.DataFrame
        From :func:`curve_table`.
    """
    if table.empty:
        return "No specification has a headline at 80 steps to count."
    leads, inside = [], []
    for dataset, block in table.groupby("dataset", sort=False):
        n = len(block)
        leads.append(f"{int(block['beats_all'].astype(bool).sum())} of {n} on {dataset}")
        known = block["paper_inside"].notna()
        if known.any():
            paper = block.loc[known, "paper_ratio"].iloc[0]
            inside.append(
                f"{int((block.loc[known, 'paper_inside'] == True).sum())} of {int(known.sum())} on {dataset} "  # noqa: E712
                f"({block.loc[known, 'paper_map'].iloc[0]}: {paper:.2f})"
            )
    known = table["paper_inside"].notna()
    total = len(table)
    lead_all = int(table["beats_all"].astype(bool).sum())
    referenced = table["null_p"].notna()
    inside_all = int((table.loc[known, "paper_inside"] == True).sum())  # noqa: E712
    level = f"{100 * CONFIDENCE:.0f} %"
    sentence = (
        f"Topic perplexity leads every other walker at p < {ALPHA:g} (a higher mean MI at {HEADLINE_LENGTH} steps "
        f"and a paired Wilcoxon p below {ALPHA:g} against each) in {'; '.join(leads)}: {lead_all} of {total} "
        f"specification-map pairs in all"
    )
    if known.any():
        sentence += (
            f"; the paper's ratio lies inside the {level} interval in {'; '.join(inside)}: {inside_all} of "
            f"{int(known.sum())} in all"
        )
    else:
        sentence += "; no map stands in for one of the paper's, so no paper ratio is compared"
    if referenced.any():
        block = table[referenced]
        sentence += (
            f". Against its null reference (the walkers' labels permuted within each restart), the ratio to the next "
            f"best has p < {ALPHA:g} in {int((block['null_p'] < ALPHA).sum())} of {len(block)} points; the points' median "
            f"ratio is {block['ratio'].median():.2f}, {100 * (block['ratio'] < 1).mean():.0f} % of them below 1, where "
            f"no difference at all gives a median of {block['null_median'].median():.2f} (the median of the points' null "
            f"medians) and {100 * (block['ratio'] < block['null_median']).mean():.0f} % of the points lie below their "
            "null median"
        )
    return sentence + "."
