"""Parameter sweeps: ``curiosity reproduce CONFIG --sweep KEY=V1,V2 --sweep KEY2=W1,...``.

A sweep runs the whole pipeline (:func:`curiosity_cli.study.pipeline.reproduce`) once per
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
written. A study config may also declare specifications, named sets of overrides under
each of which every combination runs (:mod:`curiosity_cli.study.specifications`): a
combination is then a (specification, swept values) pair, named
``specification-NAME_KEY-VALUE...``.

Layout
------
For an experiment config named ``quick``, everything goes under
``<results>/quick-sweep/``::

    quick-sweep/
      sweep.yaml                               the config, --set options, and per combination
                                               its folder and overrides (written first)
      SWEEP.md, sweep.csv, sensitivity.csv     the report (written last: :mod:`curiosity_cli.study.report`)
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
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import replace
from pathlib import Path

from curiosity_cli.config import config_file, load_config
from curiosity_cli.errors import ConfigError, CuriosityError
from curiosity_cli.files import atomic_path, display_path
from curiosity_cli.paths import DEFAULT_RESULTS
from curiosity_cli.schema import MAX_NAME, OVERRIDES
from curiosity_cli.study.hypotheses import declared_hypotheses
from curiosity_cli.study.specifications import check_specifications, specification_error
from curiosity_cli.study.types import (
    SPECIFICATION,
    Combination,
    Outcome,
    Specification,
    Sweep,
    SweepAxis,
    SweepError,
    SweepSyntaxError,
    count,
    overlap,
    override_at,
    parsed_value,
    value_text,
)

_SAFE = re.compile(r"[^A-Za-z0-9_.-]+")
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
_OPENING, _CLOSING = "[{", "]}"


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
            if overlap(key, other):
                raise SweepSyntaxError(f"{text!r}: {other} is already swept; give each key once")
        for other in set_keys:
            if overlap(key, other):
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
        texts = [value_text(value) for value in values]
        if any(split_values(text) != [text] for text in texts):
            raise ConfigError(f"{where}.{key}: a value with a comma outside brackets; write it as a list")
        options.append(f"{key}={','.join(texts)}")
    return options


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
    if len(name) > MAX_NAME:
        name = f"{name[:MAX_NAME - 9].rstrip('-_.')}-{_digest(json.dumps(overrides), 8)}"
    return name


def _part(key: str, value: str) -> str:
    key, value = key.strip(), value.strip()
    safe = _SAFE.sub("-", value).strip("-")
    if safe == value:
        return f"{key}-{value}"
    digest = _digest(json.dumps([key, parsed_value(value)], sort_keys=True, default=str), 6)
    return f"{key}-{safe}-{digest}" if safe else f"{key}-{digest}"


def _digest(text: str, digits: int) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:digits]


# --------------------------------------------------------------------------- planning


def plan_sweep(
    config_path: str | Path, axes: Sequence[SweepAxis], sets: Sequence[str] = (),
    specifications: Sequence[Specification] = (), declared: Iterable[str] = (),
) -> Sweep:
    """Load and validate every combination of a sweep; nothing is written.

    Parameters
    ----------
    config_path : str or Path
        The experiment YAML.
    axes : sequence of SweepAxis
        From :func:`parse_sweeps`; at least one, unless there are ``specifications``.
    sets : sequence of str
        ``--set KEY=VALUE`` options applied to every combination, before its own values.
    specifications : sequence of Specification
        A study's (:func:`curiosity_cli.study.specifications.declared_specifications`): every
        combination of ``axes`` runs under each, its overrides after ``sets``.
    declared : iterable of str
        The keys of ``axes`` whose values the config file's ``sweep:`` gave
        (:func:`declared_sweeps`), not a ``--sweep`` option: an error in one names the file.

    Returns
    -------
    Sweep

    Raises
    ------
    ConfigError
        The first combination that does not validate, in one line: the error its
        overrides give, naming the specification's key in the config file, or the sweeps,
        when one of theirs is at fault, else followed by the combination; or a
        specification's key also swept or given with ``--set``; a declared hypothesis at odds with the study
        (:func:`~curiosity_cli.study.hypotheses.declared_hypotheses`).
    """
    if not axes and not specifications:
        raise ValueError("a sweep needs at least one axis or specification")
    config_path = config_file(config_path)
    sets = tuple(sets)
    keys = [axis.key for axis in axes]
    check_specifications(config_path, specifications, keys, sets)
    loaded, base_name = [], None
    for specification in specifications or (None,):
        own = specification.overrides if specification is not None else ()
        for values in combinations(axes):
            overrides = values if specification is None else (f"{SPECIFICATION}={specification.name}", *values)
            try:
                config = load_config(config_path, [*sets, *own, *values])
            except ConfigError as exc:
                error = specification_error(exc, config_path, specification) if specification is not None else None
                raise error or _combination_error(exc, keys, overrides, config_path, set(declared)) from None
            base_name = config.name  # the same for every combination: name cannot be swept
            name = combination_name(overrides)
            assert _NAME.match(name), name  # by construction: keys are config fields, values made safe
            loaded.append(Combination(len(loaded) + 1, overrides, name, replace(config, name=name)))
    _check_each_changes_something(loaded)
    hypotheses = declared_hypotheses(config_path, specifications, loaded)
    return Sweep(base_name, config_path, sets, tuple(axes), tuple(loaded), tuple(specifications), hypotheses)


def _check_each_changes_something(combinations: Sequence[Combination]) -> None:
    """Refuse two combinations of one seed that make the same experiment: a swept or specified
    value that no setting reads under the others (``words.orb_grid_step`` with the keypoints
    detector) would be reported as two treatments that are one. The words and explore
    sections are compared by the keys their numbers depend on
    (:meth:`~curiosity_cli.config.WordsConfig.read_settings`,
    :meth:`~curiosity_cli.config.ExploreConfig.run_settings`).

    Raises
    ------
    ConfigError
        Naming the two combinations and the keys in which they differ.
    """
    from curiosity_cli.config_yaml import to_dict

    seen = {}
    for combination in combinations:
        settings = to_dict(combination.config)
        # only the keys that change the numbers: the words its ORB detector reads, the explore keys a run reads
        settings["words"] = combination.config.words.read_settings()
        settings["explore"] = combination.config.explore.run_settings()
        settings.pop("name")
        key = json.dumps(settings, sort_keys=True, default=str)
        if (other := seen.get(key)) is not None:
            differ = [o.split("=", 1)[0] for o in combination.overrides if o not in other.overrides]
            raise ConfigError(
                f"sweeps: {', '.join(other.overrides)} and {', '.join(combination.overrides)} make the same experiment: "
                f"{', '.join(differ)} {'changes' if len(differ) == 1 else 'change'} nothing under the other settings; "
                "sweep only values that are read"
            )
        seen[key] = combination


def _combination_error(
    exc: ConfigError, keys: Sequence[str], overrides: Sequence[str], config_path: Path, declared: set[str],
) -> ConfigError:
    """The error of a combination that does not validate: the overrides' error, naming the
    sweeps (or the config file's ``sweep:``, for a key it declares) when a swept key is at
    fault, else followed by the combination."""
    from curiosity_cli.config import SWEEP_KEY

    if exc.parameter == OVERRIDES and str(exc)[len(OVERRIDES):].startswith(" "):
        return exc  # a malformed override: not the sweep's doing
    if (found := override_at(exc, keys)) is not None:
        key, at = found
        if key in declared:
            return ConfigError(f"{display_path(config_path)}: {SWEEP_KEY}.{at}")
        return ConfigError(f"sweeps: {at}", parameter="sweeps")
    return ConfigError(f"{exc} (with the sweep's {', '.join(overrides)})", parameter=exc.parameter)


# --------------------------------------------------------------------------- running


def run_sweep(
    sweep: Sweep,
    *,
    results_dir: Path = DEFAULT_RESULTS,
    on_stage: Callable[[str, int], None] | None = None,
    record: Path | None = None,
    measure: str = "mi",
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
        As :func:`~curiosity_cli.study.pipeline.reproduce`'s; each combination is also
        announced as a stage without units, ``"combination 2/3: model.topics=32"``.
    record : Path, optional
        A study's record (:mod:`curiosity_cli.study.record`): the combinations it holds are
        taken from it, not computed; each one computed is recorded there when it finishes.
    measure : str
        A study's specification curve of this measure too (:func:`~curiosity_cli.study.curve.specification_lead`).
    **pipeline
        The other keywords of :func:`curiosity_cli.study.pipeline.reproduce` (``cache_dir``,
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
    RecordError
        Before anything runs: ``sweep`` is not a study of seeds, or a recorded
        combination was made otherwise (:meth:`~curiosity_cli.study.record.StudyRecord.recorded`).
    """
    from curiosity_cli.study.pipeline import reproduce
    from curiosity_cli.study.record import StudyRecord
    from curiosity_cli.study.report import write_sweep_report
    from curiosity_cli.topics.devices import resolve_device

    kept = StudyRecord(record, sweep) if record is not None else None
    taken = kept.recorded() if kept is not None else {}
    if kept is not None and len(taken) < len(sweep.combinations):
        kept.check_writable()  # what it computes is recorded as it finishes: refused now, not after the first
    for combination in sweep.combinations:  # a GPU one combination asks for and this machine lacks: before any runs
        if combination.index not in taken:
            resolve_device(combination.config.label.device)
    folder = sweep.folder(results_dir)
    write_plan(sweep, folder)
    total = len(sweep.combinations)
    outcomes = []
    for combination in sweep.combinations:
        if on_stage is not None:
            recorded = f" (taken from {display_path(taken[combination.index])})" if combination.index in taken else ""
            on_stage(f"combination {combination.index}/{total}: {combination.label}{recorded}", 0)
        if combination.index in taken:
            outcomes.append(Outcome(combination, None, None, 0.0, taken[combination.index], taken=True))
            continue
        started = time.perf_counter()
        try:
            report = reproduce(combination.config, results_dir=folder, on_stage=on_stage, **pipeline)
            if kept is not None:
                kept.keep(combination, folder / combination.name)
            outcomes.append(Outcome(combination, report, None, time.perf_counter() - started, folder / combination.name))
        except CuriosityError as exc:
            outcomes.append(Outcome(combination, None, str(exc), time.perf_counter() - started))
    path = write_sweep_report(sweep, folder, outcomes, record, measure)
    failed = [o for o in outcomes if o.error is not None]
    if failed:
        raise SweepError(
            f"{len(failed)} of {count(total, 'combination')} failed ({display_path(path)} has the others; "
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
        "specifications": {s.name: list(s.overrides) for s in sweep.specifications},
        "combinations": [
            {"index": c.index, "folder": c.name, "overrides": list(c.overrides)} for c in sweep.combinations
        ],
    }
    path = Path(folder) / "sweep.yaml"
    with atomic_path(path) as tmp:
        tmp.write_text(yaml.safe_dump(plan, sort_keys=False))
    return path
