"""Recipes: the digest of a file's inputs, and what changed in words."""

from __future__ import annotations

from curiosity_cli.experiment.recipes import Recipe, first_of, recorded_digest


def test_the_digest_is_of_the_inputs_whatever_their_order():
    a = Recipe({"seed": 0, "model": {"topics": 32, "alpha": 0.1}})
    b = Recipe({"model": {"alpha": 0.1, "topics": 32}, "seed": 0})
    assert a.digest == b.digest and len(a.digest) == 16
    assert Recipe({"seed": 1, "model": {"topics": 32, "alpha": 0.1}}).digest != a.digest
    assert recorded_digest({"recipe": a.record()}) == a.digest and recorded_digest({}) is None


def test_changes_say_what_differs_in_words():
    made = {"recipe": Recipe({"seed": 0, "model": {"topics": 32}, "run": "abc"}).record()}
    assert Recipe({"seed": 0, "model": {"topics": 32}, "run": "abc"}).changes(made) is None
    assert Recipe({"seed": 5, "model": {"topics": 16}, "run": "abc"}).changes(made) == (
        "model.topics was 32, now 16, seed was 0, now 5"
    )
    assert Recipe({"seed": 0, "model": {"topics": 32}, "run": "xyz"}).changes(made) == "its run changed"
    # a key added to the project after the file was made
    assert Recipe({"seed": 0, "model": {"topics": 32, "eta": 0.5}, "run": "abc"}).changes(made) == (
        "model.eta was absent, now 0.5"
    )
    # a setting a recipe leaves out at its default reads as that default, not as absent
    with_reading = {"recipe": Recipe({"label": {"reading": "used-topics"}, "explore": {"candidate_sweeps": 10}}).record()}
    assert Recipe({"label": {}, "explore": {}}).changes(with_reading) == (
        "explore.candidate_sweeps was 10, now 1, label.reading was 'used-topics', now 'frozen'"
    )
    assert Recipe({"seed": 0}).changes({"seed": 0}) == "made before recipes were recorded"
    # a recorded digest that its own inputs do not give
    tampered = {"recipe": {"digest": "0" * 16, "inputs": {"seed": 0}}}
    assert Recipe({"seed": 0}).changes(tampered).startswith("its recorded digest does not match its inputs")


def test_first_of_names_one_and_counts_the_rest():
    assert first_of(["a"]) == "a"
    assert first_of(["a", "b", "c"]) == "a; and 2 more"
