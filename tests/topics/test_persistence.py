"""Snapshots of a topic model's state and model files: exact round trips, refusals."""

from __future__ import annotations

import numpy as np
import pytest
from test_model import assert_consistent, assert_same_state, build

from curiosity_cli.maps.cell_grid import SquareGrid
from curiosity_cli.errors import CuriosityError, ParameterError
from curiosity_cli.topics import TopicModel, load_model, restore_snapshot, save_model, take_snapshot


def test_snapshot_and_restore_round_trip_bit_identically():
    model = build(10)
    model.refine_batch(1)
    snap = take_snapshot(model)
    model.refine_batch(2)
    model.refine_realtime(50, eta=0.3)
    after = take_snapshot(model)
    restore_snapshot(model, snap)
    assert_same_state(model, build_restored(snap))
    model.refine_batch(2)
    model.refine_realtime(50, eta=0.3)
    assert_same_state(model, model_from(after, model))
    assert_consistent(model)


def build_restored(snap):
    model = build(10)
    restore_snapshot(model, snap)
    return model


def model_from(snap, like):
    twin = TopicModel(
        like.n_topics, like.vocabulary_size, like.neighbours, alpha=like.alpha, beta=like.beta, seed=like.seed
    )
    restore_snapshot(twin, snap)
    return twin


def test_restore_rejects_a_snapshot_of_another_shape():
    snap = take_snapshot(build(11, n_topics=6))
    other = build(11, n_topics=7)
    with pytest.raises(ParameterError, match="snapshot"):
        restore_snapshot(other, snap)
    with pytest.raises(ParameterError, match="snapshot"):
        restore_snapshot(other, "not a snapshot")
    with pytest.raises(ParameterError, match="neighbour table"):
        restore_snapshot(build(11, spatial=0), take_snapshot(build(11)))


def test_restore_also_undoes_added_cells():
    model = TopicModel(3, 5, SquareGrid(2, 2).neighbour_table(), alpha=0.1, beta=0.1, seed=0)
    model.add_cell(0, [1, 2])
    snap = take_snapshot(model)
    model.add_cell(1, [3] * 2000)  # grows the word arrays
    restore_snapshot(model, snap)
    assert model.n_words == 2 and not model.is_observed(1)
    model.add_cell(1, [3])
    assert_consistent(model)


@pytest.mark.parametrize("frozen", [False, True])
def test_save_and_load_round_trip_bit_identically(tmp_path, frozen):
    kwargs = {"vocabulary_hashes": {"orb": "ab12", "texton": "cd34"}}
    if frozen:
        kwargs["frozen_counts"] = np.arange(15 * 6).reshape(15, 6) % 4
    model = build(12, **kwargs)
    model.refine_batch(2)
    path = tmp_path / "sub" / "model.npz"
    save_model(model, path)
    loaded = load_model(path)
    assert_same_state(model, loaded)
    assert (loaded.alpha, loaded.beta, loaded.seed, loaded.frozen) == (0.2, 0.1, 12, frozen)
    assert loaded.vocabulary_hashes == {"orb": "ab12", "texton": "cd34"}
    np.testing.assert_array_equal(loaded.neighbours, model.neighbours)
    # and both continue identically
    model.refine_realtime(100, eta=0.5)
    loaded.refine_realtime(100, eta=0.5)
    assert_same_state(model, loaded)
    assert [p.name for p in path.parent.iterdir()] == ["model.npz"]


def test_save_and_load_an_empty_model_with_hash_tuple(tmp_path):
    table = SquareGrid(2, 3).neighbour_table(0)
    model = TopicModel(4, 9, table, alpha=0.5, beta=0.25, seed=2**64 - 1, vocabulary_hashes=("x", "y"))
    save_model(model, tmp_path / "m.npz")
    loaded = load_model(tmp_path / "m.npz")
    assert_same_state(model, loaded)
    assert loaded.vocabulary_hashes == ("x", "y") and loaded.seed == 2**64 - 1


def test_load_of_a_bad_file_is_a_one_line_error_naming_it(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_text("not numpy")
    for path in (bad, tmp_path / "missing.npz"):
        with pytest.raises(CuriosityError, match=path.name) as info:
            load_model(path)
        assert "\n" not in str(info.value)
    model = build(13)
    save_model(model, tmp_path / "m.npz")
    with np.load(tmp_path / "m.npz") as data:
        arrays = dict(data)
    arrays["topics"] = arrays["topics"] + 100
    np.savez(tmp_path / "corrupt.npz", **arrays)
    with pytest.raises(CuriosityError, match="corrupt.npz.*topics"):
        load_model(tmp_path / "corrupt.npz")
    arrays["meta"] = np.array('{"format": 99}')
    np.savez(tmp_path / "future.npz", **arrays)
    with pytest.raises(CuriosityError, match="future.npz: format: got 99"):
        load_model(tmp_path / "future.npz")
