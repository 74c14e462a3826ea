"""``REPORT.md``: one experiment's result, as a reader of the paper would want to check it.

It opens with the answer: per map, a verdict in words on whether topic perplexity beats
every other walker at 80 steps, by how much, with what confidence, and beside the
paper's figure (:func:`verdict`). Then the tables behind it: the headline, the maps, MI
with the ceilings, the check that the labels behind MI are converged, paired effect
sizes, what each walker found beside MI and the tests.
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from curiosity_cli.config import ExperimentConfig
from curiosity_cli.config_yaml import to_yaml
from curiosity_cli.evaluate.headline import HEADLINE_LENGTH, HEADLINE_WEIGHT, headline_length
from curiosity_cli.evaluate.power import POWER, TARGET_LEAD
from curiosity_cli.evaluate.statistics import ALPHA, CONFIDENCE, CONVERGENCE_TOLERANCE, smallest_wilcoxon_p
from curiosity_cli.evaluate.stage import Evaluation
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.experiment.recipes import CLASS_SHARE_PERCENT
from curiosity_cli.explore.weights import CEILINGS, WEIGHT_FUNCTIONS, in_verdict
from curiosity_cli.files import atomic_path

# the paper: "For short path lengths (40 steps or less), we do not see any statistical difference"
_SHORT = 40
_MINUS = "\u2212"
#: What each ``against`` of the tables is called in the report's tables.
_TARGETS = {"human": "Z_h", "batch": "Z_b"}
_CEILING_NOTE = (
    "Ceilings ({names}) are not walkers: the MI of a model learned from L scattered cells / an L-cell block "
    "around the start, the room a path of L steps leaves; they take no part in the tests, the effect sizes or "
    "the verdict."
)


def _order(names) -> list[str]:
    """Walkers in the registry's order (unknown ones after, by name), then ceilings."""
    known = list(WEIGHT_FUNCTIONS)
    return sorted(set(names), key=lambda n: (n in CEILINGS, known.index(n) if n in known else len(known), n))


def _label(name: str) -> str:
    return f"{name} (ceiling)" if name in CEILINGS else name


def _signed(x: float, digits: int | None = None) -> str:
    """``+0.01`` / ``−0.05``: a difference with its sign, a true minus sign; ``digits``
    decimals, by default two (three for a difference too small to show in two)."""
    return f"{'+' if x >= 0 else _MINUS}{abs(x):.{_digits(x) if digits is None else digits}f}"


def _digits(x: float) -> int:
    # two decimals, three for a difference too small to show in two
    return 3 if abs(x) < 0.01 else 2


def _p(p: float) -> str:
    if not np.isfinite(p):
        return "p n/a"
    return "p < 0.001" if p < 0.001 else f"p = {p:.3f}" if p < 0.01 else f"p = {p:.2f}"


def _text(value) -> str:
    """A text cell of a table row: "" for a missing one (NaN once read back from CSV)."""
    return value if isinstance(value, str) else ""


def verdict(row: Mapping, effects=None) -> str:
    """One map's verdict in words, from its ``headline.csv`` row and ``effects.csv``.

    E.g. ``zurich-zh17: topic perplexity does not beat every walker at 80 steps; against
    each alone, MI ratio random-walk 1.10 (95 % CI 1.01 to 1.20), p = 0.04,
    stochastic-coverage 0.97 (...), p = 0.62, word-perplexity 0.95 (...), p = 0.48; the
    next best, word-perplexity: 0.02 bits below (95 % CI −0.05 to +0.01), p = 0.48; ratio
    0.95 (...; walkers that do not differ give 0.96, 95 % 0.90 to 1.02: null p = 0.58)
    against the paper's 1.51 on Montreal1.`` "Beats" is
    :func:`~curiosity_cli.evaluate.headline.headline`'s ``beats_all``: a higher mean than
    every other walker and a paired Wilcoxon p below 0.05 against each, the walkers
    compared one by one (``effects``: the rows of :func:`~curiosity_cli.evaluate.headline.paired_effects`;
    without them, only the next best's numbers are given); the next best's ratio is a
    summary, read against its null reference (:mod:`~curiosity_cli.evaluate.comparisons`).
    """
    dataset, against, next_best = row["dataset"], row["against"], row["next_best"]
    where = f"{dataset}" if against == "human" else f"{dataset} (MI against Z_b: the map has no human labels)"
    length = int(row["path_length"])
    steps = f"{length} steps" + ("" if length == HEADLINE_LENGTH else f" (its longest path; the paper reads {HEADLINE_LENGTH})")
    holm = row.get("p_each_holm", np.nan)
    if row["beats_all"] and holm < ALPHA:
        claim = (
            f"topic perplexity beats every other walker at {steps} ({_p(row['p_each'])} against each, "
            f"Holm {_p(holm)} over the experiment's maps)"
        )
    elif row["beats_all"]:
        claim = (
            f"topic perplexity beats every other walker at {steps} on this map alone ({_p(row['p_each'])} against each), "
            f"not after correcting for the experiment's maps (Holm {_p(holm)})"
        )
    elif row["topic_perplexity"] > row["next_best_mi"]:
        claim = f"topic perplexity leads every other walker at {steps}, but not clearly"
    else:
        claim = f"topic perplexity does not beat every walker at {steps}"
    each = _each_walker(row, effects)
    if each:
        claim += f"; against each alone, MI ratio {each}"
    diff = row["mean_difference"]
    if np.isfinite(diff):
        side = "above" if diff >= 0 else "below"
        amount = f"{abs(diff):.{_digits(diff)}f} bits {side} {next_best}{', the next best' if diff >= 0 else ''}"
        if np.isfinite(row["ci_low"]):
            amount += f" ({100 * CONFIDENCE:.0f} % CI {_signed(row['ci_low'])} to {_signed(row['ci_high'])})"
    else:
        amount = f"{row['topic_perplexity']:.2f} bits against {next_best}'s {row['next_best_mi']:.2f}"
    text = f"{where}: {claim}: {amount}, {_p(row['p_value'])}"
    if np.isfinite(row.get("pairs", np.nan)) and (least := smallest_wilcoxon_p(int(row["pairs"]))) >= ALPHA:
        text += f" (with {int(row['pairs'])} pairs no paired test can reach p < {ALPHA}: the smallest p is {least:.2g})"
    others = [o for o in _text(row["not_beaten"]).split(";") if o and o != next_best]
    if others and not row["beats_all"]:
        text += f"; not clearly ahead of {', '.join(others)} either"
    if not np.isfinite(row["ratio"]):
        # a ratio over 0 bits: every path labels the map into one class against its labels
        text += (
            f"; ratio undefined: {next_best}'s MI is 0 bits (a map whose {'human labels hold' if against == 'human' else 'Z_b holds'} "
            "one class, or whose words give one topic, has no MI for any walker to gather)"
        )
    else:
        text += f"; ratio {row['ratio']:.2f}"
    if np.isfinite(row.get("ratio_ci_low", np.nan)):
        text += f" ({100 * CONFIDENCE:.0f} % CI {row['ratio_ci_low']:.2f} to {row['ratio_ci_high']:.2f}"
        if np.isfinite(row.get("null_no_rw_median", np.nan)):
            text += (
                f"; walkers that do not differ (the random walk left out) give {row['null_no_rw_median']:.2f}, "
                f"{100 * CONFIDENCE:.0f} % {row['null_no_rw_low']:.2f} to {row['null_no_rw_high']:.2f}: "
                f"null {_p(row['null_no_rw_p'])}"
            )
        text += ")"
    if _text(row["paper_map"]) and np.isfinite(row["paper_ratio"]):
        text += f" against the paper's {row['paper_ratio']:.2f} on {row['paper_map']}"
        if against != "human":
            text += " (against human labels there)"
    else:
        text += " (no paper map to compare with)"
    text += "."
    if _text(row["best_ceiling"]) and np.isfinite(row["ceiling_share"]):
        text += (
            f" It reaches {100 * row['ceiling_share']:.0f} % of the better ceiling's MI "
            f"({row['best_ceiling']}, {row['ceiling_mi']:.2f} bits)."
        )
    return text + power_sentence(row)


def _each_walker(row: Mapping, effects) -> str:
    """Topic perplexity against each other walker at the row's length and labels, in words; "" without ``effects``."""
    if effects is None or effects.empty:
        return ""
    rows = effects[
        (effects["dataset"] == row["dataset"]) & (effects["path_length"] == row["path_length"])
        & (effects["against"] == row["against"])
    ]
    parts = []
    for r in rows.to_dict("records"):
        interval = (
            f" ({100 * CONFIDENCE:.0f} % CI {r['ratio_ci_low']:.2f} to {r['ratio_ci_high']:.2f})"
            if np.isfinite(r.get("ratio_ci_low", np.nan)) else ""
        )
        ratio = f"{r['ratio']:.2f}" if np.isfinite(r["ratio"]) else "undefined (its MI is 0)"
        parts.append(f"{r['other']} {ratio}{interval}, {_p(r['p_value'])}")
    return ", ".join(parts)


def power_sentence(row: Mapping) -> str:
    """What the experiment could have found, from a headline row's power columns; "" without them.

    E.g. `` With 10 pairs it could detect a lead of 21 % or more at 80 % power; a 10 %
    lead would need 41 pairs.``
    """
    detectable = row.get("detectable_ratio", np.nan)
    if not np.isfinite(detectable):
        return ""
    needed = row["pairs_for_lead"]
    text = (
        f" With {int(row['pairs'])} pairs it could detect a lead of {100 * (detectable - 1):.0f} % or more "
        f"at {100 * POWER:.0f} % power; a {100 * TARGET_LEAD:.0f} % lead would need "
    )
    return text + (f"{int(needed)} pairs." if np.isfinite(needed) else "more than a million pairs.")


def _no_verdict(summary, dataset: str) -> str:
    """Why a map has no verdict."""
    block = summary[summary["dataset"] == dataset]
    if headline_length(block["path_length"].unique()) is None:
        return f"{dataset}: no verdict: no checkpoint of {HEADLINE_LENGTH} steps or fewer."
    walkers = {name for name in block["weight_function"] if in_verdict(name)}
    if HEADLINE_WEIGHT not in walkers:
        return f"{dataset}: no verdict: {HEADLINE_WEIGHT} was not run."
    return f"{dataset}: no verdict: no other walker to compare with."


#: The heading of a report's answer, a line per map (:func:`read_verdict` finds it by this).
VERDICT_HEADING = "## Verdict"


def read_verdict(report: Path) -> list[str]:
    """The verdict of a ``REPORT.md``, a line per map, without their list marks; empty for a file without one
    (a sweep's ``SWEEP.md``)."""
    lines = Path(report).read_text().splitlines()
    if VERDICT_HEADING not in lines:
        return []
    verdict = []
    for line in lines[lines.index(VERDICT_HEADING) + 2 :]:
        if not line.startswith("- "):
            break
        verdict.append(line[2:])
    return verdict


def _verdicts(summary, top, effects, coverage: str) -> list[str]:
    """The answer first, a line per map; then how to read it."""
    lines = [VERDICT_HEADING, ""]
    rows = {r["dataset"]: r for r in top.to_dict("records")}
    for dataset in dict.fromkeys(summary["dataset"]):
        lines.append(f"- {verdict(rows[dataset], effects) if dataset in rows else _no_verdict(summary, dataset)}")
    return lines + [
        "",
        f"Does {HEADLINE_WEIGHT} beat every other walker at {HEADLINE_LENGTH} steps? Mean MI against human labels "
        "(against the batch labels Z_b where a map has none), paired by restart (which share start cells). It is "
        "compared with each other walker the config runs, one by one: the ratio of the means with its "
        f"{100 * CONFIDENCE:.0f} % studentized bootstrap interval and the paired Wilcoxon signed-rank p; \"beats\" "
        f"means a higher mean than every other walker with p < {ALPHA} against each, and on an experiment of several "
        "maps the verdict reads that p adjusted for the maps (Holm). Then the next best walker: the "
        f"mean paired difference with its {100 * CONFIDENCE:.0f} % Student-t confidence interval and p, and the "
        "ratio of the two means, beside the paper's for the map the dataset stands in for. The next best is chosen "
        "after seeing the data, so that ratio leans toward \"no lead\": its interval chooses the next best again "
        "in each bootstrap resample, and its null reference says what walkers that do not differ give (their labels "
        "permuted within each restart, the random walk left out: it sees about half the cells, so it never equals "
        "the others), with the share of permutations at least as high (null p). The "
        f"smallest lead detectable at {100 * POWER:.0f} % power, and the pairs a {100 * TARGET_LEAD:.0f} % lead "
        "needs, are for a paired t-test at p < 0.05 with the spread of the paired differences observed here "
        "(evaluate/power.py); seeds run as a sweep pool their pairs in SWEEP.md. How eq. 8 treats a visited "
        f"neighbour (here `{coverage}`) can move the verdict: `configs/readings.yaml` runs every reading on "
        "the four maps, three seeds pooled.",
        "",
    ]


def _cell(row) -> str:
    return f"{row['mean']:.3f} ± {(row['ci_high'] - row['ci_low']) / 2:.3f}"


def _length_cells(rows, lengths: list[int], cell) -> list[str]:
    """A table row's cells: ``cell(row)`` for each of ``lengths`` in ``rows`` (indexed by path length), else empty."""
    return [cell(rows.loc[n]) if n in rows.index else "" for n in lengths]


def _mi_table(summary, against: str, lengths: list[int]) -> list[str]:
    block = summary[(summary["against"] == against) & summary["path_length"].isin(lengths)]
    if block.empty:
        return [f"(no MI against {against} labels)", ""]
    lines = [
        "| dataset | weight function | " + " | ".join(f"{n} steps" for n in lengths) + " |",
        "|---|---|" + "---|" * len(lengths),
    ]
    for dataset, rows in block.groupby("dataset", sort=False):
        for weight in _order(rows["weight_function"]):
            values = _length_cells(rows[rows["weight_function"] == weight].set_index("path_length"), lengths, _cell)
            lines.append(f"| {dataset} | {_label(weight)} | " + " | ".join(values) + " |")
    if block["weight_function"].isin(CEILINGS).any():
        lines += ["", _CEILING_NOTE.format(names=", ".join(c for c in CEILINGS if c in set(block["weight_function"])))]
    return lines + [""]


def _labelling_note(config: ExperimentConfig) -> list[str]:
    """How Z_p was made, and where the check that it is converged is."""
    label = config.label
    start = f"{label.sweeps} frozen-Φ Gibbs sweeps from random topics"
    if label.warm_sweeps is None:
        how = f"every checkpoint's Z_p is {start}"
    else:
        how = (f"a run's first checkpoint's Z_p is {start}, each later checkpoint {label.warm_sweeps} more sweeps "
               "from the topics the one before left")
    return [
        f"Labels: {how}; Z_b is {label.batch_sweeps} sweeps of the batch model. Each label file records the sweeps "
        "it was made with; whether they were enough is checked under \"Label convergence\"."
    ]


def _convergence_section(convergence, config: ExperimentConfig) -> list[str]:
    """The two-start check of Z_p on this experiment's maps (:func:`~curiosity_cli.evaluate.statistics.label_convergence`)."""
    lines = ["## Label convergence", ""]
    checked = config.label.check_restarts
    if convergence is None or convergence.empty:
        return lines + [
            f"Not checked: no run was labelled twice (label.check_restarts is {checked}). With "
            "`--set label.check_restarts=1`, `curiosity label` labels restart 0 of every map and weight function a "
            "second time from a placed start and this section compares the two chains.", "",
        ]
    failed = convergence[~convergence["converged"].astype(bool)]
    restarts = "restart 0" if checked == 1 else f"restarts 0-{checked - 1}"
    lines += [
        f"Z_p counts as converged when two chains over the same Φ_p, one from uniformly random topics (the labels "
        f"above) and one from a placed start (each word drawn from eq. 5 given the words placed before it, so the "
        f"labels begin smooth instead of as noise), end at the same mean MI: within {CONVERGENCE_TOLERANCE} bits "
        f"or within twice the standard error of their difference. {restarts.capitalize()} of every map and weight "
        f"function {'was' if checked == 1 else 'were'} labelled both ways with the schedule above. Cells: uniform "
        "minus placed, mean ± standard error over those runs; ✗ where the two have not met.", "",
    ]
    lengths = sorted(convergence["path_length"].unique())
    lines += [
        "| dataset | against | " + " | ".join(f"{n} steps" for n in lengths) + " |",
        "|---|---|" + "---|" * len(lengths),
    ]

    def gap(row) -> str:
        sem = "" if not np.isfinite(row["sem"]) else f" ± {row['sem']:.3f}"
        return f"{_signed(row['difference'], 3)}{sem}{'' if row['converged'] else ' ✗'}"

    for (dataset, against), block in convergence.groupby(["dataset", "against"], sort=False):
        cells = _length_cells(block.set_index("path_length"), lengths, gap)
        lines.append(f"| {dataset} | {_TARGETS[against]} | " + " | ".join(cells) + " |")
    lines.append("")
    if failed.empty:
        lines.append("The two chains agree on every map and length: the labels no longer show how their chain started.")
    else:
        worst = failed.loc[failed["difference"].abs().idxmax()]
        lines.append(
            f"The two chains have not met in {len(failed)} of {len(convergence)} cells (largest: {worst['dataset']} "
            f"at {worst['path_length']} steps against {_TARGETS[worst['against']]}, "
            f"{_signed(worst['difference'], 3)} bits): absolute MI there depends on how the labelling chain started, "
            "by about that much. Comparisons between walkers remain like for like, as every run is labelled the "
            "same way. More sweeps narrow it: on the embedded maps, 256 at every checkpoint (`curiosity label "
            "--converged`) brought the two starts together in 35 of 36 cells, at about ten times the labelling time "
            "(docs/GUIDE.md, \"Reproducing the paper\")."
        )
    return lines + [""]


def _effect_cell(row) -> str:
    ci = f" [{_signed(row['ci_low'])}, {_signed(row['ci_high'])}]" if np.isfinite(row["ci_low"]) else ""
    return f"{_signed(row['mean_difference'])}{ci}, {_p(row['p_value'])}"


def _effects_table(effects, lengths: list[int]) -> list[str]:
    """Topic perplexity minus each other walker: mean paired difference [95 % CI], Wilcoxon p."""
    lines = ["## Paired effect sizes", ""]
    block = None if effects is None else effects[effects["path_length"].isin(lengths)]
    if block is None or block.empty:
        return lines + [f"(no paired runs of {HEADLINE_WEIGHT} and another walker)", ""]
    lines += [
        f"MI of {HEADLINE_WEIGHT} minus each other walker's, in bits: the mean paired difference (paired by "
        f"restart) [{100 * CONFIDENCE:.0f} % Student-t CI], and the paired Wilcoxon p. All lengths in `effects.csv`.",
        "",
        "| dataset | against | other walker | " + " | ".join(f"{n} steps" for n in lengths) + " |",
        "|---|---|---|" + "---|" * len(lengths),
    ]
    for dataset, against in itertools.product(dict.fromkeys(block["dataset"]), ("human", "batch")):
        rows = block[(block["dataset"] == dataset) & (block["against"] == against)]
        for other in _order(rows["other"]):
            cells = _length_cells(rows[rows["other"] == other].set_index("path_length"), lengths, _effect_cell)
            lines.append(f"| {dataset} | {against} | {other} | " + " | ".join(cells) + " |")
    return lines + [""]


def _found_length(found_summary) -> int | None:
    """The length "What each walker found" shows: the headline's (:func:`~curiosity_cli.evaluate.headline.headline_length`), else the shortest."""
    if found_summary is None or found_summary.empty:
        return None
    present = set(found_summary["path_length"])
    return headline_length(present) or int(min(present))


def _found_cell(row, digits: int) -> str:
    return f"{row['mean']:.{digits}f} ± {(row['ci_high'] - row['ci_low']) / 2:.{digits}f}".replace("-", _MINUS)


def _found_versus(row, digits: int) -> str:
    ci = f" [{_signed(row['ci_low'], digits)}, {_signed(row['ci_high'], digits)}]" if np.isfinite(row["ci_low"]) else ""
    return f"{_signed(row['mean_difference'], digits)}{ci}, {_p(row['p_value'])}"


def _found_lead(row) -> str:
    if not np.isfinite(row["p_each"]):
        return "n/a"
    return f"{'yes' if row['p_each_holm'] < ALPHA else 'no'} ({_p(row['p_each'])}; Holm: {_p(row['p_each_holm'])})"


def _found_section(evaluation: Evaluation) -> list[str]:
    """Per map: each walker's classes found, mean recall, NMI and AMI, and topic perplexity against each walker on them."""
    from curiosity_cli.evaluate.found import missing_measures
    from curiosity_cli.evaluate.measures import MEASURES, WORDS, read_against

    summary, effects, leads = evaluation.found_summary, evaluation.found_effects, evaluation.found_leads
    length = _found_length(summary)
    lines = [f"## What each walker found{f' at {length} steps' if length else ''}", ""]
    if length is None:
        return lines + ["(no measure but MI in `mi.csv`: evaluate the experiment again to compute them)", ""]
    lines += [
        "MI of the whole map's labelling need not reward a path that finds more (a labeller can set unfamiliar terrain "
        "apart without visiting it), so walkers are compared on what their paths found too, with MI's statistics. "
        f"**Classes found**: human classes the path's cells reached, a class counting in a visited cell when it covers "
        f"at least {CLASS_SHARE_PERCENT} % of the cell's pixels (first steps in `classes.csv`). **Mean recall**: per "
        "class, the share of its pixels whose Z_p topic is the topic matched to the class (one topic a class, the "
        "matching that maximises the recalls' sum; unmatched classes 0), averaged over classes. **NMI**: MI over the "
        "mean of the two labellings' entropies. **AMI**: the same, less the MI labellings of the same class sizes share "
        "by chance (hypergeometric model, over the topics Z_p uses: `topics_used` in `mi.csv`); over a map's pixels "
        "that chance share is small, so AMI sits just below NMI. **Time to first find**: per class, the step the "
        "path first reached it, a class not reached by the length counting the length (censored there: the restricted "
        "mean), averaged over classes; lower is better. **MI where the path went** and **where it did not**: MI "
        "over the pixels whose word lies in a cell the path had visited (words Φ_p holds) and over the rest of the "
        "map, which tells a model that labels only what it saw from one that carries to unseen terrain (each part's "
        "MI is bounded by the entropy of the classes it holds). **Held-out log-likelihood** (bits per word, against no "
        "labelling): each cell's words split once per map into an observed half and a held-out half, the same for every "
        "walker; with Φ_p frozen, a chain over the observed words gives each cell a topic mixture (the topics of its and "
        "its neighbours' observed words, plus α), and each held-out word scores log2 of its probability under that "
        "mixture of Φ_p's topics; over every cell, and over the cells the path did not visit, whose words Φ_p never "
        "held (a uniform model scores log2(1/V)). Each walker: mean over restarts ± "
        f"{100 * CONFIDENCE:.0f} % CI half-width; topic perplexity minus each walker: mean paired difference "
        f"[{100 * CONFIDENCE:.0f} % CI], paired Wilcoxon p; \"leads each\": better than every walker with p < {ALPHA} against "
        "each (the intersection-union p), read after Holm's correction over the maps. Against human labels, or Z_b on "
        "a map without them. Every length in `found_summary.csv`, `found_effects.csv` and `found_leads.csv`.",
        "",
    ]
    lacking = missing_measures(evaluation.mi)
    if lacking:
        lines += [f"Not in `mi.csv` (made before they existed; evaluate again): {', '.join(m.title for m in lacking)}.", ""]
    shown = [m for m in MEASURES if m.found and m not in lacking]
    summary = summary[summary["path_length"] == length]
    for dataset in dict.fromkeys(summary["dataset"]):
        block = summary[summary["dataset"] == dataset]
        against = read_against(block["against"])
        read = [against, WORDS]  # a measure of no labelling beside those of the map's labelling
        block = block[block["against"].isin(read)]
        measures = [m for m in shown if (block["measure"] == m.name).any()]
        classes = evaluation.mi.loc[evaluation.mi["dataset"] == dataset, "classes"].max()
        titles = [
            f"{m.title} (of {int(classes)})" if m.name == "classes_found" else f"{m.title} ({m.unit})" if m.unit else m.title
            for m in measures
        ]
        held_out = " and its held-out words" if any(WORDS in m.columns for m in measures) else ""
        lines += [f"**{dataset}** (against {_TARGETS[against]}{held_out}):", "", "| | " + " | ".join(titles) + " |",
                  "|---|" + "---|" * len(measures)]
        for weight in _order(block["weight_function"]):
            rows = block[block["weight_function"] == weight].set_index("measure")
            lines.append(f"| {_label(weight)} | " + " | ".join(
                _found_cell(rows.loc[m.name], m.digits) if m.name in rows.index else "" for m in measures) + " |")
        versus = effects[(effects["dataset"] == dataset) & (effects["path_length"] == length) & effects["against"].isin(read)]
        for other in _order(versus["other"]):
            rows = versus[versus["other"] == other].set_index("measure")
            lines.append(f"| {HEADLINE_WEIGHT} {_MINUS} {other} | " + " | ".join(
                _found_versus(rows.loc[m.name], m.digits) if m.name in rows.index else "" for m in measures) + " |")
        lead = leads[(leads["dataset"] == dataset) & (leads["path_length"] == length) & leads["against"].isin(read)]
        if not lead.empty:
            rows = lead.set_index("measure")
            lines.append("| leads each | " + " | ".join(
                _found_lead(rows.loc[m.name]) if m.name in rows.index else "" for m in measures) + " |")
        lines += ["", *_class_times(evaluation.found_classes, dataset, length)]
    return lines


def _class_times(found_classes, dataset: str, length: int) -> list[str]:
    """A map's time to first find of each class: topic perplexity's, and its paired difference to each walker."""
    if found_classes is None:
        return []
    block = found_classes[(found_classes["dataset"] == dataset) & (found_classes["path_length"] == length)]
    if block.empty:
        return []
    others = _order(block["other"])
    lines = [
        f"Time to first find of each class (steps, restricted to {length}; in brackets the share of restarts that "
        f"found it), {HEADLINE_WEIGHT}'s and its paired difference to each walker [95 % CI], p (`found_classes.csv`):",
        "",
        f"| class | {HEADLINE_WEIGHT} | " + " | ".join(f"{_MINUS} {o}" for o in others) + " |",
        "|---|---|" + "---|" * len(others),
    ]
    for class_id, rows in block.groupby("class_id", sort=True):
        rows = rows.set_index("other")
        first = rows.iloc[0]
        name = f"{first['class_name']} ({class_id})" if isinstance(first["class_name"], str) and first["class_name"] else str(class_id)
        cells = [
            f"{_found_versus(rows.loc[o], 1)} ({100 * rows.loc[o, 'other_found']:.0f} %)" if o in rows.index else ""
            for o in others
        ]
        lines.append(
            f"| {name} | {first['topic_perplexity_steps']:.1f} ({100 * first['topic_perplexity_found']:.0f} %) | "
            + " | ".join(cells) + " |"
        )
    return lines + [""]


def _significance(tests) -> list[str]:
    block = tests[(tests["against"] == "human") & ((tests["a"] == HEADLINE_WEIGHT) | (tests["b"] == HEADLINE_WEIGHT))]
    if block.empty:
        return ["(no paired tests against human labels)", ""]
    lines = [
        f"Wilcoxon signed-rank tests of {HEADLINE_WEIGHT} against each other walker, "
        "paired by restart (shared start cells), MI against human labels; p < 0.05 in bold.",
        "",
        "| dataset | other | " + " | ".join(f"{n}" for n in sorted(block["path_length"].unique())) + " |",
        "|---|---|" + "---|" * block["path_length"].nunique(),
    ]
    for (dataset, a, b), rows in block.groupby(["dataset", "a", "b"], sort=False):
        other = b if a == HEADLINE_WEIGHT else a
        cells = []
        for _, r in rows.sort_values("path_length").iterrows():
            sign = "+" if (r["median_difference"] > 0) == (a == HEADLINE_WEIGHT) else _MINUS
            p = r["p_value"]
            text = "n/a" if not np.isfinite(p) else f"{sign} p<0.001" if p < 0.001 else f"{sign} p={p:.3f}"
            cells.append(f"**{text}**" if p < ALPHA else text)
        lines.append(f"| {dataset} | {other} | " + " | ".join(cells) + " |")
    short = block[block["path_length"] <= _SHORT]
    significant = short[short["p_value"] < ALPHA]
    most = int(short["n"].max()) if not short.empty and np.isfinite(short["n"].max()) else 0
    if not significant.empty:
        finding = f"{len(significant)} of {len(short)} pairs differ at p < 0.05 (the paper reports no difference)."
    elif smallest_wilcoxon_p(most) >= ALPHA:
        finding = (
            f"no pair differs at p < 0.05, but with {most} pairs or fewer no test could: the smallest p of "
            f"{most} pairs is {smallest_wilcoxon_p(most):.2g}. This says nothing about the paper's finding."
        )
    else:
        finding = "no pair differs at p < 0.05, as the paper reports."
    lines += [
        "",
        f"(+: {HEADLINE_WEIGHT} higher by the median paired difference.) At {_SHORT} steps or fewer, " + finding,
        "",
    ]
    return lines


def _headline_table(top) -> list[str]:
    lines = [
        "## Headline",
        "",
        f"Mean MI of {HEADLINE_WEIGHT} exploration at {HEADLINE_LENGTH} steps, or a map's longest path below it "
        "(steps), against human labels, or Z_b on a map without them, divided by the next best walker's; the ratio "
        "walkers that do not differ give (topic perplexity permuted with the walkers that could equal it, the random "
        "walk left out: null median, its 95 % band, and the share of permutations at least as high: null p); the "
        "mean paired difference to the next best with its 95 % CI; whether it beats every walker (a higher mean and "
        "p < 0.05 against each: that p, and Holm's adjustment of it for the experiment's maps, which the verdict "
        "reads); its share of the better ceiling's MI:",
        "",
    ]
    if top.empty:
        return lines + [
            f"(no checkpoint of {HEADLINE_LENGTH} steps or fewer with {HEADLINE_WEIGHT} and another walker: no headline "
            "ratio)", "",
        ]
    lines += [
        "| dataset | steps | against | ratio | null median [95 %], null p | next best | difference (95 % CI) | paired "
        "Wilcoxon p (pairs) | beats every walker: p; Holm | share of ceiling | paper's map | paper's ratio |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in top.to_dict("records"):
        paper = f"{r['paper_ratio']:.2f}" if np.isfinite(r["paper_ratio"]) else ""
        p = "" if not np.isfinite(r["p_value"]) else ("< 0.001" if r["p_value"] < 0.001 else f"{r['p_value']:.3f}")
        diff = ""
        if np.isfinite(r["mean_difference"]):
            diff = _signed(r["mean_difference"])
            if np.isfinite(r["ci_low"]):
                diff += f" ({_signed(r['ci_low'])} to {_signed(r['ci_high'])})"
        share = f"{100 * r['ceiling_share']:.0f} % of {r['best_ceiling']}" if np.isfinite(r["ceiling_share"]) else ""
        null = (
            f"{r['null_no_rw_median']:.2f} [{r['null_no_rw_low']:.2f}, {r['null_no_rw_high']:.2f}], "
            f"{_p(r['null_no_rw_p'])}" if np.isfinite(r.get("null_no_rw_median", np.nan)) else ""
        )
        beats = "yes" if r["beats_all"] else "no"
        if np.isfinite(r.get("p_each", np.nan)):
            beats += f": {_p(r['p_each'])}; Holm {_p(r['p_each_holm'])}"
        lines.append(
            f"| {r['dataset']} | {int(r['path_length'])} | {r['against']} | {r['ratio']:.2f} | {null} | {r['next_best']} | {diff} | {p} ({r['pairs']}) | "
            f"{beats} | {share} | {_text(r['paper_map'])} | {paper} |"
        )
    return lines + [""]


def _maps_table(maps) -> list[str]:
    """Each map's words and ORB share beside the paper's map it stands in for (Table 1)."""
    from curiosity_cli.paper import PAPER_MAPS

    if maps is None or maps.empty:
        return []
    lines = [
        "## The maps",
        "",
        "Visual words per map, and the share of ORB words, beside the paper's map each stands in for "
        "(the paper's share is implied by its Table 1 with a texton word at every pixel, every 2nd on "
        "SouthBellairs):",
        "",
        "| dataset | cells | words | ORB share | paper's map | paper's words | paper's ORB share |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in maps.itertuples():
        paper = PAPER_MAPS.get(r.stands_in_for) if isinstance(r.stands_in_for, str) else None
        theirs = f"| {paper.name} | {paper.words:,} | {100 * paper.orb_share:.0f} % |" if paper else "| | | |"
        lines.append(f"| {r.dataset} | {r.cells:,} | {r.words:,} | {100 * r.orb_share:.1f} % {theirs}")
    return lines + [""]


def _revisits_section(revisits, lengths: list[int], config: ExperimentConfig) -> list[str]:
    """Distinct cells, steps onto visited cells and boxed-in steps per walker (mean ± 95 % CI half-width)."""
    if revisits is None or revisits.empty:
        return []
    lines = [
        "## Revisits",
        "",
        f"Eq. 8 read as `{config.explore.coverage}` (`explore.coverage`; docs/GUIDE.md, \"Readings of eq. 8\"). Per walker "
        "and path length L: the distinct cells the path saw, its steps onto a cell seen before (L minus distinct "
        "cells) and its moves made with every neighbour visited (boxed in); mean ± 95 % CI half-width over "
        "restarts. A walker ahead on MI with fewer distinct cells saw better cells, not more of them "
        "(figure `mi-vs-distinct`).",
        "",
    ]
    measures = {"distinct_cells": "distinct", "revisit_steps": "revisits", "boxed_in_steps": "boxed in"}
    for dataset, block in revisits.groupby("dataset", sort=False):
        header = [f"{measures[m]} at {n}" for n in lengths for m in measures]
        lines += [f"{dataset}:", "", f"| walker | {' | '.join(header)} |", "|---" * (len(header) + 1) + "|"]
        cells = {(r["weight_function"], r["path_length"], r["measure"]): r for r in block.to_dict("records")}
        for name in _order(block["weight_function"]):
            row = [
                (f"{cells[k]['mean']:.1f} ± {(cells[k]['ci_high'] - cells[k]['ci_low']) / 2:.1f}" if k in cells else "")
                for n in lengths for m in measures for k in [(name, n, m)]
            ]
            lines.append(f"| {_label(name)} | {' | '.join(row)} |")
        lines.append("")
    return lines


def _mechanism_section(mechanism, lengths: list[int]) -> list[str]:
    """Per map and walker at the headline's length (else the shortest), whether surprise pointed at what is new
    (:mod:`~curiosity_cli.evaluate.mechanism`): M1-M5 pooled over restarts, in two tables."""
    from curiosity_cli.evaluate.mechanism import summarise_mechanism

    if mechanism is None or mechanism.empty:
        return []
    length = headline_length(lengths) or min(lengths)
    summary = summarise_mechanism(mechanism)
    summary = summary[summary["path_length"] == length]
    if summary.empty:
        return []
    lines = [
        "## Does surprise point at what is new?",
        "",
        f"Per map and walker at {length} steps (`mechanism.csv` has every run and length). **M1** the within-step "
        "AUC of the walker's score (its own perplexity; topic perplexity's for walkers without one) for the "
        "candidates holding a human class new to the path against the other unvisited candidates (0.5: it cannot "
        "tell them apart); **M2** the share of moves with such a candidate, and of candidates holding one; **M3** "
        "the chance the walker put on them beyond stochastic coverage's, at those moves; **M4** the cells it "
        "entered that held a class new to the path, and the classes it found; **M5** the share of its candidates "
        "with infinite topic perplexity, and the share holding a word id the path had not seen among those and "
        "among the finite ones. The AUCs and the ties are pooled over every restart's pairs (all wins over all "
        "pairs), with a 95 % interval clustered by restart (delta method); the rest are means over restarts. "
        "Empty: undefined, or not in a `mechanism.csv` written before the measure existed.",
        "",
        "A candidate holding a new class mostly lies on a boundary and so holds two textures, while most of M1's "
        "other candidates hold one: a score high on any mixed cell beats those without telling what is new. "
        "**Against mixed texture** compares the same candidates only with unvisited ones holding two or more "
        "classes, all seen before: near 0.5 there, M1's AUC is heterogeneity, not novelty. **Tied at ∞** is the "
        "share of M1's pairs where both scores were infinite, each counted half a win: an AUC near 0.5 made of "
        "them says the score could not rank at all. M2 per candidate compares experiments offering different "
        "numbers of candidates per move.",
        "",
        "| map | walker | M1 AUC | M1 against mixed texture | M1 tied at ∞ | M2 moves | M2 candidates | M3 gain |",
        "|---|---|---|---|---|---|---|---|",
    ]
    records = summary.to_dict("records")
    for r in records:
        cells = [
            _with_interval(r, "auc"), _with_interval(r, "auc_mixed"), number(r["infinite_ties"]),
            number(r["opportunity"]), number(r["new_share"]), number(r["gain"], 3),
        ]
        lines.append(f"| {r['dataset']} | {_label(r['weight_function'])} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "M5's unseen words among the finite candidates are the base rate for those among the infinite ones: next "
        "to a short path most cells hold a word it has not seen, and only if the infinite ones hold one clearly "
        "more often does infinite topic perplexity mark word novelty (which need not be class novelty).",
        "",
        "| map | walker | M4 new-class cells | M4 classes found | M5 infinite | M5 unseen words, infinite "
        "| M5 unseen words, finite |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in records:
        cells = [
            number(r["new_class_cells"], 1), number(r["classes_found"], 1), number(r["infinite_share"]),
            number(r["infinite_unseen"]), number(r["finite_unseen"]),
        ]
        lines.append(f"| {r['dataset']} | {_label(r['weight_function'])} | " + " | ".join(cells) + " |")
    return lines + [""]


def _with_interval(row: Mapping, measure: str) -> str:
    """A summary's measure with its 95 % interval in brackets; the interval left out where undefined."""
    low, high = number(row[f"{measure}_low"]), number(row[f"{measure}_high"])
    return number(row[measure]) + (f" [{low}, {high}]" if low and high else "")


def number(value, digits: int = 2) -> str:
    """A number for a table: ``digits`` decimals, empty for NaN or nothing."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        return ""
    return f"{value:.{digits}f}" if value == value else ""


def p_text(value) -> str:
    """A p-value for a table: 3 decimals, ``< 0.001`` below that."""
    text = number(value, 3)
    return "< 0.001" if text and float(value) < 0.001 else text


def _steering_section(steering, lengths: list[int]) -> list[str]:
    """Per map and walker, the mean steering at the headline's length (else the shortest),
    with what it means (:mod:`~curiosity_cli.evaluate.steering`)."""
    from curiosity_cli.evaluate.statistics import summarise_steering

    if steering is None or steering.dropna(subset=["steering"]).empty:
        return []
    length = headline_length(lengths) or min(lengths)
    summary = summarise_steering(steering)
    summary = summary[summary["path_length"] == length]
    if summary.empty:
        return []
    walkers = _order(summary["weight_function"])
    lines = [
        "## Steering",
        "",
        f"How strongly each walker's moves depended on its weights: at every move of a path of {length} steps, the "
        "total-variation distance between the walker's chances of stepping to each neighbour and stochastic "
        "coverage's chances on the same neighbours, averaged over the moves; mean ± 95 % CI half-width over "
        "restarts (`steering.csv` has every run and length). 0 means the walker stepped exactly as stochastic "
        "coverage would have: its perplexities changed no move. Random walk, which ignores coverage, shows how far "
        "from coverage a walker can get on these paths; a perplexity walker close to 0 and far below random walk "
        "is stochastic coverage in all but name, and a reading that leaves this number unchanged cannot explain a "
        "change in its MI.",
        "",
        f"| map | {' | '.join(_label(w) for w in walkers)} |",
        "|---" * (len(walkers) + 1) + "|",
    ]
    for dataset, block in summary.groupby("dataset", sort=False):
        cells = {r["weight_function"]: r for r in block.to_dict("records")}
        row = [
            f"{cells[w]['mean']:.3f} ± {(cells[w]['ci_high'] - cells[w]['ci_low']) / 2:.3f}" if w in cells else ""
            for w in walkers
        ]
        lines.append(f"| {dataset} | {' | '.join(row)} |")
    return lines + [""]


def _short_means(mi, restarts: int) -> list[str]:
    """A note per (dataset, weight function) whose means are over fewer runs than the configured ``restarts``."""
    counts = mi.groupby(["dataset", "weight_function"], sort=True)["restart"].nunique()
    return [
        f"{dataset} / {name}: means over {n} of {restarts} restarts"
        for (dataset, name), n in counts.items() if n < restarts
    ]


def write_report(
    folder: Path, config: ExperimentConfig, evaluation: Evaluation, figures: list[Path], figure_notes: list[str],
    seconds: dict[str, float], provenance: dict, shared: dict | None = None,
) -> Path:
    """Write ``folder/REPORT.md`` and return its path (``plot`` does, after the figures).

    ``figure_notes`` says which figures were left out and why (from ``write_figures``);
    ``seconds`` the seconds of each stage and their total, empty when none were recorded;
    ``shared`` what the last ``label`` took from other experiments (``shared.json``), None if not recorded.
    """
    summary, tests, top = evaluation.summary, evaluation.tests, evaluation.headline
    # the lengths the paper discusses: 80 (about a map's width) and the longest
    present = set(summary["path_length"])
    lengths = sorted({n for n in (HEADLINE_LENGTH,) if n in present} | {int(max(present))})
    names = config.explore.weight_functions
    walkers = [n for n in names if n not in CEILINGS]
    ceilings = [n for n in names if n in CEILINGS]
    lines = [
        f"# Curiosity-driven exploration: experiment `{config.name}`",
        "",
        f"Reproduction of Girdhar & Dudek's 2-D map experiments (section 5.1) on {len(config.datasets)} map(s): "
        f"{len(walkers)} walkers{f' and {len(ceilings)} ceilings' if ceilings else ''}, {config.explore.restarts} "
        f"restarts, paths of up to {config.explore.path_length} steps, seed {config.seed}, eq. 8 read as "
        f"`{config.explore.coverage}`.",
        "",
    ]
    lines += _verdicts(summary, top, evaluation.effects, config.explore.coverage)
    lines += _headline_table(top)
    lines += _maps_table(evaluation.maps)
    lines += ["## Mutual information (bits, mean ± 95 % CI half-width)", "", *_labelling_note(config), "",
              "Against human labels (paper Fig. 5):", ""]
    lines += _mi_table(summary, "human", lengths)
    lines += ["Against the batch labeling Z_b (paper Fig. 4):", ""]
    lines += _mi_table(summary, "batch", lengths)
    lines += _revisits_section(evaluation.revisits, lengths, config)
    lines += _steering_section(evaluation.steering, lengths)
    lines += _mechanism_section(evaluation.mechanism, lengths)
    lines += _convergence_section(evaluation.convergence, config)
    lines += _effects_table(evaluation.effects, lengths)
    lines += _found_section(evaluation)
    lines += ["## Significance", ""] + _significance(tests)
    left_out = [*_short_means(evaluation.mi, config.explore.restarts), *evaluation.skipped, *figure_notes]
    if left_out:
        lines += ["## Left out", "", *[f"- {note}" for note in left_out], ""]
    lines += ["## Figures", ""]
    for path in figures:
        if Path(path).suffix == ".png":
            relative = os.path.relpath(path, folder)
            lines += [f"![{Path(path).stem}]({relative})", ""]
    lines += ["## Time", ""]
    if seconds:
        lines += ["| stage | seconds |", "|---|---|"]
        lines += [f"| {stage} | {value:.0f} |" for stage, value in seconds.items()] + [""]
    else:
        lines += ["Not recorded (the stages ran before their times were kept).", ""]
    if shared is not None:
        lines += [
            f"The last `label` that labelled anything took {shared['labels']} of its {shared['labelled']} label files and "
            f"{shared['batches']} batch references from other experiments that had computed them from the same inputs "
            "(the cache's `shared/` items: the same bytes; `label --no-reuse` computes them).", "",
        ]
    lines += [
        "## Config",
        "",
        f"Commit `{provenance.get('git_commit', 'unknown')}`{' (with uncommitted changes)' if provenance.get('git_dirty') else ''}, "
        f"curiosity {provenance.get('curiosity')}; {config.explore.samples_per_step:,} word samples of refinement per step.",
        "",
        "```yaml", to_yaml(config).rstrip(), "```", "",
    ]
    path = ExperimentFolder(folder).report
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines))
    return path
