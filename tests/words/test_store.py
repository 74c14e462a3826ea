from __future__ import annotations

import numpy as np
import pytest

from curiosity_cli.errors import CuriosityError
from curiosity_cli.words.store import WordType, build_store, load_store, save_store

TYPES = (WordType("orb", "orb-10", 0, 10, "a" * 64), WordType("texton", "texton-5", 10, 5, "b" * 64))


def random_words(n=500, shape=(40, 50), seed=0):
    rng = np.random.default_rng(seed)
    return rng.integers(0, shape[0], n), rng.integers(0, shape[1], n), rng.integers(0, 15, n)


def test_words_are_grouped_by_cell_including_partial_border_cells():
    rows, cols, words = random_words()
    store = build_store(rows, cols, words, (40, 50), 16, TYPES, {"dataset": "t"})
    assert store.grid.shape == (3, 4)  # 40 / 16 and 50 / 16 rounded up
    assert store.cell_start[-1] == len(rows) and store.cell_start[0] == 0
    for cell in range(store.n_cells):
        sl = slice(store.cell_start[cell], store.cell_start[cell + 1])
        assert np.all(store.rows[sl] // 16 * 4 + store.cols[sl] // 16 == cell)
    # the same multiset of (row, col, word) triples, whatever the input order
    before = sorted(zip(rows.tolist(), cols.tolist(), words.tolist()))
    after = sorted(zip(store.rows.tolist(), store.cols.tolist(), store.words.tolist()))
    assert before == after


def test_order_does_not_depend_on_input_order():
    rows, cols, words = random_words()
    perm = np.random.default_rng(1).permutation(len(rows))
    a = build_store(rows, cols, words, (40, 50), 16, TYPES, {})
    b = build_store(rows[perm], cols[perm], words[perm], (40, 50), 16, TYPES, {})
    for name in ("rows", "cols", "words", "cell_start"):
        assert np.array_equal(getattr(a, name), getattr(b, name))


def test_smallest_fitting_integer_types():
    rows, cols, words = random_words()
    small = build_store(rows, cols, words, (40, 50), 16, TYPES, {})
    assert small.rows.dtype == np.uint8 and small.words.dtype == np.uint8
    big = build_store(rows * 60, cols, words, (2500, 50), 16, (WordType("orb", "orb-6000", 0, 6000, ""),), {})
    assert big.rows.dtype == np.uint16 and big.words.dtype == np.uint16


def test_store_round_trips(tmp_path):
    rows, cols, words = random_words()
    store = build_store(rows, cols, words, (40, 50), 16, TYPES, {"dataset": "t", "stride": 1})
    save_store(store, tmp_path / "s.npz")
    again = load_store(tmp_path / "s.npz")
    for name in ("rows", "cols", "words", "cell_start"):
        assert np.array_equal(getattr(again, name), getattr(store, name))
        assert getattr(again, name).dtype == getattr(store, name).dtype
    assert (again.grid.shape, again.grid.cell_width, again.types, again.params) == (
        store.grid.shape, store.grid.cell_width, store.types, store.params,
    )


def test_counts_and_slices():
    store = build_store([0, 0, 20, 39], [0, 17, 0, 49], [3, 12, 14, 0], (40, 50), 16, TYPES, {})
    assert store.count_by_type() == {"orb": 2, "texton": 2}
    assert store.vocabulary_size == 15
    assert store.cell_words(0).tolist() == [3] and store.cell_words(1).tolist() == [12]
    assert store.words_per_cell().tolist() == [1, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1]


def test_a_file_that_is_not_a_store_is_refused(tmp_path):
    path = tmp_path / "x.npz"
    np.savez(path, something=np.zeros(3))
    with pytest.raises(CuriosityError, match=r"x\.npz: corrupt or truncated \(meta is not a file in the archive\)"):
        load_store(path)


def test_a_store_whose_words_were_edited_is_named_and_extracted_again(own_map, tmp_path):
    """Issue 44: an edited word store made `label --force` fail naming no file, and kept it."""
    import json

    from small_maps import grid_yaml
    from typer.testing import CliRunner

    from curiosity_cli.cli import app

    runner = CliRunner()
    common = ["--jobs", "1", "--cache-dir", str(tmp_path / "cache")]
    result = runner.invoke(app, ["explore", str(grid_yaml(own_map, tmp_path)), *common, "--results-dir", str(tmp_path / "results")])
    assert result.exit_code == 0, result.output
    (store,) = (tmp_path / "cache").glob("own-*.npz")
    with np.load(store) as npz:
        arrays = {name: npz[name] for name in npz.files}
    assert "arrays_sha256" in json.loads(str(arrays["meta"]))
    words = arrays["words"].copy()
    words[0] = (int(words[0]) + 1) % 10
    np.savez_compressed(store, **{**arrays, "words": words})  # its meta as it was
    result = runner.invoke(app, ["label", str(tmp_path / "results" / "grid"), "--force", *common,
                                 "--set", "label.sweeps=2", "--set", "label.batch_sweeps=2"])
    assert f"{store.name}: its words are not those it was written with (altered since); extracting the words again" in result.stderr
    assert result.exit_code == 0, result.output
    with np.load(store) as npz:
        assert np.array_equal(npz["words"], arrays["words"]), "made again as it was"
