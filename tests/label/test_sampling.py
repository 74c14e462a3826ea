"""Labelling whole maps: pixels from texton words, Z_p from a frozen Φ, Z_b in batch mode."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from small_maps import small_config, synthetic_store

from curiosity_cli.errors import ParameterError
from curiosity_cli.label.sampling import batch_labels, label_paths, pixel_labels
from curiosity_cli.words.store import WordType, build_store


def label_with_phi(store, phi, model, *, sweeps, seed):
    """Z_p of every word of the map from one path model's word-topic counts: one chain, one checkpoint."""
    _, _, labels = next(label_paths(store, model, [[phi]], [seed], sweeps=sweeps, warm_sweeps=None))
    return labels[:, 0]


@pytest.mark.parametrize("stride", [1, 2, 3])
def test_each_pixel_takes_the_label_of_its_nearest_texton_word(stride):
    shape = (7, 11)
    rows, cols = np.meshgrid(np.arange(0, 7, stride), np.arange(0, 11, stride), indexing="ij")
    rows, cols = rows.ravel(), cols.ravel()
    # texton ids 10.., plus ORB words (ids < 10) at odd places that must not label pixels
    words = np.concatenate([10 + np.arange(rows.size) % 20, [1, 2]])
    all_rows, all_cols = np.concatenate([rows, [1, 5]]), np.concatenate([cols, [3, 8]])
    types = (WordType("orb", "o", 0, 10, "a"), WordType("texton", "t", 10, 20, "b"))
    store = build_store(all_rows, all_cols, words, shape, 4, types, {"stride": stride})
    word_labels = store.words.astype(np.int64) * 3 + 1  # any labelling of the store's words
    got = pixel_labels(store, word_labels, shape)
    assert got.shape == shape
    is_texton = store.words >= 10
    for r in range(shape[0]):
        for c in range(shape[1]):
            d2 = (store.rows[is_texton].astype(int) - r) ** 2 + (store.cols[is_texton].astype(int) - c) ** 2
            nearest = word_labels[is_texton][d2 == d2.min()]
            assert got[r, c] in nearest


def test_labelling_with_the_batch_models_own_phi_gives_back_the_batch_labels():
    regions = np.zeros((8, 8), int)
    regions[:, 4:] = 1
    regions[5:, :] = 2
    store = synthetic_store(regions)
    model = small_config().model
    batch, trace = batch_labels(store, model, sweeps=30, seed=3)
    assert trace.shape == (30,) and trace[-1] > trace[0]
    phi = np.zeros((store.vocabulary_size, model.topics), np.int64)
    np.add.at(phi, (store.words.astype(np.int64), batch.astype(np.int64)), 1)
    again = label_with_phi(store, phi, model, sweeps=4, seed=5)
    assert again.shape == batch.shape and again.dtype == np.int16
    assert np.mean(again == batch) > 0.9


def test_labels_follow_the_seed():
    store = synthetic_store(np.arange(16).reshape(4, 4) % 3)
    model = dataclasses.replace(small_config().model, topics=4)
    phi = np.random.default_rng(0).integers(0, 5, (store.vocabulary_size, 4))
    one = label_with_phi(store, phi, model, sweeps=3, seed=1)
    np.testing.assert_array_equal(one, label_with_phi(store, phi, model, sweeps=3, seed=1))
    assert not np.array_equal(one, label_with_phi(store, phi, model, sweeps=3, seed=2))


def test_a_phi_of_the_wrong_shape_is_refused():
    store = synthetic_store(np.zeros((2, 2), int))
    with pytest.raises(ParameterError, match=r"phis: chain 0 has shape \(3, 8\), expected \(V, K\) = \(100, 8\)"):
        label_with_phi(store, np.zeros((3, 8)), small_config().model, sweeps=1, seed=0)


@pytest.mark.parametrize("warm_sweeps", [2, None])
def test_paths_are_labelled_by_their_own_chains_cold_then_warm(warm_sweeps):
    from naive import NaiveModel, ml_topics_naive, start_chain_naive, sweep_chain_naive

    from curiosity_cli.label.sampling import label_paths, whole_map_model

    store = synthetic_store(np.arange(12).reshape(3, 4) % 3, words_per_cell=10)
    model = dataclasses.replace(small_config().model, topics=5)
    rng = np.random.default_rng(4)
    paths = [[rng.integers(0, 6, (store.vocabulary_size, 5)) for _ in range(n)] for n in (3, 1, 2)]
    seeds, placed = [21, 2**64 - 1, 8], [False, False, True]
    got = {}
    for j, active, labels in label_paths(store, model, paths, seeds, placed=placed, sweeps=3, warm_sweeps=warm_sweeps):
        for column, c in enumerate(active):
            got[c, j] = labels[:, column]
    assert sorted(got) == [(0, 0), (0, 1), (0, 2), (1, 0), (2, 0), (2, 1)]

    for c, path in enumerate(paths):
        twin = NaiveModel.of(whole_map_model(store, model, 0, frozen_counts=path[0]))
        cells = sorted(twin.topics)
        for j, phi in enumerate(path):
            twin.frozen = phi
            if j > 0 and warm_sweeps is not None:
                todo = warm_sweeps  # warm: the topics stay, only Φ changes
            else:
                start_chain_naive(twin, (seeds[c] + j) % 2**64, placed[c])
                todo, sweeps = 3, 0
            for _ in range(todo):
                sweep_chain_naive(twin, store.n_cells + sweeps)
                sweeps += 1
            np.testing.assert_array_equal(got[c, j], ml_topics_naive(twin, cells))


def test_warm_started_checkpoints_reach_the_labels_of_a_long_cold_chain():
    from curiosity_cli.evaluate.information import contingency, mutual_information
    from curiosity_cli.label.sampling import label_paths

    regions = np.zeros((8, 8), int)
    regions[:, 4:] = 1
    regions[5:, :] = 2
    store = synthetic_store(regions)
    model = small_config().model
    truth = regions.ravel()[np.repeat(np.arange(64), 64)]
    # a path's Φ as it grows: the counts of the batch model's labels on more and more cells
    batch, _ = batch_labels(store, model, sweeps=30, seed=3)
    phis = []
    for cells in (8, 24, 64):
        keep = np.repeat(np.arange(64) < cells, 64)
        phi = np.zeros((store.vocabulary_size, model.topics), np.int64)
        np.add.at(phi, (store.words[keep].astype(np.int64), batch[keep].astype(np.int64)), 1)
        phis.append(phi)

    def mi(labels):
        return np.array([mutual_information(contingency(labels[:, c], truth, model.topics, 3)) for c in range(4)])

    cold = [np.mean(mi(next(label_paths(store, model, [[phi]] * 4, range(4), sweeps=64, warm_sweeps=None))[2])) for phi in phis]
    warm = [np.mean(mi(labels)) for _, _, labels in label_paths(store, model, [phis] * 4, range(4), sweeps=64, warm_sweeps=4)]
    assert cold[-1] > 1.0  # the planted regions are found
    np.testing.assert_allclose(warm, cold, atol=0.02)
