"""The paper's open choices of exploration, each a named reading (``explore.candidates``,
``candidate_context``, ``candidate_sweeps``, ``candidate_labels``, ``candidate_words``,
``path_topics``, ``revisits``, ``refine_picks``): each against a hand computation, and the
defaults against the runs made before they existed."""

from __future__ import annotations

import hashlib
import math
import re

import numpy as np
import pytest
from small_maps import small_config, two_region_store

from curiosity_cli.config import CONFIG_DIR, UNRECORDED_READINGS, load_config
from curiosity_cli.experiment.recipes import Recipe, run_recipe
from curiosity_cli.explore.walker import explore, move_probabilities
from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.topics import TopicModel
from curiosity_cli.topics.map_model import map_topic_model
from curiosity_cli.topics.perplexity import topic_perplexity

_FIELDS = (
    "path", "first_visit", "words_sampled", "log_likelihood", "fallback", "boxed_in", "candidate_step",
    "candidate_cell", "coverage", "word_perplexity", "topic_perplexity", "weight", "chosen",
)


def run(weight_function="topic-perplexity", start=9, seed=(4,), **settings):
    config = small_config(**{"path_length": 30, "checkpoints": (10, 30), **settings})
    return explore(two_region_store(), weight_function, start, model=config.model, settings=config.explore, seed=seed)


def runs_digest(**settings) -> str:
    """SHA-256 of every record and checkpoint of five walkers' runs on the two-region map."""
    digest = hashlib.sha256()
    for name in ("random-walk", "stochastic-coverage", "word-perplexity", "topic-perplexity", "lawnmower"):
        e = run(name, **settings)
        for field in _FIELDS:
            digest.update(np.ascontiguousarray(getattr(e, field)).tobytes())
        for length in sorted(e.checkpoints):
            digest.update(e.checkpoints[length].dense().tobytes())
    return digest.hexdigest()


@pytest.mark.parametrize(
    ("coverage", "expected"),
    [
        # made by runs_digest at commit b3bd0fa, before any of these readings existed
        ("literal", "416bf731b813a0e465d1621518efbe2060728a5c9bf428e45439b3938974222e"),
        ("clamp", "ffeb86b773e938821c8616d37993ecd69293428f8d6579187dda396933f5997a"),
        ("others", "77b6501353daf287a50e61f95edc13c0ec5ccee932597dca47b2fc340baee5aa"),
    ],
)
def test_the_default_of_every_reading_gives_the_runs_made_before_the_readings(coverage, expected):
    config = small_config()
    assert {key: getattr(config.explore, key) for key in UNRECORDED_READINGS} == UNRECORDED_READINGS
    assert runs_digest(coverage=coverage) == expected


@pytest.mark.slow
def test_each_reading_changes_the_runs():
    base = runs_digest()
    for key, value in [
        ("candidates", 8), ("candidate_context", "own"), ("candidate_sweeps", 10), ("candidate_labels", "argmax"),
        ("candidate_words", "added"), ("path_topics", "counts"), ("revisits", "again"), ("refine_picks", "recent"),
        ("refine_picks", "recent-64-ours"),
    ]:
        assert runs_digest(**{key: value}) != base, key


def test_eight_candidates_at_a_corner_are_its_three_neighbours():
    # cell 0 of the 6 x 8 grid: right (1), down (8) and down-right (9); cell 9: all eight
    e = run("random-walk", start=0, candidates=8, path_length=2, checkpoints=(2,))
    assert sorted(e.candidate_cell[e.candidate_step == 0]) == [1, 8, 9]
    e = run("random-walk", start=9, candidates=8, path_length=2, checkpoints=(2,))
    assert sorted(e.candidate_cell[e.candidate_step == 0]) == [0, 1, 2, 8, 10, 16, 17, 18]
    # coverage of a diagonal candidate: the walker's own cell at d^2 = 2
    diagonal = e.candidate_cell == 18
    assert e.coverage[diagonal] == pytest.approx(0.5)
    # walks of 8 candidates take diagonal steps (a random walk: half its steps or so)
    e = run("random-walk", candidates=8, path_length=60, checkpoints=(60,))
    rows, cols = np.divmod(e.path, 8)
    steps = np.abs(np.diff(rows)) + np.abs(np.diff(cols))
    assert set(steps.tolist()) <= {1, 2} and (steps == 2).sum() > 10
    assert (np.maximum(np.abs(np.diff(rows)), np.abs(np.diff(cols))) == 1).all()


def test_a_revisit_adds_the_cells_words_again():
    store = two_region_store()
    for revisits in ("once", "again"):
        e = run("random-walk", revisits=revisits, path_length=40, checkpoints=(10, 40))
        assert (~e.first_visit).any(), "the walk must revisit a cell for the test to mean anything"
        for length, counts in e.checkpoints.items():
            cells = e.path[:length] if revisits == "again" else np.unique(e.path[:length])
            words = np.concatenate([store.cell_words(c) for c in cells])
            np.testing.assert_array_equal(
                counts.dense().sum(axis=1), np.bincount(words, minlength=store.vocabulary_size)
            )


def test_temporary_labels_with_and_without_the_neighbourhood():
    # a model of the left region's path; a candidate of the right region: with its
    # neighbourhood (the walker's left cells beside it) against its own labels alone
    store = two_region_store()
    config = small_config()
    model = map_topic_model(store, config.model, 7)
    for t, cell in enumerate([1, 2, 3, 11, 10, 9]):
        model.add_cell(cell, store.cell_words(cell), time=t)
    model.refine_batch(30)
    words = store.cell_words(4)  # right region, beside cell 3 of the path
    near = topic_perplexity(model, words, 4, return_topics=True)[1]
    own = topic_perplexity(model, words, 4, context="own", sweeps=10, return_topics=True)[1]
    # right-region words are unknown to the model: eq. 5 gives word w of topic k the weight
    # β / (n_k + Vβ) · (prior_k + α), so with the neighbourhood as prior their labels follow
    # the path's topics at cell 3; alone, the prior is their own labels and the draw favours
    # the topics holding the fewest words (largest 1 / (n_k + Vβ)), which they then reinforce
    path_topics = np.unique(model.topics([3]))
    assert np.isin(near, path_topics).mean() > 0.5 > np.isin(own, path_topics).mean()
    totals = model.topic_totals()
    assert totals[own].mean() < totals[near].mean()


def labelled_model(cells: dict) -> TopicModel:
    """2 topics, 3 words, α = β = 0.5, on a 1 x 3 grid; ``cells`` maps a cell to its (words, topics)."""
    model = TopicModel(2, 3, SquareGrid(1, 3).neighbour_table(), alpha=0.5, beta=0.5, seed=0)
    for cell, (words, _) in cells.items():
        model.add_cell(cell, words)
    state = model.full_state()
    counts = {name: np.zeros_like(state[name]) for name in ("nwk", "nk", "ncz", "ng")}
    for cell, (words, topics) in cells.items():
        first = state["cell_first"][cell]
        state["topics"][first : first + len(topics)] = topics
        for w, z in zip(words, topics):
            counts["nwk"][w, z] += 1
            counts["nk"][z] += 1
            counts["ncz"][cell, z] += 1
    for cell, row in enumerate(model.neighbours):
        counts["ng"][cell] = counts["ncz"][cell] + sum(counts["ncz"][d] for d in row if d >= 0)
    model.set_full_state(**state | counts)
    return model


@pytest.mark.parametrize(
    ("context", "words_in_model", "topics", "smoothed", "counts"),
    [
        # Cell 0 holds words 0, 0 at topic 0; topic 1 holds nothing. Eq. 5's weight of topic k
        # for word w is (n_kw + β) / (n_k + Vβ) · (local_k + α), Vβ = 1.5. The candidate, at
        # cell 1, holds words 2 then 0.
        # own, held out: word 2: 0.5/3.5 · 0.5 = 0.071 against 0.5/1.5 · 0.5 = 0.167: topic 1;
        # word 0: 2.5/3.5 · 0.5 = 0.357 against 0.5/1.5 · 1.5 = 0.5: topic 1. P(1 | path) is
        # (0 + 0.5) / (2 + 1) = 1/6 smoothed (perplexity 6), 0 / 2 by counts (infinite).
        ("own", "held-out", [1, 1], 6.0, math.inf),
        # own, added: word 2 as before, topic 1, which then holds it (n_1 = 1); word 0:
        # 0.357 against 0.5/2.5 · 1.5 = 0.3: topic 0. The path's n = (2 + 1, 0 + 1), N = 4:
        # smoothed P = 3.5/5, 1.5/5 (perplexity 1 / √0.21); counts 3/4, 1/4 (4 / √3).
        ("own", "added", [1, 0], 1 / math.sqrt(0.21), 4 / math.sqrt(3)),
        # neighbourhood: cell 1's counts (2, 0), from cell 0. Held out: word 2: 0.5/3.5 · 2.5 =
        # 0.357 against 0.167, topic 0; word 0 too (2.5/3.5 · 3.5 against 0.167). P(0 | path)
        # = 2.5/3 smoothed (perplexity 1.2), 2/2 by counts (1).
        ("neighbourhood", "held-out", [0, 0], 1.2, 1.0),
        # added: the same labels (word 0: 2.5/4.5 · 3.5 against 0.167), and n = (4, 0), N = 4:
        # P(0 | path) = 4.5/5 smoothed, 4/4 by counts
        ("neighbourhood", "added", [0, 0], 1 / 0.9, 1.0),
    ],
)
def test_argmax_labels_of_held_out_and_added_words_by_hand(context, words_in_model, topics, smoothed, counts):
    model = labelled_model({0: ([0, 0], [0, 0])})
    assert model.topic_totals().tolist() == [2, 0]
    before = model.full_state()
    for path_topics, expected in (("smoothed", smoothed), ("counts", counts)):
        value, labels = topic_perplexity(
            model, [2, 0], 1, context=context, labels="argmax", words_in_model=words_in_model, path_topics=path_topics,
            return_topics=True,
        )
        assert labels.tolist() == topics
        assert value == pytest.approx(expected, rel=1e-12)
    # the added words left the model, and its random state did not move
    after = model.full_state()
    assert after["counter"] == before["counter"]
    for name in ("topics", "nwk", "nk", "ncz", "ng"):
        np.testing.assert_array_equal(after[name], before[name], err_msg=name)


def test_argmax_sweeps_choose_each_label_again_by_hand():
    # Topic 0 holds words 0, 2 (cell 0), topic 1 words 1, 1, 2 (cell 2): Φ_0 = (2.5, 0.5, 1.5) / 3.5,
    # Φ_1 = (0.5, 2.5, 1.5) / 4.5. The candidate's words 2 then 1, each against the other's label
    # only (own), held out. Pass 1: word 2: Φ_0(2) · 0.5 = 0.214 against Φ_1(2) · 0.5 = 0.167,
    # topic 0; word 1: Φ_0(1) · 1.5 = 0.214 against Φ_1(1) · 0.5 = 0.278, topic 1. Pass 2:
    # word 2, with word 1 at topic 1: 0.214 against Φ_1(2) · 1.5 = 0.5, topic 1; word 1: 0.071
    # against 0.833, topic 1. P(k | path), smoothed: (2.5, 3.5) / 6.
    model = labelled_model({0: ([0, 2], [0, 0]), 2: ([1, 1, 2], [1, 1, 1])})
    for sweeps, topics in ((1, [0, 1]), (2, [1, 1]), (5, [1, 1])):
        value, labels = topic_perplexity(
            model, [2, 1], 1, context="own", sweeps=sweeps, labels="argmax", return_topics=True
        )
        assert labels.tolist() == topics
        path = np.array([2.5, 3.5]) / 6
        assert value == pytest.approx(math.exp(-np.mean(np.log(path[topics]))), rel=1e-12)
    assert topic_perplexity(model, [2, 1], 1, context="own", sweeps=2, labels="argmax") == pytest.approx(12 / 7)


def test_added_words_are_never_infinitely_surprising_under_counts():
    # held out, the walker meets candidates of topics its path has not seen (the test below);
    # added, a candidate's own words make every label's count at least 1
    e = run("topic-perplexity", path_topics="counts", candidate_words="added", path_length=40, checkpoints=(40,))
    assert np.isfinite(e.topic_perplexity).all() and (e.topic_perplexity >= 1).all()
    held_out = run("topic-perplexity", path_topics="counts", path_length=40, checkpoints=(40,))
    assert np.isinf(held_out.topic_perplexity).any()


def test_counts_path_topics_make_unseen_topics_infinite_and_the_walker_takes_them():
    e = run("topic-perplexity", path_topics="counts", path_length=40, checkpoints=(40,))
    infinite = np.isinf(e.topic_perplexity)
    assert infinite.any(), "some candidate must hold a topic the path has not seen"
    assert np.isfinite(e.topic_perplexity[~infinite]).all()
    for step in np.unique(e.candidate_step[infinite]):
        here = e.candidate_step == step
        probabilities, _ = move_probabilities(e.weight[here])
        chosen = e.chosen[here]
        # an infinitely surprising unvisited candidate takes every chance (weight inf / U)
        if np.isinf(e.weight[here]).any():
            assert np.isinf(e.weight[here][chosen]).all()
            assert probabilities[np.isinf(e.weight[here])].sum() == 1.0
    assert not e.fallback.any()


def test_a_reading_enters_the_run_recipe_only_when_it_is_not_the_default():
    config = load_config(CONFIG_DIR / "quick.yaml")
    inputs = run_recipe(config, "m", "store", [], "topic-perplexity", 0).inputs["explore"]
    assert not set(UNRECORDED_READINGS) & set(inputs)
    changed = load_config(CONFIG_DIR / "quick.yaml", ["explore.revisits=again", "explore.candidate_sweeps=10"])
    inputs = run_recipe(changed, "m", "store", [], "topic-perplexity", 0).inputs["explore"]
    assert inputs["revisits"] == "again" and inputs["candidate_sweeps"] == 10
    assert "candidates" not in inputs and "path_topics" not in inputs


def test_a_run_made_when_recent_picked_among_64_observations_is_not_current():
    # the run.json recipe of quick.yaml's run with refine_picks: recent as commit fdd091f wrote
    # it, when recent picked among the newest 64 observation times
    old = {"recipe": {"digest": "be2140a9958332cf", "inputs": {
        "dataset": "m", "restart": 0, "seed": 0, "store": "store", "vocabulary_hashes": [],
        "weight_function": "topic-perplexity",
        "model": {"alpha": 0.1, "beta": 0.1, "eta": 0.5, "spatial_neighbours": 4, "topics": 64},
        "explore": {
            "checkpoints": [10, 20, 40, 80, 160], "coverage": "literal", "path_length": 160, "refine_picks": "recent",
            "samples_per_step": 100000, "step_seconds": None,
        },
    }}}
    assert Recipe(old["recipe"]["inputs"]).digest == old["recipe"]["digest"]
    now = run_recipe(
        load_config(CONFIG_DIR / "quick.yaml", ["explore.refine_picks=recent"]), "m", "store", [], "topic-perplexity", 0
    )
    assert now.inputs["explore"]["refine_newest"] == 1
    assert "explore.refine_newest was absent, now 1" in now.changes(old)
    # nor is it current as ours, which says so by name
    ours = run_recipe(
        load_config(CONFIG_DIR / "quick.yaml", ["explore.refine_picks=recent-64-ours"]), "m", "store", [],
        "topic-perplexity", 0,
    )
    assert ours.inputs["explore"]["refine_newest"] == 64
    assert "explore.refine_picks was 'recent', now 'recent-64-ours'" in ours.changes(old)
    # uniform records neither key, as before
    default = run_recipe(load_config(CONFIG_DIR / "quick.yaml"), "m", "store", [], "topic-perplexity", 0)
    assert "refine_newest" not in default.inputs["explore"] and "refine_picks" not in default.inputs["explore"]


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("explore.candidates=6", "explore.candidates: got 6 (int), expected one of 4, 8"),
        ("explore.candidate_context=cells", "explore.candidate_context: got 'cells' (str), expected one of neighbourhood, own"),
        ("explore.candidate_sweeps=0", "explore.candidate_sweeps: got 0 (int), expected an integer >= 1"),
        ("explore.candidate_labels=mode", "explore.candidate_labels: got 'mode' (str), expected one of sample, argmax"),
        ("explore.candidate_words=kept", "explore.candidate_words: got 'kept' (str), expected one of held-out, added"),
        ("explore.path_topics=raw", "explore.path_topics: got 'raw' (str), expected one of smoothed, counts"),
        ("explore.revisits=twice", "explore.revisits: got 'twice' (str), expected one of once, again"),
        (
            "explore.refine_picks=newest",
            "explore.refine_picks: got 'newest' (str), expected one of uniform, recent, recent-64-ours",
        ),
    ],
)
def test_bad_readings_are_named(override, message):
    from curiosity_cli.errors import ConfigError

    with pytest.raises(ConfigError, match="^overrides: " + re.escape(message)):
        load_config(CONFIG_DIR / "quick.yaml", [override])


def test_a_run_under_the_authors_readings_is_the_same_for_the_same_seed():
    settings = dict(
        candidate_labels="argmax", candidate_words="added", path_topics="counts", revisits="again",
        refine_picks="recent",
    )
    a, b = run(**settings), run(**settings)
    for field in _FIELDS:
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


def test_rost_yaml_sets_every_reading_as_the_authors_code():
    # each value is the one configs/rost.yaml cites from the authors' ROST code
    rost = load_config(CONFIG_DIR / "rost.yaml")
    assert {key: getattr(rost.explore, key) for key in UNRECORDED_READINGS} == {
        "candidates": 4, "candidate_context": "neighbourhood", "candidate_sweeps": 1, "candidate_labels": "argmax",
        "candidate_words": "added", "path_topics": "counts", "revisits": "again", "refine_picks": "recent",
    }
    assert (rost.model.topics, rost.model.alpha, rost.model.beta, rost.model.eta) == (64, 0.1, 0.1, 0.5)
    assert rost.words.colour_words and rost.words.orb_detector == "keypoints"
