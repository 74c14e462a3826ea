"""Contingency tables of word labelings' pixel maps, without the pixel maps: the same integers."""

from __future__ import annotations

import numpy as np
import pytest
from naive import pixel_tables_naive

from curiosity_cli.errors import ParameterError
from curiosity_cli.evaluate.information import contingency
from curiosity_cli.label.sampling import pixel_labels, pixel_words
from curiosity_cli.label.pixel_tables import PixelTables
from curiosity_cli.words.store import WordType, build_store


def _store(shape, stride):
    rows, cols = np.meshgrid(np.arange(0, shape[0], stride), np.arange(0, shape[1], stride), indexing="ij")
    rows, cols = rows.ravel(), cols.ravel()
    words = np.concatenate([10 + np.arange(rows.size) % 20, [1, 2]])  # textons, and two ORB words
    all_rows, all_cols = np.concatenate([rows, [1, 5]]), np.concatenate([cols, [3, 8]])
    types = (WordType("orb", "o", 0, 10, "a"), WordType("texton", "t", 10, 20, "b"))
    return build_store(all_rows, all_cols, words, shape, 4, types, {"stride": stride})


@pytest.mark.parametrize("stride", [1, 2, 3])
def test_tables_are_the_drawn_pixel_maps_counted(stride):
    shape = (13, 17)
    store = _store(shape, stride)
    rng = np.random.default_rng(stride)
    reference = rng.integers(0, 5, shape)
    labels = rng.integers(0, 7, (store.words.size, 6)).astype(np.int16)
    got = PixelTables(pixel_words(store, shape), reference, 5).tables(labels, 7)
    np.testing.assert_array_equal(got, pixel_tables_naive(pixel_words(store, shape), reference, 5, labels, 7))
    for r in range(labels.shape[1]):
        np.testing.assert_array_equal(got[r], contingency(pixel_labels(store, labels[:, r], shape), reference, 7, 5))
    assert got.dtype == np.int64 and got.sum() == labels.shape[1] * reference.size


@pytest.mark.parametrize("stride", [1, 3])
def test_kept_tables_count_only_the_pixels_of_each_columns_kept_words(stride):
    shape = (13, 17)
    store = _store(shape, stride)
    rng = np.random.default_rng(10 + stride)
    reference = rng.integers(0, 5, shape)
    labels = rng.integers(0, 7, (store.words.size, 4)).astype(np.int16)
    kept = rng.random(labels.shape) < 0.4
    kept[:, 3] = False  # a column that keeps nothing counts nothing
    words = pixel_words(store, shape)
    tables = PixelTables(words, reference, 5)
    got = tables.tables(labels, 7, kept)
    np.testing.assert_array_equal(got, pixel_tables_naive(words, reference, 5, labels, 7, kept))
    for r in range(labels.shape[1]):
        mask = kept[:, r][words]
        np.testing.assert_array_equal(got[r], contingency(labels[:, r][words][mask], reference[mask], 7, 5))
    assert got[3].sum() == 0 and got[:3].sum(axis=(1, 2)).tolist() == kept[words].sum(axis=(0, 1))[:3].tolist()
    # what the kept tables leave is the table of the other words' pixels
    np.testing.assert_array_equal(tables.tables(labels, 7) - got, tables.tables(labels, 7, ~kept))
    with pytest.raises(ParameterError, match=r"kept: got shape \(3, 4\), expected word_labels' "):
        tables.tables(labels, 7, kept[:3])


def test_pixel_words_name_the_word_each_pixel_takes_its_label_from():
    shape = (7, 11)
    store = _store(shape, 2)
    words = pixel_words(store, shape)
    assert words.shape == shape and words.dtype == np.int64
    np.testing.assert_array_equal(pixel_labels(store, np.arange(store.words.size), shape), words)
    assert np.all(store.words[words] >= 10)  # texton words only


def test_bad_inputs_are_named():
    words = np.zeros((3, 4), np.int64)
    with pytest.raises(ParameterError, match="reference: got shape"):
        PixelTables(words, np.zeros((4, 3), int), 2)
    with pytest.raises(ParameterError, match="reference: labels 0 .. 2, expected 0 .. 1"):
        PixelTables(words, np.arange(12).reshape(3, 4) % 3, 2)
    tables = PixelTables(words + 2, np.zeros((3, 4), int), 1)
    with pytest.raises(ParameterError, match=r"word_labels: got shape \(2, 1\), expected \(N >= 3, R\)"):
        tables.tables(np.zeros((2, 1), np.int16), 4)
    with pytest.raises(ParameterError, match="word_labels: labels 0 .. 4, expected 0 .. 3"):
        tables.tables(np.array([[0], [0], [4]]), 4)
