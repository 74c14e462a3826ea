"""Label files and batch references shared between experiments, stored by what they depend on.

A study runs the same walker under many specifications, and most of them change nothing
that walker reads: its path and checkpoint counts Φ_p come out the same, and so would its
labels. Every map's batch reference Z_b likewise depends only on the words, the model
and the batch sweeps. So ``label`` keeps what it computes in the cache, beside the word
stores, under a *key*: the digest of exactly what the item depends on, never of the
settings of the experiment that first made it:

- a batch reference: its recipe (:func:`~curiosity_cli.experiment.recipes.batch_recipe`);
- a run's labels: its label recipe without the run's own recipe digest (which names every
  setting of the run's specification), and in its place the run's content: its seed,
  restart, walker, checkpoint lengths, path and Φ_p at each checkpoint
  (:func:`label_key`). Two runs that read different settings and still made the same
  path and counts share their labels; any difference in what labelling reads gives
  another key.

An experiment whose item is in the cache takes it instead of computing it, and writes
it into its own folder as it would have written it (a label file with its own meta and
recipe): the same bytes as a computed one, timing fields aside. Each stored file is
named ``<key>.<sha256>.npz`` by its own digest, written under a temporary name and
renamed into place, so two experiments storing one item at once leave one whole file,
and one altered since (a disk error, an edit) no longer matches its name: it is named,
removed and computed again, never used. An item also holds the key it was made for (a run's
labels: :data:`KEY_FIELD`; a batch reference: its recipe's digest, which is its key), so a
whole file under another item's name, its digest its own, is named, removed and computed
again too. ``reuse=False`` (``--no-reuse``) computes everything and stores nothing; ``--force``
computes everything and stores what it computed.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

from curiosity_cli.experiment.wholeness import record
from curiosity_cli.files import display_path, note, open_npz, unwritable

#: Where under the cache folder (``cache_dir``, beside the word stores) shared items live.
SHARED_FOLDER = "shared"
#: The kinds of item, each a folder of its own.
BATCH, LABELS = "batch", "labels"
_EXAMPLE = "example_"
#: The member of a stored run's labels that holds the key it was made for.
KEY_FIELD = "item_key"
#: Hex digits of a file's SHA-256 in its name.
_NAMED_DIGEST = 16


def label_key(recipe_inputs: dict, run_meta: dict, checkpoints: dict, path: np.ndarray) -> str:
    """The key of a run's labels: what labelling reads of the run and of the experiment.

    Parameters
    ----------
    recipe_inputs : dict
        The run's label recipe's inputs (:func:`~curiosity_cli.experiment.recipes.label_recipe`);
        its ``run`` (the run recipe's digest) is replaced by the run's content.
    run_meta : dict
        Its ``run.json``: ``seed``, ``restart``, ``weight_function``, ``checkpoints``,
        ``store``, ``n_topics``.
    checkpoints : dict of int to SparseCounts
        Φ_p at each checkpoint length.
    path : (L,) int ndarray
        The run's cells.
    """
    digest = hashlib.sha256()
    for length in sorted(checkpoints):
        checkpoints[length].hash_into(digest)
    digest.update(np.ascontiguousarray(path, np.int64).tobytes())
    content = {key: run_meta[key] for key in ("seed", "restart", "weight_function", "checkpoints", "store", "n_topics")}
    inputs = {**{k: v for k, v in recipe_inputs.items() if k != "run"}, "run_content": content, "counts": digest.hexdigest()}
    return hashlib.sha256(json.dumps(inputs, sort_keys=True, separators=(",", ":")).encode()).hexdigest()[:32]


class SharedItems:
    """The shared items under a cache folder (module docstring).

    Parameters
    ----------
    cache_dir : Path
        The cache of word stores; items go in its ``shared/`` folder.
    """

    def __init__(self, cache_dir: Path):
        self.root = Path(cache_dir) / SHARED_FOLDER
        self._keyless = 0  # items stored before items held their key, found by this object

    def writable(self) -> str | None:
        """None when items can be stored here; else why not, in words (checked before any work, so that a
        read-only cache or one under a file is not found after the labelling)."""
        why = unwritable(self.root)
        return None if why is None else f"{display_path(self.root)}: cannot be written ({why})"

    def find(self, kind: str, key: str) -> Path | None:
        """The stored file of an item, if there is one whose bytes still match its name; one that does not is
        named on stderr and removed."""
        folder = self.root / kind
        for path in sorted(folder.glob(f"{key}.*.npz")) if folder.is_dir() else []:
            try:
                if record(path)["sha256"][:_NAMED_DIGEST] == path.name[len(key) + 1:-len(".npz")]:
                    return path
            except OSError:  # removed meanwhile by another experiment that found it altered
                continue
            self.discard(path, "altered since it was stored (its digest is not its name's)")
        return None

    def keep_file(self, kind: str, key: str, source: Path) -> None:
        """Store a copy of ``source`` as the item ``key``."""
        self._keep(kind, key, lambda tmp: shutil.copyfile(source, tmp))

    def labels(self, key: str) -> tuple[dict, dict] | None:
        """A run's stored label arrays and example maps (``(arrays, examples)``, as
        :func:`~curiosity_cli.label.stage.label_block` gives them), or None; an item made for another key (or
        stored before items held theirs) is named on stderr and removed."""
        path = self.find(LABELS, key)
        if path is None:
            return None
        with open_npz(path) as npz:
            made_for = str(npz[KEY_FIELD]) if KEY_FIELD in npz.files else None
            arrays = {name: npz[name] for name in npz.files if not name.startswith(_EXAMPLE) and name != KEY_FIELD}
            examples = {int(name[len(_EXAMPLE):]): npz[name] for name in npz.files if name.startswith(_EXAMPLE)}
        if made_for is None:  # a cache from before keys: every item is so, and named once, not once each
            self._keyless += 1
            if self._keyless == 1:
                note(
                    f"{display_path(path)}: stored before shared items held the key they were made for; it and any "
                    "other such item are computed again, once"
                )
            path.unlink(missing_ok=True)
            return None
        if made_for != key:
            self.discard(path, "made for another run's labels")
            return None
        return arrays, examples

    def keep_labels(self, key: str, arrays: dict, examples: dict) -> None:
        """Store a run's label arrays and example maps as the item ``key``, with the key."""
        def write(tmp: Path) -> None:
            with open(tmp, "wb") as handle:
                np.savez_compressed(
                    handle, **arrays, **{f"{_EXAMPLE}{length}": pixels for length, pixels in examples.items()},
                    **{KEY_FIELD: np.array(key)},
                )

        self._keep(LABELS, key, write)

    @staticmethod
    def discard(path: Path, why: str) -> None:
        """Remove a stored item that cannot be taken, saying why on stderr."""
        note(f"{display_path(path)}: {why}; computing it again")
        path.unlink(missing_ok=True)

    def _keep(self, kind: str, key: str, write) -> None:
        """Write an item under a temporary name, then rename it to ``<key>.<its sha256>.npz``: atomic, so two
        writers of one item leave one whole file, and a killed one only a hidden ``.tmp`` file."""
        folder = self.root / kind
        folder.mkdir(parents=True, exist_ok=True)
        handle, name = tempfile.mkstemp(dir=folder, prefix=f".{key}.", suffix=".tmp.npz")
        os.close(handle)
        tmp = Path(name)
        try:
            write(tmp)
            target = folder / f"{key}.{record(tmp)['sha256'][:_NAMED_DIGEST]}.npz"
            os.replace(tmp, target)
        finally:
            tmp.unlink(missing_ok=True)
        for other in folder.glob(f"{key}.*.npz"):  # what it replaces: one stored before it held its key, or altered
            if other != target:
                other.unlink(missing_ok=True)
