"""Labelling whole maps: pixels from texton words, Z_p from a frozen Φ, Z_b in batch mode."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from small_maps import small_config, synthetic_store

from curiosity_cli.errors import ParameterError
from curiosity_cli.evaluate.labeling import batch_labels, label_with_phi, pixel_labels
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
