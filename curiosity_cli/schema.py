"""Typed YAML mappings → frozen dataclasses, and the one-line message of every value that does not fit.

A field declares its checks with :func:`spec` (bounds, choices, a file that must exist, a
name that becomes a file name); :func:`build` turns a merged mapping (:class:`Raw`, which
remembers which file or option set every key) into the dataclass, and :func:`invalid`
names a bad value by where it was set: the file, the key, what was given and what was
expected. The experiment configs (:mod:`curiosity_cli.config`) and the dataset YAMLs
(:mod:`curiosity_cli.maps.datasets`) are both built here.
"""

from __future__ import annotations

import dataclasses
import math
import re
import types
import typing
from dataclasses import field
from pathlib import Path
from typing import Any

from curiosity_cli.errors import ConfigError
from curiosity_cli.files import display_path, resolved
from curiosity_cli.yamlfile import SHOWN_CHARS, shown

#: Where a value given in :func:`~curiosity_cli.config.load_config`'s ``overrides`` "comes from": the name of
#: that argument, which begins the message of any error about it.
OVERRIDES = "overrides"


#: The longest experiment or dataset name; a sweep names its experiments in up to this many.
MAX_NAME = 120
# Names become file and folder names: no separators, no leading dot, no path of '..'.
NAME_PATTERN = re.compile(rf"^[A-Za-z0-9][A-Za-z0-9_.-]{{0,{MAX_NAME - 1}}}$")
NAME_RULE = f"1 to {MAX_NAME} letters, digits, '-', '_' or '.', starting with a letter or digit"


def spec(
    *,
    min: float | None = None,
    max: float | None = None,
    min_exclusive: bool = False,
    max_exclusive: bool = False,
    choices: tuple | None = None,
    must_exist: bool = False,
    file_name: bool = False,
    named: dict[str, Path] | None = None,
    default: Any = dataclasses.MISSING,
):
    """A dataclass field with the checks the validator applies to it.

    ``file_name`` marks a string that becomes a file or folder name (:data:`MAX_NAME`).
    ``named`` gives a path field names for paths of this checkout (e.g.
    :data:`SHIPPED_VOCABULARIES`): a config may use the name, and a saved config does.

    Only dataset YAMLs, which a user writes per map, have optional keys (``default``);
    experiment configs name every key, their values coming from ``configs/paper.yaml``.
    """
    return field(
        default=default,
        metadata=dict(
            min=min,
            max=max,
            min_exclusive=min_exclusive,
            max_exclusive=max_exclusive,
            choices=choices,
            must_exist=must_exist,
            file_name=file_name,
            named=named,
        )
    )


class Raw:
    """A merged YAML mapping plus, for every key path, the file (or option) that set it."""

    def __init__(self, top: str):
        self.data: dict = {}
        self.origins: dict[tuple, str] = {}
        self.top = top

    def origin(self, keys: tuple) -> str:
        # The deepest recorded prefix: a whole section set by one file names that file.
        for n in range(len(keys), 0, -1):
            if keys[:n] in self.origins:
                return self.origins[keys[:n]]
        return self.top

    def merge(self, mapping: dict, source: str, prefix: tuple = ()) -> None:
        target = self.data
        for key in prefix:
            target = target.setdefault(key, {})
        for key, value in mapping.items():
            keys = prefix + (key,)
            if isinstance(value, dict) and isinstance(target.get(key), dict):
                self.merge(value, source, keys)
            else:
                target[key] = value
                self.origins[keys] = source


def invalid(raw: Raw, keys: tuple, problem: str) -> ConfigError:
    """The error of the value at ``keys``, named by where it was set: a file, or the overrides."""
    parameter = OVERRIDES if raw.origin(keys) == OVERRIDES else None
    return ConfigError(f"{_where(raw, keys)}: {problem}", parameter=parameter)


def _where(raw: Raw, keys: tuple) -> str:
    source = raw.origin(keys)
    label = source if source == OVERRIDES else display_path(Path(source))
    key = "".join(_key_text(k) for k in keys).lstrip(".")
    # a key is user input too: an unknown one may be of any length
    key = key if len(key) <= SHOWN_CHARS else key[: SHOWN_CHARS - 3] + "..."
    return f"{label}: {key}" if key else label


def _key_text(key) -> str:
    """One step of a key path: ``[0]`` for a list index, ``.name`` for a plain key."""
    if isinstance(key, int):
        return f"[{key}]"
    # an unknown key may be empty, hold a newline or not be a string at all: show its repr
    plain = isinstance(key, str) and key.isprintable() and key
    return f".{key}" if plain else f".{shown(key)}"


#: What a value of each leaf type is called in a message: one, and a list of them.
_NOUNS = {
    int: ("an integer", "integers"),
    float: ("a number", "numbers"),
    bool: ("true or false", "true or false values"),
    str: ("a string", "strings"),
    Path: ("a file path", "file paths"),
}


def _expected(tp) -> str:
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        inner = [a for a in typing.get_args(tp) if a is not type(None)]
        return f"{_expected(inner[0])} or null"
    if origin is tuple:
        return f"a list of {_NOUNS[typing.get_args(tp)[0]][1]}"
    return _NOUNS.get(tp, ("a mapping",))[0]


def _bound_text(bound: float) -> str:
    """A bound as a person writes it: whole numbers in full (4294967295, not 4.29497e+09)."""
    return str(int(bound)) if float(bound).is_integer() else f"{bound:g}"


def _range_text(meta: dict) -> str:
    parts = []
    if meta["min"] is not None:
        parts.append(f"{'>' if meta['min_exclusive'] else '>='} {_bound_text(meta['min'])}")
    if meta["max"] is not None:
        parts.append(f"{'<' if meta['max_exclusive'] else '<='} {_bound_text(meta['max'])}")
    return " and ".join(parts)


def build(cls, data: Any, keys: tuple, raw: Raw):
    if not isinstance(data, dict):
        raise invalid(raw, keys, f"got {shown(data)} ({type(data).__name__}), expected a mapping of keys")
    hints = typing.get_type_hints(cls)
    names = [f.name for f in dataclasses.fields(cls)]
    retired = getattr(cls, "RETIRED", {})
    for key in data:
        if key in retired:
            value, why = retired[key]
            if data[key] != value:
                raise invalid(raw, keys + (key,), f"got {shown(data[key])}, but the key is retired: {why}")
        elif key not in names:
            raise invalid(raw, keys + (key,), f"unknown key; expected one of {', '.join(names)}")
    values = {}
    for f in dataclasses.fields(cls):
        if f.name not in data:
            if f.default is not dataclasses.MISSING:
                values[f.name] = f.default
                continue
            raise invalid(raw, keys + (f.name,), "missing key")
        values[f.name] = _convert(hints[f.name], f.metadata, data[f.name], keys + (f.name,), raw)
    return cls(**values)


def _convert(tp, meta: dict, value: Any, keys: tuple, raw: Raw):
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        if value is None:
            return None
        (inner,) = [a for a in typing.get_args(tp) if a is not type(None)]
        tp, origin = inner, typing.get_origin(inner)

    def refuse(expected: str):
        given = f"{shown(value)} ({type(value).__name__})" if not isinstance(value, dict) else "a mapping"
        raise invalid(raw, keys, f"got {given}, expected {expected}")

    if dataclasses.is_dataclass(tp):
        return build(tp, value, keys, raw)
    if origin is tuple:
        if not isinstance(value, list) or not value:
            refuse(f"a non-empty {_expected(tp)[2:]}")
        item_type = typing.get_args(tp)[0]
        return tuple(
            _convert(item_type, meta, item, keys + (i,), raw) for i, item in enumerate(value)
        )
    if tp is bool:
        if not isinstance(value, bool):
            refuse("true or false")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            refuse(_expected(int) + (f" {_range_text(meta)}" if _range_text(meta) else ""))
        result = value
    elif tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            refuse("a finite number" + (f" {_range_text(meta)}" if _range_text(meta) else ""))
        result = float(value)
    elif tp is str:
        if not isinstance(value, str):
            refuse("a string")
        if meta["file_name"] and not NAME_PATTERN.match(value):
            refuse(f"{NAME_RULE} (it names files and folders)")
        result = value
    elif tp is Path:
        if not isinstance(value, str) or not value or "\0" in value:
            refuse("a file path")
        named = meta["named"] or {}
        result = named[value] if value in named else _resolve_path(value, keys, raw)
        if meta["must_exist"] and not result.exists():
            raise invalid(raw, keys, f"file not found: {display_path(result)}")
        return result
    else:  # pragma: no cover - a field type the validator does not know is a bug here
        raise TypeError(f"unsupported config field type {tp!r}")

    if meta["choices"] is not None and result not in meta["choices"]:
        refuse(f"one of {', '.join(str(c) for c in meta['choices'])}")
    if isinstance(result, (int, float)):
        low, high = meta["min"], meta["max"]
        too_low = low is not None and (result <= low if meta["min_exclusive"] else result < low)
        too_high = high is not None and (result >= high if meta["max_exclusive"] else result > high)
        if too_low or too_high:
            refuse(f"{'an integer' if tp is int else 'a number'} {_range_text(meta)}")
    return result


def _resolve_path(value: str, keys: tuple, raw: Raw) -> Path:
    """Relative paths count from the YAML file that wrote them (from the cwd for overrides)."""
    try:
        path = Path(value).expanduser()
    except RuntimeError:  # ~user of a user this machine does not know
        raise invalid(raw, keys, f"got {shown(value)}, expected a file path; no such home folder") from None
    if path.is_absolute():
        return path
    source = raw.origin(keys)
    base = Path.cwd() if source == OVERRIDES else Path(source).parent
    return resolved(base / path)
