"""The paper's figures from an experiment folder's results (paper section 5.1, figs. 2-5).

:func:`write_figures` writes, as PNG and PDF under ``results/<experiment>/figures/``:

- ``mi-vs-length-human``: MI between path labels Z_p and human labels Z_h against path
  length, mean and 95% CI over restarts, one panel per map (the paper's fig. 5);
- ``mi-vs-length-batch``: the same against the batch labels Z_b (fig. 4);
- ``path-<dataset>``: an exploration path over its map, blue at the start to red at the
  end, beside the map labelled with the topic model learned on that path (fig. 2);
- ``labelings-<dataset>``: input image, ground truth, Z_b and Z_p side by side (fig. 3),
  topic colours matched between Z_p and Z_b (see :mod:`curiosity_cli.plots.palette`);
- ``batch-convergence``: the batch model's log-likelihood per Gibbs sweep, per map;

and then the experiment's ``REPORT.md`` (:mod:`curiosity_cli.evaluate.report`), from its
tables, the figures and the seconds its stages took, so that the stages run one at a time
give the report that ``reproduce`` gives.

Weight functions keep the paper's visual language: topic perplexity blue squares,
stochastic coverage orange circles, random walk purple triangles, word perplexity green
diamonds; our lawnmower baseline brown crosses; any other weight function a grey marker of
its own. The ceilings (scattered cells, a compact block) are grey dashed lines without
markers or bands in the MI figures.
"""

from __future__ import annotations

import contextlib
import json
import math
import time
from pathlib import Path

import numpy as np

from curiosity_cli.errors import RERUN, CuriosityError
from curiosity_cli.experiment.experiment import Experiment
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.explore.weights import CEILINGS
from curiosity_cli.files import atomic_path, display_path
from curiosity_cli.evaluate.tables import read_table
from curiosity_cli.plots import missing_glyphs_noted, palette
from curiosity_cli.plots.experiment_inputs import (
    MI_COLUMNS,
    SUMMARY_COLUMNS,
    Example,
    PlotError,
    find_examples,
    load_maps,
    read_label_map,
    read_log_likelihood,
    read_path,
)
from curiosity_cli.plots.preview import shrink_image, shrink_labels

#: (colour, marker) of the paper's weight functions and our lawnmower baseline, in the
#: order legends list them.
WEIGHT_STYLES = {
    "topic-perplexity": ("tab:blue", "s"),
    "stochastic-coverage": ("tab:orange", "o"),
    "word-perplexity": ("tab:green", "D"),
    "random-walk": ("tab:purple", "^"),
    "lawnmower": ("tab:brown", "x"),
}
#: (colour, dash pattern) of the ceilings, in the order of ``CEILINGS``: lines without
#: markers or bands, since they bound the walkers rather than compete with them.
CEILING_STYLES = (("0.15", (0, (5, 2))), ("0.5", (0, (2, 2))))
#: Styles for any other weight function, taken in turn (sorted by name).
OTHER_STYLES = (("0.3", "v"), ("0.55", "P"), ("0.4", "X"), ("0.6", "h"), ("0.35", "*"), ("0.5", "p"), ("0.45", "<"))
#: The example path shown in figs. 2 and 3: the paper's method, first restart.
EXAMPLE_WEIGHT = "topic-perplexity"

_DPI = 150
_RC = {
    "font.size": 10,
    "axes.titlesize": 10.5,
    "axes.labelsize": 10,
    "xtick.labelsize": 9,
    "ytick.labelsize": 9,
    "legend.fontsize": 9.5,
    "figure.titlesize": 12,
    "figure.labelsize": 9,
}
_MATCH_NOTE = (
    "Topic colours: $Z_b$'s topics by size, largest first; each $Z_p$ topic takes the colour of the $Z_b$ topic "
    "it is matched to (one to one, the matching that shares the most pixels); $Z_p$ topics left unmatched get colours $Z_b$ does not use."
)


class WrittenFigures(list):
    """The figure files written (PNG and PDF of each figure), a ``list`` of Path.

    Attributes
    ----------
    skipped : list of str
        One line per figure (or panel) left out, saying which input was missing or bad.
    report : Path or None
        ``REPORT.md``, written with the figures (None where a table it reads is missing,
        named in ``skipped``).
    """

    def __init__(self, paths=(), skipped=()):
        super().__init__(paths)
        self.skipped = list(skipped)
        self.report = None


def _check_runs(experiment: Experiment) -> None:
    """Refuse the figures of runs whose files are not as explore wrote them (each ``run.json`` records their sizes
    and digests, the check every stage that reads runs makes): the tables were made from them.

    Raises
    ------
    PlotError
        The first such file, and what is wrong with it.
    """
    import json

    from curiosity_cli.experiment.wholeness import FILES_KEY, changed

    for planned in experiment.planned():
        folder = experiment.folder.run(planned.dataset, planned.weight_function, planned.restart)
        try:
            meta = json.loads((folder / ExperimentFolder.RUN_META).read_text())
        except (OSError, ValueError):
            continue  # a run.json that is gone or changed makes the tables stale, which check_tables says
        recorded = meta.get(FILES_KEY, {}) if isinstance(meta, dict) else {}
        if (change := changed(folder, recorded)) is not None:
            raise PlotError(
                f"{display_path(change[0])}: {change[1]}; {RERUN} redoes the run", rerun="explore", force=False
            )


def write_figures(experiment_dir: Path) -> WrittenFigures:
    """Write every figure the experiment folder has the inputs for.

    Parameters
    ----------
    experiment_dir : Path
        ``results/<experiment>/``, holding at least ``mi.csv`` from ``curiosity evaluate``.

    Returns
    -------
    WrittenFigures
        The PNG and PDF files written under ``experiment_dir/figures/``, a list of Path;
        its ``skipped`` attribute says, one line each, which figures were left out and
        why (no human labels, no batch labels, a missing run...).

    Raises
    ------
    PlotError
        No such folder, ``mi.csv`` missing or malformed, or a run of the grid whose files
        are not as its ``run.json`` records them (the check every stage makes of the runs it reads).
    ConfigError
        No ``config.yaml``, or one that does not validate.
    FolderInUseError
        Another process works in the folder (:mod:`~curiosity_cli.experiment.lock`).
    StaleTablesError
        The tables are not one complete set made from the experiment's files and maps as
        they are now (:meth:`~curiosity_cli.experiment.experiment.Experiment.check_tables`).
    """
    import pandas as pd

    from curiosity_cli.experiment.stage_seconds import record_stage_seconds, stage_seconds_problem

    started = time.perf_counter()
    experiment_dir = Path(experiment_dir)
    layout = ExperimentFolder(experiment_dir)
    if not experiment_dir.is_dir():
        raise PlotError(
            f"{display_path(experiment_dir)}: no such experiment folder; {RERUN} makes it", rerun="explore", force=False
        )
    from curiosity_cli.experiment.lock import working_in
    from curiosity_cli.experiment.saved_config import refuse_drive_folder

    with working_in(experiment_dir, "plot"):
        refuse_drive_folder(experiment_dir)  # named as one, not as a folder without mi.csv
        mi = read_table(layout.table("mi"), MI_COLUMNS, error=PlotError)
        if mi.empty:
            raise PlotError(f"{display_path(layout.table('mi'))}: no rows; {RERUN} makes it", rerun="evaluate", force=False)
        experiment = Experiment.open(experiment_dir)
        experiment.check_tables()
        _check_runs(experiment)
        out = layout.figures
        written = WrittenFigures()
        notes = written.skipped
        maps = load_maps(experiment.config, notes)
        order = list(maps) + [d for d in dict.fromkeys(mi["dataset"].astype(str)) if d not in maps]

        summary_path = layout.table("summary")
        try:
            summary = read_table(summary_path, SUMMARY_COLUMNS, error=PlotError)
            for column in ("path_length", "n", "mean", "std", "ci_low", "ci_high"):
                summary[column] = pd.to_numeric(summary[column], errors="coerce")  # a stray text cell: NaN, not a crash
            summary = summary.dropna(subset=["path_length"])
        except PlotError as exc:
            notes.append(f"no MI figures: {exc}")
            summary = None
        with figure_style():
            if summary is not None:
                for against, stem in (("human", "mi-vs-length-human"), ("batch", "mi-vs-length-batch")):
                    fig = mi_figure(summary, against, order, _largest_mi(maps, experiment.config, against))
                    if fig is None:
                        notes.append(f"{stem}: {summary_path.name} has no MI against {against} labels (no map has them)")
                    else:
                        written += save_figure(fig, out / stem)

            if "distinct_cells" in mi:
                written += save_figure(distinct_figure(mi, order), out / "mi-vs-distinct")
            else:
                notes.append("mi-vs-distinct: mi.csv has no distinct_cells column (evaluate the experiment again)")

            # the runs of the config's grid: a narrowed config's other runs are not drawn
            grid = {(r.dataset, r.weight_function, r.restart) for r in experiment.planned()}
            traces = {}
            for name, m in maps.items():
                batch_file = layout.batch(name)
                z_b = read_label_map(batch_file, m.image.shape[:2], notes)
                trace = read_log_likelihood(batch_file, notes) if batch_file.is_file() else None
                if trace is not None:
                    traces[name] = trace
                examples = _chosen_examples(
                    [e for e in find_examples(experiment_dir, name) if (name, e.weight_function, e.restart) in grid]
                )
                z_ps = [(e, z) for e in examples if (z := read_label_map(e.path, m.image.shape[:2], notes)) is not None]

                if z_ps:
                    example, z_p = z_ps[-1]
                    path = read_path(experiment_dir, name, example.weight_function, example.restart, notes)
                    if path is not None:
                        written += save_figure(path_figure(m, path, example, z_p, z_b), out / f"path-{name}")
                elif not examples:
                    notes.append(f"path-{name}: no example path labelling under labels/{name}/examples/ (label the experiment)")
                if z_b is None and not z_ps:
                    notes.append(f"labelings-{name}: neither a batch nor a path labelling to draw")
                else:
                    written += save_figure(labelings_figure(m, z_b, z_ps), out / f"labelings-{name}")

            if traces:
                written += save_figure(convergence_figure(traces), out / "batch-convergence")
            else:
                notes.append("batch-convergence: no batch log-likelihood trace under batch/ (label the experiment)")
        written.skipped[:] = list(dict.fromkeys(notes))  # a corrupt file is named once, not once per figure
        if (lost := stage_seconds_problem(experiment_dir)) is not None:  # before plot's time replaces the file
            written.skipped.append(f"{lost}: the time table lacks the stage times it held")
        record_stage_seconds(experiment_dir, "plot", time.perf_counter() - started, add=False)
        written.report = _write_report(experiment, written)
        return written


def _write_report(experiment: Experiment, figures: WrittenFigures) -> Path | None:
    """``REPORT.md`` of the experiment, from its tables, these figures and the seconds its stages took; None,
    with a note among the figures' ``skipped``, where a table of ``evaluate`` is missing."""
    from curiosity_cli.evaluate.report import write_report
    from curiosity_cli.evaluate.stage import read_evaluation
    from curiosity_cli.evaluate.tables import EvaluationError
    from curiosity_cli.experiment.stage_seconds import read_stage_seconds
    from curiosity_cli.yamlfile import read_yaml

    root = experiment.folder.root
    seconds = read_stage_seconds(root)
    if seconds:
        seconds["total"] = sum(seconds.values())
    try:
        provenance = read_yaml(experiment.folder.provenance, "provenance file")
    except CuriosityError:  # a folder from before provenance.yaml: the report says "unknown"
        provenance = {}
    try:
        evaluation = read_evaluation(experiment)
    except EvaluationError as exc:
        figures.skipped.append(f"REPORT.md: {exc}")
        return None
    try:
        shared = json.loads(experiment.folder.shared.read_text())
    except (OSError, ValueError):  # labelled before items were shared, or the file is not readable: not said
        shared = None
    return write_report(
        root, experiment.config, evaluation, list(figures), figures.skipped, seconds, provenance, shared,
    )


# --------------------------------------------------------------------------- the figures


def weight_style(name: str, others: list[str]) -> tuple[str, str]:
    """(colour, marker) of a weight function; ``others`` lists the non-paper ones in use, sorted."""
    if name in WEIGHT_STYLES:
        return WEIGHT_STYLES[name]
    return OTHER_STYLES[others.index(name) % len(OTHER_STYLES)]


def _weight_order(names) -> list[str]:
    """Walkers in legend order: ours by WEIGHT_STYLES, then any other by name; ceilings last."""
    names = set(names)
    ceilings = [n for n in CEILINGS if n in names]
    return [n for n in WEIGHT_STYLES if n in names] + sorted(names - set(WEIGHT_STYLES) - set(ceilings)) + ceilings


def _ceiling_style(name: str) -> tuple[str, tuple]:
    return CEILING_STYLES[CEILINGS.index(name) % len(CEILING_STYLES)]


def _label(weight_function: str) -> str:
    return weight_function.replace("-", " ").replace("_", " ")


def mi_figure(summary, against: str, datasets: list[str], largest: dict[str, float] | None = None):
    """MI against path length, one panel per map: mean line and 95% CI band per weight function
    (an error bar where a map has one path length), and a dashed line per ceiling.

    Parameters
    ----------
    summary : pandas.DataFrame
        ``summary.csv``: dataset, weight_function, path_length, against, n, mean, std,
        ci_low, ci_high.
    against : {"human", "batch"}
    datasets : list of str
        Panel order; maps without finite means against ``against`` are left out.
    largest : dict of str to float, optional
        Per map, the largest MI there can be against ``against`` (log2 of its classes or
        topics): a Student-t interval of few restarts can reach past it, and is drawn
        only up to it (the title says so where it was cut).

    Returns
    -------
    matplotlib.figure.Figure or None
        None when no map has a finite mean against ``against``.
    """
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.ticker import FixedLocator, NullLocator, ScalarFormatter

    rows = summary[(summary["against"].astype(str) == against) & np.isfinite(summary["mean"].astype(float))]
    panels = [d for d in datasets if (rows["dataset"].astype(str) == d).any()]
    panels += [d for d in dict.fromkeys(rows["dataset"].astype(str)) if d not in panels]
    if not panels:
        return None
    weights = _weight_order(rows["weight_function"].astype(str))
    others = [w for w in weights if w not in WEIGHT_STYLES and w not in CEILINGS]
    n_cols = min(len(panels), 3)
    n_rows = math.ceil(len(panels) / n_cols)
    fig = Figure(figsize=(0.6 + 4.0 * n_cols, 0.9 + 3.2 * n_rows), layout="constrained")
    axes = fig.subplots(n_rows, n_cols, squeeze=False)
    cut = False
    for ax, dataset in zip(axes.flat, panels):
        table = rows[rows["dataset"].astype(str) == dataset]
        for weight in weights:
            curve = table[table["weight_function"].astype(str) == weight].sort_values("path_length")
            if curve.empty:
                continue
            x = curve["path_length"].to_numpy(float)
            if weight in CEILINGS:
                colour, dashes = _ceiling_style(weight)
                ax.plot(x, curve["mean"].to_numpy(float), color=colour, linestyle=dashes, linewidth=1.3)
                continue
            colour, marker = weight_style(weight, others)
            low, high = curve["ci_low"].to_numpy(float), curve["ci_high"].to_numpy(float)
            low = np.maximum(low, 0.0)  # MI is never negative, nor above its largest value
            if (bound := (largest or {}).get(dataset)) is not None and np.any(high > bound):
                high, cut = np.minimum(high, bound), True
            band = np.isfinite(low) & np.isfinite(high)
            mean = curve["mean"].to_numpy(float)
            if x.size == 1:  # one length: no band to stretch between lengths
                if band[0]:
                    ax.errorbar(x, mean, yerr=[mean - low, high - mean], color=colour, capsize=4, linewidth=1.2,
                                linestyle="none")
            else:
                ax.fill_between(x, low, high, where=band, color=colour, alpha=0.15, linewidth=0, interpolate=False)
            ax.plot(
                x, mean, color=colour, marker=marker, markersize=5.5,
                linewidth=1.5, linestyle="-" if weight in WEIGHT_STYLES else "--",
            )
        lengths = sorted(table["path_length"].astype(int).unique())
        ax.set_xscale("log", base=2)
        ax.xaxis.set_major_locator(FixedLocator(lengths))
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.xaxis.set_minor_locator(NullLocator())
        if len(lengths) > 1:
            ax.set_xlim(lengths[0] / 2**0.25, lengths[-1] * 2**0.25)
        ax.set_ylim(bottom=0)
        ax.grid(True, color="0.9", linewidth=0.8)
        ax.set_axisbelow(True)
        n = table["n"].dropna()
        if n.empty:
            restarts = "?"
        else:
            restarts = f"{int(n.min())}" if n.min() == n.max() else f"{int(n.min())}-{int(n.max())}"
        ax.set_title(f"{dataset}  ({restarts} restart{'' if restarts == '1' else 's'})")
        ax.set_xlabel("path length (steps)")
        ax.set_ylabel("mutual information (bits)")
    for ax in axes.flat[len(panels):]:
        ax.set_visible(False)
    reference = "human labels $Z_h$" if against == "human" else "batch labels $Z_b$"
    handles = [
        Line2D([], [], color=_ceiling_style(w)[0], linestyle=_ceiling_style(w)[1], label=f"ceiling: {_label(w)}")
        if w in CEILINGS else
        Line2D([], [], color=weight_style(w, others)[0], marker=weight_style(w, others)[1], markersize=6,
               linestyle="-" if w in WEIGHT_STYLES else "--", label=_label(w))
        for w in weights
    ]
    if len(panels) == 1:
        fig.set_size_inches(6.2, 4.8)
    fit = max(1, int(fig.get_figwidth() / 2.0))  # a legend entry takes about 2 inches
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), fit), frameon=False)
    title = f"Mutual information of path labels $Z_p$ with {reference}: mean and 95% CI over restarts"
    if cut:
        title += f" (cut at the largest MI there can be, log2 of the {'classes' if against == 'human' else 'topics'})"
    fig.suptitle(_wrap(title, fig.get_figwidth(), _RC["figure.titlesize"]))
    return fig


def distinct_figure(mi, datasets: list[str]):
    """MI against the distinct cells a path saw, one point per run and checkpoint, walkers coloured.

    A walker ahead on MI at the same number of distinct cells saw better cells; one ahead
    only by seeing more of them sits further right on the same cloud.

    Parameters
    ----------
    mi : pandas.DataFrame
        ``mi.csv``, with ``distinct_cells``; ceilings are left out (they are not paths).
    datasets : list of str
        Panel order.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.ticker import ScalarFormatter

    rows = mi[~mi["weight_function"].astype(str).isin(CEILINGS)]
    panels = [d for d in datasets if (rows["dataset"].astype(str) == d).any()]
    weights = _weight_order(rows["weight_function"].astype(str))
    others = [w for w in weights if w not in WEIGHT_STYLES]
    n_cols = min(len(panels), 2)
    fig = Figure(figsize=(0.6 + 4.4 * n_cols, 0.9 + 3.6 * math.ceil(len(panels) / n_cols)), layout="constrained")
    axes = fig.subplots(math.ceil(len(panels) / n_cols), n_cols, squeeze=False)
    for ax, dataset in zip(axes.flat, panels):
        table = rows[rows["dataset"].astype(str) == dataset]
        column = "mi_human" if table["mi_human"].notna().any() else "mi_batch"
        for weight in weights:
            runs = table[table["weight_function"].astype(str) == weight]
            colour, marker = weight_style(weight, others)
            ax.scatter(runs["distinct_cells"], runs[column], s=14, color=colour, marker=marker, alpha=0.6)
        ax.set_xscale("log", base=2)
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.grid(True, color="0.9", linewidth=0.8)
        ax.set_axisbelow(True)
        ax.set_title(dataset)
        ax.set_xlabel("distinct cells seen")
        ax.set_ylabel(f"MI with {'human labels $Z_h$' if column == 'mi_human' else 'batch labels $Z_b$'} (bits)")
    for ax in axes.flat[len(panels):]:
        ax.set_visible(False)
    handles = [
        Line2D([], [], color=weight_style(w, others)[0], marker=weight_style(w, others)[1], linestyle="", label=_label(w))
        for w in weights
    ]
    fit = max(1, int(fig.get_figwidth() / 2.0))  # a legend entry takes about 2 inches, as in mi_figure
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), fit), frameon=False)
    title = "MI against distinct cells seen: one point per run and checkpoint"
    fig.suptitle(_wrap(title, fig.get_figwidth(), _RC["figure.titlesize"]))
    return fig


def path_figure(m, path, example: Example, z_p: np.ndarray, z_b: np.ndarray | None):
    """An exploration path over its map, beside the map labelled with the path's topic model.

    Parameters
    ----------
    m : MapData
    path : (L,) int ndarray
        The cell of every step of the run; the first ``example.length`` are drawn.
    example : Example
        The run and path length the labelling ``z_p`` was learned from.
    z_p : (H, W) int ndarray
        Topic ids.
    z_b : (H, W) int ndarray or None
        The batch labelling, to colour ``z_p``'s topics as in the labelings figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.collections import LineCollection
    from matplotlib.colors import LinearSegmentedColormap, Normalize
    from matplotlib.figure import Figure

    pixel_rows, pixel_cols = m.grid.centres(np.asarray(path)[: example.length])
    height, width = m.image.shape[:2]
    fig = Figure(figsize=(10.5, 5.6), layout="constrained")
    ax_path, ax_labels = fig.subplots(1, 2)
    _show(ax_path, shrink_image(m.image), (height, width))
    points = np.stack([pixel_cols, pixel_rows], axis=1)  # matplotlib draws (x, y) = (col, row)
    segments = np.stack([points[:-1], points[1:]], axis=1)
    blue_red = LinearSegmentedColormap.from_list("blue-red", ["#1f3fff", "#b000b0", "#ff1f1f"])
    norm = Normalize(0, max(len(pixel_rows) - 1, 1))
    # a dark outline under the coloured line keeps it visible on bright and dark ground alike
    ax_path.add_collection(LineCollection(segments, colors="black", linewidths=3.2, alpha=0.55, capstyle="round"))
    line = LineCollection(segments, cmap=blue_red, norm=norm, linewidths=1.8, capstyle="round")
    line.set_array(np.arange(len(segments)))
    ax_path.add_collection(line)
    for at, marker, colour in ((0, "o", blue_red(0.0)), (-1, "s", blue_red(1.0))):
        ax_path.plot(pixel_cols[at], pixel_rows[at], marker=marker, markersize=8, color=colour, markeredgecolor="white")
    ax_path.set_title(f"{m.config.name}: {_label(example.weight_function)} path, restart {example.restart}")
    bar = fig.colorbar(line, ax=ax_path, location="bottom", shrink=0.8, pad=0.02, aspect=35)
    bar.set_label("step along the path (circle: start, square: end)")

    slots = palette.match_topics(z_p, z_b)[0] if z_b is not None else palette.rank_topics(z_p)
    _show(ax_labels, palette.paint_topics(shrink_labels(z_p), slots), (height, width))
    n_topics = np.unique(z_p).size
    ax_labels.set_title(f"$Z_p$: labels from the model of its first {example.length} steps ({n_topics} topics)")
    matched = "colours matched to $Z_b$'s" if z_b is not None else "colours by topic size"
    note = f"{m.config.cell_width} px cells; path drawn through cell centres. Topic {matched}, as in labelings-{m.config.name}."
    fig.supxlabel(_wrap(note, fig.get_figwidth()))
    return fig


def labelings_figure(m, z_b: np.ndarray | None, z_ps: list[tuple[Example, np.ndarray]]):
    """Input image, ground truth, batch labels Z_b and path labels Z_p of one map, side by side.

    Parameters
    ----------
    m : MapData
    z_b : (H, W) int ndarray or None
    z_ps : list of (Example, (H, W) int ndarray)
        Path labelings, shortest path first.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    from curiosity_cli.plots.preview import colour_labels

    height, width_px = m.image.shape[:2]
    panels = [("input image", shrink_image(m.image), None)]
    if m.labels is not None:
        legend = [
            Patch(facecolor=np.array(c.colour) / 255, edgecolor="0.5", linewidth=0.5, label=c.name) for c in m.legend
        ]
        panels.append(("ground truth $Z_h$", colour_labels(shrink_labels(m.labels), m.legend), legend))
    if z_b is not None:
        painted = palette.paint_topics(shrink_labels(z_b), palette.rank_topics(z_b))
        panels.append((f"batch labels $Z_b$ ({np.unique(z_b).size} topics)", painted, None))
    for example, z_p in z_ps:
        if z_b is not None:
            slots, _, agreement = palette.match_topics(z_p, z_b)
            extra = f"\nsame colour as $Z_b$ on {100 * agreement:.0f}% of pixels"
        else:
            slots, extra = palette.rank_topics(z_p), ""
        title = f"$Z_p$ after {example.length} steps ({np.unique(z_p).size} topics){extra}"
        panels.append((title, palette.paint_topics(shrink_labels(z_p), slots), None))

    # one row of up to four maps (plus a narrow column for the legend), else two rows of three
    # with the legend in the sixth slot
    n = len(panels)
    legend = next((handles for _, _, handles in panels if handles), None)
    if n <= 4:
        n_rows, n_cols = 1, n + (legend is not None)
        ratios = [1.0] * n + ([0.5] if legend is not None else [])
    else:
        n_rows, n_cols = 2, 3
        ratios = [1.0] * 3
    width = 3.4 * sum(ratios) + 0.3
    fig = Figure(figsize=(width, 3.75 * n_rows + 0.9), layout="constrained")
    axes = fig.subplots(n_rows, n_cols, squeeze=False, gridspec_kw={"width_ratios": ratios})
    for ax, (title, rgb, _) in zip(axes.flat, panels):
        _show(ax, rgb, (height, width_px))
        ax.set_title(title)
    for ax in axes.flat[n:]:
        ax.set_axis_off()
    if legend is not None:
        axes.flat[n].legend(handles=legend, loc="center left", frameon=False, title="ground truth classes",
                            alignment="left", handlelength=1.3)
    path_from = ""
    if z_ps:
        e = z_ps[0][0]
        path_from = (
            f"$Z_p$: the map labelled with the model learned on the {_label(e.weight_function)} path "
            f"of restart {e.restart}. "
        )
    fig.suptitle(f"{m.config.name} ({height} x {width_px} px)")
    note = path_from + (_MATCH_NOTE if z_b is not None and z_ps else "Topic colours by topic size, largest first.")
    fig.supxlabel(_wrap(note, width))
    return fig


def _largest_mi(maps: dict, config, against: str) -> dict[str, float]:
    """Per map, the largest MI of path labels with ``against``: log2 of the classes with pixels, or of the topics."""
    if against == "batch":
        return {name: math.log2(config.model.topics) for name in maps}
    return {
        name: math.log2(max(1, np.unique(m.labels).size)) for name, m in maps.items() if m.labels is not None
    }


def convergence_figure(traces: dict[str, np.ndarray]):
    """The batch model's mean per-word log-likelihood after each Gibbs sweep, one column per map.

    The top row shows every sweep; the bottom row zooms on the second half, where a model
    that has converged is flat up to sampling noise.

    Parameters
    ----------
    traces : dict of str to (n_sweeps,) float ndarray
        Nats per word, by dataset name.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    n = len(traces)
    fig = Figure(figsize=(max(5.2, 0.5 + 3.7 * n), 5.6), layout="constrained")
    axes = fig.subplots(2, n, squeeze=False)
    for i, (name, trace) in enumerate(traces.items()):
        sweeps = np.arange(1, trace.size + 1)
        half = trace.size // 2
        tail = trace[-max(3, trace.size // 10):]
        for ax, start in ((axes[0, i], 0), (axes[1, i], half)):
            ax.plot(sweeps[start:], trace[start:], color="tab:blue", linewidth=1.5,
                    marker="." if trace.size - start <= 60 else None)
            ax.axhline(trace[-1], color="0.5", linewidth=0.8, linestyle=":")
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
            ax.grid(True, color="0.9", linewidth=0.8)
            ax.set_axisbelow(True)
        axes[0, i].set_title(f"{name}: all {trace.size} sweeps")
        axes[1, i].set_title(f"second half, zoomed\n{_trend(trace, tail)}")
        axes[1, i].set_xlabel("Gibbs sweep")
    for ax in axes[:, 0]:
        ax.set_ylabel("log-likelihood per word (nats)")
    title = "Batch reference $Z_b$: mean log-likelihood per word of the model learned on the whole map"
    fig.suptitle(_wrap(title, fig.get_figwidth(), _RC["figure.titlesize"]))
    return fig


# --------------------------------------------------------------------------- helpers


def _trend(trace: np.ndarray, tail: np.ndarray) -> str:
    """What the last sweeps of a log-likelihood trace say about convergence, in words."""
    if trace.size < 2 * tail.size:
        return f"{trace.size} sweeps: too few to tell whether it converged"
    if np.all(np.diff(tail) > 0):
        return f"still rising: +{tail[-1] - tail[0]:.2g} nats over the last {tail.size} sweeps"
    return f"last {tail.size} sweeps within {np.ptp(tail):.2g} nats"


def _chosen_examples(examples: list[Example]) -> list[Example]:
    """The example labelings figs. 2 and 3 show: one run (topic perplexity, lowest restart), its
    shortest and longest path, shortest first."""
    if not examples:
        return []
    weights = _weight_order({e.weight_function for e in examples})
    weight = EXAMPLE_WEIGHT if EXAMPLE_WEIGHT in weights else weights[0]
    restart = min(e.restart for e in examples if e.weight_function == weight)
    run = [e for e in examples if e.weight_function == weight and e.restart == restart]
    return [run[0]] if len(run) == 1 else [run[0], run[-1]]


def _wrap(text: str, width_inches: float, font_size: float = _RC["figure.labelsize"]) -> str:
    """Break a title or caption into lines that fit a figure ``width_inches`` wide at ``font_size`` points."""
    import textwrap

    chars_per_inch = 130 / font_size  # DejaVu Sans averages a little over half an em per character
    return textwrap.fill(text, width=max(30, int(width_inches * chars_per_inch)))


def _show(ax, rgb: np.ndarray, shape: tuple[int, int]) -> None:
    """Draw an (h, w, 3) picture over the map's full (H, W) pixel extent, without ticks."""
    height, width = shape
    ax.imshow(rgb, extent=(0, width, height, 0), interpolation="nearest")
    ax.set_xlim(0, width)
    ax.set_ylim(height, 0)
    ax.set_xticks([])
    ax.set_yticks([])


@contextlib.contextmanager
def figure_style():
    """The house style of every figure (font sizes), as a context."""
    import matplotlib

    with matplotlib.rc_context(_RC):
        yield


def save_figure(fig, stem: Path) -> list[Path]:
    """Write ``stem``.png and ``stem``.pdf atomically; returns both paths.

    A character the font lacks (an emoji in a legend's class name) is one note for both
    files (:func:`~curiosity_cli.plots.missing_glyphs_noted`). The PDF keeps the layout
    the PNG was drawn with: the same panels in the same places, without a second layout pass.
    """
    paths = []
    with missing_glyphs_noted():
        for suffix in (".png", ".pdf"):
            path = stem.with_name(stem.name + suffix)
            with atomic_path(path) as tmp:
                fig.savefig(tmp, dpi=_DPI, format=suffix[1:])
            paths.append(path)
            fig.set_layout_engine("none")  # laid out by the first save
    return paths
