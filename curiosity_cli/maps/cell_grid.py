"""The cell grid: how pixels fall into cells, and how cells lie next to one another.

A map is cut into cells; the word store, the topic model, the walkers, the run files,
the figures and the drive all work on cells numbered ``0 .. n_cells - 1``, and each asks
a grid object what a cell is: which cell a pixel falls in, where a cell lies, which
cells are its neighbours and how far apart two cells are. Numba kernels never see the
object, only the arrays it builds (the neighbour table).

:class:`SquareGrid` is the paper's lattice: ``rows x cols`` square cells of
``cell_width`` pixels, numbered row-major, each with up to four neighbours.

:func:`map_grid` is the one place that picks the lattice a map is cut into (the word
store, the runs, the labels and the figures all take the map's grid from it, or from a
store that recorded it); a camera frame's image cells (``drive``) are square by design.

Another lattice (hexagonal cells, say) is another class here, with the same methods:

- ``covering(image_shape, cell_width)`` (class method): the grid over an image, and
  ``shape``, ``n_cells``, ``cell_width``;
- ``cells_of_pixels(pixel_rows, pixel_cols, frame_shape=None)``: the cell of each pixel
  of a map, or of a camera frame of any size the grid is stretched over (the drive);
- ``row_col(cells)`` and its inverse ``cell_of(rows, cols)``: a cell's place on the
  lattice, as run files record it;
- ``centres(cells, frame_shape=None)``: cell centres in pixels, on a map or a frame;
- ``neighbour_table(spatial)``: the ``(n_cells, spatial) int32`` table the topic model
  takes and the walkers move on, ``-1`` where a neighbour is off the grid, one
  direction per column;
- ``squared_distances(a, b)``: squared Euclidean distances between cell centres, in
  cell units (the coverage potential, the compact-block ceiling).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from curiosity_cli.checks import check_choice, check_int
from curiosity_cli.errors import ParameterError


# neighbour offsets (row, col) in neighbour_table's column order: the cross, then the diagonals
_STEPS = ((-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (-1, 1), (1, -1), (1, 1))


@dataclass(frozen=True)
class SquareGrid:
    """``rows x cols`` square cells of ``cell_width`` pixels, numbered row-major.

    Cell ``c`` is at row ``c // cols``, column ``c % cols``; its pixels are rows
    ``row * cell_width .. (row + 1) * cell_width - 1`` and likewise for columns.

    Parameters
    ----------
    rows, cols : int
        Cells per column and per row, each >= 1.
    cell_width : int, optional
        Cell side in pixels, >= 1. The default 1 makes each cell one pixel, for a grid
        used for its cells alone (synthetic maps, a camera frame's image cells).

    Raises
    ------
    ParameterError
        A size that is not an integer >= 1.
    """

    rows: int
    cols: int
    cell_width: int = 1

    def __post_init__(self):
        object.__setattr__(self, "rows", check_int("rows", self.rows, 1))
        object.__setattr__(self, "cols", check_int("cols", self.cols, 1))
        object.__setattr__(self, "cell_width", check_int("cell_width", self.cell_width, 1))

    @classmethod
    def covering(cls, image_shape: tuple[int, int], cell_width: int) -> SquareGrid:
        """The grid of ``cell_width`` cells over an image.

        A partial cell at the bottom or right border counts as a cell, with fewer
        pixels, as in the paper (2500 px at 32 px cells gives 79 x 79 = 6241 cells,
        its Table 1).

        Parameters
        ----------
        image_shape : (int, int)
            Image rows and columns in pixels.
        cell_width : int
            Cell side in pixels.

        Returns
        -------
        SquareGrid
            ``ceil(H / cell_width) x ceil(W / cell_width)`` cells.
        """
        height = check_int("image rows", image_shape[0], 1)
        width = check_int("image cols", image_shape[1], 1)
        cell_width = check_int("cell_width", cell_width, 1)
        return cls(-(-height // cell_width), -(-width // cell_width), cell_width)

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)``: cells per column and per row."""
        return self.rows, self.cols

    @property
    def n_cells(self) -> int:
        return self.rows * self.cols

    def cells_of_pixels(self, pixel_rows, pixel_cols, frame_shape: tuple[int, int] | None = None) -> np.ndarray:
        """The cell of each pixel.

        On a map (no ``frame_shape``), pixel ``(r, c)`` is in cell
        ``(r // cell_width, c // cell_width)``. On a frame of any size (``frame_shape``
        given, the drive's camera frames) the grid is stretched over the frame, which is
        cut into ``rows x cols`` cells of (near) equal size, and ``cell_width`` plays no
        part: pixel ``(r, c)`` of an ``H x W`` frame is in cell ``(r * rows // H, c * cols // W)``.

        Parameters
        ----------
        pixel_rows, pixel_cols : (...) int ndarrays
            Pixel positions, broadcast together, inside the grid's
            ``rows * cell_width x cols * cell_width`` pixels, or inside the frame.
        frame_shape : (int, int), optional
            ``(H, W)``, the frame's rows and columns in pixels.

        Returns
        -------
        (...) int64 ndarray
            Row-major cell indices.

        Raises
        ------
        ParameterError
            A pixel outside the grid or the frame.
        """
        if frame_shape is None:
            pixel_rows = _inside("pixel_rows", pixel_rows, self.rows * self.cell_width)
            pixel_cols = _inside("pixel_cols", pixel_cols, self.cols * self.cell_width)
            return (pixel_rows // self.cell_width) * self.cols + pixel_cols // self.cell_width
        height, width = frame_shape
        pixel_rows = _inside("pixel_rows", pixel_rows, height)
        pixel_cols = _inside("pixel_cols", pixel_cols, width)
        return (pixel_rows * self.rows // height) * self.cols + pixel_cols * self.cols // width

    def row_col(self, cells) -> tuple[np.ndarray, np.ndarray]:
        """Row and column of each cell.

        Parameters
        ----------
        cells : (...) int ndarray
            Row-major cell indices.

        Returns
        -------
        rows, cols : (...) int64 ndarrays
        """
        return np.divmod(np.asarray(cells, np.int64), self.cols)

    def cell_of(self, rows, cols) -> np.ndarray:
        """The cell at each row and column, the inverse of :meth:`row_col`.

        Parameters
        ----------
        rows, cols : (...) int ndarrays
            Broadcast together.

        Returns
        -------
        (...) int64 ndarray
        """
        return np.asarray(rows, np.int64) * self.cols + np.asarray(cols, np.int64)

    def centres(self, cells, frame_shape: tuple[int, int] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The centre of each cell in pixels, on a map or on a frame the grid is stretched over.

        Parameters
        ----------
        cells : (...) int ndarray
        frame_shape : (int, int), optional
            ``(H, W)`` of the frame (see :meth:`cells_of_pixels`); none for the map.

        Returns
        -------
        rows, cols : (...) float64 ndarrays
            On a map ``(row + 1/2) * cell_width`` and likewise for columns (a partial
            border cell's centre is that of the full cell it is cut from); on a frame
            ``(row + 1/2) * H / rows`` and ``(col + 1/2) * W / cols``.
        """
        rows, cols = self.row_col(cells)
        if frame_shape is None:
            half = self.cell_width / 2
            return rows * self.cell_width + half, cols * self.cell_width + half
        height, width = frame_shape
        return (rows + 0.5) * height / self.rows, (cols + 0.5) * width / self.cols

    def neighbour_table(self, spatial: int = 4) -> np.ndarray:
        """The neighbour table of the grid, as the topic model takes it.

        Parameters
        ----------
        spatial : {4, 8, 0}
            4 for up, down, left and right; 8 for those and the four diagonal cells
            (a walker's candidates, ``explore.candidates``); 0 for none (the model is
            then plain LDA).

        Returns
        -------
        (n_cells, spatial) int32 ndarray
            Row ``c`` lists the neighbours of cell ``c`` in the columns up
            ``(row - 1, col)``, down ``(row + 1, col)``, left ``(row, col - 1)``, right
            ``(row, col + 1)``, then with 8 up-left, up-right, down-left, down-right;
            ``-1`` where that cell is off the grid.

        Raises
        ------
        ParameterError
            ``spatial`` not 4, 8 or 0.
        """
        steps = _STEPS[: check_choice("spatial", spatial, (4, 8, 0))]
        rows, cols = self.row_col(np.arange(self.n_cells))
        table = np.full((self.n_cells, len(steps)), -1, np.int32)
        for j, (d_row, d_col) in enumerate(steps):
            r, c = rows + d_row, cols + d_col
            inside = (r >= 0) & (r < self.rows) & (c >= 0) & (c < self.cols)
            table[inside, j] = self.cell_of(r, c)[inside]
        return table

    def squared_distances(self, a, b) -> np.ndarray:
        """Squared Euclidean distances between the centres of two sets of cells, in cell units.

        Parameters
        ----------
        a : (n,) int ndarray
            Row-major cell indices.
        b : (m,) int ndarray
            Row-major cell indices.

        Returns
        -------
        (n, m) int64 ndarray
            ``(row_a - row_b)² + (col_a - col_b)²``.
        """
        a_rows, a_cols = self.row_col(a)
        b_rows, b_cols = self.row_col(b)
        return (a_rows[:, None] - b_rows[None, :]) ** 2 + (a_cols[:, None] - b_cols[None, :]) ** 2


def _inside(name: str, pixels, size: int) -> np.ndarray:
    """``pixels`` as int64, if each is in ``0 .. size - 1``."""
    pixels = np.asarray(pixels)
    if pixels.size and (pixels.dtype == np.bool_ or not np.issubdtype(pixels.dtype, np.integer)):
        raise ParameterError(f"{name}: got dtype {pixels.dtype}, expected integers")
    pixels = pixels.astype(np.int64)
    if pixels.size and (pixels.min() < 0 or pixels.max() >= size):
        raise ParameterError(f"{name}: got {pixels.min()} .. {pixels.max()}, expected 0 .. {size - 1}")
    return pixels


def map_grid(image_shape: tuple[int, int], cell_width: int) -> SquareGrid:
    """The cell grid of a map of ``image_shape`` pixels: the paper's square lattice,
    :meth:`SquareGrid.covering` (its parameters)."""
    return SquareGrid.covering(image_shape, cell_width)
