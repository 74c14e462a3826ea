"""Keeping a topic model's state: snapshots in memory, ``.npz`` files on disk.

- :func:`take_snapshot` / :func:`restore_snapshot`: a :class:`ModelSnapshot` is an exact
  copy of a model's whole mutable state (:meth:`TopicModel.full_state
  <curiosity_cli.topics.model.TopicModel.full_state>`), to go back to it later.
- :func:`save_model` / :func:`load_model`: a file holds the parameters, the neighbour
  table, the observed cells with their words and topics (the compact state,
  :func:`~curiosity_cli.topics.compact_state.compact_state`), the random state and, for
  a frozen model, the frozen counts; the other counts are recomputed on load.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from curiosity_cli.errors import CuriosityError, ParameterError
from curiosity_cli.files import atomic_path, display_path
from curiosity_cli.topics.compact_state import compact_state, set_compact_state
from curiosity_cli.topics.model import TopicModel

MODEL_FORMAT = 1


@dataclass(frozen=True)
class ModelSnapshot:
    """A copy of a model's whole mutable state, for :func:`restore_snapshot`.

    The first four fields say which models it fits; the others are the arrays of
    :meth:`TopicModel.full_state <curiosity_cli.topics.model.TopicModel.full_state>`
    (copied), trimmed to the words and cells in use; ``counter`` is the random state
    (with the model's fixed seed).
    """

    n_topics: int
    vocabulary_size: int
    neighbours: np.ndarray  # the model's (read-only) table, to check a restore
    frozen: bool
    words: np.ndarray
    topics: np.ndarray
    cell_first: np.ndarray
    cell_count: np.ndarray
    order: np.ndarray
    times: np.ndarray
    nwk: np.ndarray
    nk: np.ndarray
    ncz: np.ndarray
    ng: np.ndarray
    counter: int


#: The fields of a :class:`ModelSnapshot` that say which models it fits, not their state.
_FITS = ("n_topics", "vocabulary_size", "neighbours", "frozen")


def take_snapshot(model: TopicModel) -> ModelSnapshot:
    """A copy of the whole state of ``model``, random state included."""
    return ModelSnapshot(
        n_topics=model.n_topics,
        vocabulary_size=model.vocabulary_size,
        neighbours=model.neighbours,
        frozen=model.frozen,
        **model.full_state(),
    )


def restore_snapshot(model: TopicModel, snapshot: ModelSnapshot) -> None:
    """Return ``model`` to the state of ``snapshot``, random state included.

    The snapshot may come from this model or another with the same K, V, neighbour
    table and frozenness; α, β and the seed stay the model's.

    Raises
    ------
    ParameterError
        ``snapshot`` is not a :class:`ModelSnapshot`, or comes from a model it does not fit.
    """
    if not isinstance(snapshot, ModelSnapshot):
        raise ParameterError(f"snapshot: got {type(snapshot).__name__}, expected a ModelSnapshot")
    mine = (model.n_topics, model.vocabulary_size, model.frozen)
    theirs = (snapshot.n_topics, snapshot.vocabulary_size, snapshot.frozen)
    if mine != theirs:
        raise ParameterError(f"snapshot: taken from a model with (K, V, frozen) = {theirs}, this one has {mine}")
    if not np.array_equal(snapshot.neighbours, model.neighbours):
        raise ParameterError("snapshot: taken from a model with another neighbour table")
    state = {f.name: getattr(snapshot, f.name) for f in dataclasses.fields(snapshot) if f.name not in _FITS}
    model.set_full_state(**state)


def save_model(model: TopicModel, path: Path) -> None:
    """Write a model to an ``.npz`` file, atomically.

    The file holds the parameters (K, V, α, β, seed, vocabulary hashes, format version)
    in ``meta`` (JSON), the neighbour table, the words and topics of the observed cells
    in the order added, their times and word counts, the random state and, for a frozen
    model, the frozen counts (``frozen_counts``, (V, K)).
    """
    state = compact_state(model)
    meta = {
        "format": MODEL_FORMAT,
        "n_topics": model.n_topics,
        "vocabulary_size": model.vocabulary_size,
        "alpha": model.alpha,
        "beta": model.beta,
        "seed": model.seed,
        "counter": state["counter"],
        "vocabulary_hashes": model.vocabulary_hashes,
        "frozen": model.frozen,
    }
    # the order of the entries is the order of the members in the file
    arrays = {
        "neighbours": model.neighbours,
        **{name: state[name] for name in ("order", "times", "sizes", "words", "topics")},
        "meta": np.array(json.dumps(meta, sort_keys=True)),
    }
    if model.frozen:
        arrays["frozen_counts"] = model.topic_word_counts()
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez_compressed(handle, **arrays)


def load_model(path: Path) -> TopicModel:
    """Read a model written by :func:`save_model`; the loaded model equals the saved one.

    Raises
    ------
    CuriosityError
        One line naming the file: missing, not a topic model, another format version,
        or inconsistent contents.
    """
    path = Path(path)
    where = display_path(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            if not isinstance(meta, dict):
                raise ValueError("meta is not a mapping")
            arrays = {k: data[k] for k in ("neighbours", "order", "times", "sizes", "words", "topics")}
            frozen_counts = data["frozen_counts"] if meta.get("frozen") else None
    except (OSError, KeyError, ValueError, TypeError) as exc:
        raise CuriosityError(f"{where}: not a topic model ({_one_line(exc)})") from None
    if meta.get("format") != MODEL_FORMAT:
        raise CuriosityError(f"{where}: format: got {meta.get('format')!r}, expected {MODEL_FORMAT}")
    try:
        model = TopicModel(
            meta["n_topics"],
            meta["vocabulary_size"],
            arrays.pop("neighbours"),
            alpha=meta["alpha"],
            beta=meta["beta"],
            seed=meta["seed"],
            vocabulary_hashes=meta["vocabulary_hashes"],
            frozen_counts=frozen_counts,
        )
        set_compact_state(model, **arrays, counter=meta["counter"])
    except (KeyError, ParameterError, ValueError, TypeError) as exc:
        raise CuriosityError(f"{where}: not a valid topic model ({_one_line(exc)})") from None
    return model


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__
