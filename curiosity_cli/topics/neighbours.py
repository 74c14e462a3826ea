"""Neighbourhood graphs of cells, as fixed-width tables: streams of frames, and the check of any table.

A table is an ``(n_cells, width) int32`` array: row ``c`` lists the neighbours of cell
``c``, one per column, ``-1`` where a neighbour does not exist (at a border). Each column
has a fixed meaning, so a caller can read directions from it. A map's table is its
grid's (:meth:`curiosity_cli.maps.cell_grid.SquareGrid.neighbour_table`); a stream's adds two
columns to it:

======  ==========================================================
column  neighbour of ``(row, col)`` (frame ``t``)
======  ==========================================================
0       up, ``(row - 1, col)``
1       down, ``(row + 1, col)``
2       left, ``(row, col - 1)``
3       right, ``(row, col + 1)``
4       the same cell in the previous frame (``t - 1``), streams only
5       the same cell in the next frame (``t + 1``), streams only
======  ==========================================================

Without spatial neighbours the four spatial columns are left out, so a table with no
columns is plain LDA (each cell its own document).

A cell never lists itself: the model adds a cell's own topic counts to its neighbours'
(eq. 3 of the paper sums over the cell *and* its neighbours).

Streams are a fixed number of frames: cell ``frame * rows * cols + row * cols + col``.
The model's arrays are sized by the table, so a driver that runs indefinitely needs a
frame budget (or a fresh model per budget).
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.checks import check_choice, check_int
from curiosity_cli.errors import ParameterError


def stream_neighbours(
    grid: SquareGrid, n_frames: int, *, spatial: int = 4, temporal: int = 2, ring: bool = False
) -> np.ndarray:
    """Neighbour table of a stream of ``n_frames`` frames of a grid's cells.

    Parameters
    ----------
    grid : SquareGrid
        The cells of one frame.
    n_frames : int
        Number of frames, >= 1.
    spatial : {4, 0}
        4 for up, down, left and right within a frame; 0 for none.
    temporal : {2, 0}
        2 for the same cell in the previous and next frame; 0 for none.
    ring : bool
        The frames are slots of a ring: the first frame's previous is the last, the
        last's next the first (a stream that forgets its oldest frame reuses its slot).
        Needs ``n_frames >= 3``.

    Returns
    -------
    (n_frames * grid.n_cells, spatial + temporal) ndarray of int32
        Cell ``frame * grid.n_cells + cell``; the columns of
        :meth:`~curiosity_cli.maps.cell_grid.SquareGrid.neighbour_table` (if ``spatial``),
        then previous, next (if ``temporal``); ``-1`` where the neighbour is off the grid
        or outside the stream.
    """
    n_frames = check_int("n_frames", n_frames, 3 if ring else 1)
    within = np.tile(grid.neighbour_table(spatial).astype(np.int64), (n_frames, 1))  # (n_frames * n, spatial)
    temporal = check_choice("temporal", temporal, (2, 0))
    n = grid.n_cells
    first = np.repeat(np.arange(n_frames, dtype=np.int64) * n, n)[:, None]  # the first cell of each cell's frame
    columns = [np.where(within >= 0, within + first, -1)]
    if temporal:
        cells = np.arange(n_frames * n, dtype=np.int64)
        if ring:
            columns += [(cells - n) % cells.size, (cells + n) % cells.size]
        else:
            columns += [np.where(cells >= n, cells - n, -1), np.where(cells < (n_frames - 1) * n, cells + n, -1)]
    return np.column_stack(columns).astype(np.int32)


def check_neighbours(neighbours) -> np.ndarray:
    """A neighbour table as a C-contiguous int32 array, if it is a valid undirected graph.

    Valid: 2-D integer array, at least one row, entries ``-1`` or a cell index, no cell
    listing itself or the same neighbour twice, and symmetric (``d`` in row ``c`` exactly
    when ``c`` is in row ``d``): the model keeps each cell's neighbourhood sum up to date
    by updating the sums of the cells a changed word's cell lists.

    Raises
    ------
    ParameterError
        Naming ``neighbours`` and the first problem found.
    """
    table = np.asarray(neighbours)
    if table.ndim != 2 or table.shape[0] < 1:
        raise ParameterError(f"neighbours: got shape {table.shape}, expected (n_cells, width) with n_cells >= 1")
    if table.dtype == np.bool_ or not np.issubdtype(table.dtype, np.integer):
        raise ParameterError(f"neighbours: got dtype {table.dtype}, expected integers")
    n_cells = table.shape[0]
    if table.size and (table.min() < -1 or table.max() >= n_cells):
        raise ParameterError(f"neighbours: entries must be -1 or a cell index below {n_cells}")
    table = np.ascontiguousarray(table, dtype=np.int32)
    # row by row and column by column, in time and memory linear in the table: a stream's
    # table of 3 million cells is checked in a second where sorting its edges took twenty
    cells = np.arange(n_cells)
    listed = table >= 0
    itself = np.flatnonzero((table == cells[:, None]).any(axis=1))
    if itself.size:
        raise ParameterError(f"neighbours: cell {itself[0]} lists itself")
    ordered = np.sort(table, axis=1)
    if ((ordered[:, 1:] == ordered[:, :-1]) & (ordered[:, 1:] >= 0)).any():
        raise ParameterError("neighbours: a cell lists the same neighbour twice")
    answered = ~listed  # (c, j): row table[c, j] lists c, or there is no neighbour there
    for j in range(table.shape[1]):
        rows = np.flatnonzero(listed[:, j])
        back = table[table[rows, j]]  # the rows of cell c's j-th neighbours
        answered[rows, j] = (back == rows[:, None]).any(axis=1)
    if not answered.all():
        cell = int(np.flatnonzero(~answered.all(axis=1))[0])
        other = int(table[cell][~answered[cell]].min())
        raise ParameterError(
            f"neighbours: not symmetric: cell {cell} lists {other}, but not the other way round"
        )
    return table
