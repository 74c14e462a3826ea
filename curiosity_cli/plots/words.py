"""What `extract` found: word density over the map, and the words of a few cells up close."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from curiosity_cli.maps.map_data import MapData
from curiosity_cli.files import atomic_path
from curiosity_cli.words.store import PIXEL_KINDS, WordStore

# Side, in cells, of the close-up window shown in the third panel.
_CLOSE_UP_CELLS = 6


def write_word_density(map_data: MapData, store: WordStore, path: Path) -> None:
    """Write a PNG: the map, distinct words per cell, and a close-up of a few cells' words.

    The close-up is the window of cells at the map's centre; each texton word is a pixel
    coloured by its word id and ORB words are white crosses, so how finely the words cut
    the texture, and where the keypoints fall, can be seen at a glance.
    """
    from matplotlib.figure import Figure

    rows, cols = store.grid.shape
    per_cell = store.words_per_cell()
    # every cell of a full grid holds the same number of texton words, so the count of
    # distinct words is what shows where the texture is rich and where it is plain
    cells = np.repeat(np.arange(store.n_cells), per_cell)
    pairs = np.unique(cells * store.vocabulary_size + store.words.astype(np.int64))
    distinct = np.bincount(pairs // store.vocabulary_size, minlength=store.n_cells).reshape(rows, cols)
    fig = Figure(figsize=(16, 5.8), layout="constrained")
    ax_map, ax_density, ax_close = fig.subplots(1, 3)
    ax_map.imshow(map_data.image)
    ax_map.set_title(f"{map_data.config.name}")
    shown = ax_density.imshow(distinct, cmap="viridis", interpolation="nearest")
    fig.colorbar(shown, ax=ax_density, shrink=0.8, label="distinct words per cell")
    ax_density.set_title(
        f"{len(store.words):,} words in {store.n_cells} cells of {store.grid.cell_width} px\n"
        f"words per cell: min {per_cell.min()}, median {int(np.median(per_cell))}, max {per_cell.max()}"
    )

    cw = store.grid.cell_width
    top, left = (rows // 2) * cw, (cols // 2) * cw
    side = _CLOSE_UP_CELLS * cw
    inside = (store.rows >= top) & (store.rows < top + side) & (store.cols >= left) & (store.cols < left + side)
    # a generated map's words take the textons' place, and it has no ORB words
    orb = next((t for t in store.types if t.kind == "orb"), None)
    texton = next(t for t in store.types if t.kind in PIXEL_KINDS)
    is_texton = (store.words >= texton.offset) & (store.words < texton.offset + texton.size)
    is_orb = store.words < orb.offset + orb.size if orb is not None else np.zeros(store.words.shape, bool)
    canvas = np.full((side, side), np.nan)
    sel = inside & is_texton
    canvas[store.rows[sel] - top, store.cols[sel] - left] = store.words[sel]
    ax_close.imshow(canvas, cmap="tab20", interpolation="nearest")
    sel = inside & is_orb
    ax_close.scatter(store.cols[sel] - left, store.rows[sel] - top, marker="+", c="white", s=30)
    for k in range(1, _CLOSE_UP_CELLS):
        ax_close.axhline(k * cw - 0.5, color="black", lw=0.5)
        ax_close.axvline(k * cw - 0.5, color="black", lw=0.5)
    ax_close.set_title(f"{_CLOSE_UP_CELLS} x {_CLOSE_UP_CELLS} cells at the centre: texton ids, ORB +")
    for ax in (ax_map, ax_density, ax_close):
        ax.set_xticks([])
        ax.set_yticks([])
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100, format="png")
