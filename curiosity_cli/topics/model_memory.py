"""How a :class:`~curiosity_cli.topics.TopicModel`'s cells change after it is made.

A camera stream's model (:class:`~curiosity_cli.drive.stream.StreamModel`) never starts
again: it grows its neighbour table as frames arrive (:meth:`CellMemory.grow`, amortised
by doubling) and, with a bounded memory, forgets its oldest frame's cells one frame at a
time (:meth:`CellMemory.remove_cells`). Both keep every count exact, so the model after
them is the model that had the larger table, or never saw the forgotten cells' words,
all along (``tests/topics/test_model_memory.py``).
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.errors import ParameterError
from curiosity_cli.topics.batch_sweeps import aligned_zeros
from curiosity_cli.topics.model_checks import check_model_cells
from curiosity_cli.topics.neighbours import check_neighbours

# removed cells' words stay stored until they outnumber the live ones and this many
_MIN_DEAD = 1024


class CellMemory:
    """The growing and forgetting half of :class:`~curiosity_cli.topics.TopicModel`, which owns the arrays."""

    def remove_cells(self, cells) -> None:
        """Forget observed cells: their words leave every count, and the cells are unobserved again.

        A stream with a bounded memory forgets its oldest frame this way, one frame at
        a time, and may later add new words to the same cells. Draws nothing at random.

        Parameters
        ----------
        cells : (n,) int array_like
            Distinct observed cells.

        Raises
        ------
        ParameterError
            Naming ``cells``: not observed, or listed twice.
        """
        from curiosity_cli.topics._gibbs_kernels import remove_cells_kernel

        cells = check_model_cells(cells, "cells", self._cell_first)
        if np.unique(cells).size != cells.size:
            raise ParameterError("cells: a cell is listed twice")
        remove_cells_kernel(
            cells, self._cell_first, self._cell_count, self._words, self._topics, self._nwk, self._nk, self._inv,
            self._ncz, self._ng, self._table, self._k, self._v * self._beta, not self._frozen,
        )
        n = self._n_observed
        kept = ~np.isin(self._order[:n], cells)
        self._n_observed = int(kept.sum())
        self._grouped = 0
        self._order[: self._n_observed] = self._order[:n][kept]
        self._times[: self._n_observed] = self._times[:n][kept]
        self._n_dead += int(self._cell_count[cells].sum())
        self._cell_first[cells] = -1
        self._cell_count[cells] = 0
        if self._n_dead > max(self.n_words, _MIN_DEAD):  # amortised: each word moves once per halving
            self._compact()

    def grow(self, neighbours) -> None:
        """Take a neighbour table of at least as many cells, keeping every word, topic and count.

        New cells are unobserved; a stream's model grows this way as frames arrive
        instead of starting again. Every cell whose row of the table changed has its
        neighbourhood sum counted again, so the counts stay exact whatever the new rows link.

        Parameters
        ----------
        neighbours : (n_cells, width) int ndarray
            As for the constructor, ``n_cells`` at least :attr:`n_cells`.

        Raises
        ------
        ParameterError
            ``neighbours`` is not a valid table, or has fewer cells.
        """
        table = check_neighbours(neighbours).copy()
        old, n = self.n_cells, table.shape[0]
        if n < old:
            raise ParameterError(f"neighbours: got {n} cells, expected at least the model's {old}")
        # new cells hold no words: a new row's sum is not zero only where it links an old cell,
        # and the rows left alone stay untouched zero pages until a frame lands there
        changed = np.zeros(n, bool)
        changed[old:] = np.any((table[old:] >= 0) & (table[old:] < old), axis=1)
        if table.shape[1] == self._table.shape[1]:
            changed[:old] = np.any(table[:old] != self._table, axis=1)
        else:
            changed[:old] = True
        self._cell_first = np.concatenate([self._cell_first, np.full(n - old, -1, np.int64)])
        self._cell_count = np.concatenate([self._cell_count, np.zeros(n - old, np.int64)])
        self._order = np.concatenate([self._order, np.zeros(n - old, np.int32)])
        self._times = np.concatenate([self._times, np.zeros(n - old, np.int64)])
        for name in ("_ncz", "_ng"):
            grown = aligned_zeros((n, self._kp), np.int32)
            grown[:old] = getattr(self, name)
            setattr(self, name, grown)
        rows = np.flatnonzero(changed)
        self._ng[rows] = self._ncz[rows]
        for column in table[rows].T:
            linked = column >= 0
            self._ng[rows[linked]] += self._ncz[column[linked]]
        table.flags.writeable = False
        self._table, self._colours = table, None

    def _compact(self) -> None:
        """Close the gaps removed cells left in the stored words, keeping each cell's words one run."""
        cells = self._order[: self._n_observed].astype(np.int64)
        cells = cells[np.argsort(self._cell_first[cells], kind="stable")]
        counts = self._cell_count[cells]
        first = np.cumsum(counts) - counts
        source = np.repeat(self._cell_first[cells] - first, counts) + np.arange(int(counts.sum()))
        for array in (self._words, self._topics):
            array[: source.size] = array[source]
        self._cell_first[cells] = first
        self._n_words, self._n_dead = source.size, 0
