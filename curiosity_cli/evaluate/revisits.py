"""Revisits: how many distinct cells a path saw by each checkpoint, and how it got there.

A walker can win on MI by seeing more cells or by seeing better ones. Stepping back onto
visited cells costs steps, and how often a walker does so depends on the reading of
eq. 8 (:mod:`curiosity_cli.explore.weights`); these counts, beside MI in ``mi.csv``, let
a reader tell the two apart.
"""

from __future__ import annotations

import numpy as np

#: ``mi.csv``'s revisit columns, in order (:func:`revisit_counts`).
REVISIT_COLUMNS = ("distinct_cells", "revisit_steps", "boxed_in_steps")


def revisit_counts(path: np.ndarray, boxed_in: np.ndarray, length: int) -> dict[str, int]:
    """What the first ``length`` steps of a path saw.

    Parameters
    ----------
    path : (L,) int ndarray
        Row-major cell of each step.
    boxed_in : (L,) bool ndarray
        Steps whose neighbours were all visited (``path.csv``); step ``t`` is the move
        from ``path[t]`` to ``path[t + 1]``.
    length : int
        The checkpoint path length, 1 .. L.

    Returns
    -------
    dict of str to int
        ``distinct_cells``: cells seen; ``revisit_steps``: steps onto a cell seen
        before (``length - distinct_cells``); ``boxed_in_steps``: moves within the
        first ``length`` steps made with every neighbour visited.
    """
    if not 1 <= length <= path.size or boxed_in.shape != path.shape:
        raise ValueError(f"length: got {length} for a path of {path.size} steps and {boxed_in.size} boxed_in flags")
    distinct = int(np.unique(path[:length]).size)
    return {
        "distinct_cells": distinct,
        "revisit_steps": length - distinct,
        "boxed_in_steps": int(np.count_nonzero(boxed_in[: length - 1])),
    }
