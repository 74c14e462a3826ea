"""What each derived file of an experiment was made from, so that a stale one is never taken as current.

A file's presence says nothing about whether it still belongs to its experiment: a config
edited by hand, a ``--set`` at a later stage or a re-explored run leave older files that
look finished. So every derived file records its *recipe*: exactly the inputs and
settings its contents depend on, and their digest. A stage compares the recipe a file
recorded with the one its inputs give now; a file whose digests differ is redone or
refused, and :meth:`Recipe.changes` says what differs in words.

The recipes, each built by the module that writes the file:

- a run (``run.json``, :func:`curiosity_cli.explore.grid.run_recipe`): its map's word
  store (named by a hash of the image's pixels, the word settings and the vocabularies),
  weight function, restart and the experiment seed, and the model and exploration
  settings except those that only choose which runs a grid holds;
- a map's batch reference (:func:`curiosity_cli.evaluate.label_stage.batch_recipe`): the word
  store, the experiment seed, the model settings and the batch sweeps;
- a run's label file (:func:`curiosity_cli.evaluate.label_stage.label_recipe`): the digests of
  its run and of the batch reference it is compared with, the label settings, the share
  that makes a class found and a digest of the map's human labels.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterator
from dataclasses import dataclass, field

#: Where a file's meta (``run.json``, an ``.npz``'s ``meta``) holds its recipe.
RECIPE_KEY = "recipe"
#: Inputs whose values are other files' digests, named in words when they differ.
_DIGEST_INPUTS = {"run": "its run", "batch": "the batch reference", "human": "the map's human labels"}


@dataclass(frozen=True)
class Recipe:
    """The inputs a derived file is made from (JSON-ready, nested dicts allowed) and their digest."""

    inputs: dict
    digest: str = field(init=False)

    def __post_init__(self) -> None:
        text = json.dumps(self.inputs, sort_keys=True, separators=(",", ":"))
        object.__setattr__(self, "digest", hashlib.sha256(text.encode()).hexdigest()[:16])

    def record(self) -> dict:
        """What a file stores under :data:`RECIPE_KEY`."""
        return {"digest": self.digest, "inputs": self.inputs}

    def changes(self, meta: dict) -> str | None:
        """``None`` when the file whose meta is ``meta`` was made from this recipe; else what differs, in words.

        Parameters
        ----------
        meta : dict
            The file's meta (``run.json`` or an ``.npz``'s ``meta``).
        """
        inputs = recorded_inputs(meta)
        if not inputs:
            return "made before recipes were recorded"
        if recorded_digest(meta) == self.digest:
            return None
        changed = [_in_words(keys, old, new) for keys, old, new in differences(inputs, self.inputs)]
        return ", ".join(changed) or "its recorded digest does not match its inputs (edited by hand?)"


def recorded_digest(meta: dict) -> str | None:
    """The digest a file's meta records, if any."""
    recorded = meta.get(RECIPE_KEY)
    return recorded.get("digest") if isinstance(recorded, dict) else None


def recorded_inputs(meta: dict) -> dict:
    """The inputs a file's meta records ({} if none)."""
    recorded = meta.get(RECIPE_KEY)
    inputs = recorded.get("inputs") if isinstance(recorded, dict) else None
    return inputs if isinstance(inputs, dict) else {}


class _Absent:
    """A key one of two mappings lacks (a file made before the key existed), shown as ``absent``."""

    def __repr__(self) -> str:
        return "absent"


ABSENT = _Absent()


def differences(old, new, keys: tuple = ()) -> Iterator[tuple[tuple, object, object]]:
    """``(keys, old value, new value)`` for each leaf where two nested mappings differ, in key order.

    A key only one of them has differs, with :data:`ABSENT` for the other's value.
    """
    if isinstance(old, dict) and isinstance(new, dict):
        for key in sorted(set(old) | set(new)):
            yield from differences(old.get(key, ABSENT), new.get(key, ABSENT), keys + (key,))
    elif old != new:
        yield keys, old, new


def first_of(lines: list[str]) -> str:
    """The first of several lines of files made otherwise, and how many more there are, for one error line."""
    return lines[0] + (f"; and {len(lines) - 1} more" if len(lines) > 1 else "")


def _in_words(keys: tuple, old, new) -> str:
    name = ".".join(map(str, keys))
    if name in _DIGEST_INPUTS:
        return f"{_DIGEST_INPUTS[name]} changed"
    return f"{name} was {old!r}, now {new!r}"
