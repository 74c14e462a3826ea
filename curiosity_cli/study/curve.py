"""A study's specification curve: the lead of ``SWEEP.md``, its table and figures.

``SWEEP.md`` leads with the specification curve (:func:`specification_lead`): topic
perplexity against each of the paper's other walkers (the decision), and the ratio to the
next best with its null reference (a summary); the figure ``specification-curve.png``
(and ``.pdf``), the table of its points, also written as ``specifications.csv``, and the
sentence counting the specifications in which topic perplexity leads every walker at
p < 0.05, those whose interval holds the paper's ratio, and where the points lie against
their null reference (:mod:`curiosity_cli.evaluate.specification_curve`); then the same
against Z_b (``specifications-batch.csv``, ``specification-curve-batch.png``); then the same decision on
every measure of what each walker found beside MI (``specifications-found.csv``,
:mod:`curiosity_cli.evaluate.found_curve`). It takes the place of the
sweep's sensitivity table, which would repeat the same pooled numbers in the same rows;
``sensitivity.csv`` is still written. Every number comes from one pooling of each
specification's seeds (:func:`curiosity_cli.study.report.pool_treatments`), over the
paper's four walkers.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from curiosity_cli.files import atomic_path, display_path
from curiosity_cli.study.types import REPLICATE_KEY, SPECIFICATION, Sweep, Treatment

if TYPE_CHECKING:
    from curiosity_cli.config import ExperimentConfig


#: The table, the joint tests and the figure of a study's curve, in its sweep folder: MI against human labels,
#: and against Z_b.
TABLE, JOINT_TABLE, FIGURE = "specifications.csv", "specifications-joint.csv", "specification-curve"
BATCH_TABLE, BATCH_JOINT_TABLE, BATCH_FIGURE = (
    "specifications-batch.csv", "specifications-joint-batch.csv", "specification-curve-batch",
)


#: Every measure beside MI under every specification (:mod:`~curiosity_cli.evaluate.found_curve`).
FOUND_TABLE = "specifications-found.csv"

#: The mechanism's figure (SWEEP.md's "Does surprise point at what is new?").
MECHANISM_FIGURE = "mechanism"


def specification_lead(sweep: Sweep, folder: Path, treatments: Sequence[Treatment], measure: str = "mi") -> list[str]:
    """Write ``specifications.csv``, ``specifications-batch.csv`` and their figures, and return
    the section ``SWEEP.md`` leads with.

    Parameters
    ----------
    sweep : Sweep
        A study's, with its specifications.
    folder : Path
        The study's sweep folder.
    treatments : sequence of Treatment
        Each specification (and any other swept key but the seed) with its seeds pooled
        (:func:`curiosity_cli.study.report.pool_treatments`).
    measure : str
        A measure of :data:`~curiosity_cli.evaluate.measures.MEASURES` compared beside MI draws its own curve too,
        ``specification-curve-<measure>.png`` (:func:`~curiosity_cli.evaluate.found_curve.measure_curve`).

    Returns
    -------
    list of str
        Markdown lines.
    """
    from curiosity_cli.evaluate.found_curve import found_curve_lines, found_curve_table, measure_curve
    from curiosity_cli.evaluate.measures import WORDS, measure_named
    from curiosity_cli.evaluate.specification_curve import VERSUS, curve_sentence, curve_table, joint_lines
    from curiosity_cli.evaluate.headline import HEADLINE_LENGTH
    from curiosity_cli.plots.specification_curve import write_specification_curve

    folder = Path(folder)
    pooled = [t for t in treatments if t.pooled is not None]
    names = list(pooled[0].values) if pooled else [SPECIFICATION]  # specification, then any other swept key
    choices = {", ".join(t.values.values()): _choices(sweep, t) for t in pooled}
    seeds = sorted({s for t in pooled for s in t.pooled.seeds})
    datasets = list(dict.fromkeys(d for t in pooled for d in t.pooled.headline["dataset"]))  # the config's order
    versus = ", ".join(w.replace("-", " ") for w in VERSUS)
    lines = [
        "## Specification curve",
        "",
        f"Every specification `{display_path(sweep.config_path)}` declares ({len(sweep.specifications)}), on every "
        f"map, seeds {', '.join(map(str, seeds)) or '(none finished)'} pooled as replicates (a restart is paired with the same "
        f"restart of the same seed), MI at {HEADLINE_LENGTH} steps. **The decision** compares topic perplexity with "
        f"each of the paper's other walkers ({versus}), named before anything ran: the ratio of mean MI with its "
        "95 % studentized bootstrap interval and the paired Wilcoxon p against each; it *leads* only where its "
        "mean is higher and p < 0.05 against every one (its p, `p_each`, is the largest of the three), and a point "
        "*leads* only where that p stays below 0.05 after correcting for every point of the curve (Holm; "
        "uncorrected leads are exploratory). **The curve** shows a summary: the ratio to the next best "
        "of them, chosen after seeing the data and so biased toward \"no lead\", with its 95 % bootstrap interval "
        "(the next best chosen again in each resample) and, in grey behind each point, its **null reference**: "
        "where the ratio lies when topic perplexity does not differ from the walkers that could equal it (their "
        "labels permuted within each restart, the random walk left out: it sees about half the cells, so no "
        "reading makes it exchangeable, and permuting it in puts the null too low; band: 95 %, dash: median), with "
        "the share of permutations at least as high as the observed ratio (`null p`). Dashed, the paper's ratio "
        "for the map each stands in for; filled, the points that lead after correction; tinted, those that lead "
        "uncorrected only. Below the curve, the value of each varied key each specification used (Simonsohn, "
        "Simmons & Nelson's specification-curve analysis). **The joint test** asks whether the curve as a whole "
        "shows more than no difference gives: its points' counts and median against their distribution when each "
        "restart's walkers are permuted once for every specification, so that runs the specifications share stay "
        f"shared. The tables are `{TABLE}` and `{JOINT_TABLE}` (human labels), `{BATCH_TABLE}` and "
        f"`{BATCH_JOINT_TABLE}` (Z_b).",
        "",
    ]
    for against, table_name, joint_name, figure, words in (
        ("human", TABLE, JOINT_TABLE, FIGURE, "human labels"),
        ("batch", BATCH_TABLE, BATCH_JOINT_TABLE, BATCH_FIGURE, "Z_b"),
    ):
        table, joint = curve_table([(t.values, t.pooled) for t in pooled], against=against)
        with atomic_path(folder / table_name) as tmp:
            table.to_csv(tmp, index=False)
        with atomic_path(folder / joint_name) as tmp:
            joint.to_csv(tmp, index=False)
        if against == "batch":
            lines += [
                "### Against Z_b", "",
                "The same curve with MI against the batch labelling Z_b of each map, the paper's other measure:", "",
            ]
        if len(table):
            table = table.assign(label=[", ".join(map(str, v)) for v in table[names].itertuples(index=False)])
            write_specification_curve(table, choices, folder / figure, label="label", datasets=datasets, against=words)
            lines += [f"![specification curve, MI against {words}]({figure}.png)", ""]
        lines += _curve_rows(table, names) + ["", curve_sentence(table), ""] + joint_lines(joint)
        if against == "human":
            lines += _mechanism_section(table, names, folder, datasets)
    found = found_curve_table([(t.values, t.pooled) for t in pooled])
    with atomic_path(folder / FOUND_TABLE) as tmp:
        found.to_csv(tmp, index=False)
    lines += found_curve_lines(found, list(dict.fromkeys(m for t in pooled for m in t.pooled.missing)))
    if measure != "mi":
        table = measure_curve(found, measure)
        if len(table):
            table = table.assign(label=[", ".join(map(str, v)) for v in table[names].itertuples(index=False)])
            figure = f"{FIGURE}-{measure}"
            # a measure of no labelling (the held-out log-likelihood) is scored against the map's held-out words
            against = "held-out words" if WORDS in measure_named(measure).columns else "human labels"
            write_specification_curve(
                table, choices, folder / figure, label="label", datasets=datasets, against=against,
                measure=measure_named(measure),
            )
            lines += [f"![specification curve, {measure_named(measure).title}]({figure}.png)", ""]
        else:
            lines += [f"No point has {measure_named(measure).title}: no curve of it.", ""]
    lines += [f"- `{', '.join(t.values.values())}`: not pooled: {t.error}" for t in treatments if t.pooled is None]
    return lines + [""] * any(t.pooled is None for t in treatments)


def _mechanism_section(table, names: list[str], folder: Path, datasets: list[str]) -> list[str]:
    """SWEEP.md's "Does surprise point at what is new?": topic perplexity's mechanism per specification and map,
    a figure and a table (:mod:`~curiosity_cli.evaluate.mechanism`), beside its MI ratio to each walker."""
    from curiosity_cli.evaluate.specification_curve import VERSUS
    from curiosity_cli.plots.mechanism import write_mechanism_figure
    from curiosity_cli.evaluate.report import number

    lines = [
        "## Does surprise point at what is new?",
        "",
        "Per specification and map, over topic perplexity's pooled runs at "
        "80 steps (`mechanism.csv` of each experiment): **M1** the within-step AUC of its score for the candidates "
        "holding a human class new to the path against the other unvisited candidates (0.5: it cannot tell them "
        "apart); **M2** the share of moves with such a candidate next to the walker (how often there was anything "
        "new to point at); **M3** the chance it put on them beyond what stochastic coverage would have (did it act "
        "on it); **M5** the share of its candidates whose topic perplexity was infinite; beside them its MI ratio "
        "to each walker. Where M1 is above 0.5 but M2 or M3 is small, surprise points at the new but the walker "
        "rarely has, or takes, the chance to follow it.",
        "",
    ]
    if table.empty:
        return lines + ["(no specification pooled)", ""]
    figure = table.assign(
        specification=table["label"],
        **{f"mi_ratio_{w}": table[f"ratio_{w}"] for w in VERSUS},
    )
    if figure[["auc", "opportunity", "gain"]].notna().any(axis=None):
        write_mechanism_figure(figure, folder / MECHANISM_FIGURE, datasets=datasets)
        lines += [f"![mechanism per specification and map]({MECHANISM_FIGURE}.png)", ""]
    lines += [
        "| " + " | ".join(names) + " | map | M1 AUC | M2 opportunity | M3 gain | M5 infinite | "
        + " | ".join(f"MI ratio to {w}" for w in VERSUS) + " |",
        "|" + "---|" * (len(names) + 5 + len(VERSUS)),
    ]
    for r in table.to_dict("records"):
        lines.append("| " + " | ".join([
            *(f"`{r[k]}`" for k in names), r["dataset"], number(r["auc"]), number(r["opportunity"]),
            number(r["gain"], 3), number(r["infinite_share"]), *(number(r[f"ratio_{w}"]) for w in VERSUS),
        ]) + " |")
    return lines + [""]


def _curve_rows(table, names: list[str]) -> list[str]:
    """The curve's points as a Markdown table: each walker compared alone, then the next-best summary."""
    from curiosity_cli.evaluate.specification_curve import STEERING_WALKER, VERSUS, lead_word
    from curiosity_cli.evaluate.report import number, p_text

    def versus(r: dict, walker: str) -> str:
        low, high = r[f"ratio_{walker}_low"], r[f"ratio_{walker}_high"]
        return f"{number(r[f'ratio_{walker}'])} [{number(low)}, {number(high)}], p = {p_text(r[f'p_{walker}'])}"

    lines = [
        "| # | " + " | ".join(names) + " | map | " + " | ".join(f"vs {w}" for w in VERSUS)
        + " | leads each: p; Holm, BH, Westfall-Young over the curve | next best: ratio [95 % CI] "
        "| null (random walk left out): median [95 %], p; Holm, Westfall-Young | paper's ratio | pairs "
        f"| detectable lead | distinct cells: topic perplexity / stochastic coverage | steering: {STEERING_WALKER} |",
        "|---|" + "---|" * len(names) + "---|" * (len(VERSUS) + 9),
    ]
    for i, r in enumerate(table.to_dict("records"), start=1):
        lead = r["detectable_ratio"] - 1
        lines.append("| " + " | ".join([
            str(i), *(f"`{r[k]}`" for k in names), r["dataset"], *(versus(r, w) for w in VERSUS),
            f"{lead_word(r)}: {p_text(r['p_each'])}; {p_text(r['p_each_holm'])}, {p_text(r['p_each_bh'])}, "
            f"{p_text(r['p_each_wy'])}",
            f"{number(r['ratio'])} [{number(r['ratio_ci_low'])}, {number(r['ratio_ci_high'])}] ({r['next_best']})",
            f"{number(r['null_no_rw_median'])} [{number(r['null_no_rw_low'])}, {number(r['null_no_rw_high'])}], "
            f"{p_text(r['null_no_rw_p'])}; {p_text(r['null_no_rw_p_holm'])}, {p_text(r['null_no_rw_p_wy'])}",
            number(r["paper_ratio"]), str(r["pairs"]), f"{number(100 * lead, 0)} %" if lead == lead else "",
            f"{number(r[f'distinct_{STEERING_WALKER}'], 1)} / {number(r['distinct_stochastic-coverage'], 1)}",
            number(r[f"steering_{STEERING_WALKER}"], 3),
        ]) + " |")
    return lines


def _choices(sweep: Sweep, treatment: Treatment) -> dict[str, str]:
    """The value of each varied key (set by any specification, or swept but the seed) in a treatment."""
    keys = list(dict.fromkeys(k for s in sweep.specifications for k in s.keys))
    keys += [axis.key for axis in sweep.axes if axis.key != REPLICATE_KEY and axis.key not in keys]
    config = treatment.combinations[0].config
    return {key: _shown(config, key) for key in keys}


def _shown(config: ExperimentConfig, key: str) -> str:
    """A dotted key's value in a resolved config, as a reader reads it (YAML-like)."""
    value = config
    for part in key.split("."):
        if isinstance(value, Mapping) and part in value:
            value = value[part]
        elif hasattr(value, part):
            value = getattr(value, part)
        else:
            return "?"
    if isinstance(value, str):
        return value
    if isinstance(value, tuple):
        value = list(value)
    try:
        return json.dumps(value)
    except TypeError:
        return str(value)
