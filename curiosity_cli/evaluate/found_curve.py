"""A study's curve on what each walker found: every measure beside MI, under every specification.

Per measure of :data:`~curiosity_cli.evaluate.measures.MEASURES` compared beside MI,
specification and map, from the seeds pooled as replicates
(:func:`~curiosity_cli.evaluate.replicates.pool`), at the headline's length: topic
perplexity against **each** of the paper's other walkers, named before any run
(:data:`~curiosity_cli.evaluate.specification_curve.VERSUS`): the mean paired difference
with its 95 % interval and the paired Wilcoxon p (``difference_<walker>``,
``difference_<walker>_low``, ``difference_<walker>_high``, ``p_<walker>``), whether it
leads every one (``beats_all``, ``not_beaten``, the intersection-union ``p_each``), and
``p_each`` adjusted over every point of the measure's curve (``p_each_holm``,
``p_each_bh``): a point leads only after Holm, as on MI's curve. The curve of one measure
(:func:`measure_curve`, ``reproduce --measure``) draws each point's difference to the
closest of those walkers, where topic perplexity's advantage is least (``closest``,
``closest_difference`` and its interval): the one the decision turns on, chosen after
seeing the data and so biased toward "no lead", as MI's next best is; no difference is 0.
A measure that a specification's recorded seeds lack has no points there
(:attr:`~curiosity_cli.evaluate.replicates.Pooled.missing`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from curiosity_cli.evaluate.headline import headline_length, lead_each
from curiosity_cli.evaluate.measures import MEASURES, Measure, read_against
from curiosity_cli.evaluate.multiplicity import adjusted_columns, with_adjusted_p
from curiosity_cli.evaluate.specification_curve import VERSUS
from curiosity_cli.evaluate.statistics import ALPHA

if TYPE_CHECKING:
    from curiosity_cli.evaluate.replicates import Pooled


def _versus_names(walker: str) -> tuple[str, str, str, str]:
    return f"difference_{walker}", f"difference_{walker}_low", f"difference_{walker}_high", f"p_{walker}"


#: A found curve's columns after those naming its specification.
FOUND_CURVE_COLUMNS = (
    "measure", "dataset", "against", "path_length", "seeds", "beats_all", "not_beaten", "p_each",
    *adjusted_columns(["p_each"]), *(name for w in VERSUS for name in _versus_names(w)), "closest", "closest_difference",
    "closest_low", "closest_high",
)


def found_curve_table(specifications: Sequence[tuple[Mapping[str, str], Pooled]]):
    """A row per measure, specification and map (module docstring), in the order given.

    Against human labels, or Z_b on a map without them, as MI's curve; a measure of no labelling against the
    map's held-out words (:data:`~curiosity_cli.evaluate.measures.WORDS`).

    Parameters
    ----------
    specifications : sequence of (mapping of str to str, Pooled)
        Per specification: the columns that name it, and its seeds pooled.

    Returns
    -------
    pandas.DataFrame
        The naming columns, then :data:`FOUND_CURVE_COLUMNS`.
    """
    import pandas as pd

    by_name = {m.name: m for m in MEASURES}
    rows, names = [], []
    for labels, pooled in specifications:
        names += [k for k in labels if k not in names]
        effects = pooled.found_effects
        for (measure, dataset), block in effects.groupby(["measure", "dataset"], sort=False):
            against = read_against(block["against"])
            block = block[block["against"] == against]
            length = headline_length(block["path_length"].unique())
            versus = block[block["path_length"] == length].set_index("other")
            row = {**labels, "measure": measure, "dataset": dataset, "against": against, "path_length": length,
                   "seeds": " ".join(map(str, pooled.seeds))}
            for walker in VERSUS:
                values = versus.loc[walker] if walker in versus.index else None
                for column, source in zip(_versus_names(walker), ("mean_difference", "ci_low", "ci_high", "p_value")):
                    row[column] = float(values[source]) if values is not None else np.nan
            ours = [versus.loc[w, "topic_perplexity"] if w in versus.index else np.nan for w in VERSUS]
            theirs = [versus.loc[w, "other_mean"] if w in versus.index else np.nan for w in VERSUS]
            row.update(lead_each(by_name[measure], VERSUS, ours, theirs, [row[f"p_{w}"] for w in VERSUS]))
            # the closest walker: where topic perplexity's advantage is least
            advantage = np.array([row[f"difference_{w}"] for w in VERSUS]) * (-1 if by_name[measure].lower_is_better else 1)
            if np.isfinite(advantage).any():
                closest = VERSUS[int(np.nanargmin(advantage))]
                mean, low, high, _ = _versus_names(closest)
                row.update({"closest": closest, "closest_difference": row[mean], "closest_low": row[low],
                            "closest_high": row[high]})
            rows.append(row)
    return with_adjusted_p(pd.DataFrame(rows, columns=[*names, *FOUND_CURVE_COLUMNS]), "measure", ["p_each"])


def found_curve_lines(table, missing: Sequence[str]) -> list[str]:
    """SWEEP.md's account of :func:`found_curve_table`: per measure, the points where topic perplexity leads each walker.

    Parameters
    ----------
    table : pandas.DataFrame
        From :func:`found_curve_table`.
    missing : sequence of str
        Measures some specification's seeds lack (recorded before they existed).
    """
    versus = ", ".join(w.replace("-", " ") for w in VERSUS)
    lines = [
        "### What each walker found",
        "",
        f"The same decision on each measure beside MI (REPORT.md's \"What each walker found\"), at the headline's length: "
        f"topic perplexity leads where its mean is better (higher; lower for a time) than each of {versus} with a "
        f"paired Wilcoxon p below {ALPHA:g} against each, read after Holm's correction over the measure's points. The points, with the paired "
        "difference to each walker and its interval, are in `specifications-found.csv`.",
        "",
        "| measure | points | lead after Holm | uncorrected (exploratory) | " +
        " | ".join(f"median difference to {w.replace('-', ' ')}" for w in VERSUS) + " |",
        "|---|---|---|---|" + "---|" * len(VERSUS),
    ]
    by_name = {m.name: m for m in MEASURES}
    for measure, block in table.groupby("measure", sort=False):
        m: Measure = by_name[measure]
        medians = [block[f"difference_{w}"].median() for w in VERSUS]
        lines.append(
            f"| {m.title} | {len(block)} | {int((block['p_each_holm'] < ALPHA).sum())} | "
            f"{int(block['beats_all'].astype(bool).sum())} | "
            + " | ".join(f"{x:+.{m.digits}f}" if np.isfinite(x) else "" for x in medians) + " |"
        )
    if missing:
        titles = ", ".join(by_name[name].title for name in missing)
        lines += ["", f"Not pooled ({titles}): some seeds' recorded `mi.csv` was made before the measure existed, and "
                  f"their runs and label files are not kept to compute it; recording those seeds again adds it."]
    if table.empty:
        lines += ["", "(no point to count)"]
    return lines + [""]


def measure_curve(table, measure: str):
    """The points of one measure of :func:`found_curve_table`, sorted by their difference to the closest walker
    (a point without one last), ties in the order given."""
    return table[table["measure"] == measure].sort_values(
        "closest_difference", kind="stable", na_position="last", ignore_index=True,
    )
