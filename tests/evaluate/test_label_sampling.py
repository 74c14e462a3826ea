"""Labelling whole maps: pixels from texton words, Z_p from a frozen Φ, Z_b in batch mode."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from small_maps import small_config, synthetic_store

from curiosity_cli.errors import ParameterError
from curiosity_cli.evaluate.label_sampling import batch_labels, label_with_phi, pixel_labels
from curiosity_cli.words.store import WordType, build_store


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


def test_labels_do_not_depend_on_threads_and_follow_the_seed():
    store = synthetic_store(np.arange(16).reshape(4, 4) % 3)
    model = dataclasses.replace(small_config().model, topics=4)
    phi = np.random.default_rng(0).integers(0, 5, (store.vocabulary_size, 4))
    one = label_with_phi(store, phi, model, sweeps=3, seed=1, threads=1)
    np.testing.assert_array_equal(one, label_with_phi(store, phi, model, sweeps=3, seed=1, threads=2))


def test_a_phi_of_the_wrong_shape_is_refused():
    store = synthetic_store(np.zeros((2, 2), int))
    with pytest.raises(ParameterError, match=r"phi: shape \(3, 8\), expected \(V, K\) = \(100, 8\)"):
        label_with_phi(store, np.zeros((3, 8)), small_config().model, sweeps=1, seed=0)


def test_a_path_labelling_is_the_exact_sampler_cold_then_warm():
    from naive import NaiveModel, ml_topics_naive, refine_batch_naive, restart_naive

    from curiosity_cli.evaluate.label_sampling import PathLabeller

    store = synthetic_store(np.arange(12).reshape(3, 4) % 3, words_per_cell=10)
    model = dataclasses.replace(small_config().model, topics=5)
    rng = np.random.default_rng(4)
    phis = [rng.integers(0, 6, (store.vocabulary_size, 5)) for _ in range(3)]
    labeller = PathLabeller(store, model)
    got = labeller.label_path(phis, seed=21, sweeps=3, warm_sweeps=2, threads=2)

    twin = NaiveModel.of(labeller._model)
    cells = sorted(twin.topics)
    twin.frozen = phis[0]
    restart_naive(twin, 21)
    refine_batch_naive(twin, 3)
    expected = [ml_topics_naive(twin, cells)]
    for phi in phis[1:]:
        twin.frozen = phi  # warm: the topics stay, only Φ changes
        refine_batch_naive(twin, 2)
        expected.append(ml_topics_naive(twin, cells))
    for a, b in zip(got, expected):
        np.testing.assert_array_equal(a, b)


def test_the_placed_start_of_a_convergence_study_is_the_models_place():
    from naive import NaiveModel, place_naive

    from curiosity_cli.evaluate.label_sampling import PathLabeller

    store = synthetic_store(np.arange(12).reshape(3, 4) % 3, words_per_cell=10)
    model = dataclasses.replace(small_config().model, topics=5)
    phi = np.random.default_rng(8).integers(0, 6, (store.vocabulary_size, 5))
    labeller = PathLabeller(store, model)
    labeller.start(phi, 2**64 + 9, placed=True)  # seeds wrap as label's path seeds do
    twin = NaiveModel.of(labeller._model)
    place_naive(twin, 9)
    for cell in twin.order:
        np.testing.assert_array_equal(labeller._model.topics([cell]), twin.topics[cell])
    labeller.start(phi, 9)
    assert not np.array_equal(labeller._model.topics(), np.concatenate([twin.topics[c] for c in twin.order]))


def test_warm_started_checkpoints_reach_the_labels_of_a_long_cold_chain():
    from curiosity_cli.evaluate.information import contingency, mutual_information
    from curiosity_cli.evaluate.label_sampling import PathLabeller

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
    labeller = PathLabeller(store, model)

    def mi(words):
        return mutual_information(contingency(words, truth, model.topics, 3))

    cold = [np.mean([mi(labeller.label_path([phi], seed=s, sweeps=64, warm_sweeps=None)[0]) for s in range(4)]) for phi in phis]
    warm = np.mean([[mi(w) for w in labeller.label_path(phis, seed=s, sweeps=64, warm_sweeps=4)] for s in range(4)], axis=0)
    assert cold[-1] > 1.0  # the planted regions are found
    np.testing.assert_allclose(warm, cold, atol=0.02)
