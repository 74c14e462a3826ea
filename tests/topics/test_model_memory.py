"""TopicModel.grow and remove_cells: a stream's model grows and forgets without starting again."""

from __future__ import annotations

import numpy as np
import pytest
from naive import (
    NaiveModel,
    add_cell_naive,
    refine_cells_naive,
    refine_realtime_naive,
    remove_cells_naive,
    topic_perplexity_naive,
)
from test_kernels import assert_matches

from curiosity_cli.errors import ParameterError
from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.topics import TopicModel, stream_neighbours, topic_perplexity
from curiosity_cli.topics import model_memory

GRID = SquareGrid(2, 3)


def frame_words(n_frames: int, seed: int = 0) -> list[list[np.ndarray]]:
    rng = np.random.default_rng(seed)
    return [[rng.integers(0, 20, rng.integers(0, 9)) for _ in range(GRID.n_cells)] for _ in range(n_frames)]


def add_frame(model: TopicModel, slot: int, time: int, cell_words) -> None:
    for cell, words in enumerate(cell_words):
        model.add_cell(slot * GRID.n_cells + cell, words, time=time)


@pytest.mark.parametrize("frozen", [False, True])
def test_a_grown_model_draws_as_a_twin_that_had_the_large_table_all_along(frozen):
    counts = np.random.default_rng(1).integers(0, 5, (20, 6)) if frozen else None
    grown = TopicModel(6, 20, stream_neighbours(GRID, 1), alpha=0.2, beta=0.1, seed=4, frozen_counts=counts)
    twin = NaiveModel.of(grown)
    twin.table = stream_neighbours(GRID, 8)
    for t, cell_words in enumerate(frame_words(8)):
        if (t + 1) * GRID.n_cells > grown.n_cells:  # doubling, as the stream model does
            grown.grow(stream_neighbours(GRID, 2 * t))
        add_frame(grown, t, t, cell_words)
        for cell, words in enumerate(cell_words):
            add_cell_naive(twin, t * GRID.n_cells + cell, words, t)
        grown.refine_realtime(40, eta=0.5, picks="recent")
        refine_realtime_naive(twin, 40, 0.5, "recent")
        assert_matches(grown, twin)
        assert topic_perplexity(grown, [1, 2, 3], 0) == topic_perplexity_naive(twin, [1, 2, 3], 0)[0]
    assert grown.n_cells == 8 * GRID.n_cells


def test_growing_recounts_the_neighbourhoods_of_changed_rows():
    # a table whose old rows change (a frame's cells gain neighbours that hold words) stays exact
    model = TopicModel(4, 20, stream_neighbours(GRID, 2, temporal=0), alpha=0.2, beta=0.1, seed=2)
    for t, cell_words in enumerate(frame_words(2)):
        add_frame(model, t, t, cell_words)
    model.grow(stream_neighbours(GRID, 3))
    assert model.n_cells == 18
    assert_matches(model, NaiveModel.of(model))
    with pytest.raises(ParameterError, match="^neighbours: got 6 cells, expected at least the model's 18$"):
        model.grow(stream_neighbours(GRID, 1))


@pytest.mark.parametrize("compact_at", [0, 1024])
def test_removing_cells_matches_a_twin_that_never_saw_them(monkeypatch, compact_at):
    monkeypatch.setattr(model_memory, "_MIN_DEAD", compact_at)  # 0: every removal compacts the stored words
    model = TopicModel(5, 20, stream_neighbours(GRID, 4), alpha=0.3, beta=0.2, seed=7)
    twin = NaiveModel.of(model)
    frames = frame_words(12, seed=3)
    for t, cell_words in enumerate(frames):
        slot = t % 4  # a ring of 4 slots holding the newest 3 frames: the oldest leaves before one arrives
        if t >= 3:
            gone = [((t - 3) % 4) * GRID.n_cells + c for c in range(GRID.n_cells)]
            model.remove_cells(gone)
            remove_cells_naive(twin, gone)
            assert_matches(model, twin)
        for cell, words in enumerate(cell_words):
            model.add_cell(slot * GRID.n_cells + cell, words, time=t)
            add_cell_naive(twin, slot * GRID.n_cells + cell, words, t)
        model.refine_realtime(60, eta=0.5)
        refine_realtime_naive(twin, 60, 0.5)
        model.refine_cells(model.observed_cells()[:3])
        refine_cells_naive(twin, twin.order[:3])
        assert_matches(model, twin)
        assert model.n_words == sum(w.size for f in frames[max(0, t - 2) : t + 1] for w in f)
        assert model.n_observed == min(t + 1, 3) * GRID.n_cells


def test_remove_cells_names_what_it_cannot_remove():
    model = TopicModel(3, 20, stream_neighbours(GRID, 2), alpha=0.3, beta=0.2, seed=1)
    add_frame(model, 0, 0, frame_words(1)[0])
    with pytest.raises(ParameterError, match="^cells: a cell is listed twice$"):
        model.remove_cells([1, 1])
    with pytest.raises(ParameterError, match="^cells: cell 7 is not in the model$"):
        model.remove_cells([1, 7])
    assert model.n_observed == 6
