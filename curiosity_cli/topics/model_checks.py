"""Checks of what a :class:`~curiosity_cli.topics.model.TopicModel` is given.

The model's constructor and methods take vocabulary hashes, frozen word-topic counts,
word ids and lists of cells from callers and files; these functions check them and
return them in the dtype the model stores, or raise :class:`ParameterError` naming the
argument. They know the model only through the sizes passed to them, so the model
keeps its state and sampling, and the rules for its inputs live here.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from curiosity_cli.errors import ParameterError


def check_vocabulary_hashes(hashes):
    """The model's ``vocabulary_hashes``, checked and copied.

    Parameters
    ----------
    hashes : None, mapping of str to str, or sequence of str

    Returns
    -------
    None, dict or tuple
        A mapping as a dict, a sequence as a tuple.

    Raises
    ------
    ParameterError
        Naming ``vocabulary_hashes``: another type, or entries that are not str.
    """
    if hashes is None:
        return None
    if isinstance(hashes, Mapping):
        if not all(isinstance(k, str) and isinstance(v, str) for k, v in hashes.items()):
            raise ParameterError("vocabulary_hashes: expected a mapping of str to str")
        return dict(hashes)
    if isinstance(hashes, Sequence) and not isinstance(hashes, str):
        if not all(isinstance(h, str) for h in hashes):
            raise ParameterError("vocabulary_hashes: expected a sequence of str")
        return tuple(hashes)
    raise ParameterError(f"vocabulary_hashes: got {type(hashes).__name__}, expected a mapping or a sequence of str")


def check_frozen_counts(counts, n_words: int, n_topics: int) -> np.ndarray:
    """Frozen word-topic counts (Φ as counts), checked.

    Parameters
    ----------
    counts : (V, K) int array_like
    n_words, n_topics : int
        The model's V and K.

    Returns
    -------
    (V, K) int32 ndarray

    Raises
    ------
    ParameterError
        Naming ``frozen_counts``: another shape, a non-integer dtype, negative counts, or
        a topic whose total does not fit the model's int32 counts.
    """
    counts = np.asarray(counts)
    if counts.shape != (n_words, n_topics):
        raise ParameterError(f"frozen_counts: got shape {counts.shape}, expected (V, K) = ({n_words}, {n_topics})")
    if counts.dtype == np.bool_ or not np.issubdtype(counts.dtype, np.integer):
        raise ParameterError(f"frozen_counts: got dtype {counts.dtype}, expected integer counts")
    if counts.size and (counts.min() < 0 or counts.sum(axis=0, dtype=np.int64).max() > np.iinfo(np.int32).max):
        raise ParameterError("frozen_counts: counts must be >= 0 and each topic's total fit in int32")
    return counts.astype(np.int32)


def check_word_ids(words, vocabulary_size: int) -> np.ndarray:
    """Word ids to add to a cell, checked.

    Parameters
    ----------
    words : (n,) int array_like
        Ids in ``0 .. vocabulary_size - 1``; may be empty (of any dtype).
    vocabulary_size : int
        The model's V.

    Returns
    -------
    (n,) int32 ndarray

    Raises
    ------
    ParameterError
        Naming ``words``: not 1-D, not integer (bool is not), or ids out of range.
    """
    words = np.asarray(words)
    if words.ndim != 1:
        raise ParameterError(f"words: got shape {words.shape}, expected (n,)")
    if words.size == 0:
        return np.zeros(0, np.int32)
    if words.dtype == np.bool_ or not np.issubdtype(words.dtype, np.integer):
        raise ParameterError(f"words: got dtype {words.dtype}, expected integer word ids")
    if words.min() < 0 or words.max() >= vocabulary_size:
        raise ParameterError(f"words: ids must be in 0..{vocabulary_size - 1}, got {words.min()}..{words.max()}")
    return words.astype(np.int32)


def check_model_cells(cells, name: str, cell_first: np.ndarray) -> np.ndarray:
    """A list of cells that must all be in the model (observed), checked.

    Parameters
    ----------
    cells : (m,) int array_like
        Cell indices, repeats allowed; may be empty (of any dtype).
    name : str
        The argument's name, for the message.
    cell_first : (n_cells,) int64 ndarray
        The model's index of each cell's first word, ``-1`` for a cell not in the model;
        its length is the model's number of cells.

    Returns
    -------
    (m,) int64 ndarray

    Raises
    ------
    ParameterError
        Naming ``name``: not 1-D, not integer (bool is not), out of ``0 .. n_cells - 1``,
        or a cell not in the model.
    """
    n_cells = cell_first.size
    cells = np.asarray(cells)
    if cells.ndim != 1:
        raise ParameterError(f"{name}: got shape {cells.shape}, expected a 1-D list of cells")
    if cells.size == 0:
        return np.zeros(0, np.int64)
    if cells.dtype == np.bool_ or not np.issubdtype(cells.dtype, np.integer):
        raise ParameterError(f"{name}: got dtype {cells.dtype}, expected integer cell indices")
    if cells.min() < 0 or cells.max() >= n_cells:
        raise ParameterError(f"{name}: cells must be in 0..{n_cells - 1}")
    cells = cells.astype(np.int64)
    missing = cells[cell_first[cells] < 0]
    if missing.size:
        raise ParameterError(f"{name}: cell {missing[0]} is not in the model")
    return cells
