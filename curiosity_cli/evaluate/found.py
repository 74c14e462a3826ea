"""What each walker found: every measure of the table beside MI, summarised and compared as MI is.

MI of the whole map's labelling need not reward a path that finds more (a labeller can
set unfamiliar terrain apart without visiting it), so a comparison of walkers reads the
other measures of :data:`~curiosity_cli.evaluate.measures.MEASURES` too, each with the
same statistics as MI's headline:

- ``found_summary.csv``: per (measure, dataset, weight function, path length, against):
  ``n``, ``mean``, ``std`` and the 95 % Student-t CI of the mean over restarts;
- ``found_effects.csv``: per (measure, dataset, path length, against) and other walker,
  topic perplexity against it, paired by restart
  (:func:`~curiosity_cli.evaluate.headline.paired_effects`: the mean paired difference
  with its CI, the ratio of the means with its bootstrap interval, the paired Wilcoxon p);
- ``found_leads.csv``: per (measure, dataset, path length, against), whether topic
  perplexity leads each other walker (``beats_all``, ``not_beaten``) and the p of that
  lead (``p_each``, the intersection-union p,
  :func:`~curiosity_cli.evaluate.multiplicity.intersection_union_p`), adjusted for the
  maps as the headline's is (``p_each_holm``, ``p_each_bh``, per measure, length and labelling);
- ``found_classes.csv``: per (dataset, path length, human class) and other walker, how soon
  topic perplexity first reached the class against it, paired by restart: each walker's
  restricted mean time to first find (a class not reached by the length counts the length:
  :func:`~curiosity_cli.evaluate.measures.restricted_steps`), the mean paired difference
  with its CI and the paired Wilcoxon p, and the share of restarts that found the class by
  the length (``found`` in ``classes.csv``), each walker's.

``against`` is the labelling a measure is taken against, or ``words`` for one of no labelling (the held-out
log-likelihood, :data:`~curiosity_cli.evaluate.measures.WORDS`). A measure whose columns ``mi.csv`` lacks (a table
recorded before the measure existed) has no rows, and :func:`missing_measures` names it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from curiosity_cli.evaluate import headline
from curiosity_cli.evaluate.headline import HEADLINE_WEIGHT, lead_each, paired_effects, versus_pairs
from curiosity_cli.evaluate.measures import MEASURES, Measure, measure_named
from curiosity_cli.evaluate.multiplicity import adjusted_columns, with_adjusted_p
from curiosity_cli.evaluate.statistics import summarise

if TYPE_CHECKING:
    import pandas as pd

SUMMARY_COLUMNS = ["measure", "dataset", "weight_function", "path_length", "against", "n", "mean", "std", "ci_low", "ci_high"]
EFFECT_COLUMNS = ["measure", *headline.EFFECT_COLUMNS]
LEAD_COLUMNS = [
    "measure", "dataset", "path_length", "against", "walkers", "beats_all", "not_beaten", "p_each",
    *adjusted_columns(["p_each"]),
]


def found_measures(mi) -> list[Measure]:
    """The measures compared beside MI whose columns ``mi`` has."""
    return [m for m in MEASURES if m.found and any(column in mi for column in m.columns.values())]


def missing_measures(mi) -> list[Measure]:
    """The measures compared beside MI whose columns ``mi`` lacks (a table from before they existed)."""
    present = found_measures(mi)
    return [m for m in MEASURES if m.found and m not in present]


def summarise_found(mi):
    """``found_summary.csv`` (module docstring): every walker's and ceiling's mean of each measure with its CI."""
    import pandas as pd

    parts = [summarise(mi, measure).assign(measure=measure.name) for measure in found_measures(mi)]
    if not parts:
        return pd.DataFrame(columns=SUMMARY_COLUMNS)
    return pd.concat(parts, ignore_index=True)[SUMMARY_COLUMNS]


def found_effects(mi):
    """``found_effects.csv`` (module docstring): topic perplexity against each other walker on each measure."""
    import pandas as pd

    parts = [paired_effects(mi, measure=measure).assign(measure=measure.name) for measure in found_measures(mi)]
    parts = [part for part in parts if not part.empty]
    if not parts:
        return pd.DataFrame(columns=EFFECT_COLUMNS)
    return pd.concat(parts, ignore_index=True)[EFFECT_COLUMNS]


def found_leads(effects):
    """``found_leads.csv`` (module docstring), from :func:`found_effects`' rows.

    Topic perplexity leads when its mean over each walker's pairs is better than that walker's
    (above, or below for a measure where lower is better) and the paired Wilcoxon p against each is below
    :data:`~curiosity_cli.evaluate.statistics.ALPHA`; ``walkers`` counts the walkers it
    is compared with.
    """
    import pandas as pd

    rows = []
    for (measure, dataset, length, against), block in effects.groupby(
        ["measure", "dataset", "path_length", "against"], sort=False,
    ):
        # each pair's own mean of topic perplexity: a walker with fewer runs pairs fewer restarts
        ours = block["topic_perplexity"].to_numpy(float)
        theirs, p = block["other_mean"].to_numpy(float), block["p_value"].to_numpy(float)
        rows.append({
            "measure": measure, "dataset": dataset, "path_length": length, "against": against, "walkers": len(block),
            **lead_each(measure_named(measure), block["other"], ours, theirs, p),
        })
    return with_adjusted_p(pd.DataFrame(rows, columns=LEAD_COLUMNS), ["measure", "path_length", "against"], ["p_each"])


#: ``found_classes.csv``'s columns (:func:`class_times`).
CLASS_COLUMNS = [
    "dataset", "path_length", "class_id", "class_name", "other", "n", "topic_perplexity_steps", "other_steps",
    "mean_difference", "ci_low", "ci_high", "p_value", "topic_perplexity_found", "other_found",
]


def class_times(classes):
    """``found_classes.csv`` (module docstring), from ``classes.csv``'s rows; ceilings take no part."""
    import pandas as pd

    from curiosity_cli.evaluate.measures import restricted_steps
    from curiosity_cli.evaluate.statistics import paired_difference, walkers_only, wilcoxon_pair_p

    walkers = walkers_only(classes).dropna(subset=["found"])  # label files without first steps say nothing here
    if walkers.empty:
        return pd.DataFrame(columns=CLASS_COLUMNS)
    walkers = walkers.assign(
        steps=restricted_steps(walkers["first_step"].fillna(-1).to_numpy(), walkers["path_length"].to_numpy()),
        found=walkers["found"].astype(float),
        class_name=walkers["class_name"].fillna(""),  # a group key: a missing name would drop the class
    )
    index = ["dataset", "path_length", "class_id", "class_name"]
    wide = walkers.pivot_table(index=[*index, "restart"], columns="weight_function", values=["steps", "found"])
    if HEADLINE_WEIGHT not in wide["steps"].columns:
        return pd.DataFrame(columns=CLASS_COLUMNS)
    rows = []
    for names, block in wide.groupby(level=index, sort=False):
        found = block["found"]
        for other, pairs, ours, theirs in versus_pairs(block["steps"]):
            mean, low, high = paired_difference(ours, theirs)
            rows.append({
                **dict(zip(index, names)), "other": other, "n": len(pairs), "topic_perplexity_steps": float(ours.mean()),
                "other_steps": float(theirs.mean()), "mean_difference": mean, "ci_low": low, "ci_high": high,
                "p_value": wilcoxon_pair_p(ours - theirs),
                "topic_perplexity_found": float(found.loc[pairs, HEADLINE_WEIGHT].mean()),
                "other_found": float(found.loc[pairs, other].mean()),
            })
    return pd.DataFrame(rows, columns=CLASS_COLUMNS)
