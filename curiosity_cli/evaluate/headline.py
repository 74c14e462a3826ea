"""The headline statistics of an experiment: topic perplexity against each other walker
(``effects.csv``) and over the next best (``headline.csv``), how sure the ratio is, and its
p-values adjusted for the family of maps.

The evaluation stage (:mod:`~curiosity_cli.evaluate.stage`) writes them; pooled replicates
(:mod:`~curiosity_cli.evaluate.replicates`) and a study's curve
(:mod:`~curiosity_cli.evaluate.specification_curve`) compute them again over more pairs.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.evaluate.measures import MI, Measure
from curiosity_cli.evaluate.multiplicity import adjusted_columns, intersection_union_p, with_adjusted_p
from curiosity_cli.evaluate.statistics import (
    ALPHA, paired_blocks, paired_difference, wilcoxon_p, wilcoxon_pair_p,
)
from curiosity_cli.explore.weights import CEILINGS, in_verdict

#: The path length the paper reads its headline at (about a map's width); a map without
#: that checkpoint is read at its longest one below it (:func:`headline_length`).
HEADLINE_LENGTH = 80
HEADLINE_WEIGHT = "topic-perplexity"


def headline_length(lengths) -> int | None:
    """The path length a map's headline is read at: :data:`HEADLINE_LENGTH`, or the longest of ``lengths``
    below it; None when every length is longer."""
    below = [int(n) for n in lengths if n <= HEADLINE_LENGTH]
    return max(below) if below else None


def versus_pairs(block):
    """Topic perplexity against each other walker of ``block`` (a row per restart, a column per walker): per
    walker, ``(other, pairs, ours, theirs)``: the restarts both have, and the two walkers' values on them;
    nothing when topic perplexity is not a column."""
    if HEADLINE_WEIGHT not in block.columns:
        return
    for other in block.columns.drop(HEADLINE_WEIGHT):
        pair = block[[HEADLINE_WEIGHT, other]].dropna()
        if len(pair):
            yield other, pair.index, pair[HEADLINE_WEIGHT].to_numpy(), pair[other].to_numpy()


def paired_effects(mi, tests=None, measure: Measure = MI):
    """Topic perplexity against each other walker on a measure (MI unless told), paired by restart (ceilings and
    validation walkers left out).

    Per (dataset, path length, against, other walker): ``n`` pairs, the two means over
    those pairs, the mean paired difference with its 95 % Student-t CI
    (:func:`~curiosity_cli.evaluate.statistics.paired_difference`), the ratio of the
    means with its 95 % studentized paired-bootstrap interval
    (:func:`~curiosity_cli.evaluate.comparisons.ratio_interval`) and the Wilcoxon p of
    the same pairs, from ``tests`` (:func:`~curiosity_cli.evaluate.statistics.paired_tests` of
    the same measure, as ``tests.csv`` reports it) or, without, from the pairs themselves
    (:func:`~curiosity_cli.evaluate.statistics.wilcoxon_pair_p`): each walker a
    pre-specified comparison (:mod:`~curiosity_cli.evaluate.comparisons`).
    """
    import pandas as pd

    from curiosity_cli.evaluate.comparisons import ratio_interval

    rows = []
    for against, dataset, length, block in paired_blocks(mi, measure):
        for other, pair, ours, theirs in versus_pairs(block):
            mean, low, high = paired_difference(ours, theirs)
            ratio_low, ratio_high = ratio_interval(ours, theirs)
            rows.append({
                "dataset": dataset, "path_length": length, "against": against, "other": other, "n": len(pair),
                "topic_perplexity": float(ours.mean()), "other_mean": float(theirs.mean()),
                "mean_difference": mean, "ci_low": low, "ci_high": high,
                "ratio": float(ours.mean() / theirs.mean()) if theirs.mean() > 0 else np.nan,
                "ratio_ci_low": ratio_low, "ratio_ci_high": ratio_high,
                "p_value": wilcoxon_pair_p(ours - theirs) if tests is None
                else wilcoxon_p(tests, dataset, length, against, HEADLINE_WEIGHT, other)[0],
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
ADJUSTED_COLUMNS = adjusted_columns(ADJUSTED_P)
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
    no paper ratio). Ceilings and validation walkers are never the next best.
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
        walkers = means[[in_verdict(name) for name in means.index]]
        if HEADLINE_WEIGHT not in walkers or len(walkers) < 2:
            continue
        ours = walkers[HEADLINE_WEIGHT]
        others = walkers.drop(HEADLINE_WEIGHT).sort_values(ascending=False, kind="stable")
        next_best = others.index[0]
        p_values = {o: wilcoxon_p(tests, dataset, length, read, HEADLINE_WEIGHT, o) for o in others.index}
        lead = lead_each(MI, others.index, ours, others.to_numpy(), [p_values[o][0] for o in others.index])
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
            **lead,
            "best_ceiling": best_ceiling, "ceiling_mi": ceiling_mi,
            "ceiling_share": ours / ceiling_mi if best_ceiling and ceiling_mi > 0 else np.nan,
            "paper_map": paper.name if paper else "", "paper_ratio": paper.headline_ratio if paper else np.nan,
        })
    return pd.DataFrame(rows, columns=HEADLINE_COLUMNS)


def lead_each(measure: Measure, others, ours, theirs, p) -> dict:
    """``beats_all``, ``not_beaten`` and ``p_each`` of topic perplexity against ``others`` on ``measure``: it leads
    where its mean is better than each walker's (above, or below where lower is better) with a paired Wilcoxon p
    below :data:`~curiosity_cli.evaluate.statistics.ALPHA` against each, and ``p_each`` is the intersection-union p
    of that (:func:`~curiosity_cli.evaluate.multiplicity.intersection_union_p`).

    Parameters
    ----------
    measure : Measure
        Whose direction says which mean is ahead.
    others : sequence of str
        The walkers, and per walker ``ours`` (topic perplexity's mean: one for all, or over each walker's pairs),
        ``theirs`` (the walker's) and ``p`` (the paired Wilcoxon p).
    """
    ours, theirs, p = (np.asarray(x, np.float64) for x in (ours, theirs, p))
    not_beaten = [o for o, ahead, q in zip(others, measure.ahead(ours, theirs), p) if not (ahead and q < ALPHA)]
    sign = -1.0 if measure.lower_is_better else 1.0  # the intersection-union p reads "above"
    return {"beats_all": not not_beaten, "not_beaten": ";".join(not_beaten),
            "p_each": intersection_union_p(sign * ours, sign * theirs, p)}


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
    return with_adjusted_p(top, "against", ADJUSTED_P)
