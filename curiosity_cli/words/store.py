"""The word store: every visual word of a map, grouped by cell, in one compact file.

All word types share one id space with fixed offsets, in this order: ORB words
``[0, n_orb)``, texton words ``[n_orb, n_orb + n_texton)``, then hue words (when on).
With the paper's vocabularies that is ORB 0–4999, texton 5000–5999, hue 6000–6179.

A generated map's store holds one kind, ``generated``: ids ``0 .. V - 1`` of its
generative model (:mod:`curiosity_cli.words.drawn`).

The cell of a word is the cell of its pixel on the map's grid
(:class:`~curiosity_cli.maps.cell_grid.SquareGrid`: ``(row // cell_width, col // cell_width)``,
numbered row-major, a partial cell at the bottom or right border a cell of its own).
Words are sorted by cell, so the words of cell ``c`` are the contiguous slice
``cell_start[c]:cell_start[c + 1]``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from curiosity_cli.maps.cell_grid import SquareGrid, map_grid
from curiosity_cli.errors import RERUN, CuriosityError
from curiosity_cli.files import CorruptFileError, arrays_digest, atomic_path, display_path, open_npz

STORE_FORMAT = 1

#: The kind of a generated map's words (:mod:`curiosity_cli.words.drawn`).
GENERATED = "generated"
#: The kinds of word laid one every ``stride`` px from pixel (0, 0), whose labels the map's pixels take
#: (:func:`~curiosity_cli.label.sampling.pixel_words`): an image's textons, and a generated map's words.
PIXEL_KINDS = ("texton", GENERATED)


@dataclass(frozen=True)
class WordType:
    """One kind of word and where its ids sit in the shared id space."""

    kind: str  # "orb", "texton" or "hue"; "generated" for a generated map's words
    name: str  # vocabulary name, e.g. "orb-5000"
    offset: int
    size: int
    sha256: str  # content hash of the vocabulary ("" for hue bins, which need none)


@dataclass(frozen=True)
class WordStore:
    """The words of one map.

    Attributes
    ----------
    rows, cols : (N,) unsigned integer ndarrays
        Pixel position of each word.
    words : (N,) unsigned integer ndarray
        Word id in the shared id space (see :attr:`types`).
    cell_start : (n_cells + 1,) int64 ndarray
        Words of cell ``c`` are ``[cell_start[c], cell_start[c + 1])``.
    grid : SquareGrid
        The map's cells.
    types : tuple of WordType
    params : dict
        What made the store: dataset, image hash, stride, ORB settings, package version.
    """

    rows: np.ndarray
    cols: np.ndarray
    words: np.ndarray
    cell_start: np.ndarray
    grid: SquareGrid
    types: tuple[WordType, ...]
    params: dict

    @property
    def n_cells(self) -> int:
        return self.grid.n_cells

    @property
    def vocabulary_size(self) -> int:
        """Size of the shared id space (V)."""
        return max(t.offset + t.size for t in self.types)

    def cell_words(self, cell: int) -> np.ndarray:
        """Word ids of one cell (row-major cell index)."""
        return self.words[self.cell_start[cell] : self.cell_start[cell + 1]]

    def words_per_cell(self) -> np.ndarray:
        """(n_cells,) int64 ndarray of word counts."""
        return np.diff(self.cell_start)

    def word_cells(self) -> np.ndarray:
        """(N,) int64 ndarray: the cell of each word, in the store's order."""
        return np.repeat(np.arange(self.n_cells), self.words_per_cell())

    def count_by_type(self) -> dict[str, int]:
        """Number of words of each kind."""
        return {
            t.kind: int(np.count_nonzero((self.words >= t.offset) & (self.words < t.offset + t.size)))
            for t in self.types
        }


def _smallest_unsigned(values: np.ndarray, upper: int) -> np.ndarray:
    return values.astype(np.min_scalar_type(max(int(upper), 1)))


def build_store(
    rows: np.ndarray,
    cols: np.ndarray,
    words: np.ndarray,
    image_shape: tuple[int, int],
    cell_width: int,
    types: tuple[WordType, ...],
    params: dict,
) -> WordStore:
    """Group words by cell and pack them into the smallest fitting integer types.

    Parameters
    ----------
    rows, cols : (N,) integer ndarrays
        Pixel positions, inside ``image_shape``.
    words : (N,) integer ndarray
        Ids in the shared id space.
    image_shape : (int, int)
        Image rows and columns.
    cell_width : int
        Cell side in pixels.
    types : tuple of WordType
    params : dict
        JSON-serialisable description of how the words were made.

    Returns
    -------
    WordStore
        Sorted by cell, then row, column and word id, so the order does not depend on
        the order the extractors produced words in.
    """
    grid = map_grid(image_shape, cell_width)
    rows = np.asarray(rows, dtype=np.int64)
    cols = np.asarray(cols, dtype=np.int64)
    words = np.asarray(words, dtype=np.int64)
    cells = grid.cells_of_pixels(rows, cols)
    order = np.lexsort((words, cols, rows, cells))
    counts = np.bincount(cells, minlength=grid.n_cells)
    cell_start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    vocabulary_size = max(t.offset + t.size for t in types)
    return WordStore(
        rows=_smallest_unsigned(rows[order], image_shape[0] - 1),
        cols=_smallest_unsigned(cols[order], image_shape[1] - 1),
        words=_smallest_unsigned(words[order], vocabulary_size - 1),
        cell_start=cell_start,
        grid=grid,
        types=tuple(types),
        params=dict(params),
    )


_ARRAYS = ("rows", "cols", "words", "cell_start")


def save_store(store: WordStore, path: Path) -> None:
    """Write a store as one compressed ``.npz``, atomically, with the digest of its arrays in its meta."""
    meta = {
        "format": STORE_FORMAT,
        "grid_shape": list(store.grid.shape),
        "cell_width": store.grid.cell_width,
        "types": [t.__dict__ for t in store.types],
        "params": store.params,
        "arrays_sha256": arrays_digest({name: getattr(store, name) for name in _ARRAYS}),
    }
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as handle:
            np.savez_compressed(
                handle,
                rows=store.rows,
                cols=store.cols,
                words=store.words,
                cell_start=store.cell_start,
                meta=np.array(json.dumps(meta, sort_keys=True)),
            )


def load_store(path: Path) -> WordStore:
    """Read a store written by :func:`save_store`.

    Raises
    ------
    CuriosityError
        The file is missing, or of another format version.
    CorruptFileError
        The file is not a store: truncated, empty, or another kind of ``.npz``; or its
        arrays are not those it was written with (a store written before their digest was
        recorded is taken as it is).
    """
    path = Path(path)
    try:
        with open_npz(path) as data:
            meta = json.loads(str(data["meta"]))
            arrays = {k: data[k] for k in _ARRAYS}
    except FileNotFoundError:
        raise CuriosityError(f"{display_path(path)}: not found; {RERUN} makes it", rerun="extract", force=False) from None
    if meta.get("format") != STORE_FORMAT:
        raise CuriosityError(
            f"{display_path(path)}: format: got {meta.get('format')!r}, expected {STORE_FORMAT}; "
            f"run {RERUN} to rebuild it",
            rerun="extract",
        )
    if "arrays_sha256" in meta and arrays_digest(arrays) != meta["arrays_sha256"]:
        raise CorruptFileError(f"{display_path(path)}: its words are not those it was written with (altered since)")
    return WordStore(
        **arrays,
        grid=SquareGrid(*meta["grid_shape"], meta["cell_width"]),
        types=tuple(WordType(**t) for t in meta["types"]),
        params=meta["params"],
    )
