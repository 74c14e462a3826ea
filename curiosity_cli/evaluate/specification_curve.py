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
  (``beats_all``, an intersection-union test, its p ``p_each``): the decision, read
  after correcting for every point of the curve (``p_each_holm``, which the curve's
  verdict reads; ``p_each_bh``; ``p_each_wy``, Westfall-Young from the joint null);
- the curve as a whole against its joint null (:mod:`~curiosity_cli.evaluate.joint_null`,
  :func:`curve_table`'s ``joint``): counts of points and the median ratio against their
  distribution when every restart's walkers are permuted once for all specifications;
- the ratio to the next best of them, a summary only (the next best is chosen after
  seeing the data, which biases it toward "no lead"): its bootstrap interval with the
  next best chosen in every resample, and its null reference with the walkers
  exchangeable (``null_median``, ``null_low``, ``null_high``, ``null_p``;
  :mod:`~curiosity_cli.evaluate.comparisons`) and with the random walk left out of them
  (``null_no_rw_*``, the one the figure and the verdict read), so a reader sees where
  "no difference" lies; the paired Wilcoxon p against that walker, the pairs, the smallest lead
  detectable at 80 % power and whether the paper's ratio for the map lies inside the
  interval (``paper_inside``);
- the distinct cells of topic perplexity and stochastic coverage in 80 steps, topic
  perplexity's steering (:mod:`~curiosity_cli.evaluate.steering`), and whether its
  surprise points at what is new (:mod:`~curiosity_cli.evaluate.mechanism`): M1 the AUC
  of its score for candidates holding a class new to the path, M2 the share of moves with
  such a candidate, M3 the chance it put on them beyond stochastic coverage, M5 the share
  of candidates with infinite perplexity (``auc``, ``opportunity``, ``gain``,
  ``infinite_share``; over the pooled runs as :func:`~curiosity_cli.evaluate.mechanism.summarise_mechanism`
  has them: the AUC every run's wins over every run's pairs, the rest means). Every number is the pooled headline's
(:func:`~curiosity_cli.evaluate.headline.headline`, :func:`~curiosity_cli.evaluate.headline.with_uncertainty`);
this module only puts them in rows, sorted by ratio, and counts.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from curiosity_cli.config import PAPER_WALKERS
from curiosity_cli.evaluate.statistics import ALPHA, CONFIDENCE
from curiosity_cli.evaluate.joint_null import CurvePoint, joint_null
from curiosity_cli.evaluate.headline import (
    ADJUSTED_COLUMNS, HEADLINE_LENGTH, HEADLINE_WEIGHT, NOT_EXCHANGEABLE, with_adjusted,
)

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


#: The two nulls of a curve's joint test (:mod:`~curiosity_cli.evaluate.joint_null`): which of :data:`VERSUS` are
#: permuted with topic perplexity, and the columns of each point's Westfall-Young min-P adjusted intersection-union
#: p and null p under it. The random walk left out is the one the curve's verdict reads.
JOINT_NULLS = {
    "without random walk": (tuple(w != NOT_EXCHANGEABLE for w in VERSUS), "p_each_wy", "null_no_rw_p_wy"),
    "all walkers": (tuple(True for _ in VERSUS), "p_each_wy_all", "null_p_wy"),
}
#: The p-values of a curve corrected over all its points: Holm and Benjamini-Hochberg
#: (:data:`~curiosity_cli.evaluate.headline.ADJUSTED_COLUMNS`), and Westfall-Young's under each joint null.
WY_COLUMNS = tuple(column for _, *columns in JOINT_NULLS.values() for column in columns)

#: A curve row's columns after those naming its specification (:func:`curve_table`).
CURVE_COLUMNS = (
    "dataset", "against", "seeds", "beats_all", "not_beaten", "p_each", *ADJUSTED_COLUMNS, *WY_COLUMNS,
    *(name for w in VERSUS for name in _versus_names(w)),
    "ratio", "ratio_ci_low", "ratio_ci_high", "null_median", "null_low", "null_high", "null_p",
    "null_no_rw_median", "null_no_rw_low", "null_no_rw_high", "null_no_rw_p", "p_value", "pairs",
    "next_best", "detectable_ratio", "pairs_for_lead", "paper_map", "paper_ratio", "paper_inside",
    *(f"distinct_{w}" for w in DISTINCT_WALKERS), f"steering_{STEERING_WALKER}", *MECHANISM_MEASURES,
)


def curve_table(specifications: Sequence[tuple[Mapping[str, str], Pooled]], against: str = "human"):
    """A row per specification and map, sorted by ratio (module docstring), and the curve's joint tests.

    The adjusted p-values (:data:`~curiosity_cli.evaluate.headline.ADJUSTED_COLUMNS`,
    :data:`WY_COLUMNS`) are over every point of the curve: its family is the study, not
    one specification's maps.

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
    table : pandas.DataFrame
        The naming columns, then :data:`CURVE_COLUMNS`; rows in increasing ratio (a row
        without one last), ties in the order given.
    joint : pandas.DataFrame
        Per null of :data:`JOINT_NULLS` (``null``) and statistic of
        :data:`~curiosity_cli.evaluate.joint_null.STATISTICS`: observed, the null's median
        and 95 % interval, and p (:class:`~curiosity_cli.evaluate.joint_null.JointNull`);
        empty when no point has every walker of :data:`VERSUS`.
    """
    import pandas as pd

    rows, names, points = [], [], []
    for labels, pooled in specifications:
        names += [k for k in labels if k not in names]
        seeds = " ".join(map(str, pooled.seeds))
        for r in (pooled.headline if against == "human" else pooled.batch_headline).to_dict("records"):
            dataset = r["dataset"]
            versus = pooled.versus(dataset, r["against"])
            points.append(_curve_point(", ".join(labels.values()), pooled, r))
            rows.append({
                **labels, "dataset": dataset, "seeds": seeds, **{k: r[k] for k in CURVE_COLUMNS if k in r},
                **_versus_columns(versus),
                "paper_inside": _inside(r["paper_ratio"], r["ratio_ci_low"], r["ratio_ci_high"]),
                **{f"distinct_{w}": pooled.mean_distinct_cells(dataset, w) for w in DISTINCT_WALKERS},
                f"steering_{STEERING_WALKER}": pooled.mean_steering(dataset, STEERING_WALKER),
                **{m: pooled.mean_mechanism(dataset, STEERING_WALKER, m) for m in MECHANISM_MEASURES},
            })
    table = pd.DataFrame(rows, columns=[*names, *CURVE_COLUMNS])
    table = with_adjusted(table)
    joint = []
    tested = [i for i, point in enumerate(points) if point is not None]
    if tested:
        for null, (exchangeable, each, ratio) in JOINT_NULLS.items():
            result = joint_null([points[i] for i in tested], exchangeable)
            table.loc[tested, each], table.loc[tested, ratio] = result.p_each_wy, result.null_p_wy
            joint.append(result.statistics.assign(null=null, points=len(tested), permutations=result.permutations))
    joint = pd.concat(joint, ignore_index=True) if joint else pd.DataFrame(columns=JOINT_COLUMNS)
    table = table.sort_values("ratio", kind="stable", na_position="last", ignore_index=True)
    return table, joint[list(JOINT_COLUMNS)]


#: A curve's joint tests' columns (:func:`curve_table`).
JOINT_COLUMNS = ("null", "statistic", "observed", "null_median", "null_low", "null_high", "p", "points", "permutations")


def _curve_point(specification: str, pooled: Pooled, row: Mapping) -> CurvePoint | None:
    """A curve row's runs for the joint null; None without every walker of :data:`VERSUS` (or without runs)."""
    block = pooled.blocks.get((row["against"], row["dataset"], row["path_length"]))
    walkers = [HEADLINE_WEIGHT, *VERSUS]
    if block is None or not set(walkers) <= set(block.columns):
        return None
    block = block[walkers].dropna()
    if block.empty:
        return None
    return CurvePoint(specification, row["dataset"], list(block.index), block.to_numpy(np.float64))


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


def lead_word(row: Mapping) -> str:
    """Whether a curve row leads each walker: ``leads`` after Holm over the curve, ``uncorrected only``, or ``no``."""
    if row["p_each_holm"] < ALPHA:
        return "leads"
    return "uncorrected only" if row["beats_all"] else "no"


def _points(block) -> str:
    """The rows of a curve table as "specification on map" phrases."""
    names = list(block.columns[:block.columns.get_loc("dataset")])  # the naming columns come first
    return ", ".join(f"`{', '.join(str(r[n]) for n in names)}` on {r['dataset']}" for r in block.to_dict("records"))


def curve_sentence(table) -> str:
    """How many points lead every walker, corrected for the curve's size and not; where the paper's ratio lies; where
    the points lie against their null reference.

    Parameters
    ----------
    table : pandas.DataFrame
        From :func:`curve_table`.
    """
    if table.empty:
        return "No specification has a headline at 80 steps to count."
    total = len(table)
    holm = table[table["p_each_holm"] < ALPHA]
    wy = (
        f"in {int((table['p_each_wy'] < ALPHA).sum())} with Westfall-Young's correction, which uses how the points "
        "depend on each other (the random walk left out of the permuted walkers)"
        if table["p_each_wy"].notna().any() else "no Westfall-Young correction (no point has every walker's runs)"
    )
    bh = int((table["p_each_bh"] < ALPHA).sum())
    uncorrected = table["beats_all"].astype(bool)
    per_map = "; ".join(
        f"{int(block['beats_all'].astype(bool).sum())} of {len(block)} on {dataset}"
        for dataset, block in table.groupby("dataset", sort=False)
    )
    sentence = (
        f"Topic perplexity leads every other walker (a higher mean MI at {HEADLINE_LENGTH} steps and a paired "
        f"Wilcoxon p below {ALPHA:g} against each) in **{len(holm)} of {total}** points after correcting for the "
        f"{total} (Holm{': ' + _points(holm) if len(holm) else ''}); {wy}; and in {bh} "
        f"at a false discovery rate of {ALPHA:g} (Benjamini-Hochberg). Uncorrected, which is exploratory, in "
        f"{int(uncorrected.sum())} of {total} ({per_map})"
    )
    known = table["paper_inside"].notna()
    if known.any():
        inside = []
        for dataset, block in table[known].groupby("dataset", sort=False):
            inside.append(
                f"{int((block['paper_inside'] == True).sum())} of {len(block)} on {dataset} "  # noqa: E712
                f"({block['paper_map'].iloc[0]}: {block['paper_ratio'].iloc[0]:.2f})"
            )
        level = f"{100 * CONFIDENCE:.0f} %"
        sentence += (
            f". The paper's ratio lies inside the {level} interval in {'; '.join(inside)}: "
            f"{int((table.loc[known, 'paper_inside'] == True).sum())} of {int(known.sum())} in all"  # noqa: E712
        )
    else:
        sentence += "; no map stands in for one of the paper's, so no paper ratio is compared"
    referenced = table["null_no_rw_p"].notna()
    if referenced.any():
        block = table[referenced]
        sentence += (
            f". Against its null reference (topic perplexity exchangeable with the walkers that could equal it), the "
            f"ratio to the next best has p < {ALPHA:g} in {int((block['null_no_rw_p'] < ALPHA).sum())} of {len(block)} "
            f"points uncorrected and in {int((block['null_no_rw_p_holm'] < ALPHA).sum())} after Holm "
            f"({int((block['null_p'] < ALPHA).sum())} uncorrected with every walker permuted); the points' median "
            f"ratio is {block['ratio'].median():.2f}, {100 * (block['ratio'] < 1).mean():.0f} % of them below 1, where "
            f"no difference gives a median of {block['null_no_rw_median'].median():.2f} (the median of the points' "
            f"null medians) and {100 * (block['ratio'] < block['null_no_rw_median']).mean():.0f} % of the points lie "
            "below their null median. Counts of points are not tests of the curve: the points share runs; the joint "
            "test below is"
        )
    return sentence + "."


#: How the report names each joint statistic (:data:`~curiosity_cli.evaluate.joint_null.STATISTICS`).
_STATISTIC_WORDS = {
    "leads": "points that lead each walker (uncorrected p < 0.05)",
    "null_p_below": "points whose next-best ratio has null p < 0.05",
    "median_ratio": "median next-best ratio",
    "most_maps_led": "most maps of one specification that lead each walker",
    "most_maps_null_p_below": "most maps of one specification with null p < 0.05",
}


def joint_lines(joint) -> list[str]:
    """The curve's joint tests (:func:`curve_table`'s ``joint``) as a Markdown table with what it means."""
    from curiosity_cli.evaluate.report import number, p_text

    if joint.empty:
        return ["No point has every walker's runs: no joint test.", ""]
    first = joint.iloc[0]
    lines = [
        f"**The joint test** ({int(first['points'])} points, {int(first['permutations']):,} permutations; in each, "
        "every restart's walkers shuffled once and the same shuffle applied to every specification): each statistic "
        "on the data, where no difference puts it (median and 95 %), and the share of permutations at least as "
        "large (p). The verdict reads the null without the random walk.",
        "",
        "| null | statistic | observed | no difference: median [95 %] | p |",
        "|---|---|---|---|---|",
    ]
    for r in joint.to_dict("records"):
        digits = 3 if r["statistic"] == "median_ratio" else 0
        lines.append(
            f"| {r['null']} | {_STATISTIC_WORDS.get(r['statistic'], r['statistic'])} | {number(r['observed'], digits)} "
            f"| {number(r['null_median'], digits)} [{number(r['null_low'], digits)}, {number(r['null_high'], digits)}] "
            f"| {p_text(r['p'])} |"
        )
    return lines + [""]
