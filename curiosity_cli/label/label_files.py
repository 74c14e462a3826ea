"""The label file of a run and its example maps: what ``curiosity label`` writes and later stages read.

- ``labels/<dataset>/<weight function>/restart-<NNN>.npz``: for one run, per checkpoint
  length (``lengths``), the contingency tables of Z_p against the human labels
  (``human``, (n, K, C) int64, absent for a map without labels) and against Z_b
  (``batch``, (n, K, K) int64), and ``meta`` (JSON). Tables rather than label maps: MI and
  NMI follow from them exactly, in kilobytes instead of a megabyte per checkpoint. A
  restart below ``label.check_restarts`` also has ``placed_batch`` and ``placed_human``
  (:data:`SECOND_PREFIX`): the same tables for a second labelling chain from a placed
  start (:meth:`~curiosity_cli.topics.chains.FrozenChains.start`), which evaluation
  compares with the first to check that Z_p has forgotten its start. ``visited_batch``
  and ``visited_human`` (:data:`VISITED_PREFIX`) are the first chain's tables of only
  the pixels whose word lies in a cell the path had visited by each length (the words
  Φ_p holds then); the rest of the map's are the whole tables less these. ``heldout_bits``
  ((n, 2) float64) and ``heldout_words`` ((n, 2) int64): the held-out log-likelihood of
  the map's words under Φ_p (:mod:`curiosity_cli.label.heldout`), the sum of ``log2`` of
  each held-out word's probability and the number of held-out words, over every cell
  (column 0) and over the cells the path had not visited by each length (column 1). For a map with
  human labels also ``class_first_step`` ((C,) int32): the step at which the path first
  stood in a cell where class ``h`` covers at least ``CLASS_SHARE_PERCENT`` % of the
  pixels, -1 if never (:mod:`curiosity_cli.maps.cell_classes`); ``meta["class_share_percent"]``
  records the share.
- ``labels/<dataset>/examples/<weight function>-restart-<NNN>-<length>.npz``: the pixel
  label map Z_p (``labels``, (H, W) int16) of restart 0 at the :data:`EXAMPLE_LENGTHS` and
  at its last checkpoint, for the figures.

Paths are :class:`~curiosity_cli.experiment.layout.ExperimentFolder`'s; each file is
written atomically, the label file last, recording its example maps' sizes and digests
and the digest of its own arrays (``arrays_sha256``): a label file whose tables were
altered since it was written is corrupt, and labelled again, never counted.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.experiment.recipes import SECOND_START, Recipe
from curiosity_cli.experiment.wholeness import FILES_KEY, changed, records
from curiosity_cli.files import CorruptFileError, arrays_digest, atomic_path, display_path, note, open_npz, read_meta

#: Why a run without a label file is labelled (:func:`label_changes`).
NOT_LABELLED = "not labelled yet"
#: Path lengths whose Z_p maps are kept for restart 0 (besides the last checkpoint).
EXAMPLE_LENGTHS = (80,)
#: The prefix of the second chain's tables' names in a checked run's label file.
SECOND_PREFIX = f"{SECOND_START}_"
#: The prefix of the tables of only the pixels whose word lies in a cell the path visited.
VISITED_PREFIX = "visited_"
#: The held-out log-likelihood's arrays: its bits and its words, over every cell and over the cells not visited.
HELDOUT_BITS, HELDOUT_WORDS = "heldout_bits", "heldout_words"

#: Where a label file's meta records the digest of its arrays.
ARRAYS_KEY = "arrays_sha256"
#: What every label file's ``meta`` names: a file without one of these is corrupt (one from before
#: label files recorded their arrays' digest, too: labelled again rather than trusted).
LABEL_META_KEYS = ("dataset", "weight_function", "restart", "run_seed", "store", "vocabulary_hashes", "sweeps", ARRAYS_KEY)


def write_labels(folder: Path, arrays: dict, examples: dict, meta: dict) -> None:
    """Write a run's label file and its example maps, each atomically: the examples first,
    then the label file, whose meta records their sizes and digests (``files``) and the
    digest of its own arrays (``arrays_sha256``)."""
    written = []
    for length, pixels in examples.items():
        path = ExperimentFolder(folder).example(meta["dataset"], meta["weight_function"], meta["restart"], length)
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as handle:
                np.savez_compressed(handle, labels=pixels)
        written.append(str(path.relative_to(folder)))
    meta = {**meta, FILES_KEY: records(folder, written), ARRAYS_KEY: arrays_digest(dict(sorted(arrays.items())))}
    path = ExperimentFolder(folder).label_file(meta["dataset"], meta["weight_function"], meta["restart"])
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as handle:
            np.savez_compressed(handle, **arrays, meta=json.dumps(meta, sort_keys=True))


def read_label_file(path: Path) -> tuple[dict, dict]:
    """``(meta, arrays)`` of a run's label file, as :func:`~curiosity_cli.label.stage.label_block` makes it.

    Raises
    ------
    FileNotFoundError, OSError
        As :func:`~curiosity_cli.files.open_npz`.
    CorruptFileError
        The file cannot be read, lacks an array a label file has, has a table array
        without one table per checkpoint length (or held-out arrays not (n, 2)), or arrays
        that are not those it was written with (its meta's ``arrays_sha256``).
    """
    tables = tuple(prefix + against for prefix in ("", SECOND_PREFIX, VISITED_PREFIX) for against in ("batch", "human"))
    with open_npz(path) as npz:
        meta = read_meta(npz, LABEL_META_KEYS)
        written = {name: npz[name] for name in sorted(npz.files) if name != "meta"}  # each member decompressed once
        arrays = {"lengths": written["lengths"], "batch": written["batch"]}  # a file without them is corrupt (KeyError)
        arrays.update({
            name: written[name] for name in (*tables, HELDOUT_BITS, HELDOUT_WORDS, "class_first_step") if name in written
        })
        n = len(arrays["lengths"])
        for name in tables:
            if name in arrays and (arrays[name].ndim != 3 or len(arrays[name]) != n):
                # raised inside open_npz: reported as a corrupt file, not as an IndexError later
                raise ValueError(f"{name} has shape {arrays[name].shape}, expected one table for each of {n} lengths")
        for name in (HELDOUT_BITS, HELDOUT_WORDS):
            if name in arrays and arrays[name].shape != (n, 2):
                raise ValueError(f"{name} has shape {arrays[name].shape}, expected ({n}, 2): a row per length")
        if arrays_digest(written) != meta[ARRAYS_KEY]:
            raise ValueError("its tables are not those it was written with (altered since)")
    return meta, arrays


def label_changes(path: Path, recipe: Recipe) -> str | None:
    """Why a run's label file at ``path`` must be made again, in words; ``None`` when it was made from ``recipe``.

    A missing file gives :data:`NOT_LABELLED`; a corrupt one (:func:`read_label_file`)
    is noted on stderr as labelled again. So is a file whose example maps (``files``) are
    missing or not as it wrote them.
    """
    try:
        meta = read_label_file(path)[0]
    except FileNotFoundError:
        return NOT_LABELLED
    except CorruptFileError as exc:
        note(f"{exc}; labelling the run again")
        return str(exc)
    if (change := recipe.changes(meta)) is not None:
        return change
    return examples_changed(path, meta)


def examples_changed(path: Path, meta: dict) -> str | None:
    """``None`` when the example maps the label file at ``path`` records (its ``meta``'s
    ``files``) are as it wrote them; else the first that is not, in words."""
    change = changed(ExperimentFolder.holding_label_file(path).root, meta.get(FILES_KEY, {}))
    return None if change is None else f"{display_path(change[0])}: {change[1]}"
