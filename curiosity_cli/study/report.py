"""A sweep's report: ``SWEEP.md``, ``sweep.csv`` and ``sensitivity.csv`` (:mod:`curiosity_cli.study.sweep` runs it).

``SWEEP.md`` opens with how to run the sweep again, then the study's declared hypotheses, each
confirmed or not (:mod:`curiosity_cli.study.hypotheses`, ``hypotheses.csv``), then, for a study that declares
specifications (:mod:`curiosity_cli.study.specifications`), the specification curve; else the
sensitivity table, which pools the seeds of each treatment (:func:`pool_treatments`);
then every combination's headline. ``sweep.csv`` has a row per combination and dataset,
``sensitivity.csv`` a row per treatment and dataset, the seeds pooled.

Seeds are replicates, not treatments: the combinations that differ only in ``seed``
(:data:`REPLICATE_KEY`) are pooled into one headline
(:func:`curiosity_cli.evaluate.replicates.pool`), once per treatment, and every table
that shows a treatment's numbers reads them from that one pooling.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from curiosity_cli.config import PAPER_WALKERS
from curiosity_cli.evaluate.report import number, p_text
from curiosity_cli.evaluate.specification_curve import DISTINCT_WALKERS
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.files import atomic_path, display_path
from curiosity_cli.study.types import REPLICATE_KEY, Outcome, Sweep, Treatment, count

#: The headline columns, as ``headline.csv`` has them (:func:`curiosity_cli.evaluate.headline.headline`).
HEADLINE_COLUMNS = (
    "dataset", "topic_perplexity", "next_best", "next_best_mi", "ratio", "p_value", "pairs", "paper_map", "paper_ratio",
    "ratio_ci_low", "ratio_ci_high", "detectable_ratio", "pairs_for_lead",
)


def read_headline(folder: Path):
    """An experiment's ``headline.csv`` as a DataFrame (empty, with its columns, if absent).

    Parameters
    ----------
    folder : Path
        An experiment folder.

    Returns
    -------
    pandas.DataFrame
        The columns of :data:`HEADLINE_COLUMNS`.
    """
    import pandas as pd

    from curiosity_cli.evaluate.tables import read_table

    text = {"dataset": str, "next_best": str, "paper_map": str}  # an empty paper_map stays ""
    numbers = {column: [""] for column in HEADLINE_COLUMNS if column not in text}
    return read_table(
        ExperimentFolder(folder).table("headline"), absent=pd.DataFrame(columns=list(HEADLINE_COLUMNS)), dtype=text,
        keep_default_na=False, na_values=numbers,
    )


def write_sweep_report(
    sweep: Sweep, folder: Path, outcomes: Sequence[Outcome], record: Path | None = None, measure: str = "mi",
) -> Path:
    """Write ``SWEEP.md``, ``sweep.csv`` and ``sensitivity.csv`` from the combinations' tables (module docstring).

    A study that declares specifications also gets its specification curve
    (:func:`curiosity_cli.study.curve.specification_lead`: ``specifications.csv`` and
    the figure), which SWEEP.md leads with in place of the sensitivity table: the same
    pooled numbers, in the same rows, and more. Every treatment's seeds are pooled once
    (:func:`pool_treatments`), over the paper's walkers only in a study.

    Parameters
    ----------
    sweep : Sweep
    folder : Path
        The sweep's folder; each combination's experiment folder is in it.
    outcomes : sequence of Outcome
        One per combination run, in product order.
    record : Path, optional
        The study's record the sweep kept (:mod:`curiosity_cli.study.record`).
    measure : str
        A study's curve of this measure too (:func:`~curiosity_cli.study.curve.specification_lead`).

    Returns
    -------
    Path
        ``SWEEP.md``.
    """
    import pandas as pd

    from curiosity_cli.evaluate.headline import HEADLINE_LENGTH, HEADLINE_WEIGHT
    from curiosity_cli.study.curve import specification_lead
    from curiosity_cli.study.specifications import study_size

    folder = Path(folder)
    keys = sweep.keys
    treatments = pool_treatments(sweep, outcomes, PAPER_WALKERS if sweep.specifications else None)
    sensitivity, pooled_rows = _sensitivity(sweep, treatments)
    # a study's curve has the sensitivity table's rows and numbers, and more: it takes its place
    lead = specification_lead(sweep, folder, treatments, measure) if sweep.specifications else sensitivity
    lead = _hypotheses(sweep, folder, outcomes, record) + lead
    rows, sections = [], []
    overview = [
        "| # | " + " | ".join(keys) + " | dataset | ratio | next best | paired Wilcoxon p (pairs) | paper's ratio |",
        "|---|" + "---|" * len(keys) + "---|---|---|---|---|",
    ]
    for outcome in outcomes:
        c = outcome.combination
        values = [text.split("=", 1)[1] for text in c.overrides]
        cells = " | ".join(f"`{v}`" for v in values)
        link = f"{c.index} (recorded)" if outcome.taken else f"[{c.index}]({c.name}/REPORT.md)"
        sections += [f"## {c.index}. {c.label}", ""]
        if outcome.error is not None:
            overview.append(f"| {c.index} | {cells} | failed | | | | |")
            sections += [f"Failed: {outcome.error}", ""]
            continue
        top = read_headline(outcome.tables)
        sections += [
            f"Taken from the record `{display_path(outcome.tables)}/`: its tables, not computed again "
            "(runs and label files are not kept there)." if outcome.taken else
            f"Folder `{c.name}/`, report [{c.name}/REPORT.md]({c.name}/REPORT.md), {outcome.seconds:.0f} s.", "",
        ]
        for row in top.to_dict("records") or [dict.fromkeys(HEADLINE_COLUMNS)]:
            rows.append({"combination": c.index, "folder": c.name, **dict(zip(keys, values)), **row})
        if top.empty:
            overview.append(f"| {link} | {cells} | (no headline) | | | | |")
            sections += [
                f"(no checkpoint of {HEADLINE_LENGTH} steps or fewer with {HEADLINE_WEIGHT} and another walker: "
                "no headline ratio)", "",
            ]
            continue
        sections += [
            "| dataset | topic perplexity MI | next best | its MI | ratio | paired Wilcoxon p | pairs | paper's map | paper's ratio |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for r in top.itertuples():
            overview.append(
                f"| {link} | {cells} | {r.dataset} | {number(r.ratio)} | {r.next_best} | "
                f"{p_text(r.p_value)} ({r.pairs}) | {number(r.paper_ratio)} |"
            )
            sections.append(
                f"| {r.dataset} | {number(r.topic_perplexity, 3)} | {r.next_best} | {number(r.next_best_mi, 3)} | "
                f"{number(r.ratio)} | {p_text(r.p_value)} | {r.pairs} | {r.paper_map} | {number(r.paper_ratio)} |"
            )
        sections += ["", *_distinct_table(_read_revisits(outcome.tables))]
    sets = ", ".join(f"`--set {s}`" for s in sweep.sets) or "none"
    taken = sum(outcome.taken for outcome in outcomes)
    kept = [
        f"Record `{display_path(record)}`: {taken} of {count(len(outcomes), 'combination')} taken from it (their tables, "
        "recorded earlier: not computed again), the others computed here and recorded there as each finished.", "",
    ] if record is not None else []
    lines = [
        f"# Specification curve of `{sweep.name}`: {study_size(sweep)} ({count(len(outcomes), 'combination')})"
        if sweep.specifications else f"# Parameter sweep of `{sweep.name}`: {count(len(outcomes), 'combination')}",
        "",
        f"Config `{display_path(sweep.config_path)}`; --set: {sets}. Each combination is an experiment folder "
        f"here, named by its values (`sweep.yaml` lists them). The headline is the mean MI of {HEADLINE_WEIGHT} "
        f"exploration against human labels at {HEADLINE_LENGTH} steps (or a map's longest path below it) over the "
        "next best weight function's.",
        "",
        *kept,
        "Run again (finished runs and labels are kept):",
        "",
        "```console",
        f"$ {sweep.command(folder.parent, record)}",
        "```",
        "",
        *lead,
        "## Headlines",
        "",
        *overview,
        "",
        *sections,
    ]
    columns = ["combination", "folder", *keys, *HEADLINE_COLUMNS]
    with atomic_path(folder / "sweep.csv") as tmp:
        pd.DataFrame(rows, columns=columns).to_csv(tmp, index=False)
    pooled_columns = [
        *(key for key in keys if key != REPLICATE_KEY), "seeds", *HEADLINE_COLUMNS,
        *(f"distinct_{w}" for w in DISTINCT_WALKERS),
    ]
    with atomic_path(folder / "sensitivity.csv") as tmp:
        pd.DataFrame(pooled_rows, columns=pooled_columns).to_csv(tmp, index=False)
    path = folder / "SWEEP.md"
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines))
    return path


def _hypotheses(sweep: Sweep, folder: Path, outcomes: Sequence[Outcome], record: Path | None) -> list[str]:
    """Write ``hypotheses.csv`` and return the section SWEEP.md leads with, for a study that declares hypotheses."""
    from curiosity_cli.study.hypotheses import TABLE, hypothesis_lines, hypothesis_table

    if not sweep.hypotheses:
        return []
    table, declared = hypothesis_table(sweep, outcomes, record)
    with atomic_path(folder / TABLE) as tmp:
        table.to_csv(tmp, index=False)
    return hypothesis_lines(sweep, table, declared)


def _read_revisits(folder: Path):
    """An experiment's ``revisits.csv`` (:func:`~curiosity_cli.evaluate.statistics.summarise_revisits`), or None if absent."""
    from curiosity_cli.evaluate.tables import read_table

    return read_table(ExperimentFolder(folder).table("revisits"), absent=None)


def _distinct_at_headline(revisits):
    """The rows of ``revisits.csv`` for distinct cells at the headline length."""
    from curiosity_cli.evaluate.headline import HEADLINE_LENGTH

    return revisits[(revisits["measure"] == "distinct_cells") & (revisits["path_length"] == HEADLINE_LENGTH)]


def _distinct_table(revisits) -> list[str]:
    """Mean distinct cells per walker at the headline length, a row per dataset."""
    from curiosity_cli.evaluate.headline import HEADLINE_LENGTH

    if revisits is None:
        return ["(no revisits.csv: evaluate the experiments again for distinct cells)", ""]
    at = _distinct_at_headline(revisits)
    if at.empty:
        return []
    walkers = list(dict.fromkeys(at["weight_function"]))
    lines = [
        f"Distinct cells seen in {HEADLINE_LENGTH} steps (mean over restarts):",
        "",
        "| dataset | " + " | ".join(walkers) + " |",
        "|---|" + "---|" * len(walkers),
    ]
    for dataset, block in at.groupby("dataset", sort=False):
        means = block.set_index("weight_function")["mean"]
        lines.append(f"| {dataset} | " + " | ".join(number(means.get(w), 1) for w in walkers) + " |")
    return lines + [""]


def pool_treatments(
    sweep: Sweep, outcomes: Sequence[Outcome], walkers: Sequence[str] | None = None,
) -> list[Treatment]:
    """Pool each treatment's seeds once (:func:`~curiosity_cli.evaluate.replicates.pool`), in the order of
    their first combination; combinations that failed take no part.

    Parameters
    ----------
    sweep : Sweep
    outcomes : sequence of Outcome
        Each pooled from the folder its tables are in (:attr:`~curiosity_cli.study.types.Outcome.tables`).
    walkers : sequence of str, optional
        As :func:`~curiosity_cli.evaluate.replicates.pool`'s.
    """
    from curiosity_cli.evaluate.replicates import pool
    from curiosity_cli.evaluate.tables import EvaluationError

    keys = [key for key in sweep.keys if key != REPLICATE_KEY]
    groups: dict[tuple, list[Outcome]] = {}
    for outcome in outcomes:
        if outcome.error is None:
            values = dict(text.split("=", 1) for text in outcome.combination.overrides)
            groups.setdefault(tuple(values[k] for k in keys), []).append(outcome)
    treatments = []
    for values, members in groups.items():
        try:
            pooled, error = pool([outcome.tables for outcome in members], walkers), None
        except EvaluationError as exc:
            pooled, error = None, str(exc)
        treatments.append(Treatment(dict(zip(keys, values)), tuple(o.combination for o in members), pooled, error))
    return treatments


def _sensitivity(sweep: Sweep, treatments: Sequence[Treatment]) -> tuple[list[str], list[dict]]:
    """SWEEP.md's sensitivity table and ``sensitivity.csv``'s rows: per treatment (the combination's
    values but the seed) and dataset, the headline over every seed's pairs pooled
    (:func:`pool_treatments`), its interval and power, and the distinct cells of
    :data:`DISTINCT_WALKERS`."""
    from curiosity_cli.evaluate.headline import HEADLINE_LENGTH

    keys = [key for key in sweep.keys if key != REPLICATE_KEY]
    pooled = REPLICATE_KEY in sweep.keys
    lines = [
        "## Sensitivity" + (" (seeds pooled)" if pooled else ""),
        "",
        f"Per {' x '.join([*keys, 'dataset'])}: topic perplexity's mean MI at "
        f"{HEADLINE_LENGTH} steps over the next best walker, "
        + (
            f"every seed's paired restarts pooled (the seeds are replicates: `{REPLICATE_KEY}` is not a treatment), "
            if pooled else ""
        )
        + "with the ratio's 95 % bootstrap interval, the paired Wilcoxon p against the next best, the smallest lead "
        "detectable at 80 % power and the pairs a 10 % lead would need (REPORT.md's verdict says how), and the mean "
        f"distinct cells {' and '.join(DISTINCT_WALKERS)} saw in {HEADLINE_LENGTH} steps, beside the paper's ratio.",
        "",
        "| " + " | ".join([*keys, "dataset", "seeds", "pairs", "ratio [95 % CI]", "p", "next best",
                         "detectable lead", "pairs for +10 %", *(f"distinct: {w}" for w in DISTINCT_WALKERS),
                         "paper's ratio"]) + " |",
        "|" + "---|" * (len(keys) + 9 + len(DISTINCT_WALKERS)),
    ]
    rows = []
    for treatment in treatments:
        values = treatment.values.values()
        result = treatment.pooled
        if result is None:
            lines.append("| " + " | ".join(f"`{v}`" for v in values) + f" | not pooled: {treatment.error} |")
            continue
        seeds = " ".join(map(str, result.seeds))
        for r in result.headline.to_dict("records"):
            distinct = {f"distinct_{w}": result.mean_distinct_cells(r["dataset"], w) for w in DISTINCT_WALKERS}
            rows.append({**treatment.values, "seeds": seeds, **r, **distinct})
            lead = r["detectable_ratio"] - 1
            lines.append(
                "| " + " | ".join([
                    *(f"`{v}`" for v in values), r["dataset"], seeds, str(r["pairs"]),
                    f"{number(r['ratio'])} [{number(r['ratio_ci_low'])}, {number(r['ratio_ci_high'])}]",
                    p_text(r["p_value"]), r["next_best"], f"{number(100 * lead, 0)} %" if lead == lead else "",
                    number(r["pairs_for_lead"], 0) or ("> 10^6" if lead == lead else ""),
                    *(number(v, 1) for v in distinct.values()),
                    number(r["paper_ratio"]),
                ]) + " |"
            )
    return lines + [""], rows
