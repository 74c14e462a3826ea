"""Visual words of a camera frame, cut into the driver's grid of image cells.

The same extractors and vocabularies as ``curiosity extract`` (texton words from the
MR8 filter bank, ORB words, optional hue words, one id space), on a frame first resized
to ``drive.frame_width``: at camera resolution the filter bank alone would take longer
than a frame. The ORB pyramid depth, the cap per tile and the top-up threshold are the
driver's own settings (``drive.orb_levels``, ``drive.orb_per_tile``,
``drive.orb_fill_threshold``) for the same reason: a frame of 192 px is too small for
every keypoint to describe its cells, while a map keeps them all.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.config import DriveConfig, WordsConfig
from curiosity_cli.errors import ParameterError
from curiosity_cli.words.extract import HUE_BINS


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
        from curiosity_cli.words.vocab import load_vocabulary

        self._words = words
        self._drive = drive
        self._orb = load_vocabulary(words.vocabulary_dir, "orb", words.orb_vocabulary)
        self._texton = load_vocabulary(words.vocabulary_dir, "texton", words.texton_vocabulary)
        self.texton_offset = len(self._orb.centres)
        self.hue_offset = self.texton_offset + len(self._texton.centres)
        self.vocabulary_size = self.hue_offset + (HUE_BINS if words.colour_words else 0)
        self.grid = (drive.grid_rows, drive.grid_cols)
        self.vocabulary_hashes = {"orb": self._orb.sha256, "texton": self._texton.sha256}

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
                f"({self._drive.grid_rows} x {self._drive.grid_cols})"
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
            into ``grid_rows x grid_cols`` cells of (near) equal size, a pixel at
            ``(r, c)`` belonging to cell ``(r * grid_rows // h, c * grid_cols // w)``.
        """
        import cv2

        from curiosity_cli.words.hamming import nearest_binary_words
        from curiosity_cli.words.orb import detect_orb
        from curiosity_cli.words.textons import texton_words

        drive, words = self._drive, self._words
        grey = cv2.cvtColor(small, cv2.COLOR_RGB2GRAY)
        t_rows, t_cols, t_words = texton_words(grey, self._texton.centres, drive.texton_stride)
        features = detect_orb(
            grey,
            tile=words.orb_tile,
            per_tile=drive.orb_per_tile,
            max_features=words.orb_max_features,
            fast_threshold=words.orb_fast_threshold,
            n_levels=drive.orb_levels,
            fill_threshold=drive.orb_fill_threshold,
        )
        o_words = nearest_binary_words(features.descriptors, self._orb.centres)
        rows = [features.rows, t_rows]
        cols = [features.cols, t_cols]
        ids = [o_words.astype(np.int32), t_words.astype(np.int32) + self.texton_offset]
        if words.colour_words:
            stride = drive.texton_stride
            hue = cv2.cvtColor(small, cv2.COLOR_RGB2HSV)[::stride, ::stride, 0]
            rows.append(t_rows)
            cols.append(t_cols)
            ids.append(hue.ravel().astype(np.int32) + self.hue_offset)
        return split_by_cell(np.concatenate(rows), np.concatenate(cols), np.concatenate(ids), small.shape[:2], self.grid)

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
    height, width = image_shape
    n_rows, n_cols = grid
    cell = (np.asarray(rows, np.int64) * n_rows // height) * n_cols + np.asarray(cols, np.int64) * n_cols // width
    order = np.argsort(cell, kind="stable")
    bounds = np.searchsorted(cell[order], np.arange(1, n_rows * n_cols))
    return [part.astype(np.int32) for part in np.split(np.asarray(ids)[order], bounds)]
