"""Classes found by a path and per-class recall of Z_p, against cases worked by hand."""

from __future__ import annotations

import dataclasses

import json
from types import SimpleNamespace

import numpy as np
import pytest

from curiosity_cli.config import LabelConfig
from curiosity_cli.errors import ParameterError
from curiosity_cli.evaluate.information import classes_found, matched_recall, mean_recall
from curiosity_cli.maps.cell_classes import cell_class_pixels, classes_present, first_steps
from curiosity_cli.label.label_files import NOT_LABELLED, label_changes, write_labels
from curiosity_cli.evaluate.rows import run_rows
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.experiment.recipes import CLASS_SHARE_PERCENT, Recipe, label_recipe


def test_cell_class_pixels_counts_each_cell_with_partial_border_cells_of_their_own():
    # 5 x 7 px at 3 px cells: 2 x 3 cells; the bottom row of cells is 2 px high, the right column 1 px wide
    labels = np.array([
        [0, 0, 0, 1, 1, 1, 2],
        [0, 0, 0, 1, 1, 1, 2],
        [0, 0, 1, 1, 1, 1, 2],
        [2, 2, 2, 0, 0, 0, 0],
        [2, 2, 2, 0, 0, 1, 1],
    ])
    expected = np.array([
        [8, 1, 0],  # cell (0, 0): 9 px
        [0, 9, 0],  # cell (0, 1)
        [0, 0, 3],  # cell (0, 2): 3 x 1 px
        [0, 0, 6],  # cell (1, 0): 2 x 3 px
        [5, 1, 0],  # cell (1, 1)
        [1, 1, 0],  # cell (1, 2): 2 x 1 px
    ])
    np.testing.assert_array_equal(cell_class_pixels(labels, 3, 3), expected)
    # a class id without pixels (a gap in the legend's ids) is a column of zeros
    assert cell_class_pixels(labels, 3, 5)[:, 3:].sum() == 0
    with pytest.raises(ParameterError, match=r"labels: class ids 0 \.\. 2, expected 0 \.\. 1"):
        cell_class_pixels(labels, 3, 2)


def test_a_class_counts_from_exactly_the_share_of_its_cells_own_pixels():
    assert CLASS_SHARE_PERCENT == 10
    # 10 x 13 px at 10 px cells: a full 100 px cell and a partial 10 x 3 = 30 px cell at the right border
    labels = np.zeros((10, 13), int)
    labels[0, :10] = 1  # 10 of 100 px: exactly 10 %, counts
    labels[1, :9] = 2  # 9 of 100 px: below, does not
    labels[:3, 12] = 3  # 3 of 30 px: exactly 10 % of the partial cell (0.1 * 30 is 3.0000000000000004 in floats)
    labels[:2, 11] = 4  # 2 of 30 px: below
    pixels = cell_class_pixels(labels, 10, 5)
    np.testing.assert_array_equal(pixels, [[81, 10, 9, 0, 0], [25, 0, 0, 3, 2]])
    present = classes_present(pixels, CLASS_SHARE_PERCENT)
    np.testing.assert_array_equal(present, [[True, True, False, False, False], [True, False, False, True, False]])
    # a class absent from a cell never counts, whatever the share
    assert not classes_present(np.array([[5, 0]]), 1)[0, 1]
    with pytest.raises(ParameterError, match="share_percent: got 0, expected 1 .. 100"):
        classes_present(pixels, 0)


def test_first_steps_and_classes_found_follow_the_path():
    present = np.array([
        [True, False, False],  # cell 0: class 0
        [True, True, False],  # cell 1: classes 0 and 1
        [False, False, False],  # cell 2: nothing counts (say, slivers only)
        [False, True, False],  # cell 3: class 1
    ])
    path = np.array([2, 3, 3, 1, 0, 2])
    first = first_steps(path, present)
    np.testing.assert_array_equal(first, [3, 1, -1])  # class 2 is never reached
    assert [classes_found(first, n) for n in (1, 2, 3, 4, 6)] == [0, 1, 1, 2, 2]
    # the start cell is step 0
    np.testing.assert_array_equal(first_steps(np.array([1]), present), [0, 0, -1])
    with pytest.raises(ParameterError, match=r"path: cells 0 \.\. 4, expected 0 \.\. 3"):
        first_steps(np.array([0, 4]), present)


def test_recall_under_the_best_one_to_one_matching():
    # 3 topics x 3 classes; class pixels 10, 20, 10
    table = np.array([
        [8, 2, 0],
        [2, 14, 1],
        [0, 4, 9],
    ])
    recall, topic = matched_recall(table)
    # topic 0 -> class 0 (0.8), 1 -> 1 (0.7), 2 -> 2 (0.9): the largest sum of recalls, 2.4
    np.testing.assert_allclose(recall, [0.8, 0.7, 0.9])
    np.testing.assert_array_equal(topic, [0, 1, 2])
    assert mean_recall(table) == pytest.approx(0.8)


def test_a_topic_serves_one_class_and_the_matching_maximises_the_sum_of_recalls():
    # topic 0 holds most of classes 0 and 1; topic 1 a fifth of class 1
    table = np.array([
        [9, 12, 0],
        [1, 5, 0],
        [0, 8, 6],
    ])
    # class pixels 10, 25, 6. Candidates: {0->0, 1->1, 2->2}: 0.9 + 0.2 + 1.0 = 2.1;
    # {0->1, 1->0, 2->2}: 0.48 + 0.1 + 1.0 = 1.58; {0->0, 2->1, 1->2}: 0.9 + 0.32 + 0 = 1.22
    recall, topic = matched_recall(table)
    np.testing.assert_allclose(recall, [0.9, 0.2, 1.0])
    np.testing.assert_array_equal(topic, [0, 1, 2])


def test_with_fewer_topics_than_classes_the_unmatched_classes_get_recall_zero():
    # K = 2 topics, C = 3 classes (pixels 4, 5, 8); recalls under topic 0: 1, 0.2, 0.25; under topic 1: 0, 0.8, 0.75
    table = np.array([
        [4, 1, 2],
        [0, 4, 6],
    ])
    # 0->0, 1->1: 1.8 beats 0->0, 1->2: 1.75 and 0->2, 1->1: 1.05; class 2 is left without a topic
    recall, topic = matched_recall(table)
    np.testing.assert_allclose(recall, [1.0, 0.8, 0.0])
    np.testing.assert_array_equal(topic, [0, 1, -1])
    assert mean_recall(table) == pytest.approx(1.8 / 3)


def test_a_class_without_pixels_takes_no_part():
    table = np.array([
        [6, 0, 0],
        [0, 0, 3],
    ])
    recall, topic = matched_recall(table)
    assert np.isnan(recall[1]) and topic[1] == -1
    np.testing.assert_allclose(recall[[0, 2]], [1.0, 1.0])
    assert mean_recall(table) == 1.0
    assert np.isnan(mean_recall(np.zeros((2, 2), int)))


def label_file_arrays(first_step=True):
    human = np.array([  # 2 checkpoints, K = 2 topics, C = 3 class ids (id 1 without pixels)
        [[6, 0, 1], [2, 0, 3]],
        [[8, 0, 0], [0, 0, 4]],
    ])
    arrays = {"lengths": np.array([5, 12], np.int32), "batch": np.array([np.eye(2, dtype=int)] * 2), "human": human}
    if first_step:
        arrays["class_first_step"] = np.array([0, -1, 7], np.int32)
    return arrays


def label_meta(**extra):
    meta = {"dataset": "own", "weight_function": "random-walk", "restart": 1, "run_seed": [0, 1], "store": "s.npz",
            "sweeps": 2, "warm_sweeps": 1, "vocabulary_hashes": []}
    return {**meta, **extra}


def test_run_rows_give_classes_found_recall_and_first_steps_per_checkpoint():
    meta = label_meta(class_share_percent=CLASS_SHARE_PERCENT)
    rows, classes = run_rows(meta, label_file_arrays(), {0: "sand", 1: "mud", 2: "rock"})
    assert [r["classes_found"] for r in rows] == [1, 2]  # class 2 first reached at step 7 < 12
    assert [r["classes"] for r in rows] == [2, 2]
    # checkpoint 5: class 0 recall 6/8 under topic 0, class 2 3/4 under topic 1; checkpoint 12: both 1.0
    assert [r["mean_recall"] for r in rows] == pytest.approx([0.75, 1.0])
    first = [(c["path_length"], c["class_name"], c["found"], c["first_step"], c["topic"], c["recall"]) for c in classes]
    assert first[:2] == [(5, "sand", True, 0.0, 0, 0.75), (5, "rock", False, first[1][3], 1, 0.75)]
    assert np.isnan(first[1][3])
    assert first[2:] == [(12, "sand", True, 0.0, 0, 1.0), (12, "rock", True, 7.0, 1, 1.0)]


def test_a_label_file_is_current_only_for_the_recipe_it_was_made_from(tmp_path):
    label = LabelConfig(
        sweeps=2, warm_sweeps=1, check_restarts=1, batch_sweeps=3, device="cpu", reading="frozen", used_share=0.01,
        thaw_sweeps=4,
    )
    config = SimpleNamespace(label=label)
    recipe = label_recipe("run-digest", "batch-digest", config, "human-digest", 1)
    path = ExperimentFolder(tmp_path).label_file("own", "random-walk", 1)
    assert label_changes(path, recipe) == NOT_LABELLED
    write_labels(tmp_path, label_file_arrays(), {}, label_meta())  # from before recipes were recorded
    assert label_changes(path, recipe) == "made before recipes were recorded"
    write_labels(tmp_path, label_file_arrays(), {}, label_meta(recipe=recipe.record()))
    assert label_changes(path, recipe) is None
    # another share of a cell makes a class found; other sweeps; a batch reference made again
    other_share = Recipe({**recipe.inputs, "class_share_percent": CLASS_SHARE_PERCENT + 5})
    assert label_changes(path, other_share) == f"class_share_percent was {CLASS_SHARE_PERCENT}, now {CLASS_SHARE_PERCENT + 5}"
    more_sweeps = SimpleNamespace(label=dataclasses.replace(label, sweeps=4))
    assert label_changes(path, label_recipe("run-digest", "batch-digest", more_sweeps, "human-digest", 1)) == (
        "label.sweeps was 2, now 4"
    )
    assert label_changes(path, label_recipe("run-digest", "new-batch", config, "human-digest", 1)) == (
        "the batch reference changed"
    )
    # checking fewer restarts leaves this one's file current; checking it too asks for its second chain
    for checked, change in ((0, None), (2, "second_start was absent, now 'placed'")):
        other = SimpleNamespace(label=dataclasses.replace(label, check_restarts=checked))
        assert label_changes(path, label_recipe("run-digest", "batch-digest", other, "human-digest", 1)) == change
    # the default reading is not in the recipe (files made before readings stay current), nor a share it does not read;
    # another reading is, and used-topics' share with it
    assert "reading" not in recipe.inputs["label"] and "used_share" not in recipe.inputs["label"]
    for changed, change in (
        ({"used_share": 0.2}, None), ({"reading": "unseen-topic"}, "label.reading was 'frozen', now 'unseen-topic'"),
        ({"reading": "used-topics"}, "label.reading was 'frozen', now 'used-topics', label.used_share was absent, now 0.01"),
        ({"reading": "thawed"}, "label.reading was 'frozen', now 'thawed', label.thaw_sweeps was absent, now 4"),
    ):
        other = SimpleNamespace(label=dataclasses.replace(label, **changed))
        assert label_changes(path, label_recipe("run-digest", "batch-digest", other, "human-digest", 1)) == change
    with np.load(path) as npz:
        assert json.loads(str(npz["meta"]))["restart"] == 1


def test_a_label_file_without_classes_found_leaves_them_empty():
    rows, classes = run_rows(label_meta(), label_file_arrays(first_step=False))
    assert all(np.isnan(r["classes_found"]) for r in rows) and rows[0]["mean_recall"] == pytest.approx(0.75)
    assert all(np.isnan(c["found"]) and np.isnan(c["first_step"]) for c in classes)
