"""Planned walkers: runs whose cells are fixed when they start, not drawn step by step.

A plan is a pure function ``plan(start_cell, grid, length, rng)`` returning the
``(length,)`` row-major cells of the map's :class:`~curiosity_cli.maps.cell_grid.SquareGrid`
the run observes, in order. Two kinds use it:

- ``lawnmower``, the pre-programmed mission the paper's introduction argues against: a
  boustrophedon sweep (:func:`lawnmower`). Every step moves to a 4-neighbour, so it is a
  path like the weight functions' and is compared with them.
- the **ceilings**, which are not paths: what a model could learn from ``L`` cells
  chosen without walking, at the same refinement budget per cell. ``scattered-cells``
  observes cells in a uniformly random order (any prefix of ``L`` cells is a uniform
  random ``L``-subset), ``compact-block`` the cells nearest the start first (any prefix
  is an ``L``-cell block around the start, clipped by the map's edges).

A plan longer than the map keeps going: the lawnmower sweeps back and forth, and the
ceilings observe their order again from the top (revisits add no words but refine).
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.maps.cell_grid import SquareGrid


def lawnmower(start_cell: int, grid: SquareGrid, length: int, rng: np.random.Generator) -> np.ndarray:
    """A boustrophedon sweep from ``start_cell``: lanes along rows, one row apart.

    The first lane runs from the start towards the farther column edge (east on a tie);
    at the edge the mower steps one row on, towards the farther row edge (south on a
    tie), and runs the next lane the other way. At a corner (the end of the lane on the
    last row) it turns back: the row direction reverses and the sweep continues lane by
    lane over the rows already mowed and on to those beyond the start row (including
    the part of the start row it left behind), corner to corner, for as long as the
    path lasts; once the map is exhausted every step is a revisit. A map one row high
    is swept end to end and back; one column wide, top to bottom and back.

    Parameters
    ----------
    start_cell : int
        Row-major cell of the first step.
    grid : SquareGrid
        The map's cells, at least 2.
    length : int
        Steps of the path.
    rng : numpy.random.Generator
        Unused: the sweep is deterministic.

    Returns
    -------
    (length,) int64 ndarray
        Row-major cells; each is a 4-neighbour of the one before.
    """
    rows, cols = grid.shape
    row, col = (int(v) for v in grid.row_col(start_cell))
    d_col = 1 if cols - 1 - col >= col else -1
    d_row = 1 if rows - 1 - row >= row else -1
    cells = np.empty(length, np.int64)
    cells[0] = start_cell
    for step in range(1, length):
        if 0 <= col + d_col < cols:
            col += d_col
        elif rows == 1:  # no next lane: back along the only row
            d_col = -d_col
            col += d_col
        else:
            if not 0 <= row + d_row < rows:  # a corner: sweep back the other way
                d_row = -d_row
            row += d_row
            d_col = -d_col
        cells[step] = grid.cell_of(row, col)
    return cells


def scattered_cells(start_cell: int, grid: SquareGrid, length: int, rng: np.random.Generator) -> np.ndarray:
    """Cells in a uniformly random order drawn from ``rng`` (the start cell plays no part).

    Returns
    -------
    (length,) int64 ndarray
    """
    return np.resize(rng.permutation(grid.n_cells).astype(np.int64), length)


def compact_block(start_cell: int, grid: SquareGrid, length: int, rng: np.random.Generator) -> np.ndarray:
    """Cells by Euclidean distance from ``start_cell``, nearest first; ties in row-major order.

    ``rng`` is unused: the order is deterministic.

    Returns
    -------
    (length,) int64 ndarray
    """
    d2 = grid.squared_distances(np.arange(grid.n_cells), [start_cell])[:, 0]
    order = np.argsort(d2, kind="stable")
    return np.resize(order.astype(np.int64), length)
