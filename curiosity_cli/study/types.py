"""What the study's modules share: a sweep and its combinations, a specification, a treatment
and an outcome, and how an override's key is read.

A study (``curiosity reproduce`` of a config that declares a sweep or specifications) is
planned by :mod:`~curiosity_cli.study.sweep` and :mod:`~curiosity_cli.study.specifications`,
run one experiment at a time by :mod:`~curiosity_cli.study.pipeline`, reported by
:mod:`~curiosity_cli.study.report` and :mod:`~curiosity_cli.study.curve`, and kept by
:mod:`~curiosity_cli.study.record`; each of them imports this module and none of the others
imports back.
"""

from __future__ import annotations

import json
import shlex
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from curiosity_cli.config import ExperimentConfig
from curiosity_cli.errors import ConfigError, CuriosityError
from curiosity_cli.files import display_path
from curiosity_cli.paths import DEFAULT_RESULTS
from curiosity_cli.schema import OVERRIDES

if TYPE_CHECKING:
    from collections.abc import Iterable

    from curiosity_cli.evaluate.replicates import Pooled



#: How a combination's overrides and a sweep's report name its specification: ``specification=NAME``.
SPECIFICATION = "specification"


#: The key whose values are replicates, pooled in SWEEP.md's first table, not treatments.
REPLICATE_KEY = "seed"


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
        ``KEY=VALUE`` for every swept key, in ``--sweep`` order (``--set`` syntax); in a
        study that declares specifications, ``specification=NAME`` first
        (:data:`SPECIFICATION`).
    name : str
        Its experiment name and folder (module docstring).
    config : ExperimentConfig
        The validated config: the file, the ``--set`` options, the specification's
        overrides, then the swept values.
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
        In product order (each specification's, in the order declared, in turn).
    specifications : tuple of Specification
        The specifications the config declares (:mod:`curiosity_cli.study.specifications`);
        empty for a plain sweep.
    hypotheses : tuple of Hypothesis
        The hypotheses the config declares (:mod:`curiosity_cli.study.hypotheses`), checked against
        its specifications and seeds; empty when it declares none.
    """

    name: str
    config_path: Path
    sets: tuple[str, ...]
    axes: tuple[SweepAxis, ...]
    combinations: tuple[Combination, ...] = field(repr=False)
    specifications: tuple[Specification, ...] = ()
    hypotheses: tuple[Hypothesis, ...] = ()

    @property
    def keys(self) -> list[str]:
        """What tells the combinations apart, as their ``overrides`` name it: the swept keys,
        after ``specification`` in a study that declares specifications."""
        return [SPECIFICATION] * bool(self.specifications) + [axis.key for axis in self.axes]

    def folder(self, results_dir: Path) -> Path:
        """The sweep's folder under ``results_dir``."""
        return Path(results_dir) / f"{self.name}-sweep"

    def command(self, results_dir: Path = DEFAULT_RESULTS, record: Path | None = None) -> str:
        """The ``curiosity reproduce`` command that runs (or resumes) this sweep in ``results_dir``,
        keeping its ``record`` (:mod:`curiosity_cli.study.record`) if given."""
        words = ["curiosity", "reproduce", display_path(self.config_path)]
        if Path(results_dir) != DEFAULT_RESULTS:
            words += ["--results-dir", display_path(results_dir)]
        if record is not None:
            words += ["--record", display_path(record)]
        for text in self.sets:
            words += ["--set", text]
        for axis in self.axes:
            words += ["--sweep", f"{axis.key}={','.join(axis.values)}"]
        return shlex.join(words)


@dataclass(frozen=True)
class Outcome:
    """What running one combination gave: its report, or why it failed, and its time.

    Attributes
    ----------
    tables : Path or None
        The folder its tables are in: its experiment folder, or the folder of a study's
        record it was taken from (:mod:`curiosity_cli.study.record`); None if it failed.
    taken : bool
        Taken from a record, not computed.
    """

    combination: Combination
    report: Path | None
    error: str | None
    seconds: float
    tables: Path | None = None
    taken: bool = False


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


@dataclass(frozen=True)
class Hypothesis:
    """One declared hypothesis: that ``walker`` does better than each of ``comparators`` on a measure, pooled
    over the maps of ``scale`` and the seeds declared (:mod:`curiosity_cli.study.hypotheses` says each field).

    Attributes
    ----------
    name, claim : str
        Its name (``H1``) and the claim in words.
    primary : bool
        In the family whose p-values Holm adjusts; a secondary hypothesis is reported and decides nothing.
    specification : str
    walker : str
    comparators : tuple of str
    measure, against : str
        A measure of :data:`~curiosity_cli.evaluate.measures.MEASURES` and the labelling it is taken against.
    reading : str
        The labelling reading (``label.reading``) the specification labels with.
    path_length : int
    label_schedule : dict of str to int or None
        ``sweeps`` and ``warm_sweeps``, as the specification's ``label`` section has them.
    test : str
        ``sign-flip`` or ``stratified-t`` (:mod:`curiosity_cli.evaluate.confirmation`).
    draws : int
        The sign flips drawn.
    seeds : tuple of int
    scale : dict of str to float
        Per map, what its paired differences are divided by.
    alpha : float
        The family's one-sided level.
    """

    name: str
    claim: str
    primary: bool
    specification: str
    walker: str
    comparators: tuple[str, ...]
    measure: str
    against: str
    reading: str
    path_length: int
    label_schedule: dict
    test: str
    draws: int
    seeds: tuple[int, ...]
    scale: dict
    alpha: float

    @property
    def maps(self) -> list[str]:
        """The maps it pools, in the order declared."""
        return list(self.scale)


@dataclass(frozen=True)
class Treatment:
    """The combinations of a sweep that differ only in their seed, and their pairs pooled.

    Attributes
    ----------
    values : dict of str to str
        Each key of the sweep but the seed (``specification`` first in a study), and its value.
    combinations : tuple of Combination
        Its combinations that finished, one per seed.
    pooled : Pooled or None
        :func:`~curiosity_cli.evaluate.replicates.pool` of their folders; None when they
        could not be pooled (``error`` says why).
    error : str or None
    """

    values: dict[str, str]
    combinations: tuple[Combination, ...]
    pooled: Pooled | None
    error: str | None = None


def count(n: int, noun: str) -> str:
    """``n`` and ``noun``, plural unless ``n`` is 1: ``3 combinations``."""
    return f"{n} {noun}{'' if n == 1 else 's'}"


def overlap(key: str, other: str) -> bool:
    """Whether two dotted keys set the same leaf (equal, or one a section of the other)."""
    return key == other or key.startswith(other + ".") or other.startswith(key + ".")


def value_text(value) -> str:
    """A YAML value as a ``--sweep`` value that reads back to it: strings as typed when they can be."""
    if isinstance(value, str) and parsed_value(value) == value:
        return value
    return json.dumps(value)


def parsed_value(value: str):
    """A value as an override reads it (YAML, with the numbers a person types)."""
    from curiosity_cli.yamlfile import parse_yaml

    return parse_yaml(value, "sweeps")


def override_at(exc: ConfigError, keys: Iterable[str]) -> tuple[str, str] | None:
    """Which of ``keys`` an override's error is about, and the error from that key on
    (``model.topics: got 1 ...``); None when it is about none of them, or not an override's."""
    if exc.parameter != OVERRIDES:
        return None
    rest = str(exc)[len(OVERRIDES):]
    if not rest.startswith(": "):
        return None
    at = rest[2:]
    for key in keys:
        if at.startswith(key) and at[len(key):len(key) + 1] in (":", ".", "["):
            return key, at
    return None
