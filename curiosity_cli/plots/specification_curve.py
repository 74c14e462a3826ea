"""The specification-curve figure (Simonsohn, Simmons & Nelson, 2020) of a study.

Top: one point per specification and map, topic perplexity's ratio at 80 steps to the
next best walker with its 95 % interval, sorted by ratio
(:func:`curiosity_cli.evaluate.specification_curve.curve_table`), coloured by map; behind
each, in grey, its null reference: the 95 % band and the median (a dash) of the ratio
when topic perplexity is exchangeable with the walkers that could equal it (the random
walk left out), where "no difference" lies; a filled point where topic perplexity leads
every other walker (each compared alone) after correcting for every point of the curve
(Holm), a tinted one where it does only uncorrected (p < 0.05 against each), a hollow
one elsewhere; the paper's ratio of each paper map our maps stand in for as a dashed
line named by it, and 1 in grey. Below, aligned with the points, a panel of dots: a
row per map and per value of each varied key, a dot where the point's specification used it.

The curve of another measure (``measure``: :func:`curiosity_cli.evaluate.found_curve.measure_curve`)
draws topic perplexity's paired difference to the closest of the paper's walkers with its
95 % interval instead of the ratio, 0 for no difference, without null band or paper lines
(neither exists for it).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from curiosity_cli.evaluate.statistics import ALPHA
from curiosity_cli.plots.figures import figure_style, save_figure

if TYPE_CHECKING:
    from curiosity_cli.evaluate.measures import Measure

_MINUS = "\u2212"
#: Points up to which the specifications are named under the dot panel.
_NAMED = 40


def specification_curve_figure(
    table, choices: Mapping[str, Mapping[str, str]], label: str = "specification", datasets: list[str] | None = None,
    against: str = "human labels", measure: Measure | None = None,
):
    """The figure (module docstring).

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`~curiosity_cli.evaluate.specification_curve.curve_table`, in its order (its
        ``dataset``, ``ratio``, ``ratio_ci_low``, ``ratio_ci_high``, ``null_median``,
        ``null_no_rw_low``, ``null_no_rw_high``, ``null_no_rw_median``, ``beats_all``, ``p_each_holm``, ``paper_map`` and ``paper_ratio``), with a column ``label`` naming each row's
        specification.
    choices : mapping of str to mapping of str to str
        Per specification (as ``label`` names it): each varied key and the value it used,
        the keys in the order the panel lists them.
    label : str
        The column of ``table`` naming the specification.
    datasets : list of str, optional
        The maps in the order of the panel's rows and colours; default as they first come in ``table``.
    against : str
        What the MI was measured against, in words, for the axis.
    measure : Measure, optional
        Another measure than MI: ``table`` is its :func:`~curiosity_cli.evaluate.found_curve.measure_curve`
        (its ``closest``, ``closest_difference``, ``closest_low`` and ``closest_high``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib
    import numpy as np
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    datasets = [d for d in dict.fromkeys([*(datasets or []), *table["dataset"]]) if (table["dataset"] == d).any()]
    colours = {d: matplotlib.colormaps["tab10"](i % 10) for i, d in enumerate(datasets)}
    rows = [("map", d) for d in datasets]
    for values in choices.values():
        for key, value in values.items():
            if (key, value) not in rows:
                rows.append((key, value))
    keys = list(dict.fromkeys(k for k, _ in rows))
    rows.sort(key=lambda kv: keys.index(kv[0]))  # a key's values together (stable), keys as first seen
    n = len(table)
    x = np.arange(n)
    fig = Figure(figsize=(max(6.4, 1.8 + 0.22 * n), 3.6 + 0.2 * len(rows) + (1.2 if n <= _NAMED else 0)), layout="constrained")
    top, dots = fig.subplots(2, 1, sharex=True, height_ratios=[3.4, 0.2 * len(rows) + 0.3])
    value = ("ratio", "ratio_ci_low", "ratio_ci_high") if measure is None else ("closest_difference", "closest_low", "closest_high")
    top.axhline(1.0 if measure is None else 0.0, color="0.6", linewidth=0.8)
    handles = [Line2D([], [], color=colours[d], marker="o", linestyle="", label=d) for d in datasets]
    if measure is None:
        papers = table.dropna(subset=["paper_ratio"]).drop_duplicates("paper_map")
        for paper in papers.itertuples():
            top.axhline(paper.paper_ratio, color="0.25", linestyle="--", linewidth=1)
            top.annotate(
                f"{paper.paper_map} (paper): {paper.paper_ratio:.2f}", (0, paper.paper_ratio),
                xycoords=("axes fraction", "data"), xytext=(4, 2), textcoords="offset points", fontsize=8, color="0.25",
            )
        null_low, null_high = table["null_no_rw_low"].to_numpy(float), table["null_no_rw_high"].to_numpy(float)
        top.bar(x, null_high - null_low, bottom=null_low, width=0.7, color="0.88", zorder=0)
        top.scatter(x, table["null_no_rw_median"].to_numpy(float), marker="_", s=60, color="0.45", zorder=1)
        handles += [
            Patch(color="0.88", label="no difference (random walk left out): 95 % null band, median dashed"),
            Line2D([], [], color="0.25", linestyle="--", label="the paper's ratio of the map ours stand in for"),
        ]
    for dataset in datasets:
        at = (table["dataset"] == dataset).to_numpy()
        ratio = table.loc[at, value[0]].to_numpy(float)
        low, high = table.loc[at, value[1]].to_numpy(float), table.loc[at, value[2]].to_numpy(float)
        top.errorbar(x[at], ratio, yerr=[ratio - low, high - ratio], fmt="none", ecolor=colours[dataset], elinewidth=1)
        leads = (table.loc[at, "p_each_holm"].to_numpy(float) < ALPHA)
        uncorrected = table.loc[at, "beats_all"].astype(bool).to_numpy() & ~leads
        neither = ~(leads | uncorrected)
        top.scatter(x[at][leads], ratio[leads], color=colours[dataset], s=26, zorder=3)
        top.scatter(
            x[at][uncorrected], ratio[uncorrected], facecolor=(*colours[dataset][:3], 0.3), edgecolor=colours[dataset],
            s=26, zorder=3,
        )
        top.scatter(x[at][neither], ratio[neither], facecolor="white", edgecolor=colours[dataset], s=26, zorder=3)
    if measure is None:
        top.set_ylabel(f"MI ratio at 80 steps ({against}):\ntopic perplexity / next best")
    else:
        better = "lower" if measure.lower_is_better else "higher"
        unit = f", {measure.unit}" if measure.unit else ""
        top.set_ylabel(
            f"{measure.title} at 80 steps ({against}{unit}):\ntopic perplexity {_MINUS} closest walker ({better} is better)"
        )
    top.grid(True, axis="y", color="0.92")
    handles += [
        Line2D([], [], color="0.3", marker="o", linestyle="", label="leads each walker, Holm p < 0.05 over the curve"),
        Line2D(
            [], [], markeredgecolor="0.3", markerfacecolor=(0.3, 0.3, 0.3, 0.3), marker="o", linestyle="",
            label="leads each walker uncorrected only",
        ),
        Line2D([], [], markeredgecolor="0.3", markerfacecolor="white", marker="o", linestyle="", label="does not"),
    ]
    fig.legend(handles=handles, loc="outside lower center", fontsize=8, frameon=False, ncols=min(len(handles), 3))
    for i, record in enumerate(table.to_dict("records")):
        used = {("map", record["dataset"]), *choices.get(record[label], {}).items()}
        for j, row in enumerate(rows):
            hit = row in used
            dots.scatter(i, j, s=16 if hit else 4, color="0.1" if hit else "0.85", zorder=2)
    dots.set_yticks(range(len(rows)), [f"{k}: {v}" for k, v in rows], fontsize=8)
    dots.set_ylim(len(rows) - 0.5, -0.5)
    dots.set_xlim(-0.6, n - 0.4)
    for j in range(1, len(rows)):
        if rows[j][0] != rows[j - 1][0]:
            dots.axhline(j - 0.5, color="0.8", linewidth=0.6)
    if n <= _NAMED:
        dots.set_xticks(x, table[label].astype(str).tolist(), rotation=90, fontsize=8)
    else:
        dots.set_xticks([])
    if measure is None:
        dots.set_xlabel("specification and map, sorted by ratio")
        fig.suptitle(
            f"Specification curve: topic perplexity's lead at 80 steps, MI against {against}\n"
            "(seeds pooled; 95 % bootstrap intervals, the next best chosen in each resample)"
        )
    else:
        dots.set_xlabel("specification and map, sorted by the difference to the closest walker")
        fig.suptitle(
            f"Specification curve: topic perplexity's lead at 80 steps, {measure.title} against {against}\n"
            "(seeds pooled; paired differences with 95 % Student-t intervals; no difference is 0)"
        )
    return fig


def write_specification_curve(
    table, choices: Mapping[str, Mapping[str, str]], stem: Path, label: str = "specification",
    datasets: list[str] | None = None, against: str = "human labels", measure: Measure | None = None,
) -> list[Path]:
    """Write :func:`specification_curve_figure` as ``stem``.png and ``stem``.pdf; returns both paths."""
    with figure_style():
        return save_figure(specification_curve_figure(table, choices, label, datasets, against, measure), Path(stem))
