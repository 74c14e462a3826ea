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

Each frame is refined within a fixed budget of word samples, so a run does not depend on
the machine's speed, nor a frame's cost on the mission's length. The newest frame gets its
share of the budget for certain (``newest_share``: the paper's η of eq. 6 read as a share of
the budget rather than a coin tossed per pick): ``ceil(round(share * budget) / n)`` whole
passes over its ``n`` words, at least its share and less than one pass over, as a pick of
eq. 6 overshoots the budget by less than one frame. The rest of the budget refines the
earlier frames with the realtime sampler, each pick a uniformly random earlier frame (eq.
6's other branch; the first frame, with none before it, takes it all). With a coin per
pick (the realtime sampler as the map walkers use it) the newest frame's share was luck:
on 400 near-identical frames one frame drew one pass over its words where the median
frame drew five, and read 2.33 times the perplexity of the frames before it
(``scripts/check_drive_surprise.py`` measures it); with η 0.5 and ten picks a frame one
frame in about a thousand was never picked at all. Now a frame goes unrefined
(:attr:`StreamModel.refined` 0, its words keeping the random topics they were given) only
when its share rounds to no samples (``newest_share`` 0, or a budget of a sample or two).
Not our earlier translation of the authors' refinery (``picks="recent-64-ours"``): it
picks one of the newest 64 *observations*, which for a stream are frames, so the newest
frame would be refined in about one pick in a hundred.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.checks import check_float, check_int
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
    newest_share : float
        Share of each frame's budget its newest frame gets, 0..1 (:func:`newest_share`).
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
        newest_share: float,
        budget: int,
        seed: int,
        vocabulary_hashes=None,
    ):
        from curiosity_cli.maps.cell_grid import SquareGrid
        from curiosity_cli.topics import TopicModel

        self._grid = SquareGrid(check_int("grid rows", grid[0], 1), check_int("grid cols", grid[1], 1))
        self._slots = None if memory is None else check_int("memory", memory, 2) + 1
        self._budget = check_int("budget", budget, 0)
        self._share = check_float("newest_share", newest_share, 0, 1)
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
        sizes = np.array([np.size(words) for words in cell_words], np.int64)
        self.refined = self._refine(cells, sizes)
        k, n = self.model.n_topics, self.cells_per_frame
        topics = self.model.topics(cells).astype(np.int64)
        owner = np.repeat(np.arange(n), sizes)
        return np.bincount(owner * k + topics, minlength=n * k).reshape(n, k)

    def _refine(self, cells: np.ndarray, sizes: np.ndarray) -> int:
        """Spend the frame's budget: the newest frame's share in whole passes over its words
        (its ``cells`` that hold any, ``sizes`` words each, in order each pass), then the rest
        over the earlier frames by eq. 6 (uniform picks). Returns the word samples the newest
        frame got."""
        from curiosity_cli.topics.model import RESPONSIVE_SAMPLES

        words = int(sizes.sum())
        passes = -(-round(self._share * self._budget) // words) if words else 0
        held = cells[sizes > 0]
        done = 0
        # passes in calls of about RESPONSIVE_SAMPLES words, so that a signal stops a large budget promptly
        per_call = max(1, RESPONSIVE_SAMPLES // max(words, 1))
        for first in range(0, passes, per_call):
            done += self.model.refine_cells(np.tile(held, min(per_call, passes - first)))
        # eta 0: never the newest frame; but with a single frame that one (there is none before it)
        _, newest = self.model.refine_realtime(max(self._budget - done, 0), eta=0.0, return_newest=True)
        return done + newest

    def topic_totals(self) -> np.ndarray:
        """(K,) int64: words per topic over the frames in memory (the path's topic counts)."""
        return self.model.topic_totals().astype(np.int64)

    def frame_cells(self, back: int = 0) -> np.ndarray | None:
        """(rows * cols,) int64: the model's cells of the newest frame (``back`` 0) or of the one ``back`` frames
        before it, row-major; None when that frame never came or has been forgotten."""
        frame = self.frames - 1 - back
        if frame < 0 or back >= self.frames_in_memory:
            return None
        return self._cells_of(frame if self._slots is None else frame % self._slots)

    def recent_totals(self, frames: int) -> np.ndarray:
        """(K,) int64: words per topic over the newest ``frames`` frames in memory."""
        cells = [c for back in range(frames) if (c := self.frame_cells(back)) is not None]
        if not cells:
            return np.zeros(self.model.n_topics, np.int64)
        return self.model.cell_topic_counts(np.concatenate(cells)).sum(axis=0, dtype=np.int64)


def newest_share(config) -> float:
    """The share of each frame's budget the newest frame gets: ``drive.newest_share``, or, when
    that is null, ``model.eta`` (the paper's η of eq. 6, the share a coin per pick gives on
    average)."""
    share = config.drive.newest_share
    return config.model.eta if share is None else share
