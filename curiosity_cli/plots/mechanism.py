"""The mechanism figure: does topic perplexity point at what is new, per specification and map?

One panel row per measure of :mod:`curiosity_cli.evaluate.mechanism`, aligned on one
x axis with a point per specification and map (coloured by map, in the order given):

- topic perplexity's within-step AUC for the candidates holding a class new to the path,
  with chance (0.5) dashed;
- the opportunity: the share of moves with such a candidate;
- the gain: the chance the walker put on them over stochastic coverage's, with 0 dashed;
- if the table has them, topic perplexity's MI ratio to the other walkers (``mi_ratio``,
  and ``mi_ratio_<walker>`` per walker), with 1 (no lead) dashed.

Read down a column: a point where the AUC is above chance, there were opportunities, the
gain is positive and the ratio is above 1 is a specification where the mechanism holds.
"""

from __future__ import annotations

from pathlib import Path

from curiosity_cli.errors import ParameterError

#: The columns the figure needs; ``mi_ratio`` and ``mi_ratio_<walker>`` add a panel.
FIGURE_COLUMNS = ("specification", "dataset", "auc", "opportunity", "gain")
#: Points up to which the x axis names them.
_NAMED = 40
#: (column, label, dashed reference line) of the panels always drawn.
_PANELS = (
    ("auc", "AUC: new class vs\nother unvisited", 0.5),
    ("opportunity", "moves with a\nnew class in reach", None),
    ("gain", "chance on new classes\nover coverage's", 0.0),
)


def mechanism_figure(table, datasets: list[str] | None = None, title: str | None = None):
    """The figure (module docstring).

    Parameters
    ----------
    table : pandas.DataFrame
        A row per specification and map, in the order to draw them: ``specification``,
        ``dataset``, ``auc``, ``opportunity``, ``gain`` (topic perplexity's), and optionally
        ``mi_ratio`` and ``mi_ratio_<walker>`` columns.
    datasets : list of str, optional
        The maps in the order of their colours; default as they first come in ``table``.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib
    import numpy as np
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    _check_table(table)
    ratios = [c for c in table.columns if c == "mi_ratio" or str(c).startswith("mi_ratio_")]
    panels = [*_PANELS, *([("mi_ratio", "MI ratio: topic\nperplexity / other", 1.0)] if ratios else [])]
    datasets = [d for d in dict.fromkeys([*(datasets or []), *table["dataset"]]) if (table["dataset"] == d).any()]
    colours = {d: matplotlib.colormaps["tab10"](i % 10) for i, d in enumerate(datasets)}
    markers = ("o", "s", "D", "^", "v", "P", "X")
    n = len(table)
    x = np.arange(n)
    fig = Figure(
        figsize=(max(6.4, 1.8 + 0.22 * n), 1.9 * len(panels) + 1.2 + (1.2 if n <= _NAMED else 0)), layout="constrained",
    )
    axes = np.atleast_1d(fig.subplots(len(panels), 1, sharex=True))
    dataset = table["dataset"].to_numpy()
    for ax, (column, ylabel, reference) in zip(axes, panels):
        if reference is not None:
            ax.axhline(reference, color="0.4", linestyle="--", linewidth=1)
        series = ratios if column == "mi_ratio" else [column]
        for s, name in enumerate(series):
            values = table[name].to_numpy(float)
            for d in datasets:
                at = dataset == d
                ax.scatter(x[at], values[at], color=colours[d], marker=markers[s % len(markers)], s=24, zorder=3)
        ax.set_ylabel(ylabel)
        ax.grid(True, axis="y", color="0.92")
    axes[1].set_ylim(-0.03, 1.03)
    axes[-1].set_xlim(-0.6, n - 0.4)
    if n <= _NAMED:
        names = [f"{s} · {d}" for s, d in zip(table["specification"].astype(str), table["dataset"].astype(str))]
        axes[-1].set_xticks(x, names, rotation=90, fontsize=8)
    else:
        axes[-1].set_xticks([])
    axes[-1].set_xlabel("specification and map")
    handles = [Line2D([], [], color=colours[d], marker="o", linestyle="", label=d) for d in datasets]
    if len(ratios) > 1:
        handles += [
            Line2D([], [], color="0.3", marker=markers[s % len(markers)], linestyle="",
                   label="MI ratio" if name == "mi_ratio" else f"MI ratio to {name[len('mi_ratio_'):]}")
            for s, name in enumerate(ratios)
        ]
    fig.legend(handles=handles, loc="outside lower center", fontsize=8, frameon=False, ncols=min(len(handles), 4))
    fig.suptitle(title or "Does topic perplexity point at what is new?")
    return fig


def write_mechanism_figure(
    table, out: Path, datasets: list[str] | None = None, title: str | None = None,
) -> list[Path]:
    """Write :func:`mechanism_figure` as ``out``.png and ``out``.pdf, atomically; returns both paths.

    Parameters
    ----------
    table : pandas.DataFrame
        As :func:`mechanism_figure` takes it.
    out : Path
        The files' stem (a ``.png`` or ``.pdf`` suffix is dropped).
    datasets, title
        As :func:`mechanism_figure` takes them.

    Raises
    ------
    ParameterError
        ``table`` not a DataFrame, empty, or without one of :data:`FIGURE_COLUMNS`.
    """
    from curiosity_cli.plots.figures import figure_style, save_figure

    _check_table(table)
    stem = Path(out)
    if stem.suffix.lower() in (".png", ".pdf"):
        stem = stem.with_suffix("")
    with figure_style():
        return save_figure(mechanism_figure(table, datasets, title), stem)


def _check_table(table) -> None:
    import pandas as pd

    if not isinstance(table, pd.DataFrame):
        raise ParameterError(f"table: got {type(table).__name__}, expected a pandas DataFrame", parameter="table")
    missing = [c for c in FIGURE_COLUMNS if c not in table.columns]
    if missing:
        raise ParameterError(f"table: no column {missing[0]!r}; expected {', '.join(FIGURE_COLUMNS)}", parameter="table")
    if table.empty:
        raise ParameterError("table: no rows; expected a row per specification and map", parameter="table")
