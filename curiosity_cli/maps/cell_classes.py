"""Which human classes each cell of a map holds, and which a path's cells touched at which step.

The label stage records the first step of each class in a run's label file
(``class_first_step``); the mechanism measures read which classes a candidate held; the
oracles (:mod:`curiosity_cli.explore.weights`) read the same classes to steer. Here, in the
maps stage beneath them all, so that each reads one rule.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.errors import ParameterError


def cell_class_pixels(labels: np.ndarray, cell_width: int, n_classes: int) -> np.ndarray:
    """Pixels of each class in each cell of a map's grid.

    Cells as in the word store (:meth:`~curiosity_cli.maps.cell_grid.SquareGrid.cells_of_pixels`
    of the ``cell_width`` grid over the labels); a partial cell at the bottom or right
    border is a cell of its own with fewer pixels.

    Parameters
    ----------
    labels : (H, W) integer ndarray
        Class ids ``0 .. n_classes - 1``.
    cell_width : int
    n_classes : int

    Returns
    -------
    (n_cells, n_classes) int64 ndarray
        Each row sums to the cell's pixels.
    """
    labels = np.asarray(labels)
    if labels.ndim != 2:
        raise ParameterError(f"labels: got shape {labels.shape}, expected (H, W)")
    if labels.size and (labels.min() < 0 or labels.max() >= n_classes):
        raise ParameterError(f"labels: class ids {labels.min()} .. {labels.max()}, expected 0 .. {n_classes - 1}")
    from curiosity_cli.maps.cell_grid import map_grid

    grid = map_grid(labels.shape, cell_width)
    out = np.zeros((grid.n_cells, n_classes), np.int64)
    pixel_cols = np.arange(labels.shape[1])
    # one band of cell_width pixel rows at a time: no (H, W) int64 index array for a large map
    for top in range(0, labels.shape[0], cell_width):
        band = labels[top : top + cell_width].astype(np.int64)
        cells = grid.cells_of_pixels(np.arange(top, top + band.shape[0])[:, None], pixel_cols[None, :])
        first, last = cells.min(), cells.max()
        out[first : last + 1] += np.bincount(
            ((cells - first) * n_classes + band).ravel(), minlength=(last + 1 - first) * n_classes
        ).reshape(-1, n_classes)
    return out


def map_class_pixels(map_data) -> np.ndarray | None:
    """A map's (:class:`~curiosity_cli.maps.map_data.MapData`) class pixels per cell: :func:`cell_class_pixels`
    at its cell width, of its ``n_classes``; None without labels."""
    if map_data.labels is None:
        return None
    return cell_class_pixels(map_data.labels, map_data.config.cell_width, map_data.n_classes)


def classes_present(cell_pixels: np.ndarray, share_percent: int) -> np.ndarray:
    """Which classes count as present in each cell: at least ``share_percent`` % of its pixels.

    Compared in integers (``100 * class pixels >= share_percent * cell pixels``), so a
    class at exactly the share counts, with no rounding at the edge.

    Parameters
    ----------
    cell_pixels : (n_cells, C) integer ndarray
        From :func:`cell_class_pixels`.
    share_percent : int
        1 .. 100.

    Returns
    -------
    (n_cells, C) bool ndarray
    """
    if not 1 <= share_percent <= 100:
        raise ParameterError(f"share_percent: got {share_percent}, expected 1 .. 100")
    cell_pixels = np.asarray(cell_pixels, np.int64)
    return 100 * cell_pixels >= share_percent * cell_pixels.sum(axis=1, keepdims=True)


def first_steps(path: np.ndarray, present: np.ndarray) -> np.ndarray:
    """The step at which a path first stood in a cell where each class is present.

    Parameters
    ----------
    path : (L,) integer ndarray
        Row-major cell of each step (step 0 is the start cell).
    present : (n_cells, C) bool ndarray
        From :func:`classes_present`.

    Returns
    -------
    (C,) int64 ndarray
        0 .. L - 1; -1 for a class never reached. The classes found within the first
        ``n`` steps are those with ``0 <= step < n`` (:func:`curiosity_cli.evaluate.information.classes_found`).
    """
    path = np.asarray(path, np.int64)
    if path.size and (path.min() < 0 or path.max() >= present.shape[0]):
        raise ParameterError(f"path: cells {path.min()} .. {path.max()}, expected 0 .. {present.shape[0] - 1}")
    hits = np.asarray(present, bool)[path]  # (L, C)
    return np.where(hits.any(axis=0), hits.argmax(axis=0), -1).astype(np.int64)
