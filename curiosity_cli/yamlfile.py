"""Every YAML document the package reads goes through here, with bounds.

A YAML file is user input: a few lines of anchors and aliases ("billion laughs") expand
to billions of values that take a minute and all memory to walk or print. A document is
therefore refused above :data:`MAX_BYTES`, above :data:`MAX_VALUES` values counted with
every alias expanded, above :data:`MAX_DEPTH` levels of nesting, when an alias
refers to a node that contains it, and when a mapping gives a key twice (PyYAML would
keep the last silently). The loader is PyYAML's safe one, plus the float forms
people type that YAML 1.1 reads as strings (``1e-3``, ``1E5``, ``-.5``).
"""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path
from typing import Any

from curiosity_cli.errors import ConfigError

#: The largest YAML document read; configs, dataset YAMLs and legends are a few kB.
MAX_BYTES = 1 << 20
#: The most values (scalars, lists and mappings, every alias expanded) in one document.
MAX_VALUES = 100_000
#: The deepest nesting of lists and mappings in one document.
MAX_DEPTH = 50
#: The longest representation of a value an error message shows.
SHOWN_CHARS = 60

# Floats YAML 1.1 misses: an exponent without a dot or without a sign (1e-3, 1E5, 2.5e3),
# and a leading dot with a sign (-.5). The forms it has (0.5, .5, 5.) stay as they are.
_TYPED_FLOAT = re.compile(
    r"^(?:[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+|[-+]\.[0-9][0-9_]*)$"
)


class _Refused(Exception):
    """A document over one of the bounds; the reader adds the file's name."""


def shown(value: Any) -> str:
    """``repr(value)``, cut to :data:`SHOWN_CHARS` characters so an error stays one short line."""
    text = repr(value)
    return text if len(text) <= SHOWN_CHARS else text[: SHOWN_CHARS - 3] + "..."


def _bounded_size(node, sizes: dict, depth: int) -> int:
    """Values below ``node`` (itself included), aliases expanded; ``sizes`` memoises shared nodes.

    ``sizes`` maps a node's id to ``(values, height)``, or to None while the node is being
    counted, which is how an alias to an enclosing node shows itself.
    """
    key = id(node)
    if key in sizes:
        if sizes[key] is None:
            raise _Refused("an alias refers to a list or mapping that contains it; expected a tree of values")
        values, height = sizes[key]
    else:
        sizes[key] = None
        children = node.value if isinstance(node.value, list) else []
        children = [n for child in children for n in (child if isinstance(child, tuple) else (child,))]
        counted = [_bounded_size(child, sizes, depth + 1) for child in children]
        values = 1 + sum(counted)
        height = 1 + max((sizes[id(child)][1] for child in children), default=0)
        sizes[key] = (values, height)
    if depth + height > MAX_DEPTH:
        raise _Refused(f"nested more than {MAX_DEPTH} levels deep; expected at most that many")
    if values > MAX_VALUES:
        raise _Refused(f"more than {MAX_VALUES} values once its aliases are expanded; expected at most that many")
    return values


@cache
def _loader():
    """PyYAML's safe loader that counts the composed document before building it."""
    import yaml

    class BoundedLoader(yaml.SafeLoader):
        def get_single_node(self):
            node = super().get_single_node()
            if node is not None:
                _bounded_size(node, {}, 0)
            return node

        def construct_mapping(self, node, deep=False):
            # PyYAML keeps the last of a key given twice: a setting silently lost
            marks = {}
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(key_node, deep=True)
                mark = key_node.start_mark
                try:
                    first = marks.setdefault(key, mark)
                except TypeError:  # an unhashable key: the base class refuses it
                    continue
                if first is not mark:
                    raise _Refused(
                        f"key {shown(key)} is given twice (lines {first.line + 1} and {mark.line + 1}); "
                        "expected each key once"
                    )
            return super().construct_mapping(node, deep)

    BoundedLoader.add_implicit_resolver("tag:yaml.org,2002:float", _TYPED_FLOAT, list("-+.0123456789"))
    return BoundedLoader


@cache
def _dumper():
    """PyYAML's safe dumper that quotes the strings :func:`parse_yaml` would read as floats."""
    import yaml

    class Dumper(yaml.SafeDumper):
        pass

    Dumper.add_implicit_resolver("tag:yaml.org,2002:float", _TYPED_FLOAT, list("-+.0123456789"))
    return Dumper


def parse_yaml(text: str, where: str) -> Any:
    """Parse one YAML document within the bounds.

    Parameters
    ----------
    text : str
        The document.
    where : str
        What it came from (a file, ``--set KEY``), to start the error message with.

    Raises
    ------
    ConfigError
        Not valid YAML, or over a bound; one line starting with ``where``.
    """
    import yaml

    if len(text.encode("utf-8", "surrogatepass")) > MAX_BYTES:
        raise ConfigError(f"{where}: larger than {MAX_BYTES // 2**20} MiB; expected a YAML document of at most that size")
    try:
        return yaml.load(text, Loader=_loader())  # noqa: S506 - a SafeLoader subclass
    except _Refused as exc:
        raise ConfigError(f"{where}: {exc}") from None
    except RecursionError:  # the parser itself recursed too deep, before the count could refuse
        raise ConfigError(f"{where}: nested more than {MAX_DEPTH} levels deep; expected at most that many") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = f" (line {mark.line + 1})" if mark is not None else ""
        problem = getattr(exc, "problem", None) or "not valid YAML"
        raise ConfigError(f"{where}: not valid YAML{line}: {problem}") from None


def read_yaml(path: Path, what: str) -> dict:
    """Read a YAML file whose top level is a mapping (an empty file is an empty mapping).

    Parameters
    ----------
    path : Path
    what : str
        What the file is, for the message when it is missing, e.g. ``config file``.

    Raises
    ------
    ConfigError
        Missing file, not text, not valid YAML, over a bound of :func:`parse_yaml`, or not a
        mapping; one line naming the file.
    """
    from curiosity_cli.files import display_path

    path = Path(path)
    where = display_path(path)
    if not path.exists():
        raise ConfigError(f"{where}: {what} not found")
    if not path.is_file():  # a folder, or a link to /dev/zero: not "not found", and never read to its end
        raise ConfigError(f"{where}: not a regular file (a folder, a device or a pipe); expected a YAML {what}")
    # the size is checked before reading, so a huge file is never read into memory
    if path.stat().st_size > MAX_BYTES:
        raise ConfigError(f"{where}: larger than {MAX_BYTES // 2**20} MiB; expected a YAML {what} of at most that size")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ConfigError(f"{where}: not a text file; expected YAML") from None
    data = parse_yaml(text, where)
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: expected a mapping of keys at the top level, got {type(data).__name__}")
    return data


def dump_yaml(data: Any) -> str:
    """``data`` as YAML that :func:`parse_yaml` reads back to the same values."""
    import yaml

    return yaml.dump(data, Dumper=_dumper(), sort_keys=False)
