"""``REPORT.md``: one experiment's result, as a reader of the paper would want to check it."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from curiosity_cli.config import ExperimentConfig, to_yaml
from curiosity_cli.evaluate.tables import HEADLINE_LENGTH, HEADLINE_WEIGHT, Evaluation
from curiosity_cli.files import atomic_path

# the paper: "For short path lengths (40 steps or less), we do not see any statistical difference"
_SHORT = 40
_ALPHA = 0.05


def _cell(row) -> str:
    return f"{row['mean']:.3f} ± {(row['ci_high'] - row['ci_low']) / 2:.3f}"


def _mi_table(summary, against: str, lengths: list[int]) -> list[str]:
    block = summary[(summary["against"] == against) & summary["path_length"].isin(lengths)]
    if block.empty:
        return [f"(no MI against {against} labels)", ""]
    lines = [
        "| dataset | weight function | " + " | ".join(f"{n} steps" for n in lengths) + " |",
        "|---|---|" + "---|" * len(lengths),
    ]
    for (dataset, weight), rows in block.groupby(["dataset", "weight_function"], sort=False):
        by_length = rows.set_index("path_length")
        values = [_cell(by_length.loc[n]) if n in by_length.index else "" for n in lengths]
        lines.append(f"| {dataset} | {weight} | " + " | ".join(values) + " |")
    return lines + [""]


def _significance(tests) -> list[str]:
    block = tests[(tests["against"] == "human") & ((tests["a"] == HEADLINE_WEIGHT) | (tests["b"] == HEADLINE_WEIGHT))]
    if block.empty:
        return ["(no paired tests against human labels)", ""]
    lines = [
        f"Wilcoxon signed-rank tests of {HEADLINE_WEIGHT} against each other weight function, "
        "paired by restart (shared start cells), MI against human labels; p < 0.05 in bold.",
        "",
        "| dataset | other | " + " | ".join(f"{n}" for n in sorted(block["path_length"].unique())) + " |",
        "|---|---|" + "---|" * block["path_length"].nunique(),
    ]
    for (dataset, a, b), rows in block.groupby(["dataset", "a", "b"], sort=False):
        other = b if a == HEADLINE_WEIGHT else a
        cells = []
        for _, r in rows.sort_values("path_length").iterrows():
            sign = "+" if (r["median_difference"] > 0) == (a == HEADLINE_WEIGHT) else "−"
            p = r["p_value"]
            text = "n/a" if not np.isfinite(p) else f"{sign} p<0.001" if p < 0.001 else f"{sign} p={p:.3f}"
            cells.append(f"**{text}**" if p < _ALPHA else text)
        lines.append(f"| {dataset} | {other} | " + " | ".join(cells) + " |")
    short = block[block["path_length"] <= _SHORT]
    significant = short[short["p_value"] < _ALPHA]
    lines += [
        "",
        f"(+: {HEADLINE_WEIGHT} higher by the median paired difference.) At {_SHORT} steps or fewer, "
        + (
            "no pair differs at p < 0.05, as the paper reports."
            if significant.empty
            else f"{len(significant)} of {len(short)} pairs differ at p < 0.05 (the paper reports no difference)."
        ),
        "",
    ]
    return lines


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


def write_report(
    folder: Path, config: ExperimentConfig, evaluation: Evaluation, figures: list[Path], figure_notes: list[str],
    seconds: dict[str, float], provenance: dict,
) -> Path:
    """Write ``folder/REPORT.md`` and return its path.

    ``figure_notes`` says which figures were left out and why (from ``write_figures``).
    """
    summary, tests, top = evaluation.summary, evaluation.tests, evaluation.headline
    # the lengths the paper discusses: 80 (about a map's width) and the longest
    present = set(summary["path_length"])
    lengths = sorted({n for n in (HEADLINE_LENGTH,) if n in present} | {int(max(present))})
    lines = [
        f"# Curiosity-driven exploration: experiment `{config.name}`",
        "",
        f"Reproduction of Girdhar & Dudek's 2-D map experiments (section 5.1): {len(config.datasets)} map(s), "
        f"{len(config.explore.weight_functions)} weight functions, {config.explore.restarts} restarts, "
        f"paths of up to {config.explore.path_length} steps, {config.explore.samples_per_step:,} word samples of "
        f"refinement per step, seed {config.seed}. Commit `{provenance.get('git_commit', 'unknown')}`"
        f"{' (with uncommitted changes)' if provenance.get('git_dirty') else ''}, curiosity {provenance.get('curiosity')}.",
        "",
        "## Headline",
        "",
        f"Mean MI of {HEADLINE_WEIGHT} exploration against human labels at {HEADLINE_LENGTH} steps, "
        "divided by the next best weight function's:",
        "",
    ]
    if top.empty:
        lines += [f"(no human labels or no {HEADLINE_LENGTH}-step checkpoint: no headline ratio)", ""]
    else:
        lines += [
            "| dataset | ratio | next best | paired Wilcoxon p (pairs) | paper's map | paper's ratio |",
            "|---|---|---|---|---|---|",
        ]
        for r in top.itertuples():
            paper = f"{r.paper_ratio:.2f}" if np.isfinite(r.paper_ratio) else ""
            p = "" if not np.isfinite(r.p_value) else ("< 0.001" if r.p_value < 0.001 else f"{r.p_value:.3f}")
            lines.append(f"| {r.dataset} | {r.ratio:.2f} | {r.next_best} | {p} ({r.pairs}) | {r.paper_map} | {paper} |")
        lines.append("")
    lines += _maps_table(evaluation.maps)
    lines += ["## Mutual information (bits, mean ± 95 % CI half-width)", "", "Against human labels (paper Fig. 5):", ""]
    lines += _mi_table(summary, "human", lengths)
    lines += ["Against the batch labeling Z_b (paper Fig. 4):", ""]
    lines += _mi_table(summary, "batch", lengths)
    lines += ["## Significance", ""] + _significance(tests)
    left_out = [*evaluation.skipped, *figure_notes]
    if left_out:
        lines += ["## Left out", "", *[f"- {note}" for note in left_out], ""]
    lines += ["## Figures", ""]
    for path in figures:
        if Path(path).suffix == ".png":
            relative = os.path.relpath(path, folder)
            lines += [f"![{Path(path).stem}]({relative})", ""]
    lines += ["## Time", "", "| stage | seconds |", "|---|---|"]
    lines += [f"| {stage} | {value:.0f} |" for stage, value in seconds.items()] + [""]
    lines += ["## Config", "", "```yaml", to_yaml(config).rstrip(), "```", ""]
    path = Path(folder) / "REPORT.md"
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines))
    return path
