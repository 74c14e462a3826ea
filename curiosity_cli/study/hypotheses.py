"""Declared hypotheses: a study config's claims, tested on its seeds and reported as confirmed or not.

A finding the data picked is exploratory; a confirmation is declared (hypothesis, test, seeds, decision
rule) before any of its data exist. A study config declares its hypotheses under ``hypotheses``, beside
its specifications and seeds::

    hypotheses:
      alpha: 0.025                 # the family's one-sided level: Holm over the primary hypotheses
      H1:
        claim: topic perplexity finds the map's classes sooner than each other walker
        role: primary              # primary (in the Holm family) or secondary (reported, decides nothing)
        specification: candidates-8
        walker: topic-perplexity   # the default
        comparators: [random-walk, stochastic-coverage, word-perplexity]
        measure: time_to_find      # a measure of the table of measures; against: human (the default), batch or words
        reading: frozen            # the specification's label.reading
        path_length: 80            # one of its checkpoints
        label_schedule: {sweeps: 64, warm_sweeps: 16}   # its label.sweeps and label.warm_sweeps
        test: sign-flip            # or stratified-t (curiosity_cli/evaluate/confirmation.py)
        draws: 100000              # the sign flips drawn
        seeds: [3, 4, 5, 6, 7]     # all of them pooled: while one is not finished, it is not tested
        scale: {zurich-zh17: 9.5, aerial-mosaic: 8.1}   # per map: its paired differences are divided by this

Every field but ``walker``, ``role``, ``against``, ``test`` and ``draws`` must be given, and each must agree
with the specification it names (its reading, label schedule, checkpoints, walkers and maps); a hypothesis
that does not is refused before anything runs, naming the file, the hypothesis and the field. Its seeds
need not all be in the sweep run now (``--sweep seed=3`` measures one): it is tested only once all are.

The test
--------
Per comparator, each pair of runs (one map, seed and restart: the same start cell) gives the walker's
lead, its measure minus the comparator's (the other way round for a measure where lower is better),
divided by its map's scale; :mod:`curiosity_cli.evaluate.confirmation` tests their stratified mean above 0,
one-sided, by the declared test. The hypothesis's p is the largest of its comparators' (the
intersection-union test: it claims a lead over each). The primary hypotheses' p-values are adjusted by Holm
over the family, and a primary hypothesis is **confirmed** where its adjusted p is at most ``alpha``. As
secondary findings, the same test per map, its p the largest over the comparators, adjusted by Holm over the
hypothesis's maps. A hypothesis is not tested (and says why) while any of its seeds is missing.

Confirmatory or exploratory
---------------------------
A hypothesis is reported as **confirmatory** only when all of these hold, else as **exploratory**, with why:

- the study is kept in a record (``--record``), so that its data can be compared with other records;
- none of its runs (map and seed under its specification's settings) is in another study recorded beside
  it (``<record>/../*/seed-*/*/record.yaml`` with the same run recipe): data already seen;
- the config's ``hypotheses`` and ``specifications`` read as they do now since a commit (git), and every
  combination it pools began (``provenance.yaml``'s ``started``) after that commit's time: declared before
  its data existed.
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path

import numpy as np

from curiosity_cli.config import HYPOTHESES_KEY, SPECIFICATIONS_KEY, config_file
from curiosity_cli.errors import ConfigError
from curiosity_cli.files import display_path
from curiosity_cli.study.types import SPECIFICATION, Combination, Hypothesis, Outcome, Specification, Sweep

#: The tests a hypothesis may declare (:mod:`curiosity_cli.evaluate.confirmation`).
TESTS = ("sign-flip", "stratified-t")
#: Its roles: in the Holm family, or reported beside it.
ROLES = ("primary", "secondary")
#: The sign flips a hypothesis draws unless it says, and the bounds of what it may say.
DRAWS, MIN_DRAWS, MAX_DRAWS = 100_000, 1_000, 10_000_000
#: What the study's sweep folder holds of its hypotheses.
TABLE = "hypotheses.csv"
#: A map's scale, in its measure's unit: a lead divided by less than this, or by more than its largest, overflows
#: or vanishes.
MIN_SCALE, MAX_SCALE = 1e-9, 1e9

_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,39}$")
_REQUIRED = ("claim", "specification", "comparators", "measure", "reading", "path_length", "label_schedule", "seeds", "scale")
_OPTIONAL = ("walker", "role", "against", "test", "draws")
_SCHEDULE = ("sweeps", "warm_sweeps")


# --------------------------------------------------------------------------- declaring


def declared_hypotheses(
    config_path: str | Path, specifications: Sequence[Specification], combinations: Sequence[Combination],
) -> tuple[Hypothesis, ...]:
    """The hypotheses a study config declares under ``hypotheses``, each checked against the study.

    Parameters
    ----------
    config_path : str or Path
        The study YAML.
    specifications : sequence of Specification
        The specifications it declares.
    combinations : sequence of Combination
        Its planned combinations (:func:`~curiosity_cli.study.sweep.plan_sweep`): each hypothesis is checked
        against its specification's config and the seeds swept.

    Returns
    -------
    tuple of Hypothesis
        In the order declared; empty when the file declares none.

    Raises
    ------
    ConfigError
        A field missing, unknown or out of its range, or at odds with the study (module docstring), naming
        the file, the hypothesis and the field.
    """
    from curiosity_cli.yamlfile import read_yaml

    config_path = config_file(config_path)
    data = read_yaml(config_path, "config file")
    if HYPOTHESES_KEY not in data:
        return ()
    declared = data[HYPOTHESES_KEY]
    where = f"{display_path(config_path)}: {HYPOTHESES_KEY}"
    if not isinstance(declared, dict) or not set(declared) - {"alpha"}:
        raise ConfigError(f"{where}: expected alpha and a mapping of names to hypotheses, e.g. H1: {{claim: ...}}")
    if not specifications:
        raise ConfigError(f"{where}: a hypothesis names a specification; declare specifications too")
    alpha = _number(declared.get("alpha"), f"{where}.alpha", 0.0, 0.5, "a one-sided family level above 0, at most 0.5")
    configs = {}
    for combination in combinations:
        values = dict(text.split("=", 1) for text in combination.overrides)
        configs.setdefault(values[SPECIFICATION], {})[combination.config.seed] = combination.config
    found = []
    for name, fields in declared.items():
        if name == "alpha":
            continue
        at = f"{where}.{name}"
        if not isinstance(name, str) or not _NAME.match(name):
            raise ConfigError(f"{where}: {name!r}: expected a name of 1 to 40 letters, digits, '_', '.' or '-'")
        if not isinstance(fields, dict):
            raise ConfigError(f"{at}: expected a mapping of {', '.join(_REQUIRED)} (and {', '.join(_OPTIONAL)})")
        for key in fields:
            if key not in (*_REQUIRED, *_OPTIONAL):
                raise ConfigError(f"{at}: {key!r}: not a field; expected {', '.join((*_REQUIRED, *_OPTIONAL))}")
        for key in _REQUIRED:
            if key not in fields:
                raise ConfigError(f"{at}.{key}: missing; a hypothesis declares {', '.join(_REQUIRED)}")
        found.append(_hypothesis(name, fields, at, alpha, configs))
    return tuple(found)


def _hypothesis(name: str, fields: dict, at: str, alpha: float, configs: dict) -> Hypothesis:
    from curiosity_cli.errors import ParameterError
    from curiosity_cli.evaluate.measures import measure_named
    from curiosity_cli.maps.datasets import dataset_path, load_dataset_config

    specification = fields["specification"]
    if not isinstance(specification, str) or specification not in configs:
        raise ConfigError(f"{at}.specification: got {specification!r}, expected one of {', '.join(configs)}")
    config = next(iter(configs[specification].values()))  # its seeds differ in the seed alone
    walkers = list(config.explore.weight_functions)
    walker = fields.get("walker", "topic-perplexity")
    if not isinstance(walker, str) or walker not in walkers:
        raise ConfigError(f"{at}.walker: got {walker!r}, expected a walker {specification} runs: {', '.join(walkers)}")
    comparators = fields["comparators"]
    if (
        not isinstance(comparators, list) or not comparators or not all(isinstance(c, str) for c in comparators)
        or len(set(comparators)) != len(comparators) or walker in comparators or not set(comparators) <= set(walkers)
    ):
        raise ConfigError(
            f"{at}.comparators: got {comparators!r}, expected a list of other walkers {specification} runs, each once: "
            f"{', '.join(w for w in walkers if w != walker)}"
        )
    try:
        measure = measure_named(fields["measure"])
    except ParameterError as exc:
        raise ConfigError(f"{at}.{exc}") from None
    against = fields.get("against", next(iter(measure.columns)))
    if not isinstance(against, str) or against not in measure.columns:
        raise ConfigError(f"{at}.against: got {against!r}, expected one of {', '.join(measure.columns)} for {measure.name}")
    if not isinstance(fields["reading"], str):
        raise ConfigError(f"{at}.reading: got {fields['reading']!r}, expected a labelling reading's name, e.g. frozen")
    if fields["reading"] != config.label.reading:
        raise ConfigError(
            f"{at}.reading: got {fields['reading']!r}, but {specification} labels {config.label.reading!r} (label.reading)"
        )
    length = fields["path_length"]
    if isinstance(length, bool) or not isinstance(length, int) or length not in config.explore.checkpoints:
        raise ConfigError(
            f"{at}.path_length: got {length!r}, expected one of {specification}'s checkpoints: "
            f"{', '.join(map(str, config.explore.checkpoints))}"
        )
    schedule = fields["label_schedule"]
    given = {key: getattr(config.label, key) for key in _SCHEDULE}
    if (
        not isinstance(schedule, dict) or set(schedule) != set(_SCHEDULE)
        or any(type(schedule[k]) is not type(given[k]) or schedule[k] != given[k] for k in _SCHEDULE)
    ):
        raise ConfigError(
            f"{at}.label_schedule: got {schedule!r}, but {specification} labels with "
            f"{{sweeps: {given['sweeps']}, warm_sweeps: {given['warm_sweeps']}}}"
        )
    test = fields.get("test", TESTS[0])
    if test not in TESTS:
        raise ConfigError(f"{at}.test: got {test!r}, expected one of {', '.join(TESTS)}")
    draws = fields.get("draws", DRAWS)
    if not isinstance(draws, int) or isinstance(draws, bool) or not MIN_DRAWS <= draws <= MAX_DRAWS:
        raise ConfigError(f"{at}.draws: got {draws!r}, expected a whole number of sign flips from {MIN_DRAWS} to {MAX_DRAWS}")
    role = fields.get("role", ROLES[0])
    if role not in ROLES:
        raise ConfigError(f"{at}.role: got {role!r}, expected one of {', '.join(ROLES)}")
    seeds = fields["seeds"]
    # seeds the sweep does not run now (--sweep seed=3 runs one) leave the hypothesis untested, never tested on fewer
    if (
        not isinstance(seeds, list) or not seeds or len(set(map(str, seeds))) != len(seeds)
        or not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in seeds)
    ):
        raise ConfigError(f"{at}.seeds: got {seeds!r}, expected a list of seeds (whole numbers >= 0), each once")
    scale = fields["scale"]
    maps = [load_dataset_config(dataset_path(entry)).name for entry in config.datasets]  # as mi.csv names them
    if not isinstance(scale, dict) or not scale:
        raise ConfigError(f"{at}.scale: expected a mapping of the maps it pools to positive numbers, e.g. {{{maps[0]}: 1.0}}")
    for entry, value in scale.items():
        if entry not in maps:
            raise ConfigError(f"{at}.scale: {entry!r}: not a map of the study; expected some of {', '.join(maps)}")
        _number(value, f"{at}.scale.{entry}", MIN_SCALE, MAX_SCALE, f"a number above {MIN_SCALE:g} and at most {MAX_SCALE:g}")
    claim = fields["claim"]
    if not isinstance(claim, str) or not claim.strip() or "\n" in claim.strip():
        raise ConfigError(f"{at}.claim: expected the claim in words, on one line")
    return Hypothesis(
        name, claim.strip(), role == "primary", specification, walker, tuple(comparators), measure.name, against,
        fields["reading"], length, dict(schedule), test, draws, tuple(seeds), {k: float(v) for k, v in scale.items()}, alpha,
    )


def _number(value, at: str, low: float, high: float, expected: str) -> float:
    """``value`` as a finite float in ``(low, high]``, else refused naming ``at``."""
    if (
        isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value)
        or not low < value <= high
    ):
        raise ConfigError(f"{at}: got {value!r}, expected {expected}")
    return float(value)


# --------------------------------------------------------------------------- declared when


@dataclass(frozen=True)
class Declaration:
    """Since when the config's hypotheses read as they do now: the commit and its time; or why that is unknown."""

    commit: str | None
    time: datetime | None
    why: str | None = None


def declaration(config_path: Path) -> Declaration:
    """The earliest commit since which the config's ``hypotheses`` and ``specifications`` have read as they do now.

    Parameters
    ----------
    config_path : Path
        The study YAML, in a git work tree.

    Returns
    -------
    Declaration
        With ``why`` set, and no commit, when there is no git, the file is not in a repository, not
        committed, or edited since its last commit.
    """
    from curiosity_cli.yamlfile import parse_yaml, read_yaml

    path = Path(config_path).resolve()
    git = shutil.which("git")
    if git is None:
        return Declaration(None, None, "git is not installed, so when its hypotheses were declared cannot be read")

    def git_in(where: Path, *args: str) -> subprocess.CompletedProcess:
        return subprocess.run([git, "-C", str(where), *args], capture_output=True, text=True, check=False)

    top = git_in(path.parent, "rev-parse", "--show-toplevel")
    if top.returncode:
        return Declaration(None, None, f"{display_path(path)} is not in a git repository, so it was never committed")
    root = Path(top.stdout.strip()).resolve()
    relative = path.relative_to(root).as_posix()

    def run(*args: str) -> subprocess.CompletedProcess:
        # from the top: git reads a pathspec from the folder it runs in, and `relative` is the top's
        return git_in(root, *args)
    if run("status", "--porcelain", "--", relative).stdout.strip():
        return Declaration(None, None, f"{display_path(path)} is not committed as it is now")
    now = _declared_part(read_yaml(path, "config file"))
    found = None
    for line in run("log", "--format=%H %cI", "--", relative).stdout.split("\n"):
        if not line:
            break
        commit, when = line.split(" ", 1)
        shown = run("show", f"{commit}:{relative}")
        if shown.returncode or _declared_part(parse_yaml(shown.stdout, "config file") or {}) != now:
            break
        found = Declaration(commit, datetime.fromisoformat(when))
    return found or Declaration(None, None, f"{display_path(path)} is not committed")


def _declared_part(config) -> dict:
    """What a declaration is: the hypotheses and the specifications they name."""
    config = config if isinstance(config, dict) else {}
    return {key: config.get(key) for key in (HYPOTHESES_KEY, SPECIFICATIONS_KEY)}


# --------------------------------------------------------------------------- testing


def hypothesis_table(sweep: Sweep, outcomes: Sequence[Outcome], record: Path | None):
    """Test every hypothesis of ``sweep`` on the combinations that finished (module docstring).

    Parameters
    ----------
    sweep : Sweep
        With its :attr:`~curiosity_cli.study.types.Sweep.hypotheses`.
    outcomes : sequence of Outcome
        Every combination's, computed or taken from ``record``.
    record : Path or None
        The study's record.

    Returns
    -------
    table : pandas.DataFrame
        :data:`TABLE`'s rows (:data:`COLUMNS`): per hypothesis one row of its decision (``comparator`` empty,
        ``scope`` ``pooled``), one per comparator pooled, and per map one of its decision and one per comparator.
    declared : Declaration
        Since when the hypotheses read as they do.
    """
    import pandas as pd

    from curiosity_cli.evaluate.multiplicity import holm

    declared = declaration(sweep.config_path)
    by_index = {outcome.combination.index: outcome for outcome in outcomes}
    rows = []
    for hypothesis in sweep.hypotheses:
        combinations = _combinations(sweep, hypothesis)
        finished = {
            c.config.seed for c in combinations if by_index.get(c.index) is not None and by_index[c.index].error is None
        }
        swept = {c.config.seed for c in combinations}
        missing = sorted(set(hypothesis.seeds) - finished)
        outside = sorted(set(hypothesis.seeds) - swept)
        base = {
            "hypothesis": hypothesis.name, "role": "primary" if hypothesis.primary else "secondary",
            "specification": hypothesis.specification, "walker": hypothesis.walker, "measure": hypothesis.measure,
            "against": hypothesis.against, "reading": hypothesis.reading, "path_length": hypothesis.path_length,
            "test": hypothesis.test, "seeds": " ".join(map(str, hypothesis.seeds)), "alpha": hypothesis.alpha,
        }
        if outside:
            seeds = ", ".join(map(str, outside))
            rows.append({**base, "scope": "pooled", "decision": f"not tested: seed {seeds} not in this sweep"})
            continue
        if missing:
            seeds = ", ".join(map(str, missing))
            rows.append({**base, "scope": "pooled", "decision": f"not tested: seed {seeds} not finished"})
            continue
        status = _status(hypothesis, sweep, combinations, [by_index[c.index] for c in combinations], record, declared)
        try:
            blocks = _blocks(hypothesis, [by_index[c.index].tables for c in combinations])
        except _Untestable as exc:
            rows.append({**base, "scope": "pooled", "status": status, "decision": f"not tested: {exc}"})
            continue
        rows += _tested(hypothesis, blocks, {**base, "status": status})
    table = pd.DataFrame(rows, columns=COLUMNS)
    head = table["comparator"].isna() & (table["scope"] == "pooled")
    primary, secondary = head & (table["role"] == "primary"), head & (table["role"] == "secondary")
    untested = table.loc[primary & table["p_value"].isna(), "hypothesis"].tolist()
    if untested:  # Holm over fewer than the family declared would claim at a laxer level than declared
        table.loc[primary & table["p_value"].notna(), "decision"] = f"not decided: {', '.join(untested)} not tested"
    elif primary.any():
        table.loc[primary, "p_holm"] = holm(table.loc[primary, "p_value"].to_numpy(float))
        table.loc[primary, "decision"] = np.where(
            table.loc[primary, "p_holm"] <= table.loc[primary, "alpha"], "confirmed", "not confirmed"
        )
    tested = secondary & table["p_value"].notna()
    table.loc[tested, "decision"] = np.where(
        table.loc[tested, "p_value"] <= table.loc[tested, "alpha"], "ahead (secondary)", "not ahead (secondary)"
    )
    return table, declared


#: :data:`TABLE`'s columns.
COLUMNS = [
    "hypothesis", "role", "scope", "comparator", "specification", "walker", "measure", "against", "reading",
    "path_length", "test", "seeds", "pairs", "difference", "ci_low", "ci_high", "raw_difference", "p_value",
    "p_holm", "alpha", "decision", "status",
]


class _Untestable(Exception):
    """What keeps a hypothesis from being tested on tables it was given."""


def _combinations(sweep: Sweep, hypothesis: Hypothesis) -> list[Combination]:
    """The study's combinations of the hypothesis's specification and seeds."""
    chosen = []
    for combination in sweep.combinations:
        values = dict(text.split("=", 1) for text in combination.overrides)
        if values[SPECIFICATION] == hypothesis.specification and combination.config.seed in hypothesis.seeds:
            chosen.append(combination)
    return chosen


def _blocks(hypothesis: Hypothesis, folders: Sequence[Path]) -> dict:
    """Per map, its pairs' measure: a row per (seed, restart), a column per walker of the hypothesis."""
    import pandas as pd

    from curiosity_cli.evaluate.measures import measure_named
    from curiosity_cli.evaluate.tables import read_table
    from curiosity_cli.experiment.layout import ExperimentFolder

    column = measure_named(hypothesis.measure).columns[hypothesis.against]
    tables = []
    for folder in folders:
        path = ExperimentFolder(folder).table("mi")
        mi = read_table(path)
        if column not in mi:
            raise _Untestable(f"{display_path(path)} has no {column} (made before {hypothesis.measure} was measured)")
        tables.append(mi)
    mi = pd.concat(tables, ignore_index=True)
    walkers = [hypothesis.walker, *hypothesis.comparators]
    mi = mi[(mi["path_length"] == hypothesis.path_length) & mi["weight_function"].isin(walkers)]
    blocks = {}
    for entry in hypothesis.maps:
        rows = mi[mi["dataset"] == entry]
        block = rows.pivot_table(index=["replicate", "restart"], columns="weight_function", values=column)
        if block.empty or not set(walkers) <= set(block.columns):
            raise _Untestable(f"no runs of {', '.join(walkers)} on {entry} at {hypothesis.path_length} steps")
        blocks[entry] = block[walkers]
    return blocks


def _tested(hypothesis: Hypothesis, blocks: Mapping[str, object], base: dict) -> list[dict]:
    """The rows of a hypothesis with all its seeds: pooled, then per map."""
    from curiosity_cli.evaluate.measures import measure_named
    from curiosity_cli.evaluate.multiplicity import holm

    lower = measure_named(hypothesis.measure).lower_is_better
    pooled, per_map = [], {entry: [] for entry in blocks}
    for comparator in hypothesis.comparators:
        differences, strata, raw = [], [], []
        for entry, block in blocks.items():
            pair = block[[hypothesis.walker, comparator]].dropna().to_numpy(float)
            lead = pair[:, 1] - pair[:, 0] if lower else pair[:, 0] - pair[:, 1]
            differences.append(lead / hypothesis.scale[entry])
            raw.append(lead)
            strata += [entry] * len(lead)
            per_map[entry].append(
                _comparison(hypothesis, comparator, entry, lead / hypothesis.scale[entry], [entry] * len(lead), lead, base)
            )
        pooled.append(
            _comparison(hypothesis, comparator, "pooled", np.concatenate(differences), strata, np.concatenate(raw), base)
        )
    rows = [_decision(hypothesis, pooled, "pooled", base), *pooled]
    decisions = [_decision(hypothesis, comparisons, entry, base) for entry, comparisons in per_map.items()]
    for row, adjusted in zip(decisions, holm([row["p_value"] for row in decisions])):
        row["p_holm"] = adjusted
        row["decision"] = "ahead" if adjusted <= hypothesis.alpha else "not ahead"
    for row, (entry, comparisons) in zip(decisions, per_map.items()):
        rows += [row, *comparisons]
    return rows


def _comparison(hypothesis: Hypothesis, comparator: str, scope: str, differences, strata, raw, base: dict) -> dict:
    """One comparator's row: the stratified mean lead (scaled, and in the measure's unit), its interval and p."""
    from curiosity_cli.evaluate.confirmation import Stratified, sign_flip_test, stratified_t
    from curiosity_cli.seeds import name_key

    row = {**base, "scope": scope, "comparator": comparator, "pairs": len(strata)}
    if not len(strata):
        return {**row, "p_value": np.nan}
    stratified = Stratified.of(differences, strata)
    t = stratified_t(stratified)
    unscaled = Stratified.of(raw, strata)
    if hypothesis.test == "sign-flip":
        rng = np.random.default_rng([name_key(hypothesis.name), name_key(comparator), name_key(scope)])
        p = sign_flip_test(stratified, hypothesis.draws, rng)
    else:
        p = t.p_value
    return {
        **row, "difference": t.statistic, "ci_low": t.ci_low, "ci_high": t.ci_high,
        "raw_difference": unscaled.statistic, "p_value": p,
    }


def _decision(hypothesis: Hypothesis, comparisons: Sequence[dict], scope: str, base: dict) -> dict:
    """The intersection-union row of a scope: its p the largest of its comparators'."""
    p = [row["p_value"] for row in comparisons]
    return {
        **base, "scope": scope, "comparator": None, "pairs": min(row["pairs"] for row in comparisons),
        "p_value": float(max(p)) if all(v == v for v in p) else np.nan,
    }


# --------------------------------------------------------------------------- confirmatory or not


def _status(
    hypothesis: Hypothesis, sweep: Sweep, combinations: Sequence[Combination], outcomes: Sequence[Outcome],
    record: Path | None, declared: Declaration,
) -> str:
    """``confirmatory``, or ``exploratory: `` and every reason it is not (module docstring)."""
    from curiosity_cli.study.record import StudyRecord

    reasons = []
    if record is None:
        reasons.append("no --record, so its runs cannot be compared with the studies recorded")
    else:
        kept = StudyRecord(record, sweep)
        reasons += _seen_before(hypothesis, [kept.folder(c) for c in combinations], Path(record))
    if declared.commit is None:
        reasons.append(declared.why)
    else:
        late = [o for o in outcomes if (began := _started(o.tables)) is None or began <= declared.time]
        if late:
            names = ", ".join(o.combination.name for o in late)
            reasons.append(
                f"{names} began before its hypotheses were declared as they are (commit {declared.commit[:7]}, "
                f"{declared.time.isoformat()}), or says not when"
            )
    return "confirmatory" if not reasons else "exploratory: " + "; ".join(reasons)


def _started(folder: Path) -> datetime | None:
    """When an experiment began (``provenance.yaml``'s ``started``), or None where it does not say."""
    import yaml

    try:
        text = yaml.safe_load((Path(folder) / "provenance.yaml").read_text())
        began = datetime.fromisoformat(str(text["started"]))
    except (OSError, ValueError, TypeError, KeyError, yaml.YAMLError):
        return None
    return began if began.tzinfo is not None else None


def _seen_before(hypothesis: Hypothesis, folders: Sequence[Path], record: Path) -> list[str]:
    """Why the runs this hypothesis pools (its recorded ``folders``) were seen before: another study recorded beside
    ``record`` holds one of them (the same run recipe), or one is not recorded to compare."""
    from curiosity_cli.study.record import RECORD_FILE

    own, reasons = {}, []
    for folder in folders:
        recipes = _recipes(folder / RECORD_FILE)
        if not recipes:
            reasons.append(f"{display_path(folder)} is not recorded, so its runs cannot be compared with other studies'")
        for entry in hypothesis.maps:
            if entry in recipes:
                own[_key(recipes[entry])] = f"{entry}, {folder.parent.name}"
    root = record.resolve()
    seen = {}
    for path in sorted(record.parent.glob(f"*/seed-*/*/{RECORD_FILE}")):
        if root in path.resolve().parents:
            continue
        for run in _recipes(path).values():
            if (hit := own.get(_key(run))) is not None:
                seen.setdefault(hit, display_path(path.parent))
    return reasons + [
        f"its runs of {hit} under {hypothesis.specification}'s settings were recorded before in {where}"
        for hit, where in seen.items()
    ]


def _recipes(path: Path) -> dict:
    """Per map, the run recipe a recorded folder's ``record.yaml`` holds; empty where unreadable."""
    import yaml

    try:
        recorded = yaml.load(path.read_text(), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
        return {entry: facts["run"] for entry, facts in recorded["recipes"]["maps"].items()}
    except (OSError, TypeError, KeyError, AttributeError, yaml.YAMLError):
        return {}


def _key(run) -> str:
    import json

    return json.dumps(run, sort_keys=True, default=str)


# --------------------------------------------------------------------------- reporting


def hypothesis_lines(sweep: Sweep, table, declared: Declaration) -> list[str]:
    """The section ``SWEEP.md`` leads with: each hypothesis confirmed or not, then its comparators and maps.

    Parameters
    ----------
    sweep : Sweep
    table : pandas.DataFrame
        :func:`hypothesis_table`'s.
    declared : Declaration

    Returns
    -------
    list of str
        Markdown lines.
    """
    from curiosity_cli.evaluate.measures import measure_named
    from curiosity_cli.evaluate.report import number

    since = (
        f"reading as they do now since commit {declared.commit[:7]} ({declared.time.isoformat()})"
        if declared.commit is not None else f"not dated: {declared.why}"
    )
    primary = [h for h in sweep.hypotheses if h.primary]
    family = (
        f"Holm over the {len(primary)} primary hypotheses at a family α of {number(primary[0].alpha, 3)} (one-sided): "
        "a primary hypothesis is confirmed where its Holm p is at most α; a secondary one is reported beside "
        "them, unadjusted, and decides nothing."
    ) if primary else "Every hypothesis is secondary: reported, unadjusted; none decides anything."
    lines = [
        f"## Declared hypotheses ({TABLE})", "",
        f"Declared in `{display_path(sweep.config_path)}`, {since}. Each compares its walker with each comparator on "
        "paired runs (the same map, seed and restart: the same start cell), the walker's lead divided by its map's "
        "declared scale and pooled as the mean over maps of each map's mean (positive: the walker ahead). Its p is the "
        "largest of its comparators' one-sided p (the intersection-union test: it claims a lead over each); "
        f"{family} A hypothesis is confirmatory only when declared in a commit before any of its data began and none "
        "of its runs was recorded before by another study; else its status says why it is exploratory.",
        "",
        "| hypothesis | claim | role | specification | measure at length | seeds | pairs | p | Holm p | decision | status |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    heads = table[table["comparator"].isna() & (table["scope"] == "pooled")]
    for hypothesis, row in zip(sweep.hypotheses, heads.itertuples()):
        measure = measure_named(hypothesis.measure)
        decision = f"**{row.decision}**" if row.decision == "confirmed" else row.decision
        lines.append(
            f"| {hypothesis.name} | {hypothesis.claim.replace('|', chr(92) + '|')} | {row.role} | `{hypothesis.specification}` | {measure.title} "
            f"({hypothesis.against}) at {hypothesis.path_length} | {row.seeds} | {number(row.pairs, 0)} | "
            f"{_p(row.p_value)} | {_p(row.p_holm)} | {decision} | {row.status if row.status == row.status else ''} |"
        )
    lines += [
        "", "Per comparator, every map pooled: the lead scaled (the mean over maps) with its 95 % interval (stratified t), "
        "the same in the measure's unit, and the one-sided p of the declared test.", "",
        "| hypothesis | comparator | pairs | lead, scaled [95 % CI] | lead (unit) | p | test |",
        "|---|---|---|---|---|---|---|",
    ]
    for hypothesis in sweep.hypotheses:
        unit = measure_named(hypothesis.measure).unit
        rows = table[(table["hypothesis"] == hypothesis.name) & (table["scope"] == "pooled") & table["comparator"].notna()]
        for row in rows.itertuples():
            lines.append(
                f"| {hypothesis.name} | {row.comparator} | {number(row.pairs, 0)} | {number(row.difference, 3)} "
                f"[{number(row.ci_low, 3)}, {number(row.ci_high, 3)}] | {number(row.raw_difference, 3)} {unit} | "
                f"{_p(row.p_value)} | {hypothesis.test} |"
            )
    lines += [
        "", "Per map (secondary): the largest of the comparators' p on that map alone, Holm over the hypothesis's maps.", "",
        "| hypothesis | map | pairs | lead over each comparator (unit) | p | Holm p | at α |",
        "|---|---|---|---|---|---|---|",
    ]
    for hypothesis in sweep.hypotheses:
        mine = table[(table["hypothesis"] == hypothesis.name) & (table["scope"] != "pooled")]
        for scope, rows in mine.groupby("scope", sort=False):
            head = rows[rows["comparator"].isna()].iloc[0]
            leads = ", ".join(
                f"{r.comparator} {number(r.raw_difference, 3)}" for r in rows[rows["comparator"].notna()].itertuples()
            )
            lines.append(
                f"| {hypothesis.name} | {scope} | {number(head['pairs'], 0)} | {leads} | {_p(head['p_value'])} | "
                f"{_p(head['p_holm'])} | {head['decision']} |"
            )
    return lines + [""]


def _p(value) -> str:
    """A p-value to three significant digits (a confirmation's is read against 0.0125), empty where untested."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        return ""
    return f"{value:.3g}" if value == value else ""
