"""The square cell grid: shapes, pixels to cells, centres, neighbour tables and distances."""

from __future__ import annotations

import numpy as np
import pytest

from curiosity_cli.maps.cell_grid import SquareGrid, map_grid
from curiosity_cli.errors import ParameterError


def neighbour_table_naive(rows: int, cols: int) -> np.ndarray:
    """Up, down, left, right of every cell, one cell at a time; -1 off the grid."""
    table = []
    for row in range(rows):
        for col in range(cols):
            entry = []
            for r, c in ((row - 1, col), (row + 1, col), (row, col - 1), (row, col + 1)):
                entry.append(r * cols + c if 0 <= r < rows and 0 <= c < cols else -1)
            table.append(entry)
    return np.array(table, np.int32).reshape(rows * cols, 4)


def in_bounds(table: np.ndarray, cell: int) -> list[int]:
    return [g for g in table[cell].tolist() if g >= 0]


@pytest.mark.parametrize(
    "image_shape, cell_width, shape",
    [
        ((2500, 2500), 32, (79, 79)),  # the paper's Table 1: 6241 cells
        ((1024, 1024), 16, (64, 64)),  # an exact multiple: no partial cells
        ((40, 50), 16, (3, 4)),  # partial last row and column
        ((96, 129), 16, (6, 9)),  # one pixel over: a partial column one pixel wide
        ((5, 5), 5, (1, 1)),
    ],
)
def test_the_grid_over_an_image_counts_partial_border_cells(image_shape, cell_width, shape):
    grid = SquareGrid.covering(image_shape, cell_width)
    assert grid.shape == shape and grid.n_cells == shape[0] * shape[1] and grid.cell_width == cell_width


def test_a_pixel_on_a_cell_border_belongs_to_the_cell_it_starts():
    grid = SquareGrid.covering((40, 50), 16)
    rows = np.array([0, 15, 16, 31, 32])
    assert grid.cells_of_pixels(rows, np.zeros(5, int)).tolist() == [0, 0, 4, 4, 8]
    assert grid.cells_of_pixels(np.zeros(5, int), rows).tolist() == [0, 0, 1, 1, 2]


def test_the_last_partial_row_and_column_are_cells_of_their_own():
    grid = SquareGrid.covering((40, 50), 16)  # 3 x 4 cells; the last row 8 px high, the last column 2 px wide
    assert grid.cells_of_pixels([39, 39, 32, 47], [49, 48, 0, 49]).tolist() == [11, 11, 8, 11]
    every = grid.cells_of_pixels(np.arange(40)[:, None], np.arange(50)[None, :])
    assert every.shape == (40, 50) and every.dtype == np.int64
    np.testing.assert_array_equal(every, (np.arange(40)[:, None] // 16) * 4 + np.arange(50)[None, :] // 16)
    assert np.bincount(every.ravel()).tolist() == [256, 256, 256, 32, 256, 256, 256, 32, 128, 128, 128, 16]


def test_pixels_outside_the_grid_are_refused():
    grid = SquareGrid.covering((40, 50), 16)
    with pytest.raises(ParameterError, match=r"pixel_rows: got -1 \.\. 3, expected 0 \.\. 47"):
        grid.cells_of_pixels([-1, 3], [0, 0])
    with pytest.raises(ParameterError, match="pixel_cols"):
        grid.cells_of_pixels([0], [64])
    with pytest.raises(ParameterError, match="dtype float64"):
        grid.cells_of_pixels([0.5], [0])


def test_row_col_cell_of_and_centres():
    grid = SquareGrid(3, 4, 16)
    rows, cols = grid.row_col(np.arange(12))
    assert rows.tolist() == [0] * 4 + [1] * 4 + [2] * 4 and cols.tolist() == [0, 1, 2, 3] * 3
    np.testing.assert_array_equal(grid.cell_of(rows, cols), np.arange(12))
    centre_rows, centre_cols = grid.centres([0, 11])
    assert centre_rows.tolist() == [8.0, 40.0] and centre_cols.tolist() == [8.0, 56.0]
    # the centres are the pixels' own cells
    assert grid.cells_of_pixels(centre_rows.astype(int), centre_cols.astype(int)).tolist() == [0, 11]


@pytest.mark.parametrize("rows, cols", [(5, 7), (3, 4), (1, 6), (4, 1), (1, 1), (2, 2)])
def test_the_neighbour_table_is_up_down_left_right_as_built_one_cell_at_a_time(rows, cols):
    table = SquareGrid(rows, cols).neighbour_table()
    assert table.dtype == np.int32 and table.flags.c_contiguous
    np.testing.assert_array_equal(table, neighbour_table_naive(rows, cols))
    assert SquareGrid(rows, cols).neighbour_table(spatial=0).shape == (rows * cols, 0)


@pytest.mark.parametrize(
    "cell, expected",
    [
        (0, [4, 1]),  # top-left corner: down, right
        (3, [7, 2]),  # top-right corner: down, left
        (8, [4, 9]),  # bottom-left corner: up, right
        (11, [7, 10]),  # bottom-right corner: up, left
        (5, [1, 9, 4, 6]),  # inside: up, down, left, right
        (10, [6, 9, 11]),  # bottom edge: up, left, right
        (4, [0, 8, 5]),  # left edge: up, down, right
    ],
)
def test_neighbours_stay_on_a_3_by_4_grid(cell, expected):
    assert in_bounds(SquareGrid(3, 4).neighbour_table(), cell) == expected


def test_a_single_column_grid_has_only_vertical_neighbours():
    assert in_bounds(SquareGrid(5, 1).neighbour_table(), 2) == [1, 3]


def test_squared_distances_are_in_cell_units():
    grid = SquareGrid(4, 5, 16)  # the cell width plays no part
    a, b = np.array([0, 7, 19]), np.array([0, 12, 4])
    expected = [[(r1 - r2) ** 2 + (c1 - c2) ** 2 for r2, c2 in (divmod(int(y), 5) for y in b)]
                for r1, c1 in (divmod(int(x), 5) for x in a)]
    got = grid.squared_distances(a, b)
    assert got.dtype == np.int64 and got.tolist() == expected


def test_a_frame_is_cut_into_cells_of_near_equal_size():
    grid = SquareGrid(2, 3)
    rows, cols = np.meshgrid(np.arange(7), np.arange(10), indexing="ij")
    cells = grid.cells_of_pixels(rows, cols, (7, 10))
    # 7 rows: 4 then 3; 10 columns: 4, 3, 3
    assert np.bincount(cells.ravel()).tolist() == [16, 12, 12, 12, 9, 9]
    assert cells[3, 3] == 0 and cells[4, 4] == 4 and cells[6, 9] == 5
    centre_rows, centre_cols = grid.centres(np.arange(6), (7, 10))
    np.testing.assert_allclose(centre_rows, [1.75] * 3 + [5.25] * 3)
    np.testing.assert_allclose(centre_cols, [10 / 6, 5.0, 50 / 6] * 2)


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda: SquareGrid(0, 3), "rows"),
        (lambda: SquareGrid(3, 2.0), "cols"),
        (lambda: SquareGrid(3, 3, 0), "cell_width"),
        (lambda: SquareGrid.covering((40, 50), 0), "cell_width"),
        (lambda: SquareGrid(3, 3).neighbour_table(spatial=6), "spatial"),
    ],
)
def test_bad_sizes_are_refused_by_name(make, name):
    with pytest.raises(ParameterError, match=name):
        make()


def test_a_map_is_cut_into_the_papers_square_cells():
    grid = map_grid((2500, 2500), 32)
    assert isinstance(grid, SquareGrid) and grid == SquareGrid.covering((2500, 2500), 32)
    assert (grid.shape, grid.n_cells) == ((79, 79), 6241)  # the paper's Table 1
