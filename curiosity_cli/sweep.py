"""Parameter sweeps: ``curiosity reproduce CONFIG --sweep KEY=V1,V2 --sweep KEY2=W1,...``.

A sweep runs the whole pipeline (:func:`curiosity_cli.reproduce.reproduce`) once per
combination of values, the Cartesian product of the ``--sweep`` options, in the spirit
of Hydra's ``--multirun key=a,b``, and compares the combinations' headlines in one report.

Syntax
------
``--sweep KEY=V1,V2,...`` takes a dotted config key, as ``--set`` does, and one or more
values, each read as YAML like a ``--set`` value. Values are split on commas outside
brackets, so a list is one value: ``--sweep 'datasets=[zurich-zh17],[aerial-mosaic]'``
is two values. A single value just fixes the key for every combination. Combinations
run in product order: the first ``--sweep`` option varies slowest, the last fastest
(``itertools.product``, as Hydra's basic sweeper). ``name`` cannot be swept (the sweep
names each combination), and a key may be given once, in ``--sweep`` or ``--set``.

Every combination is loaded and validated with :func:`curiosity_cli.config.load_config`
(the ``--set`` machinery: ``--set`` options first, then the combination's values)
before the first one runs, so a bad key or value stops the sweep before anything is
written.

Layout
------
For an experiment config named ``quick``, everything goes under
``<results>/quick-sweep/``::

    quick-sweep/
      sweep.yaml                               the config, --set options, and per combination
                                               its folder and overrides (written first)
      SWEEP.md                                 every combination's overrides and headline table,
                                               linked to its REPORT.md (written last)
      sweep.csv                                a row per combination and dataset: override
                                               columns, then headline.csv's columns
      model.topics-16_explore.restarts-20/     an ordinary experiment folder (config.yaml,
      model.topics-32_explore.restarts-20/       runs/, labels/, REPORT.md, ...) per combination

A combination's folder, which is also its experiment ``name``, is made of its overrides
only: ``KEY-VALUE`` parts joined by ``_``, in ``--sweep`` order. Characters other than
letters, digits, ``_``, ``.`` and ``-`` in a value become ``-``, and such a part gets
``-`` and 6 hex digits of a hash of the key and the parsed value, so different values
never share a folder (``datasets=[zurich-zh17]`` gives ``datasets-zurich-zh17-17f3a3``).
Unlike numbered folders (Hydra's ``0/``, ``1/``, ...), a name depends only on the
combination: adding a value to a sweep, or reordering values, finds every finished
combination under the same folder, and no folder is reused for other values. The names
are valid experiment names, so ``curiosity label`` or ``evaluate`` work on a
combination's folder as on any other. The config file and ``--set`` options are not in
the name: after a change to them that alters runs, a resumed combination refuses its
folder as any experiment does (:func:`curiosity_cli.experiment.saved_config.check_saved_config`);
``--set name=...`` starts another sweep folder.

Resuming
--------
Each combination resumes like any experiment (finished runs, batch references and labels
are kept; evaluation and figures are redone), so running the same command again after
it was stopped does only the work that is missing, then rewrites ``SWEEP.md`` and
``sweep.csv``. A combination that fails does not stop the others; the sweep reports it
at the end (:class:`SweepError`) after writing the report of the ones that finished.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import re
import shlex
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from curiosity_cli.config import OVERRIDES, ExperimentConfig, config_file, load_config
from curiosity_cli.errors import ConfigError, CuriosityError
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.files import atomic_path, display_path
from curiosity_cli.paths import DEFAULT_RESULTS

#: The headline columns, as ``headline.csv`` has them (:func:`curiosity_cli.evaluate.tables.headline`).
HEADLINE_COLUMNS = (
    "dataset", "topic_perplexity", "next_best", "next_best_mi", "ratio", "p_value", "pairs", "paper_map", "paper_ratio",
    "ratio_ci_low", "ratio_ci_high", "detectable_ratio", "pairs_for_lead",
)
#: The key whose values are replicates, pooled in SWEEP.md's first table, not treatments.
REPLICATE_KEY = "seed"
#: The walkers whose distinct cells the first table of SWEEP.md shows beside the ratio.
DISTINCT_WALKERS = ("stochastic-coverage", "topic-perplexity")

_SAFE = re.compile(r"[^A-Za-z0-9_.-]+")
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
_MAX_NAME = 120
_OPENING, _CLOSING = "[{", "]}"


class SweepSyntaxError(ValueError):
    """A malformed ``--sweep`` option; the command line reports it as a usage error."""


class SweepError(CuriosityError):
    """Combinations of a sweep that failed; the others are done and reported."""


@dataclass(frozen=True)
class SweepAxis:
    """One ``--sweep KEY=V1,V2,...`` option: a dotted key and its values as given."""

    key: str
    values: tuple[str, ...]


@dataclass(frozen=True)
class Combination:
    """One experiment of a sweep.

    Attributes
    ----------
    index : int
        1-based position in product order.
    overrides : tuple of str
        ``KEY=VALUE`` for every swept key, in ``--sweep`` order (``--set`` syntax).
    name : str
        Its experiment name and folder (module docstring).
    config : ExperimentConfig
        The validated config: the file, the ``--set`` options, then ``overrides``.
    """

    index: int
    overrides: tuple[str, ...]
    name: str
    config: ExperimentConfig

    @property
    def label(self) -> str:
        """The overrides as a reader sees them, e.g. ``model.topics=16, seed=1``."""
        return ", ".join(self.overrides)


@dataclass(frozen=True)
class Sweep:
    """A validated sweep: every combination loaded, nothing written yet.

    Attributes
    ----------
    name : str
        The experiment config's name; the sweep goes to ``<results>/<name>-sweep/``.
    config_path : Path
        The experiment YAML.
    sets : tuple of str
        The ``--set`` options shared by every combination.
    axes : tuple of SweepAxis
    combinations : tuple of Combination
        In product order.
    """

    name: str
    config_path: Path
    sets: tuple[str, ...]
    axes: tuple[SweepAxis, ...]
    combinations: tuple[Combination, ...] = field(repr=False)

    def folder(self, results_dir: Path) -> Path:
        """The sweep's folder under ``results_dir``."""
        return Path(results_dir) / f"{self.name}-sweep"

    def command(self, results_dir: Path = DEFAULT_RESULTS) -> str:
        """The ``curiosity reproduce`` command that runs (or resumes) this sweep in ``results_dir``."""
        words = ["curiosity", "reproduce", display_path(self.config_path)]
        if Path(results_dir) != DEFAULT_RESULTS:
            words += ["--results-dir", display_path(results_dir)]
        for text in self.sets:
            words += ["--set", text]
        for axis in self.axes:
            words += ["--sweep", f"{axis.key}={','.join(axis.values)}"]
        return shlex.join(words)


@dataclass(frozen=True)
class Outcome:
    """What running one combination gave: its report, or why it failed, and its time."""

    combination: Combination
    report: Path | None
    error: str | None
    seconds: float


# --------------------------------------------------------------------------- parsing


def split_values(text: str) -> list[str]:
    """Split a ``--sweep`` value list on commas outside brackets.

    Parameters
    ----------
    text : str
        What follows ``KEY=``, e.g. ``16,32`` or ``[a,b],[c]``.

    Returns
    -------
    list of str
        The values, stripped of surrounding blanks.

    Raises
    ------
    SweepSyntaxError
        Unbalanced brackets.
    """
    values, depth, start = [], 0, 0
    for i, char in enumerate(text):
        if char in _OPENING:
            depth += 1
        elif char in _CLOSING:
            depth -= 1
            if depth < 0:
                raise SweepSyntaxError(f"{text!r}: a closing {char!r} without its opening bracket")
        elif char == "," and depth == 0:
            values.append(text[start:i].strip())
            start = i + 1
    if depth:
        raise SweepSyntaxError(f"{text!r}: a bracket is not closed")
    values.append(text[start:].strip())
    return values


def parse_sweeps(options: Sequence[str], sets: Sequence[str] = ()) -> tuple[SweepAxis, ...]:
    """Parse ``--sweep KEY=V1,V2,...`` options (module docstring).

    Parameters
    ----------
    options : sequence of str
        The ``--sweep`` options, in the order given.
    sets : sequence of str
        The ``--set KEY=VALUE`` options of the same command: a key may not be in both.

    Returns
    -------
    tuple of SweepAxis

    Raises
    ------
    SweepSyntaxError
        No ``=``, no key, an empty value (write ``null`` for null), unbalanced brackets,
        a value given twice, a key given twice or also with ``--set``, or ``name``.
    """
    set_keys = [text.partition("=")[0].strip() for text in sets]
    axes: list[SweepAxis] = []
    for text in options:
        key, sep, rest = text.partition("=")
        key = key.strip()
        if not sep or not key:
            raise SweepSyntaxError(f"{text!r}: expected KEY=V1,V2,..., e.g. model.topics=16,32")
        if key == "name":
            raise SweepSyntaxError(f"{text!r}: name cannot be swept; each combination is named by its values")
        values = split_values(rest)
        if not any(values):
            raise SweepSyntaxError(f"{text!r}: no values; expected KEY=V1,V2,..., e.g. model.topics=16,32")
        if not all(values):
            raise SweepSyntaxError(f"{text!r}: an empty value; write null for null")
        for other in [a.key for a in axes]:
            if _overlap(key, other):
                raise SweepSyntaxError(f"{text!r}: {other} is already swept; give each key once")
        for other in set_keys:
            if _overlap(key, other):
                raise SweepSyntaxError(f"{text!r}: {other} is also among the overrides; give it in one of them")
        parts = {}
        for value in values:
            part = _part(key, value)
            if part in parts:
                raise SweepSyntaxError(f"{text!r}: {value!r} is the same value as {parts[part]!r}; give each value once")
            parts[part] = value
        axes.append(SweepAxis(key, tuple(values)))
    return tuple(axes)


def declared_sweeps(config_path: str | Path) -> list[str]:
    """The sweep an experiment config declares under its top-level ``sweep`` key, as ``--sweep`` options.

    ``sweep`` maps dotted keys to lists of values, in the order the axes vary (the first
    slowest), e.g. ``{explore.coverage: [literal, clamp], seed: [0, 1, 2]}``.

    Parameters
    ----------
    config_path : str or Path
        The experiment YAML, or a shipped config's name.

    Returns
    -------
    list of str
        ``KEY=V1,V2,...``, one per declared key; empty when the file declares none.

    Raises
    ------
    ConfigError
        ``sweep`` is not a mapping of keys to non-empty lists, or a value cannot be
        written as one ``--sweep`` value; naming the file and the key.
    """
    from curiosity_cli.config import SWEEP_KEY
    from curiosity_cli.yamlfile import read_yaml

    config_path = config_file(config_path)
    declared = read_yaml(config_path, "config file").get(SWEEP_KEY)
    if declared is None:
        return []
    where = f"{display_path(config_path)}: {SWEEP_KEY}"
    if not isinstance(declared, dict) or not declared:
        raise ConfigError(f"{where}: expected a mapping of dotted keys to lists of values, e.g. seed: [0, 1, 2]")
    options = []
    for key, values in declared.items():
        if not isinstance(key, str) or not isinstance(values, list) or not values:
            raise ConfigError(f"{where}.{key}: expected a list of one or more values, e.g. [0, 1, 2]")
        texts = [_value_text(value) for value in values]
        if any(split_values(text) != [text] for text in texts):
            raise ConfigError(f"{where}.{key}: a value with a comma outside brackets; write it as a list")
        options.append(f"{key}={','.join(texts)}")
    return options


def _value_text(value) -> str:
    """A YAML value as a ``--sweep`` value that reads back to it: strings as typed when they can be."""
    if isinstance(value, str) and _parsed(value) == value:
        return value
    return json.dumps(value)


def merge_sweeps(declared: Sequence[str], given: Sequence[str]) -> list[str]:
    """The config's declared sweep with the command line's ``--sweep`` options: a given key
    replaces the declared key's values in place, and other given keys follow, in order."""
    merged = list(declared)
    # in place: a combination's folder is named by its axes in order, so a resumed sweep finds it
    positions = {text.partition("=")[0].strip(): i for i, text in enumerate(declared)}
    for text in given:
        i = positions.pop(text.partition("=")[0].strip(), None)
        if i is None:
            merged.append(text)  # a key given twice stays twice, for parse_sweeps to refuse
        else:
            merged[i] = text
    return merged


def _overlap(key: str, other: str) -> bool:
    """Whether two dotted keys set the same leaf (equal, or one a section of the other)."""
    return key == other or key.startswith(other + ".") or other.startswith(key + ".")


def combinations(axes: Sequence[SweepAxis]) -> list[tuple[str, ...]]:
    """The overrides of every combination, in product order (the first axis varies slowest).

    Parameters
    ----------
    axes : sequence of SweepAxis

    Returns
    -------
    list of tuple of str
        ``KEY=VALUE`` strings, one tuple per combination.
    """
    return [
        tuple(f"{axis.key}={value}" for axis, value in zip(axes, values))
        for values in itertools.product(*(axis.values for axis in axes))
    ]


def combination_name(overrides: Iterable[str]) -> str:
    """The experiment name and folder of a combination: ``KEY-VALUE`` parts joined by ``_``.

    Parameters
    ----------
    overrides : iterable of str
        ``KEY=VALUE`` strings.

    Returns
    -------
    str
        A valid experiment name (letters, digits, ``_``, ``.``, ``-``); a value with
        other characters is replaced and its part gets a hash (module docstring), and a
        name longer than 120 characters is cut and gets a hash of all of it.
    """
    overrides = list(overrides)
    name = "_".join(_part(*text.split("=", 1)) for text in overrides)
    if len(name) > _MAX_NAME:
        name = f"{name[:_MAX_NAME - 9].rstrip('-_.')}-{_digest(json.dumps(overrides), 8)}"
    return name


def _part(key: str, value: str) -> str:
    key, value = key.strip(), value.strip()
    safe = _SAFE.sub("-", value).strip("-")
    if safe == value:
        return f"{key}-{value}"
    digest = _digest(json.dumps([key, _parsed(value)], sort_keys=True, default=str), 6)
    return f"{key}-{safe}-{digest}" if safe else f"{key}-{digest}"


def _parsed(value: str):
    """A value as an override reads it (YAML, with the numbers a person types)."""
    from curiosity_cli.yamlfile import parse_yaml

    return parse_yaml(value, "sweeps")


def _digest(text: str, digits: int) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:digits]


# --------------------------------------------------------------------------- planning


def plan_sweep(config_path: str | Path, axes: Sequence[SweepAxis], sets: Sequence[str] = ()) -> Sweep:
    """Load and validate every combination of a sweep; nothing is written.

    Parameters
    ----------
    config_path : str or Path
        The experiment YAML.
    axes : sequence of SweepAxis
        From :func:`parse_sweeps`; at least one.
    sets : sequence of str
        ``--set KEY=VALUE`` options applied to every combination, before its own values.

    Returns
    -------
    Sweep

    Raises
    ------
    ConfigError
        The first combination that does not validate, in one line: the error its
        overrides give, naming the sweeps when a swept key is at fault, else followed by
        the combination.
    """
    if not axes:
        raise ValueError("a sweep needs at least one axis")
    config_path = config_file(config_path)
    sets = tuple(sets)
    keys = [axis.key for axis in axes]
    loaded, base_name = [], None
    for index, overrides in enumerate(combinations(axes), start=1):
        try:
            config = load_config(config_path, [*sets, *overrides])
        except ConfigError as exc:
            raise _combination_error(exc, keys, overrides) from None
        base_name = config.name  # the same for every combination: name cannot be swept
        name = combination_name(overrides)
        assert _NAME.match(name), name  # by construction: keys are config fields, values made safe
        loaded.append(Combination(index, overrides, name, replace(config, name=name)))
    return Sweep(base_name, config_path, sets, tuple(axes), tuple(loaded))


def _combination_error(exc: ConfigError, keys: Sequence[str], overrides: Sequence[str]) -> ConfigError:
    """The error of a combination that does not validate: the overrides' error, naming the
    sweeps when a swept key is at fault, else followed by the combination."""
    if exc.parameter == OVERRIDES:
        rest = str(exc)[len(OVERRIDES):]
        if rest.startswith(" "):  # a malformed override: not the sweep's doing
            return exc
        for key in keys:
            at = rest[2:]
            if at.startswith(key) and at[len(key):len(key) + 1] in (":", ".", "["):
                return ConfigError(f"sweeps{rest}", parameter="sweeps")
    return ConfigError(f"{exc} (with the sweep's {', '.join(overrides)})", parameter=exc.parameter)


# --------------------------------------------------------------------------- running


def run_sweep(
    sweep: Sweep,
    *,
    results_dir: Path = DEFAULT_RESULTS,
    on_stage: Callable[[str, int], None] | None = None,
    **pipeline,
) -> Path:
    """Run every combination of ``sweep`` with the whole pipeline and write ``SWEEP.md``.

    Parameters
    ----------
    sweep : Sweep
        From :func:`plan_sweep`.
    results_dir : Path
        The sweep's folder goes under ``results_dir``.
    on_stage : callable, optional
        As :func:`~curiosity_cli.reproduce.reproduce`'s; each combination is also
        announced as a stage without units, ``"combination 2/3: model.topics=32"``.
    **pipeline
        The other keywords of :func:`curiosity_cli.reproduce.reproduce` (``cache_dir``,
        ``jobs``, ``force``, ``backend``, ``scheduler``, ``on_done``), for every combination.

    Returns
    -------
    Path
        ``SWEEP.md``.

    Raises
    ------
    SweepError
        After every combination, if some failed: each named with its error (``SWEEP.md``
        and ``sweep.csv`` hold the others).
    """
    from curiosity_cli.reproduce import reproduce

    folder = sweep.folder(results_dir)
    write_plan(sweep, folder)
    total = len(sweep.combinations)
    outcomes = []
    for combination in sweep.combinations:
        if on_stage is not None:
            on_stage(f"combination {combination.index}/{total}: {combination.label}", 0)
        started = time.perf_counter()
        try:
            report = reproduce(combination.config, results_dir=folder, on_stage=on_stage, **pipeline)
            outcomes.append(Outcome(combination, report, None, time.perf_counter() - started))
        except CuriosityError as exc:
            outcomes.append(Outcome(combination, None, str(exc), time.perf_counter() - started))
    path = write_sweep_report(sweep, folder, outcomes)
    failed = [o for o in outcomes if o.error is not None]
    if failed:
        raise SweepError(
            f"{len(failed)} of {_count(total, 'combination')} failed ({display_path(path)} has the others; "
            "run the command again to retry): "
            + "; ".join(f"combination {o.combination.index} ({o.combination.label}): {o.error}" for o in failed)
        )
    return path


def write_plan(sweep: Sweep, folder: Path) -> Path:
    """Write ``sweep.yaml``: the config, the ``--set`` options and every combination's folder.

    Parameters
    ----------
    sweep : Sweep
    folder : Path
        The sweep's folder.

    Returns
    -------
    Path
    """
    import yaml

    plan = {
        "command": sweep.command(Path(folder).parent),
        "config": str(sweep.config_path.resolve()),
        "set": list(sweep.sets),
        "sweep": {axis.key: list(axis.values) for axis in sweep.axes},
        "combinations": [
            {"index": c.index, "folder": c.name, "overrides": list(c.overrides)} for c in sweep.combinations
        ],
    }
    path = Path(folder) / "sweep.yaml"
    with atomic_path(path) as tmp:
        tmp.write_text(yaml.safe_dump(plan, sort_keys=False))
    return path


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

    path = ExperimentFolder(folder).table("headline")
    if not path.is_file():
        return pd.DataFrame(columns=list(HEADLINE_COLUMNS))
    text = {"dataset": str, "next_best": str, "paper_map": str}  # an empty paper_map stays ""
    numbers = {column: [""] for column in HEADLINE_COLUMNS if column not in text}
    return pd.read_csv(path, dtype=text, keep_default_na=False, na_values=numbers)


def write_sweep_report(sweep: Sweep, folder: Path, outcomes: Sequence[Outcome]) -> Path:
    """Write ``SWEEP.md`` and ``sweep.csv`` from the combinations' ``headline.csv``.

    Parameters
    ----------
    sweep : Sweep
    folder : Path
        The sweep's folder; each combination's experiment folder is in it.
    outcomes : sequence of Outcome
        One per combination run, in product order.

    Returns
    -------
    Path
        ``SWEEP.md``.
    """
    import pandas as pd

    from curiosity_cli.evaluate.tables import HEADLINE_LENGTH, HEADLINE_WEIGHT

    folder = Path(folder)
    keys = [axis.key for axis in sweep.axes]
    sensitivity, pooled_rows = _sensitivity(sweep, folder, outcomes)
    rows, sections = [], []
    overview = [
        "| # | " + " | ".join(keys) + " | dataset | ratio | next best | paired Wilcoxon p (pairs) | paper's ratio |",
        "|---|" + "---|" * len(keys) + "---|---|---|---|---|",
    ]
    for outcome in outcomes:
        c = outcome.combination
        values = [text.split("=", 1)[1] for text in c.overrides]
        cells = " | ".join(f"`{v}`" for v in values)
        link = f"[{c.index}]({c.name}/REPORT.md)"
        sections += [f"## {c.index}. {c.label}", ""]
        if outcome.error is not None:
            overview.append(f"| {c.index} | {cells} | failed | | | | |")
            sections += [f"Failed: {outcome.error}", ""]
            continue
        top = read_headline(folder / c.name)
        sections += [f"Folder `{c.name}/`, report [{c.name}/REPORT.md]({c.name}/REPORT.md), {outcome.seconds:.0f} s.", ""]
        for row in top.to_dict("records") or [dict.fromkeys(HEADLINE_COLUMNS)]:
            rows.append({"combination": c.index, "folder": c.name, **dict(zip(keys, values)), **row})
        if top.empty:
            overview.append(f"| {link} | {cells} | (no headline) | | | | |")
            sections += [f"(no human labels or no {HEADLINE_LENGTH}-step checkpoint: no headline ratio)", ""]
            continue
        sections += [
            "| dataset | topic perplexity MI | next best | its MI | ratio | paired Wilcoxon p | pairs | paper's map | paper's ratio |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for r in top.itertuples():
            overview.append(
                f"| {link} | {cells} | {r.dataset} | {_number(r.ratio)} | {r.next_best} | "
                f"{_p(r.p_value)} ({r.pairs}) | {_number(r.paper_ratio)} |"
            )
            sections.append(
                f"| {r.dataset} | {_number(r.topic_perplexity, 3)} | {r.next_best} | {_number(r.next_best_mi, 3)} | "
                f"{_number(r.ratio)} | {_p(r.p_value)} | {r.pairs} | {r.paper_map} | {_number(r.paper_ratio)} |"
            )
        sections += ["", *_distinct_table(_read_revisits(folder / c.name))]
    sets = ", ".join(f"`--set {s}`" for s in sweep.sets) or "none"
    lines = [
        f"# Parameter sweep of `{sweep.name}`: {_count(len(outcomes), 'combination')}",
        "",
        f"Config `{display_path(sweep.config_path)}`; --set: {sets}. Each combination is an experiment folder "
        f"here, named by its values (`sweep.yaml` lists them). The headline is the mean MI of {HEADLINE_WEIGHT} "
        f"exploration against human labels at {HEADLINE_LENGTH} steps over the next best weight function's.",
        "",
        "Run again (finished runs and labels are kept):",
        "",
        "```console",
        f"$ {sweep.command(folder.parent)}",
        "```",
        "",
        *sensitivity,
        "## Headlines",
        "",
        *overview,
        "",
        *sections,
    ]
    columns = ["combination", "folder", *keys, *HEADLINE_COLUMNS]
    with atomic_path(folder / "sweep.csv") as tmp:
        pd.DataFrame(rows, columns=columns).to_csv(tmp, index=False)
    treatments = [key for key in keys if key != REPLICATE_KEY]
    pooled_columns = [*treatments, "seeds", *HEADLINE_COLUMNS, *(f"distinct_{w}" for w in DISTINCT_WALKERS)]
    with atomic_path(folder / "sensitivity.csv") as tmp:
        pd.DataFrame(pooled_rows, columns=pooled_columns).to_csv(tmp, index=False)
    path = folder / "SWEEP.md"
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines))
    return path


def _read_revisits(folder: Path):
    """An experiment's ``revisits.csv`` (:func:`~curiosity_cli.evaluate.tables.summarise_revisits`), or None if absent."""
    import pandas as pd

    path = ExperimentFolder(folder).table("revisits")
    return pd.read_csv(path) if path.is_file() else None


def _distinct_at_headline(revisits):
    """The rows of ``revisits.csv`` for distinct cells at the headline length."""
    from curiosity_cli.evaluate.tables import HEADLINE_LENGTH

    return revisits[(revisits["measure"] == "distinct_cells") & (revisits["path_length"] == HEADLINE_LENGTH)]


def _distinct_table(revisits) -> list[str]:
    """Mean distinct cells per walker at the headline length, a row per dataset."""
    from curiosity_cli.evaluate.tables import HEADLINE_LENGTH

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
        lines.append(f"| {dataset} | " + " | ".join(_number(means.get(w), 1) for w in walkers) + " |")
    return lines + [""]


def _sensitivity(sweep: Sweep, folder: Path, outcomes: Sequence[Outcome]) -> tuple[list[str], list[dict]]:
    """SWEEP.md's first table and ``sensitivity.csv``'s rows: per treatment (the combination's
    values but the seed) and dataset, the headline over every seed's pairs pooled
    (:func:`~curiosity_cli.evaluate.replicates.pool`), its interval and power, and the
    distinct cells of :data:`DISTINCT_WALKERS`."""
    from curiosity_cli.evaluate.replicates import pool
    from curiosity_cli.evaluate.tables import HEADLINE_LENGTH, EvaluationError

    keys = [axis.key for axis in sweep.axes]
    treatments = [key for key in keys if key != REPLICATE_KEY]
    groups: dict[tuple, list[Path]] = {}
    for outcome in outcomes:
        if outcome.error is None:
            values = dict(text.split("=", 1) for text in outcome.combination.overrides)
            groups.setdefault(tuple(values[k] for k in treatments), []).append(folder / outcome.combination.name)
    pooled = REPLICATE_KEY in keys
    lines = [
        "## Sensitivity" + (" (seeds pooled)" if pooled else ""),
        "",
        f"Per {' x '.join([*treatments, 'dataset'])}: topic perplexity's mean MI at "
        f"{HEADLINE_LENGTH} steps over the next best walker, "
        + (
            f"every seed's paired restarts pooled (the seeds are replicates: `{REPLICATE_KEY}` is not a treatment), "
            if pooled else ""
        )
        + "with the ratio's 95 % bootstrap interval, the paired Wilcoxon p against the next best, the smallest lead "
        "detectable at 80 % power and the pairs a 10 % lead would need (REPORT.md's verdict says how), and the mean "
        f"distinct cells {' and '.join(DISTINCT_WALKERS)} saw in {HEADLINE_LENGTH} steps, beside the paper's ratio.",
        "",
        "| " + " | ".join([*treatments, "dataset", "seeds", "pairs", "ratio [95 % CI]", "p", "next best",
                         "detectable lead", "pairs for +10 %", *(f"distinct: {w}" for w in DISTINCT_WALKERS),
                         "paper's ratio"]) + " |",
        "|" + "---|" * (len(treatments) + 9 + len(DISTINCT_WALKERS)),
    ]
    rows = []
    for values, folders in groups.items():
        try:
            result = pool(folders)
        except EvaluationError as exc:
            lines.append("| " + " | ".join(f"`{v}`" for v in values) + f" | not pooled: {exc} |")
            continue
        at = _distinct_at_headline(result.revisits).set_index(["dataset", "weight_function"])["mean"]
        seeds = " ".join(map(str, result.seeds))
        for r in result.headline.to_dict("records"):
            distinct = {f"distinct_{w}": at.get((r["dataset"], w), float("nan")) for w in DISTINCT_WALKERS}
            rows.append({**dict(zip(treatments, values)), "seeds": seeds, **r, **distinct})
            lead = r["detectable_ratio"] - 1
            lines.append(
                "| " + " | ".join([
                    *(f"`{v}`" for v in values), r["dataset"], seeds, str(r["pairs"]),
                    f"{_number(r['ratio'])} [{_number(r['ratio_ci_low'])}, {_number(r['ratio_ci_high'])}]",
                    _p(r["p_value"]), r["next_best"], f"{_number(100 * lead, 0)} %" if lead == lead else "",
                    _number(r["pairs_for_lead"], 0) or ("> 10^6" if lead == lead else ""),
                    *(_number(v, 1) for v in distinct.values()),
                    _number(r["paper_ratio"]),
                ]) + " |"
            )
    return lines + [""], rows


def _number(value, digits: int = 2) -> str:
    try:
        value = float(value)
    except (TypeError, ValueError):
        return ""
    return f"{value:.{digits}f}" if value == value else ""


def _p(value) -> str:
    text = _number(value, 3)
    return "< 0.001" if text and float(value) < 0.001 else text


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'' if n == 1 else 's'}"
