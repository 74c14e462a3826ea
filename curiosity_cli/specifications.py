"""Declared specifications: a study config's named sets of overrides, and its specification curve.

A study asks whether a finding survives every defensible way of doing the experiment
(Simonsohn, Simmons & Nelson's specification-curve analysis). Each way is a
**specification**: a name and the config overrides that make it, declared in the study
config beside the sweep of its seeds::

    sweep:
      seed: [0, 1, 2]                        # replicates, pooled
    specifications:                          # name -> overrides, as --set takes them
      default: {}                            # the config as it is
      clamp: {explore.coverage: clamp}
      beta-1: {model.beta: 1.0}
      clamp-beta-1:
        explore.coverage: clamp
        model.beta: 1.0

Names are 1 to 80 letters, digits, ``_``, ``.`` or ``-``, starting with a letter or
digit. Keys are dotted config keys and values YAML values, as ``--set KEY=VALUE`` reads
them; ``{}`` (or nothing) leaves the config as it is. A key may not be given both by a
specification and by ``--set`` or a sweep (``sweep:`` or ``--sweep``), nor twice in one
specification, and ``name`` cannot be a specification's.

Planning and running
--------------------
``curiosity reproduce CONFIG`` runs every specification, in the order declared, on every
map of the config's ``datasets`` and every combination of its sweep, each as an ordinary
experiment folder under ``<results>/<name>-sweep/`` (:func:`curiosity_cli.sweep.plan_sweep`,
:func:`~curiosity_cli.sweep.run_sweep`). Every (specification, combination) is loaded
and validated before the first runs: a bad key or value is refused in one line naming
the config file, the specification and the key
(``study.yaml: specifications.clamp.explore.coverage: got 'clmap', expected one of ...``).

A folder is named by the specification's name and the swept values only
(:func:`~curiosity_cli.sweep.combination_name` of ``specification=NAME`` and then the
swept ``KEY=VALUE``: ``specification-clamp_seed-1``), so adding a specification finds
the finished ones where they were, and a killed study resumes with its finished runs and
labels kept. The overrides are not in the name: after changing a specification's
overrides, its folders refuse the new config as any experiment does; give it a new name.

The report
----------
``SWEEP.md`` leads with the specification curve (:func:`specification_lead`): topic
perplexity against each of the paper's other walkers (the decision), and the ratio to the
next best with its null reference (a summary); the figure ``specification-curve.png``
(and ``.pdf``), the table of its points, also written as ``specifications.csv``, and the
sentence counting the specifications in which topic perplexity leads every walker at
p < 0.05, those whose interval holds the paper's ratio, and where the points lie against
their null reference (:mod:`curiosity_cli.evaluate.specification_curve`); then the same
against Z_b (``specifications-batch.csv``, ``specification-curve-batch.png``). It takes the place of the
sweep's sensitivity table, which would repeat the same pooled numbers in the same rows;
``sensitivity.csv`` is still written. Every number comes from one pooling of each
specification's seeds (:func:`curiosity_cli.sweep_report.pool_treatments`), over the
paper's four walkers.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from curiosity_cli.config import SPECIFICATIONS_KEY, config_file
from curiosity_cli.schema import OVERRIDES
from curiosity_cli.errors import ConfigError
from curiosity_cli.files import atomic_path, display_path
from curiosity_cli.sweep import overlap, value_text

if TYPE_CHECKING:
    from curiosity_cli.config import ExperimentConfig
    from curiosity_cli.sweep import Sweep
    from curiosity_cli.sweep_report import Treatment

#: How a combination's overrides and a sweep's report name its specification: ``specification=NAME``.
SPECIFICATION = "specification"
#: The table and the figure of a study's curve, in its sweep folder: MI against human labels, and against Z_b.
TABLE, FIGURE = "specifications.csv", "specification-curve"
BATCH_TABLE, BATCH_FIGURE = "specifications-batch.csv", "specification-curve-batch"
#: The mechanism's figure (SWEEP.md's "Does surprise point at what is new?").
MECHANISM_FIGURE = "mechanism"
#: A name leaves room in its folders' names (at most MAX_NAME) for ``specification-`` and the swept values.
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,79}$")


@dataclass(frozen=True)
class Specification:
    """One declared specification.

    Attributes
    ----------
    name : str
    overrides : tuple of str
        ``KEY=VALUE``, ``--set`` syntax, in the order declared.
    """

    name: str
    overrides: tuple[str, ...]

    @property
    def keys(self) -> list[str]:
        """The dotted keys it sets."""
        return [text.partition("=")[0] for text in self.overrides]


def declared_specifications(config_path: str | Path) -> tuple[Specification, ...]:
    """The specifications a study config declares under its top-level ``specifications`` key.

    Parameters
    ----------
    config_path : str or Path
        The study YAML, or a shipped config's name.

    Returns
    -------
    tuple of Specification
        In the order declared; empty when the file declares none.

    Raises
    ------
    ConfigError
        ``specifications`` is not a mapping of names to mappings of keys to values, a
        name that is not one, a key given twice or ``name``; naming the file, the
        specification and the key.
    """
    from curiosity_cli.yamlfile import read_yaml

    config_path = config_file(config_path)
    declared = read_yaml(config_path, "config file").get(SPECIFICATIONS_KEY)
    if declared is None:
        return ()
    where = f"{display_path(config_path)}: {SPECIFICATIONS_KEY}"
    if not isinstance(declared, dict) or not declared:
        raise ConfigError(f"{where}: expected a mapping of names to overrides, e.g. clamp: {{explore.coverage: clamp}}")
    found = []
    for name, overrides in declared.items():
        if not isinstance(name, str) or not _NAME.match(name):
            raise ConfigError(
                f"{where}: {name!r}: expected a name of 1 to 80 letters, digits, '_', '.' or '-', starting with a "
                "letter or digit"
            )
        overrides = {} if overrides is None else overrides
        if not isinstance(overrides, dict):
            raise ConfigError(
                f"{where}.{name}: expected a mapping of dotted keys to values, e.g. {{explore.coverage: clamp}}, "
                "or {} for the config as it is"
            )
        texts: list[str] = []
        for key, value in overrides.items():
            if not isinstance(key, str) or not key.strip() or "=" in key:
                raise ConfigError(f"{where}.{name}: {key!r}: expected a dotted config key, e.g. explore.coverage")
            if key == "name":
                raise ConfigError(f"{where}.{name}.name: a specification cannot rename the experiment; each is named by its own name")
            for earlier in texts:
                if overlap(key, earlier.partition("=")[0]):
                    raise ConfigError(f"{where}.{name}.{key}: {earlier.partition('=')[0]} is set too; give each key once")
            texts.append(f"{key}={value_text(value)}")
        found.append(Specification(name, tuple(texts)))
    return tuple(found)


def check_specifications(config_path: Path, specifications: Sequence[Specification], swept: Sequence[str], sets: Sequence[str]) -> None:
    """Refuse a specification's key that a sweep or a ``--set`` option gives too.

    Raises
    ------
    ConfigError
        Naming the file, the specification and the key.
    """
    given = [(key, "swept") for key in swept] + [(text.partition("=")[0].strip(), "given with --set") for text in sets]
    for specification in specifications:
        for key in specification.keys:
            for other, how in given:
                if overlap(key, other):
                    raise ConfigError(
                        f"{display_path(config_path)}: {SPECIFICATIONS_KEY}.{specification.name}.{key}: {other} is "
                        f"also {how}; give it in one of them"
                    )


def specification_error(exc: ConfigError, config_path: Path, specification: Specification) -> ConfigError | None:
    """The error of a specification whose own key is at fault, naming the file, the specification
    and the key; None when the error is not about one of its keys."""
    if exc.parameter != OVERRIDES:
        return None
    rest = str(exc)[len(OVERRIDES):]
    if not rest.startswith(": "):
        return None
    at = rest[2:]
    for key in specification.keys:
        if at.startswith(key) and at[len(key):len(key) + 1] in (":", ".", "["):
            return ConfigError(f"{display_path(config_path)}: {SPECIFICATIONS_KEY}.{specification.name}.{at}")
    return None


def study_size(sweep: Sweep) -> str:
    """A study's size in words: ``4 specifications x 3 seeds`` (or ``x 6 sweep combinations``)."""
    from curiosity_cli.sweep import count

    per = len(sweep.combinations) // max(len(sweep.specifications), 1)
    noun = "seed" if [axis.key for axis in sweep.axes] == ["seed"] else "sweep combination"
    return f"{count(len(sweep.specifications), 'specification')} x {count(per, noun)}"


# --------------------------------------------------------------------------- the report


def specification_lead(sweep: Sweep, folder: Path, treatments: Sequence[Treatment]) -> list[str]:
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
        (:func:`curiosity_cli.sweep_report.pool_treatments`).

    Returns
    -------
    list of str
        Markdown lines.
    """
    from curiosity_cli.evaluate.specification_curve import VERSUS, curve_sentence, curve_table
    from curiosity_cli.evaluate.tables import HEADLINE_LENGTH
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
        "mean is higher and p < 0.05 against every one. **The curve** shows a summary: the ratio to the next best "
        "of them, chosen after seeing the data and so biased toward \"no lead\", with its 95 % bootstrap interval "
        "(the next best chosen again in each resample) and, in grey behind each point, its **null reference**: "
        "where the ratio lies when the walkers do not differ (their labels permuted within each restart; band: "
        "95 %, dash: median), with the share of permutations at least as high as the observed ratio (`null p`). "
        "Dashed, the paper's ratio for the map each stands in for; filled, the points that lead. Below the curve, "
        "the value of each varied key each specification used (Simonsohn, Simmons & Nelson's specification-curve "
        f"analysis). The tables are `{TABLE}` (human labels) and `{BATCH_TABLE}` (Z_b).",
        "",
    ]
    for against, table_name, figure, words in (
        ("human", TABLE, FIGURE, "human labels"), ("batch", BATCH_TABLE, BATCH_FIGURE, "Z_b"),
    ):
        table = curve_table([(t.values, t.pooled) for t in pooled], against=against)
        with atomic_path(folder / table_name) as tmp:
            table.to_csv(tmp, index=False)
        if against == "batch":
            lines += [
                "### Against Z_b", "",
                "The same curve with MI against the batch labelling Z_b of each map, the paper's other measure:", "",
            ]
        if len(table):
            table = table.assign(label=[", ".join(map(str, v)) for v in table[names].itertuples(index=False)])
            write_specification_curve(table, choices, folder / figure, label="label", datasets=datasets, against=words)
            lines += [f"![specification curve, MI against {words}]({figure}.png)", ""]
        lines += _curve_rows(table, names) + ["", curve_sentence(table), ""]
        if against == "human":
            lines += _mechanism_section(table, names, folder, datasets)
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
    from curiosity_cli.evaluate.specification_curve import STEERING_WALKER, VERSUS
    from curiosity_cli.evaluate.report import number
    from curiosity_cli.sweep_report import p_text

    def versus(r: dict, walker: str) -> str:
        low, high = r[f"ratio_{walker}_low"], r[f"ratio_{walker}_high"]
        return f"{number(r[f'ratio_{walker}'])} [{number(low)}, {number(high)}], p = {p_text(r[f'p_{walker}'])}"

    lines = [
        "| # | " + " | ".join(names) + " | map | " + " | ".join(f"vs {w}" for w in VERSUS)
        + " | leads each | next best: ratio [95 % CI] | null: median [95 %], p | paper's ratio | pairs "
        f"| detectable lead | distinct cells: topic perplexity / stochastic coverage | steering: {STEERING_WALKER} |",
        "|---|" + "---|" * len(names) + "---|" * (len(VERSUS) + 9),
    ]
    for i, r in enumerate(table.to_dict("records"), start=1):
        lead = r["detectable_ratio"] - 1
        lines.append("| " + " | ".join([
            str(i), *(f"`{r[k]}`" for k in names), r["dataset"], *(versus(r, w) for w in VERSUS),
            "yes" if r["beats_all"] else "no",
            f"{number(r['ratio'])} [{number(r['ratio_ci_low'])}, {number(r['ratio_ci_high'])}] ({r['next_best']})",
            f"{number(r['null_median'])} [{number(r['null_low'])}, {number(r['null_high'])}], {p_text(r['null_p'])}",
            number(r["paper_ratio"]), str(r["pairs"]), f"{number(100 * lead, 0)} %" if lead == lead else "",
            f"{number(r[f'distinct_{STEERING_WALKER}'], 1)} / {number(r['distinct_stochastic-coverage'], 1)}",
            number(r[f"steering_{STEERING_WALKER}"], 3),
        ]) + " |")
    return lines


def _choices(sweep: Sweep, treatment: Treatment) -> dict[str, str]:
    """The value of each varied key (set by any specification, or swept but the seed) in a treatment."""
    from curiosity_cli.sweep_report import REPLICATE_KEY

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
