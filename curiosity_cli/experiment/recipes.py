"""What each derived file of an experiment was made from, so that a stale one is never taken as current.

A file's presence says nothing about whether it still belongs to its experiment: a config
edited by hand, a ``--set`` at a later stage or a re-explored run leave older files that
look finished. So every derived file records its *recipe*: exactly the inputs and
settings its contents depend on, and their digest. A stage compares the recipe a file
recorded with the one its inputs give now; a file whose digests differ is redone or
refused, and :meth:`Recipe.changes` says what differs in words.

The recipes, all built here so that every stage asks the same question:

- a run (``run.json``, :func:`run_recipe`): its map's word store (named by a hash of the
  image's pixels, the word settings and the vocabularies), weight function, restart and
  the experiment seed, and the model and exploration settings except those that only
  choose which runs a grid holds;
- a map's batch reference (:func:`batch_recipe`): the word store, the experiment seed,
  the model settings and the batch sweeps;
- a run's label file (:func:`label_recipe`): the digests of its run and of the batch
  reference it is compared with, the label settings, the share that makes a class found
  and a digest of the map's human labels.

A recipe says what a file was made from; :mod:`~curiosity_cli.experiment.wholeness` says
whether the files are still the ones that were written.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterator
from dataclasses import dataclass, field

from curiosity_cli.config import LABEL_READINGS, READS_TRUTH, UNRECORDED_READINGS, ExperimentConfig
from curiosity_cli.config_yaml import to_dict

#: Where a file's meta (``run.json``, an ``.npz``'s ``meta``) holds its recipe.
RECIPE_KEY = "recipe"
#: The config keys that choose which runs a grid holds, not what a run computes.
SELECTION_KEYS = {("explore", "weight_functions"), ("explore", "restarts")}
#: Label files: 2 since the chains of a map's runs advance in lock-step (their draws changed);
#: 3 since a sweep visits the cells colour by colour (``topics.chains.sweep_order``), the
#: order in which a GPU gives the CPU's bytes. The device is not in the recipe: a label
#: file is the same bytes whichever device made it.
LABEL_FORMAT = 3
#: What a label file holds beside Z_p's tables, whose draws :data:`LABEL_FORMAT` covers: 2 since the
#: tables of the pixels of the cells each path visited; 3 since the held-out log-likelihood of the map's
#: words (:mod:`~curiosity_cli.label.heldout`: a chain per run over the observed half). Not in a study's record
#: (:mod:`~curiosity_cli.study.record`): a record keeps tables, not label files, and one from before a
#: measure says that it lacks it.
LABEL_TABLES = 3
#: Batch references, whose draws did not change with the label files'.
BATCH_FORMAT = 1
#: A human class counts as found in a visited cell when it covers at least this share
#: (percent) of the cell's pixels: enough to be seen, not a sliver at the cell's edge.
CLASS_SHARE_PERCENT = 10
#: How the second labelling chain of a checked run (``label.check_restarts``) starts.
SECOND_START = "placed"
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
        changed = [change_in_words(keys, old, new) for keys, old, new in differences(inputs, self.inputs)]
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


def change_in_words(keys: tuple, old, new) -> str:
    """One difference of two recipes (:func:`differences`) as a user reads it: ``explore.candidates was 4, now 8``."""
    name = ".".join(map(str, keys))
    if name in _DIGEST_INPUTS:
        return f"{_DIGEST_INPUTS[name]} changed"
    return f"{name} was {_as_set(keys, old)}, now {_as_set(keys, new)}"


def _as_set(keys: tuple, value) -> str:
    """A recipe's value as the config set it: a setting a recipe leaves out at its default is that default."""
    if value is ABSENT:
        if keys == ("label", "reading"):
            return repr(LABEL_READINGS[0])
        if len(keys) == 2 and keys[0] == "explore" and keys[1] in UNRECORDED_READINGS:
            return repr(UNRECORDED_READINGS[keys[1]])
    return repr(value)


def run_recipe(
    config: ExperimentConfig, dataset: str, store: str, vocabulary_hashes: list[str], weight_function: str, restart: int,
    human: str | None = None,
) -> Recipe:
    """What one run's numbers depend on.

    ``store`` is the file name of the map's word store, which hashes the image's pixels,
    the word settings and the vocabularies. The start cell and the seed entropy follow
    from the map, the experiment seed and the restart. A walker that reads the map's truth
    (:data:`~curiosity_cli.config.READS_TRUTH`) depends on the digest of its ``human``
    labels and the share that makes a class present, too; no other walker's recipe holds them.
    """
    explore = {
        key: value for key, value in config.explore.run_settings().items() if ("explore", key) not in SELECTION_KEYS
    }
    inputs = {
        "store": store, "vocabulary_hashes": vocabulary_hashes, "dataset": dataset,
        "weight_function": weight_function, "restart": restart, "seed": config.seed,
        "model": to_dict(config.model), "explore": explore,
    }
    if weight_function in READS_TRUTH:
        inputs["truth"] = {"human": human, "class_share_percent": CLASS_SHARE_PERCENT}
    return Recipe(inputs)


def batch_recipe(config: ExperimentConfig, store: str, vocabulary_hashes: list[str]) -> Recipe:
    """What a map's batch reference depends on: its word store (file name), vocabularies and the model."""
    return Recipe({
        "format": BATCH_FORMAT, "store": store, "vocabulary_hashes": vocabulary_hashes,
        "seed": config.seed, "sweeps": config.label.batch_sweeps, "model": to_dict(config.model),
    })


def label_recipe(run: str, batch: str, config: ExperimentConfig, human: str | None, restart: int) -> Recipe:
    """What a run's label file depends on: the digests of its ``run`` and ``batch`` reference, and of the ``human`` labels.

    ``label.check_restarts`` enters only as whether this ``restart`` is checked (a
    second chain), so changing it relabels only the runs it adds or drops.
    """
    # the device is left out: cpu and cuda give the same bytes (topics/chains.py); the reading only when it is not
    # the default (every label file made before readings was made with it), a reading's setting only under it
    left_out = {"check_restarts", "device"}
    if config.label.reading == LABEL_READINGS[0]:
        left_out.add("reading")
    if config.label.reading != "used-topics":
        left_out.add("used_share")
    if config.label.reading != "thawed":
        left_out.add("thaw_sweeps")
    label = {key: value for key, value in to_dict(config.label).items() if key not in left_out}
    inputs = {
        "format": LABEL_FORMAT, "tables": LABEL_TABLES, "run": run, "batch": batch, "label": label,
        "class_share_percent": CLASS_SHARE_PERCENT, "human": human,
    }
    if is_checked(config, restart):
        inputs["second_start"] = SECOND_START
    return Recipe(inputs)


def is_checked(config: ExperimentConfig, restart: int) -> bool:
    """Whether a run of this ``restart`` is labelled a second time, from a placed start (``label.check_restarts``)."""
    return restart < config.label.check_restarts
