"""Visual words of a camera frame, cut into the driver's grid of image cells.

The same recipe as ``curiosity extract`` (:class:`~curiosity_cli.words.kinds.WordRecipe`:
the same kinds of words, vocabularies and id space), on a frame first resized to
``drive.frame_width``: at camera resolution the filter bank alone would take longer
than a frame. The ORB pyramid depth, the cap per tile and the top-up threshold are the
driver's own settings (``drive.orb_levels``, ``drive.orb_per_tile``,
``drive.orb_fill_threshold``) for the same reason: a frame of 192 px is too small for
every keypoint to describe its cells, while a map keeps them all. With
``words.orb_detector: grid`` a frame gets the map's grid (``words.orb_grid_step``),
which reads none of them.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.config import DriveConfig, WordsConfig
from curiosity_cli.errors import ParameterError
from curiosity_cli.words.kinds import OrbSettings, Picture, WordRecipe


class FrameWords:
    """Extract the words of frames, cell by cell.

    Parameters
    ----------
    words : WordsConfig
        Vocabularies (loaded once here) and ORB tiling.
    drive : DriveConfig
        Frame width, grid, texton stride, ORB pyramid.

    Raises
    ------
    CuriosityError
        A missing or malformed vocabulary.
    """

    def __init__(self, words: WordsConfig, drive: DriveConfig):
        self._drive = drive
        self._recipe = WordRecipe(words)
        self._orb = OrbSettings.for_frames(
            words, per_tile=drive.orb_per_tile, fill_threshold=drive.orb_fill_threshold, n_levels=drive.orb_levels
        )
        self.vocabulary_size = self._recipe.vocabulary_size
        self.grid = (drive.grid_rows, drive.grid_cols)
        # every kind's, hue's ("") too: a saved model names what all its ids mean
        self.vocabulary_hashes = {t.name: t.sha256 for t in self._recipe.types}

    def resized(self, frame: np.ndarray) -> np.ndarray:
        """The frame at ``drive.frame_width`` columns, aspect kept.

        Parameters
        ----------
        frame : (H, W, 3) uint8 ndarray
            RGB.

        Returns
        -------
        (h, frame_width, 3) uint8 ndarray
            ``h = round(H * frame_width / W)``, at least ``grid_rows``.

        Raises
        ------
        ParameterError
            A frame that is not (H, W, 3) uint8 or is too small for the grid.
        """
        import cv2

        if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
            raise ParameterError(f"frame: got {frame.dtype} of shape {frame.shape}, expected (H, W, 3) uint8 RGB")
        height, width = frame.shape[:2]
        rows = max(self._drive.grid_rows, round(height * self._drive.frame_width / width))
        if height < self._drive.grid_rows or width < self._drive.grid_cols:
            raise ParameterError(
                f"frame: got {height} x {width} px, expected at least one pixel per image cell "
                f"(drive.grid_rows x drive.grid_cols: {self._drive.grid_rows} x {self._drive.grid_cols})"
            )
        # INTER_AREA averages the pixels a smaller pixel covers: no aliasing in the textures
        return cv2.resize(frame, (self._drive.frame_width, rows), interpolation=cv2.INTER_AREA)

    def cell_words(self, small: np.ndarray) -> list[np.ndarray]:
        """The words of each image cell of a resized frame.

        Parameters
        ----------
        small : (h, w, 3) uint8 ndarray
            RGB, from :meth:`resized`.

        Returns
        -------
        list of (n_c,) int32 ndarray
            One per image cell, row-major (``row * grid_cols + col``); the frame is cut
            into ``grid_rows x grid_cols`` cells of (near) equal size
            (:meth:`~curiosity_cli.maps.cell_grid.SquareGrid.cells_of_pixels`).
        """
        import cv2

        grey = cv2.cvtColor(small, cv2.COLOR_RGB2GRAY)
        rows, cols, ids, _ = self._recipe.find(Picture(small, grey, self._drive.texton_stride, self._orb))
        return split_by_cell(rows, cols, ids, small.shape[:2], self.grid)

    def __call__(self, frame: np.ndarray) -> list[np.ndarray]:
        """:meth:`cell_words` of :meth:`resized` ``frame``."""
        return self.cell_words(self.resized(frame))


def split_by_cell(rows, cols, ids, image_shape: tuple[int, int], grid: tuple[int, int]) -> list[np.ndarray]:
    """Group word ids by image cell.

    Parameters
    ----------
    rows, cols : (n,) int ndarray
        Pixel of each word, inside ``image_shape``.
    ids : (n,) int ndarray
        Word ids.
    image_shape : (int, int)
        Rows and columns of the image in pixels.
    grid : (int, int)
        Image cells per column and per row.

    Returns
    -------
    list of (n_c,) int32 ndarray
        ``grid[0] * grid[1]`` arrays, row-major; within a cell, words keep their order.
    """
    image_cells = SquareGrid(*grid)
    cell = image_cells.cells_of_pixels(rows, cols, image_shape)
    order = np.argsort(cell, kind="stable")
    bounds = np.searchsorted(cell[order], np.arange(1, image_cells.n_cells))
    return [part.astype(np.int32) for part in np.split(np.asarray(ids)[order], bounds)]
