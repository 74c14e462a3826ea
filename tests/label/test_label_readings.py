"""The labelling readings (label.reading): which topics each word may take when a path's Φ_p labels the map."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from small_maps import small_config, synthetic_store

from curiosity_cli.config import LABEL_READINGS
from curiosity_cli.label.readings import Reading
from curiosity_cli.label.sampling import label_paths

K = 6


def path_phi(store, seen_words: np.ndarray, rng) -> np.ndarray:
    """(V, K) counts: each of ``seen_words`` counted in topics 0..2 only, every other word never seen."""
    phi = np.zeros((store.vocabulary_size, K), np.int64)
    phi[seen_words, :3] = rng.integers(1, 5, (seen_words.size, 3))
    return phi


def labels_of(store, phi, reading, seed=3):
    model = dataclasses.replace(small_config().model, topics=K)
    _, _, labels = next(label_paths(store, model, [[phi]], [seed], sweeps=3, warm_sweeps=None, reading=reading))
    return labels[:, 0]


def test_unseen_topic_gives_words_the_path_never_saw_one_label_of_their_own():
    store = synthetic_store(np.arange(16).reshape(4, 4) % 3, words_per_cell=12)
    seen = np.unique(store.words)[::2]
    phi = path_phi(store, seen, np.random.default_rng(0))
    reading = Reading("unseen-topic", 0.01)
    assert reading.labels(K) == K + 1
    counts, allowed = reading.chain_inputs(phi)
    assert counts.shape == (store.vocabulary_size, K + 1) and not counts[:, K].any()
    np.testing.assert_array_equal(counts[:, :K], phi)
    labels = labels_of(store, phi, reading)
    is_seen = np.isin(store.words, seen)
    assert is_seen.any() and (~is_seen).any()
    assert np.all(labels[~is_seen] == K) and np.all(labels[is_seen] < K)
    # no seen word may take label K, where the unseen words' counts are, nor an unseen word another
    assert np.all(allowed[seen, :K]) and not allowed[seen, K].any()


def test_used_topics_opens_only_the_topics_holding_the_share_and_always_the_largest():
    phi = np.zeros((10, K), np.int64)
    phi[0, 0], phi[1, 1], phi[2, 2] = 90, 9, 1  # 90 %, 9 %, 1 % of the path's words
    for share, used in ((0.01, [0, 1, 2]), (0.05, [0, 1]), (0.5, [0]), (1.0, [0])):
        counts, allowed = Reading("used-topics", share).chain_inputs(phi)
        assert counts is phi and allowed.shape == phi.shape
        np.testing.assert_array_equal(np.flatnonzero(allowed[0]), used)
        assert (allowed == allowed[0]).all()  # the same topics for every word


def test_used_topics_labels_every_word_with_a_used_topic():
    store = synthetic_store(np.arange(16).reshape(4, 4) % 3, words_per_cell=12)
    phi = path_phi(store, np.unique(store.words)[::3], np.random.default_rng(1))
    phi[:, 2] = 0  # topics 0 and 1 used; 2..5 spare
    labels = labels_of(store, phi, Reading("used-topics", 0.01))
    assert set(np.unique(labels)) <= {0, 1}
    assert len(np.unique(labels_of(store, phi, Reading("frozen", 0.01)))) > 2  # the spare topics take words otherwise


def test_the_frozen_reading_is_the_labelling_without_one():
    store = synthetic_store(np.arange(16).reshape(4, 4) % 3, words_per_cell=12)
    phi = path_phi(store, np.unique(store.words)[::2], np.random.default_rng(2))
    assert LABEL_READINGS[0] == "frozen"
    np.testing.assert_array_equal(labels_of(store, phi, Reading("frozen", 0.5)), labels_of(store, phi, None))


def test_an_unknown_reading_is_named():
    with pytest.raises(ValueError, match="reading: got 'melted', expected one of frozen, unseen-topic, used-topics, thawed"):
        Reading("melted", 0.01).chain_inputs(np.zeros((3, K), int))


def test_thawed_is_the_frozen_labels_then_algorithm_1_from_them():
    from curiosity_cli.label.sampling import thaw_seed, whole_map_model

    store = synthetic_store(np.arange(16).reshape(4, 4) % 3, words_per_cell=12)
    phi = path_phi(store, np.unique(store.words)[::2], np.random.default_rng(5))
    model = dataclasses.replace(small_config().model, topics=K)
    frozen = labels_of(store, phi, Reading("frozen", 0.01))
    for sweeps in (1, 4):
        reading = Reading("thawed", 0.01, sweeps)
        assert reading.labels(K) == K and reading.chain_inputs(phi) == (phi, None)
        again = whole_map_model(store, model, thaw_seed(3, 0))
        again.set_topics(frozen)
        again.refine_batch(sweeps)
        thawed = labels_of(store, phi, reading)
        np.testing.assert_array_equal(thawed, again.ml_topics())
        assert not np.array_equal(thawed, frozen)  # Φ moved with the map's words
    assert Reading("used-topics", 0.01, 4).thaw_sweeps == 0  # a thaw setting is read only under thawed


def test_a_readings_title_names_the_setting_it_reads():
    titles = [Reading(name, 0.01, 4).title for name in LABEL_READINGS]
    assert titles == ["frozen", "unseen-topic", "used-topics-0.01", "thawed-4"]
