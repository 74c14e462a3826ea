"""Declared specifications: a study config's named sets of overrides, read and checked.

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
experiment folder under ``<results>/<name>-sweep/`` (:func:`curiosity_cli.study.sweep.plan_sweep`,
:func:`~curiosity_cli.study.sweep.run_sweep`). Every (specification, combination) is loaded
and validated before the first runs: a bad key or value is refused in one line naming
the config file, the specification and the key
(``study.yaml: specifications.clamp.explore.coverage: got 'clmap', expected one of ...``).

A folder is named by the specification's name and the swept values only
(:func:`~curiosity_cli.study.sweep.combination_name` of ``specification=NAME`` and then the
swept ``KEY=VALUE``: ``specification-clamp_seed-1``), so adding a specification finds
the finished ones where they were, and a killed study resumes with its finished runs and
labels kept. The overrides are not in the name: after changing a specification's
overrides, its folders refuse the new config as any experiment does; give it a new name.

The curve they give is :mod:`curiosity_cli.study.curve`'s.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

from curiosity_cli.config import SPECIFICATIONS_KEY, config_file
from curiosity_cli.errors import ConfigError
from curiosity_cli.files import display_path
from curiosity_cli.study.types import Specification, Sweep, count, overlap, override_at, value_text


#: A name leaves room in its folders' names (at most MAX_NAME) for ``specification-`` and the swept values.
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,79}$")


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
    found = override_at(exc, specification.keys)
    if found is None:
        return None
    return ConfigError(f"{display_path(config_path)}: {SPECIFICATIONS_KEY}.{specification.name}.{found[1]}")


def study_size(sweep: Sweep) -> str:
    """A study's size in words: ``4 specifications x 3 seeds`` (or ``x 6 sweep combinations``)."""
    per = len(sweep.combinations) // max(len(sweep.specifications), 1)
    noun = "seed" if [axis.key for axis in sweep.axes] == ["seed"] else "sweep combination"
    return f"{count(len(sweep.specifications), 'specification')} x {count(per, noun)}"
