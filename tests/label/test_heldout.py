"""The held-out log-likelihood of a map's words under a path's model: the split, the chains, the scores."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from naive import NaiveModel, heldout_log2_naive, heldout_sums_naive
from small_maps import small_config, synthetic_store

from curiosity_cli.label.heldout import heldout_chains, heldout_sums, map_split, split_words, word_log2
from curiosity_cli.label.sampling import batch_labels, map_chains


def test_each_cell_holds_out_half_its_words_rounded_down_drawn_at_random():
    counts = np.array([0, 1, 2, 3, 5, 64])
    word_cells = np.repeat(np.arange(counts.size), counts)
    splits = [split_words(word_cells, np.random.SeedSequence(seed)) for seed in range(200)]
    for held in splits:
        assert np.bincount(word_cells[held], minlength=counts.size).tolist() == [0, 0, 1, 1, 2, 32]
    np.testing.assert_array_equal(splits[0], split_words(word_cells, np.random.SeedSequence(0)))
    # every word of a cell is as likely as any other to be held out: a third each in the cell of 3
    share = np.mean(splits, axis=0)[word_cells == 3]
    assert np.all(np.abs(share - 1 / 3) < 0.12)


def test_a_maps_split_depends_on_the_experiments_seed_and_the_map_only():
    store = synthetic_store(np.arange(12).reshape(3, 4) % 3, words_per_cell=10)
    held = map_split(store, 0, "own")
    np.testing.assert_array_equal(held, map_split(store, 0, "own"))
    assert not np.array_equal(held, map_split(store, 1, "own"))
    assert not np.array_equal(held, map_split(store, 0, "other"))


def test_the_scores_are_the_naive_twins_from_the_chains_topics():
    store = synthetic_store(np.arange(12).reshape(3, 4) % 3, words_per_cell=9)
    model = dataclasses.replace(small_config().model, topics=5)
    held = map_split(store, 0, "own")
    rng = np.random.default_rng(2)
    phis = [rng.integers(0, 6, (store.vocabulary_size, 5)) for _ in range(3)]
    chains = map_chains(store, model, kept=~held)
    assert chains.n_words == np.count_nonzero(~held) < store.words.size
    chains.start(phis, [4, 5, 6])
    chains.sweep(3)
    topics, (_, around) = chains.topics(), chains.counts()
    word_cells = np.repeat(np.arange(store.n_cells), store.words_per_cell())
    kept_cells = word_cells[~held]
    for r, phi in enumerate(phis):
        got = word_log2(around[:, :, r], phi, store.words[held], word_cells[held], model.alpha, model.beta)
        twin = NaiveModel(
            n_topics=5, vocabulary_size=store.vocabulary_size, table=store.grid.neighbour_table(model.spatial_neighbours),
            alpha=model.alpha, beta=model.beta, key=0, counter=0,
            words={c: store.words[~held][kept_cells == c].astype(np.int64) for c in range(store.n_cells)},
            topics={c: topics[kept_cells == c, r].astype(np.int64) for c in range(store.n_cells)},
            order=list(range(store.n_cells)), times=[0] * store.n_cells, frozen=phi,
        )
        expected = heldout_log2_naive(twin, {c: store.words[held & (word_cells == c)] for c in range(store.n_cells)})
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=0)


def test_a_paths_scores_do_not_depend_on_the_paths_scored_beside_it():
    store = synthetic_store(np.arange(12).reshape(3, 4) % 3, words_per_cell=9)
    model = dataclasses.replace(small_config().model, topics=5)
    held = map_split(store, 0, "own")
    rng = np.random.default_rng(3)
    paths = [[rng.integers(0, 6, (store.vocabulary_size, 5)) for _ in range(n)] for n in (2, 1, 3)]
    together = {(c, j): scores for j, active, block in heldout_chains(
        store, model, held, paths, [7, 8, 9], sweeps=3, warm_sweeps=2) for c, scores in zip(active, block)}
    assert sorted(together) == [(0, 0), (0, 1), (1, 0), (2, 0), (2, 1), (2, 2)]
    for j, _, (scores,) in heldout_chains(store, model, held, paths[2:], [9], sweeps=3, warm_sweeps=2):
        assert scores.tobytes() == together[2, j].tobytes()


def test_the_sums_are_the_naive_twins_over_all_and_over_the_unvisited_words():
    scores = -np.random.default_rng(0).random(1001) * 10
    unvisited = np.arange(1001) % 3 == 0
    bits, words = heldout_sums(scores, unvisited)
    assert bits.tolist() == list(heldout_sums_naive(scores, unvisited))
    assert bits.tolist() == pytest.approx([math.fsum(scores), math.fsum(scores[unvisited])], rel=1e-12)
    assert words.tolist() == [1001, 334] and words.dtype == np.int64
    bits, words = heldout_sums(scores, np.zeros(1001, bool))
    assert bits[1] == 0.0 and words[1] == 0


def test_a_model_of_zeros_scores_every_word_as_a_uniform_one():
    store = synthetic_store(np.arange(12).reshape(3, 4) % 3, words_per_cell=9)
    model = dataclasses.replace(small_config().model, topics=5)
    held = map_split(store, 0, "own")
    zeros = np.zeros((store.vocabulary_size, 5), np.int64)
    (_, _, (scores,)), = heldout_chains(store, model, held, [[zeros]], [1], sweeps=2, warm_sweeps=None)
    np.testing.assert_allclose(scores, math.log2(1 / store.vocabulary_size), rtol=1e-12, atol=0)


def test_a_model_that_saw_the_terrain_predicts_the_held_out_words_better_than_a_uniform_one():
    regions = np.zeros((8, 8), int)
    regions[:, 4:] = 1
    regions[5:, :] = 2
    store = synthetic_store(regions)
    model = small_config().model
    held = map_split(store, 0, "own")
    word_cells = np.repeat(np.arange(store.n_cells), store.words_per_cell())
    # Φ_p: the batch labels' counts over a strip of cells through the three regions, as a path along it would hold
    batch, _ = batch_labels(store, model, sweeps=30, seed=3)
    visited = np.isin(word_cells, np.flatnonzero(np.isin(np.arange(64) % 8, (3, 4))))
    phi = np.zeros((store.vocabulary_size, model.topics), np.int64)
    np.add.at(phi, (store.words[visited].astype(np.int64), batch[visited].astype(np.int64)), 1)
    (_, _, (scores,)), = heldout_chains(store, model, held, [[phi]], [1], sweeps=8, warm_sweeps=None)
    bits, words = heldout_sums(scores, ~visited[held])
    uniform = math.log2(1 / store.vocabulary_size)  # -8.2 bits; each region's 100 words alone: -6.6
    assert (bits / words > uniform + 1).all()
    assert words[1] == np.count_nonzero(held & ~visited) > 0
