"""The topic model of a camera stream that never ends.

A :class:`~curiosity_cli.topics.TopicModel` has a fixed number of cells, so the stream
lives in windows: the model holds ``window`` frames (cell ``slot * rows * cols + row *
cols + col``, neighbour table :func:`~curiosity_cli.topics.stream_neighbours`: 4 spatial
neighbours in the frame, the same image cell one frame before and after). When the
window is full, a new model (seeded from the run's seed and the window's number) takes
the newest ``carry`` frames' words in the first slots, in their order, each frame one
observation time, refines them with ``carry_sweeps`` batch sweeps, and the stream goes
on after them. Older frames are forgotten: the robot's memory is the last ``window``
frames at most and ``carry`` at least, which is what lets a place seen long ago become
interesting again.

Each frame is refined with the realtime sampler (paper eq. 6, bias ``eta``) within a
fixed budget of word samples, so a run does not depend on the machine's speed.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from curiosity_cli.checks import check_int
from curiosity_cli.errors import ParameterError


def window_seed(seed: int, window: int) -> int:
    """The seed of the ``window``-th model of a run (0, 1, ...): independent streams per window."""
    return int(np.random.SeedSequence([seed, window]).generate_state(1, np.uint64)[0])


class StreamModel:
    """Frames in, per-cell topic counts out, over a sliding memory of frames.

    Parameters
    ----------
    n_topics, vocabulary_size : int
        K and V of the topic model.
    grid : (int, int)
        Image cells per column and per row of a frame.
    window : int
        Frames one model holds, >= 2.
    carry : int
        Frames carried into the next model, ``0 <= carry < window``.
    carry_sweeps : int
        Batch sweeps over the carried frames in a new model, >= 0.
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
        Stored in each model, identifying the word ids.
    """

    def __init__(
        self,
        n_topics: int,
        vocabulary_size: int,
        grid: tuple[int, int],
        *,
        window: int,
        carry: int,
        carry_sweeps: int,
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
        from curiosity_cli.topics import stream_neighbours

        self._rows = check_int("grid rows", grid[0], 1)
        self._cols = check_int("grid cols", grid[1], 1)
        self._window = check_int("window", window, 2)
        self._carry = check_int("carry", carry, 0, self._window - 1)
        self._sweeps = check_int("carry_sweeps", carry_sweeps, 0)
        self._budget = check_int("budget", budget, 0)
        self._eta = eta
        self._seed = seed
        self._model_args = dict(
            n_topics=n_topics, vocabulary_size=vocabulary_size, alpha=alpha, beta=beta,
            vocabulary_hashes=vocabulary_hashes,
        )
        self._table = stream_neighbours(
            SquareGrid(self._rows, self._cols), self._window, spatial=spatial, temporal=temporal
        )
        self._recent: deque[list[np.ndarray]] = deque(maxlen=max(self._carry, 1))
        self.windows = 0  # models started so far
        self.model = self._new_model()
        self._slot = 0

    @property
    def cells_per_frame(self) -> int:
        return self._rows * self._cols

    def _new_model(self):
        from curiosity_cli.topics import TopicModel

        model = TopicModel(
            neighbours=self._table, seed=window_seed(self._seed, self.windows), **self._model_args
        )
        self.windows += 1
        return model

    def _add(self, slot: int, cell_words: list[np.ndarray]) -> None:
        first = slot * self.cells_per_frame
        for cell, words in enumerate(cell_words):
            self.model.add_cell(first + cell, words, time=slot)

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
        if self._slot == self._window:
            self._restart()
        self._add(self._slot, cell_words)
        self._slot += 1
        if self._carry:
            self._recent.append(cell_words)
        self.model.refine_realtime(self._budget, eta=self._eta)
        k, n = self.model.n_topics, self.cells_per_frame
        first = (self._slot - 1) * n
        topics = self.model.topics(np.arange(first, first + n)).astype(np.int64)
        owner = np.repeat(np.arange(n), [np.size(words) for words in cell_words])
        return np.bincount(owner * k + topics, minlength=n * k).reshape(n, k)

    def _restart(self) -> None:
        self.model = self._new_model()
        for slot, cell_words in enumerate(self._recent):
            self._add(slot, cell_words)
        self._slot = len(self._recent)
        if self._slot:
            self.model.refine_batch(self._sweeps)

    def topic_totals(self) -> np.ndarray:
        """(K,) int64: words per topic over the frames in memory (the path's topic counts)."""
        return self.model.topic_totals().astype(np.int64)
