"""The topic model of a camera stream that never ends.

One :class:`~curiosity_cli.topics.TopicModel` learns for the whole mission, as the
paper's robot does ("life-long learning"): frame ``f``'s image cells are the model's
cells ``f * rows * cols + row * cols + col``, linked by
:func:`~curiosity_cli.topics.stream_neighbours` (4 spatial neighbours in the frame, the
same image cell one frame before and after). The model's table holds a number of frames
that doubles when a frame does not fit (:meth:`~curiosity_cli.topics.TopicModel.grow`,
which keeps every count), so a mission of any length costs amortised constant time per
frame and memory in proportion to its frames.

With a memory bound of ``M`` frames the frames take turns in ``M + 1`` slots of a ring,
and before a frame arrives the oldest leaves, its words taken out of every count
(:meth:`~curiosity_cli.topics.TopicModel.remove_cells`): forgetting is gradual, one
frame at a time, and the empty slot keeps the newest frame from being the oldest's
temporal neighbour.

Each frame is refined with the realtime sampler (paper eq. 6: the newest frame with
probability ``eta``, else a uniformly random earlier one) within a fixed budget of word
samples, so a run does not depend on the machine's speed, nor a frame's cost on the
mission's length. Now and then no pick chooses the newest frame (with ``eta`` 0.5 and
ten picks a frame, one frame in about a thousand): its words keep the random topics
they were given, and its perplexity says so (:attr:`StreamModel.refined` is 0). Not our
earlier translation of the authors' refinery (``picks="recent-64-ours"``): it picks one
of the newest 64 *observations*, which for a stream are frames, so the newest frame would
be refined in about one pick in a hundred, and its perplexity read from topics still
nearly as random as they were drawn.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.checks import check_int
from curiosity_cli.errors import ParameterError

# frames the first table holds; it doubles from there
_FIRST_FRAMES = 64


class StreamModel:
    """Frames in, per-cell topic counts out, one model for the whole stream.

    Parameters
    ----------
    n_topics, vocabulary_size : int
        K and V of the topic model.
    grid : (int, int)
        Image cells per column and per row of a frame.
    memory : int or None
        Frames the model remembers, >= 2, the oldest forgotten as each new one arrives;
        None: every frame of the stream.
    spatial : {4, 0}
        Spatial neighbours within a frame.
    temporal : {2, 0}
        Temporal neighbours (the same image cell in the previous and next frame).
    alpha, beta : float
        Dirichlet hyper-parameters.
    eta : float
        Refinement bias of the realtime sampler, 0..1.
    budget : int
        Word samples of refinement per frame, >= 0.
    seed : int
        The run's seed.
    vocabulary_hashes : mapping, optional
        Stored in the model, identifying the word ids.
    """

    def __init__(
        self,
        n_topics: int,
        vocabulary_size: int,
        grid: tuple[int, int],
        *,
        memory: int | None,
        spatial: int,
        temporal: int,
        alpha: float,
        beta: float,
        eta: float,
        budget: int,
        seed: int,
        vocabulary_hashes=None,
    ):
        from curiosity_cli.maps.cell_grid import SquareGrid
        from curiosity_cli.topics import TopicModel

        self._grid = SquareGrid(check_int("grid rows", grid[0], 1), check_int("grid cols", grid[1], 1))
        self._slots = None if memory is None else check_int("memory", memory, 2) + 1
        self._budget = check_int("budget", budget, 0)
        self._eta = eta
        self._links = dict(spatial=spatial, temporal=temporal)
        self.frames = 0  # frames added so far
        self.refined = 0  # word samples the newest frame got in its own refinement
        self.model = TopicModel(
            n_topics, vocabulary_size, self._table(self._capacity_after(0)), alpha=alpha, beta=beta, seed=seed,
            vocabulary_hashes=vocabulary_hashes,
        )

    @property
    def cells_per_frame(self) -> int:
        return self._grid.n_cells

    @property
    def frames_in_memory(self) -> int:
        """Frames whose words the model holds now."""
        return self.frames if self._slots is None else min(self.frames, self._slots - 1)

    def _capacity_after(self, frames: int) -> int:
        """Frames the table holds once it has grown past ``frames`` frames (doubling)."""
        capacity = _FIRST_FRAMES
        while capacity <= frames:
            capacity *= 2
        return capacity if self._slots is None else min(capacity, self._slots)

    def _table(self, frames: int) -> np.ndarray:
        from curiosity_cli.topics import stream_neighbours

        return stream_neighbours(self._grid, frames, ring=frames == self._slots, **self._links)

    def _cells_of(self, slot: int) -> np.ndarray:
        return slot * self.cells_per_frame + np.arange(self.cells_per_frame)

    def add_frame(self, cell_words: list[np.ndarray]) -> np.ndarray:
        """Add a frame's cells as the newest observation, then refine within the budget.

        Parameters
        ----------
        cell_words : list of (n_c,) int ndarray
            The words of each image cell, row-major, ``rows * cols`` of them.

        Returns
        -------
        (rows * cols, K) int64 ndarray
            Topic counts of the frame's cells after refinement.

        Raises
        ------
        ParameterError
            The wrong number of cells, or word ids outside the vocabulary.
        """
        if len(cell_words) != self.cells_per_frame:
            raise ParameterError(f"cell_words: got {len(cell_words)} cells, expected {self.cells_per_frame}")
        # checked before any cell goes in, so a bad frame leaves the model as it was
        every = np.concatenate([np.asarray(words).ravel() for words in cell_words])
        if every.size and (every.min() < 0 or every.max() >= self.model.vocabulary_size):
            raise ParameterError(
                f"cell_words: word ids must be in 0..{self.model.vocabulary_size - 1}, got {every.min()}..{every.max()}"
            )
        frame = self.frames
        if self._slots is None:
            slot = frame
        else:
            slot = frame % self._slots
            if frame >= self._slots - 1:  # the oldest frame leaves, so that one slot stays empty
                self.model.remove_cells(self._cells_of((frame + 1) % self._slots))
        if (slot + 1) * self.cells_per_frame > self.model.n_cells:
            self.model.grow(self._table(self._capacity_after(slot)))
        cells = self._cells_of(slot)
        for cell, words in zip(cells, cell_words):
            self.model.add_cell(int(cell), words, time=frame)
        self.frames += 1
        _, self.refined = self.model.refine_realtime(self._budget, eta=self._eta, return_newest=True)
        k, n = self.model.n_topics, self.cells_per_frame
        topics = self.model.topics(cells).astype(np.int64)
        owner = np.repeat(np.arange(n), [np.size(words) for words in cell_words])
        return np.bincount(owner * k + topics, minlength=n * k).reshape(n, k)

    def topic_totals(self) -> np.ndarray:
        """(K,) int64: words per topic over the frames in memory (the path's topic counts)."""
        return self.model.topic_totals().astype(np.int64)
