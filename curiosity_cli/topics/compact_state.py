"""A topic model's compact state: what a model file keeps.

The compact state is the observed cells in the order added, their times and word
counts, their words and topics cell after cell, and the random state. Every count of the
model follows from it (with a frozen model's frozen counts, which a file keeps apart),
so a file holds no counts: :func:`set_compact_state` checks the arrays, since they come
from a file, and has the model recount (:meth:`TopicModel.set_topics
<curiosity_cli.topics.model.TopicModel.set_topics>`).

Both functions go through the model's whole state (:meth:`TopicModel.full_state
<curiosity_cli.topics.model.TopicModel.full_state>` and its setter), whose layout the
model owns; this module owns the compact form.
:mod:`~curiosity_cli.topics.persistence` writes and reads it.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.checks import check_int
from curiosity_cli.topics.model import TopicModel


def compact_state(model: TopicModel) -> dict:
    """The observed cells of ``model`` with their words and topics, random state included.

    What a model file keeps (:func:`~curiosity_cli.topics.persistence.save_model`):
    every count follows from it (and, for a frozen model, the frozen counts), and
    :func:`set_compact_state` recounts them.

    Returns
    -------
    dict
        ``order``: (n_observed,) int32, the cells in the order added; ``times``:
        (n_observed,) int64, their times; ``sizes``: (n_observed,) int64, their word
        counts; ``words``, ``topics``: (n_words,) int32 and the model's
        :attr:`~curiosity_cli.topics.model.TopicModel.topic_dtype`, cell after cell in
        that order; ``counter``: int, the random state.
    """
    state = model.full_state()
    order = state["order"]
    return {
        "order": order,
        "times": state["times"],
        "sizes": state["cell_count"][order],
        "words": _cell_after_cell(state["words"], state, order),
        "topics": _cell_after_cell(state["topics"], state, order),
        "counter": state["counter"],
    }


def set_compact_state(model: TopicModel, *, order, times, sizes, words, topics, counter) -> None:
    """Replace the observed cells, words, topics and random state of ``model`` by a :func:`compact_state`.

    Every count is recomputed from the topics (the frozen counts of a frozen model
    stay). The arrays may come from a file, so they are checked first; nothing changes
    if a check fails.

    Parameters
    ----------
    order, times, sizes : (n_observed,) int ndarray
        The cells in the order added, their times and their word counts.
    words, topics : (n_words,) int ndarray
        The cells' words and topics, cell after cell in ``order``.
    counter : int
        The random state.

    Raises
    ------
    ParameterError
        ``counter`` is not an int >= 0.
    ValueError
        The arrays are not 1-D integer arrays, or disagree with each other or with
        the model (cells, word ids or topics out of range, times decreasing).
    """
    counter = check_int("counter", counter, 0)
    _check_arrays(model, order, times, sizes, words, topics)
    n = order.size
    state = model.full_state()
    words = words.astype(np.int32)
    topics = topics.astype(model.topic_dtype)
    firsts = np.concatenate([[0], np.cumsum(sizes)[:-1]]) if n else np.zeros(0, np.int64)
    state["cell_first"][order] = firsts
    state["cell_count"][order] = sizes
    state.update(words=words, topics=topics, order=order, times=times, counter=counter)
    model.set_full_state(**state)
    model.set_topics(model.topics())  # the counts, made from the words and topics just put back


def _check_arrays(model: TopicModel, order, times, sizes, words, topics) -> None:
    """Raise ValueError unless the arrays of a compact state fit each other and ``model``."""
    n = order.size
    for name, a in (("order", order), ("times", times), ("sizes", sizes), ("words", words), ("topics", topics)):
        if a.ndim != 1 or (a.size and not np.issubdtype(a.dtype, np.integer)):
            raise ValueError(f"{name}: expected a 1-D integer array")
    if times.size != n or sizes.size != n:
        raise ValueError("order, times and sizes differ in length")
    if n and (order.min() < 0 or order.max() >= model.n_cells or np.unique(order).size != n):
        raise ValueError("order: cells out of range or repeated")
    if n and (np.any(np.diff(times) < 0) or times[0] < 0):
        raise ValueError("times: negative or decreasing")
    if (n and sizes.min() < 0) or sizes.sum() != words.size or topics.size != words.size:
        raise ValueError("sizes, words and topics disagree")
    if words.size and (words.min() < 0 or words.max() >= model.vocabulary_size):
        raise ValueError(f"words: ids outside 0..{model.vocabulary_size - 1}")
    if topics.size and (topics.min() < 0 or topics.max() >= model.n_topics):
        raise ValueError(f"topics: labels outside 0..{model.n_topics - 1}")


def _cell_after_cell(per_word: np.ndarray, state: dict, cells: np.ndarray) -> np.ndarray:
    """The entries of a per-word array of a full state for ``cells`` (observed), cell after cell.

    ``state['cell_first']`` and ``state['cell_count']``, (n_cells,) int64, say where
    each cell's words sit in ``per_word``, (n_words,).
    """
    if not len(cells):
        return per_word[:0].copy()
    first, count = state["cell_first"], state["cell_count"]
    return np.concatenate([per_word[first[c] : first[c] + count[c]] for c in cells])
