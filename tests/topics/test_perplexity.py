"""Word and topic perplexity (eqs. 11 and 12) against their definitions and twins."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from naive import NaiveModel, topic_perplexity_naive, word_perplexity_naive

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.errors import ParameterError
from curiosity_cli.topics import TopicModel, take_snapshot, topic_perplexity, word_perplexity


def assert_same_state(a: TopicModel, b: TopicModel):
    sa, sb = take_snapshot(a), take_snapshot(b)
    for field in dataclasses.fields(sa):
        np.testing.assert_array_equal(getattr(sa, field.name), getattr(sb, field.name), err_msg=field.name)


def path_model(seed=0, frozen=None):
    """A model of a 5-cell path on a 4 x 4 grid, refined a little."""
    rng = np.random.default_rng(seed)
    model = TopicModel(5, 12, SquareGrid(4, 4).neighbour_table(), alpha=0.3, beta=0.2, seed=seed, frozen_counts=frozen)
    for cell in [5, 6, 10, 9, 13]:
        model.add_cell(cell, rng.integers(0, 12, rng.integers(3, 15)))
    model.refine_batch(3)
    return model


def test_word_perplexity_is_eq_11():
    model = path_model(1)
    words = [0, 3, 3, 11, 7]
    phi = model.phi()  # (V, K)
    totals = model.topic_totals()
    path = (totals + model.alpha) / (totals.sum() + model.n_topics * model.alpha)
    expected = math.exp(-np.mean([math.log(phi[w] @ path) for w in words]))
    assert word_perplexity(model, words) == pytest.approx(expected, rel=1e-12)
    assert word_perplexity(model, np.array(words, np.uint16)) == pytest.approx(expected, rel=1e-12)
    twin = word_perplexity_naive(NaiveModel.of(model), words)
    assert word_perplexity(model, words) == pytest.approx(twin, rel=1e-12)


def test_word_perplexity_of_an_empty_model_is_the_vocabulary_size():
    # every word equally likely under uniform Φ: perplexity V
    model = TopicModel(3, 40, SquareGrid(2, 2).neighbour_table(), alpha=0.1, beta=0.1, seed=0)
    assert word_perplexity(model, [1, 2, 3]) == pytest.approx(40, rel=1e-12)
    assert topic_perplexity(model, [1, 2, 3], 0) == pytest.approx(3, rel=1e-12)


@pytest.mark.parametrize(("cell", "frozen"), [(1, False), (9, False), (0, False), (2, True)])
def test_topic_perplexity_matches_twin_and_eq_12_given_its_topics(cell, frozen):
    model = path_model(2, frozen=np.arange(60).reshape(12, 5) % 7 if frozen else None)
    words = np.random.default_rng(cell).integers(0, 12, 40)
    value, topics = topic_perplexity(model, words, cell, return_topics=True)
    twin_value, twin_topics = topic_perplexity_naive(NaiveModel.of(model), words, cell)
    np.testing.assert_array_equal(topics, twin_topics)
    assert value == pytest.approx(twin_value, rel=1e-12)
    totals = model.topic_totals()
    path = (totals + model.alpha) / (totals.sum() + model.n_topics * model.alpha)
    assert value == pytest.approx(math.exp(-np.mean(np.log(path[topics]))), rel=1e-12)
    # a deterministic function of the state: the same again
    assert topic_perplexity(model, words, cell) == value


def test_topic_perplexity_draws_depend_on_the_cells_neighbourhood():
    # two topics with disjoint words, cells of topic 0 on the left; a candidate on the
    # left edge labels an ambiguous word (in both topics) as topic 0 far more often
    model = TopicModel(2, 3, SquareGrid(1, 6).neighbour_table(), alpha=0.01, beta=0.01, seed=3)
    for cell in range(6):
        model.add_cell(cell, [0] * 50 if cell < 3 else [1] * 50)
    model.refine_batch(20)
    left = model.ml_topics([0])[0]
    _, near_left = topic_perplexity(model, [2] * 200, 1, return_topics=True)
    _, near_right = topic_perplexity(model, [2] * 200, 4, return_topics=True)
    assert np.mean(near_left == left) > 0.9
    assert np.mean(near_right == left) < 0.1


def test_perplexities_of_no_words_are_one():
    model = path_model(3)
    assert word_perplexity(model, []) == 1.0
    assert topic_perplexity(model, np.zeros(0, int), 0) == 1.0
    value, topics = topic_perplexity(model, [], 0, return_topics=True)
    assert value == 1.0 and topics.shape == (0,)


def test_perplexity_calls_do_not_change_the_model():
    model = path_model(4)
    before = path_model(4)
    for cell in [1, 2, 4, 14, 5]:
        word_perplexity(model, [1, 2, 3, 4])
        for labels in ("sample", "argmax"):
            for words_in_model in ("held-out", "added"):
                topic_perplexity(model, np.arange(12), cell, sweeps=2, labels=labels, words_in_model=words_in_model)
    assert_same_state(model, before)
    model.refine_realtime(50, eta=0.5)
    before.refine_realtime(50, eta=0.5)
    assert_same_state(model, before)


def test_perplexities_are_at_least_one_and_higher_for_unseen_words():
    model = TopicModel(4, 30, SquareGrid(3, 3).neighbour_table(), alpha=0.1, beta=0.1, seed=5)
    for cell in range(5):
        model.add_cell(cell, np.arange(10).repeat(5))
    model.refine_batch(10)
    seen, unseen = np.arange(10), np.arange(10, 30)
    assert 1.0 <= word_perplexity(model, seen) < word_perplexity(model, unseen)
    assert topic_perplexity(model, seen, 6) >= 1.0


def test_perplexities_name_the_bad_parameter():
    model = path_model(5)
    with pytest.raises(ParameterError, match="^words:"):
        word_perplexity(model, [12])
    with pytest.raises(ParameterError, match="^words:"):
        topic_perplexity(model, [[1]], 0)
    with pytest.raises(ParameterError, match="^cell:"):
        topic_perplexity(model, [1], 16)


# --- the readings of eq. 12 (explore.candidate_context, candidate_sweeps, candidate_labels, candidate_words,
# path_topics) ---------


@pytest.mark.parametrize("context", ["neighbourhood", "own"])
@pytest.mark.parametrize("sweeps", [1, 3])
@pytest.mark.parametrize("path_topics", ["smoothed", "counts"])
@pytest.mark.parametrize("labels", ["sample", "argmax"])
@pytest.mark.parametrize("words_in_model", ["held-out", "added"])
def test_topic_perplexity_readings_match_twin(context, sweeps, path_topics, labels, words_in_model):
    model = path_model(4)
    words = np.random.default_rng(5).integers(0, 12, 30)
    for cell in (6, 2, 15):  # on the path, beside it, away from it
        value, topics = topic_perplexity(
            model, words, cell, context=context, sweeps=sweeps, labels=labels, words_in_model=words_in_model,
            path_topics=path_topics, return_topics=True,
        )
        twin_value, twin_topics = topic_perplexity_naive(
            NaiveModel.of(model), words, cell, context, sweeps, path_topics, labels, words_in_model
        )
        np.testing.assert_array_equal(topics, twin_topics)
        assert value == pytest.approx(twin_value, rel=1e-12) or value == twin_value == math.inf


@pytest.mark.parametrize("labels", ["sample", "argmax"])
def test_added_words_of_a_frozen_model_count_only_in_the_neighbourhood(labels):
    # a frozen model's Φ and totals stay as they are when it adds words, so also here
    model = path_model(2, frozen=np.arange(60).reshape(12, 5) % 7)
    words = np.random.default_rng(3).integers(0, 12, 40)
    for cell in (1, 9):
        added = topic_perplexity(model, words, cell, labels=labels, words_in_model="added", return_topics=True)
        held_out = topic_perplexity(model, words, cell, labels=labels, return_topics=True)
        twin = topic_perplexity_naive(NaiveModel.of(model), words, cell, labels=labels, words_in_model="added")
        np.testing.assert_array_equal(added[1], twin[1])
        np.testing.assert_array_equal(added[1], held_out[1])
        assert added[0] == held_out[0] == pytest.approx(twin[0], rel=1e-12)


def test_argmax_labels_draw_nothing():
    # the same counts at another random state: other sampled labels, the same argmax ones
    model, later = path_model(6), path_model(6)
    state = later.full_state()
    later.set_full_state(**state | {"counter": state["counter"] + 7})
    words = np.random.default_rng(6).integers(0, 12, 30)
    for words_in_model in ("held-out", "added"):
        sampled = [
            topic_perplexity(m, words, 2, words_in_model=words_in_model, return_topics=True)[1] for m in (model, later)
        ]
        assert not np.array_equal(*sampled)
        first, again = (
            topic_perplexity(m, words, 2, labels="argmax", words_in_model=words_in_model, return_topics=True)
            for m in (model, later)
        )
        np.testing.assert_array_equal(first[1], again[1])
        assert first[0] == again[0]


def test_own_context_ignores_the_neighbourhood_by_hand():
    # one topic's words fill the path: with the neighbourhood prior (alpha = 0.01) an
    # ambiguous word beside the path takes that topic; drawn against its own labels only,
    # each of two words of equal Φ under both topics starts as a fair coin (hand: the first
    # word's weights are equal, so about half the candidates' first labels are topic 0)
    model = TopicModel(2, 3, SquareGrid(1, 6).neighbour_table(), alpha=0.01, beta=0.01, seed=3)
    for cell in range(3):
        model.add_cell(cell, [0] * 50)
    for cell in range(3, 6):
        model.add_cell(cell, [1] * 50)
    model.refine_batch(20)
    left = model.ml_topics([0])[0]
    # Φ(word 2) is β / (n_k + Vβ) under both topics, and both topics hold 150 words: equal weights
    assert model.topic_totals()[0] == model.topic_totals()[1] == 150
    firsts = []
    for counter_cell in range(6):
        _, topics = topic_perplexity(model, [2], counter_cell, context="own", return_topics=True)
        firsts.append(topics[0])
        _, near = topic_perplexity(model, [2] * 20, 1, context="neighbourhood", return_topics=True)
        assert np.all(near == left)
    # the own-context labels of word 2 at the six cells use six streams: not all the left topic
    assert set(firsts) == {0, 1}


def test_a_topic_the_path_never_saw_makes_counts_perplexity_infinite():
    # a path of one word: exactly one topic z0 has n = 1, the other three n = 0. By hand,
    # under counts P(z0 | path) = 1 and every other topic 0: a candidate's perplexity is
    # exp(-mean log 1) = 1 when all its temporary labels are z0, else infinite; smoothed
    # it is finite either way
    model = TopicModel(4, 3, SquareGrid(1, 6).neighbour_table(), alpha=0.1, beta=0.1, seed=0)
    model.add_cell(0, [0])
    totals = model.topic_totals()
    assert totals.sum() == 1
    z0 = int(np.argmax(totals))
    outcomes = set()
    for cell in range(6):
        for words in ([0], [1], [0, 0, 0], [2, 1]):
            value, topics = topic_perplexity(model, words, cell, path_topics="counts", return_topics=True)
            expected = 1.0 if np.all(topics == z0) else math.inf
            assert value == expected
            outcomes.add(expected)
            assert math.isfinite(topic_perplexity(model, words, cell))
    assert outcomes == {1.0, math.inf}
    # a model without words has seen no topic: every candidate is infinitely surprising
    empty = TopicModel(4, 3, SquareGrid(1, 6).neighbour_table(), alpha=0.1, beta=0.1, seed=0)
    assert topic_perplexity(empty, [1], 2, path_topics="counts") == math.inf


def test_reading_arguments_are_checked():
    model = path_model(0)
    with pytest.raises(ParameterError, match="^context: got 'cells', expected one of neighbourhood, own$"):
        topic_perplexity(model, [1], 0, context="cells")
    with pytest.raises(ParameterError, match="^sweeps:"):
        topic_perplexity(model, [1], 0, sweeps=0)
    with pytest.raises(ParameterError, match="^path_topics: got 'raw'"):
        topic_perplexity(model, [1], 0, path_topics="raw")
    with pytest.raises(ParameterError, match="^labels: got 'mode', expected one of sample, argmax$"):
        topic_perplexity(model, [1], 0, labels="mode")
    with pytest.raises(ParameterError, match="^words_in_model: got 'kept', expected one of held-out, added$"):
        topic_perplexity(model, [1], 0, words_in_model="kept")
