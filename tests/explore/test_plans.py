"""Planned walkers against hand-drawn paths on small grids."""

from __future__ import annotations

import numpy as np
import pytest

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.explore.plans import compact_block, lawnmower, scattered_cells


def cells(rows_cols: list[tuple[int, int]], cols: int) -> list[int]:
    return [r * cols + c for r, c in rows_cols]


def test_the_lawnmower_sweeps_lanes_turns_at_edges_and_sweeps_back_from_the_corner():
    # 4 x 5 grid, start (1, 1): the farther column edge is east, the farther row edge south
    #
    #   col:  0  1  2  3  4        first sweep (steps 0..13), then from the corner (3, 4)
    #   row 0 .  .  .  .  .        back north: lanes on rows 2, 1, 0 (revisits on 2 and
    #   row 1 .  0  1  2  3        the east of 1), so row 1's west part and row 0 are
    #   row 2 8  7  6  5  4        mowed on the way back
    #   row 3 9 10 11 12 13
    expected = [(1, 1), (1, 2), (1, 3), (1, 4), (2, 4), (2, 3), (2, 2), (2, 1), (2, 0),
                (3, 0), (3, 1), (3, 2), (3, 3), (3, 4),
                (2, 4), (2, 3), (2, 2), (2, 1), (2, 0),
                (1, 0), (1, 1), (1, 2), (1, 3), (1, 4),
                (0, 4), (0, 3), (0, 2), (0, 1), (0, 0),
                (1, 0), (1, 1)]
    got = lawnmower(6, SquareGrid(4, 5), len(expected), np.random.default_rng(0))
    assert got.tolist() == cells(expected, 5)


def test_the_lawnmower_heads_for_the_farther_edges_and_east_south_on_ties():
    # start (2, 3) of 4 x 5: west is farther (3 > 1) and north is farther (2 > 1)
    got = lawnmower(2 * 5 + 3, SquareGrid(4, 5), 9, np.random.default_rng(0))
    assert got.tolist() == cells([(2, 3), (2, 2), (2, 1), (2, 0), (1, 0), (1, 1), (1, 2), (1, 3), (1, 4)], 5)
    # centre of 3 x 3: ties go east, then south
    assert lawnmower(4, SquareGrid(3, 3), 4, None).tolist() == cells([(1, 1), (1, 2), (2, 2), (2, 1)], 3)


@pytest.mark.parametrize("shape, start, expected", [
    ((1, 4), 1, [1, 2, 3, 2, 1, 0, 1, 2]),  # one row: end to end and back
    ((4, 1), 2, [2, 1, 0, 1, 2, 3, 2, 1]),  # one column: north is farther (2 > 1)
    ((2, 2), 3, [3, 2, 0, 1, 3, 2, 0, 1]),  # a corner start: west, north, then round
])
def test_the_lawnmower_on_thin_maps_keeps_to_4_neighbours(shape, start, expected):
    got = lawnmower(start, SquareGrid(*shape), len(expected), None)
    assert got.tolist() == expected


def test_every_lawnmower_step_is_a_4_neighbour_move_and_it_covers_the_map():
    rows, cols = 7, 9
    for start in range(rows * cols):
        path = lawnmower(start, SquareGrid(rows, cols), 3 * rows * cols, None)
        r, c = np.divmod(path, cols)
        assert (np.abs(np.diff(r)) + np.abs(np.diff(c)) == 1).all()
        assert set(path.tolist()) == set(range(rows * cols))


def test_the_compact_block_takes_the_nearest_cells_first_ties_row_major():
    got = compact_block(12, SquareGrid(5, 5), 25, None)
    assert got[:5].tolist() == [12, 7, 11, 13, 17]  # the start, then its 4 neighbours
    assert set(got[5:9].tolist()) == {6, 8, 16, 18}  # then the diagonals
    d2 = [(c // 5 - 2) ** 2 + (c % 5 - 2) ** 2 for c in got]
    assert d2 == sorted(d2) and sorted(got.tolist()) == list(range(25))
    # a corner start: the block is clipped by the edges; longer than the map, it starts again
    corner = compact_block(0, SquareGrid(3, 3), 11, None)
    assert corner[:3].tolist() == [0, 1, 3] and corner[9:].tolist() == corner[:2].tolist()


def test_scattered_cells_are_a_random_permutation_from_the_stream():
    a = scattered_cells(0, SquareGrid(4, 6), 24, np.random.default_rng(3))
    b = scattered_cells(0, SquareGrid(4, 6), 24, np.random.default_rng(3))
    assert sorted(a.tolist()) == list(range(24)) and a.tolist() == b.tolist()
    assert a.tolist() != scattered_cells(0, SquareGrid(4, 6), 24, np.random.default_rng(4)).tolist()
    assert scattered_cells(0, SquareGrid(2, 2), 6, np.random.default_rng(0)).size == 6
