from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from curiosity_cli.config import CONFIG_DIR, load_words_config
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.errors import ConfigError, CuriosityError
from curiosity_cli.words.extract import extract_words, store_name
from curiosity_cli.words.store import load_store

GOLDEN = Path(__file__).parent.parent / "data" / "golden_words.npz"
WORDS = load_words_config(CONFIG_DIR / "paper.yaml")


@pytest.fixture
def golden_map(tmp_path: Path) -> Path:
    """A 96 x 128 px crop of aerial-mosaic across several classes, as its own dataset."""
    image = cv2.imread(str(Path(load_map("aerial-mosaic").config.image)))
    cv2.imwrite(str(tmp_path / "crop.png"), image[400:496, 180:308])
    path = tmp_path / "crop.yaml"
    path.write_text(
        yaml.safe_dump(
            {"name": "crop", "description": "", "image": "crop.png", "labels": None, "legend": None,
             "cell_width": 16, "word_stride": 1, "size": [96, 128], "source": "aerial-mosaic", "licence": "CC0"}
        )
    )
    return path


def test_word_ids_stay_in_their_types_ranges(own_map, tmp_path):
    store = extract_words(load_map(own_map), WORDS, cache_dir=tmp_path / "cache").store
    orb, texton = store.types
    assert (orb.kind, orb.offset, orb.size) == ("orb", 0, 5000)
    assert (texton.kind, texton.offset, texton.size) == ("texton", 5000, 1000)
    counts = store.count_by_type()
    assert counts["texton"] == 96 * 128  # every pixel
    assert counts["orb"] > 0 and counts["orb"] + counts["texton"] == len(store.words)
    assert store.words.max() < 6000 and store.words.dtype == np.uint16


def test_stride_two_samples_every_second_pixel(own_map, tmp_path):
    store = extract_words(load_map(own_map), WORDS, stride=2, cache_dir=tmp_path).store
    textons = store.words >= 5000
    assert textons.sum() == 48 * 64
    assert np.all(store.rows[textons] % 2 == 0) and np.all(store.cols[textons] % 2 == 0)


def test_golden_image_gives_the_stored_word_histogram(golden_map, tmp_path):
    store = extract_words(load_map(golden_map), WORDS, cache_dir=tmp_path).store
    histogram = np.bincount(store.words, minlength=store.vocabulary_size)
    if os.environ.get("CURIOSITY_REGENERATE_GOLDEN"):
        np.savez_compressed(GOLDEN, histogram=histogram)
    expected = np.load(GOLDEN)["histogram"]
    assert np.array_equal(histogram, expected), (
        f"{np.count_nonzero(histogram != expected)} word counts differ; if the change is intended, "
        "rerun with CURIOSITY_REGENERATE_GOLDEN=1"
    )


def test_second_extract_reuses_the_cache_and_force_recomputes(own_map, tmp_path):
    m, cache = load_map(own_map), tmp_path / "cache"
    first = extract_words(m, WORDS, cache_dir=cache)
    second = extract_words(m, WORDS, cache_dir=cache)
    assert not first.reused and second.reused and second.path == first.path
    assert np.array_equal(first.store.words, second.store.words)
    forced = extract_words(m, WORDS, cache_dir=cache, force=True)
    assert not forced.reused and np.array_equal(forced.store.words, first.store.words)
    assert sorted(p.name for p in cache.iterdir()) == [first.path.name]


def test_a_change_of_image_or_parameters_gets_its_own_store(own_map, tmp_path):
    first = extract_words(load_map(own_map), WORDS, cache_dir=tmp_path)
    assert extract_words(load_map(own_map), WORDS, stride=2, cache_dir=tmp_path).path != first.path
    image = cv2.imread(str(own_map.parent / "map.png"))
    cv2.imwrite(str(own_map.parent / "map.png"), 255 - image)
    changed = extract_words(load_map(own_map), WORDS, cache_dir=tmp_path)
    assert not changed.reused and changed.path != first.path


def test_colour_words_follow_the_textons(own_map, tmp_path):
    words = load_words_config(CONFIG_DIR / "paper.yaml", ["words.colour_words=true"])
    store = extract_words(load_map(own_map), words, cache_dir=tmp_path).store
    hue = store.types[2]
    assert (hue.kind, hue.offset, hue.size) == ("hue", 6000, 180)
    assert store.count_by_type()["hue"] == 96 * 128
    assert store.words.max() < 6180


def test_grey_image_with_colour_words_is_refused(own_map, tmp_path):
    grey = cv2.cvtColor(cv2.imread(str(own_map.parent / "map.png")), cv2.COLOR_BGR2GRAY)
    cv2.imwrite(str(own_map.parent / "map.png"), grey)
    words = load_words_config(CONFIG_DIR / "paper.yaml", ["words.colour_words=true"])
    with pytest.raises(CuriosityError, match=r"map\.png: the image is grey; colour words need colour"):
        extract_words(load_map(own_map), words, cache_dir=tmp_path)


@pytest.mark.parametrize("option, value", [("stride", 0), ("cell_width", -1), ("stride", 1.5)])
def test_bad_stride_or_cell_width(own_map, tmp_path, option, value):
    with pytest.raises(CuriosityError, match=rf"^{option}: got {value}, expected an integer >= 1$"):
        extract_words(load_map(own_map), WORDS, cache_dir=tmp_path, **{option: value})


def test_cell_width_larger_than_the_image(own_map, tmp_path):
    with pytest.raises(CuriosityError, match=r"cell_width: got 200, expected at most the image's smaller side \(96 px\)"):
        extract_words(load_map(own_map), WORDS, cell_width=200, cache_dir=tmp_path)


@pytest.mark.parametrize(
    "centres, message",
    [
        (np.zeros((1000, 7), np.float32), r"centres: got float32 of shape \(1000, 7\), expected float32 of shape \(1000, 8\)"),
        (np.zeros((1000, 8), np.float64), r"centres: got float64 of shape \(1000, 8\), expected float32"),
        (np.full((1000, 8), np.nan, np.float32), r"centres: got non-finite values"),
    ],
)
def test_a_malformed_vocabulary_is_named(own_map, tmp_path, centres, message):
    vocab = tmp_path / "vocab"
    vocab.mkdir()
    shipped = WORDS.vocabulary_dir
    (vocab / "orb-5000.npz").write_bytes((shipped / "orb-5000.npz").read_bytes())
    np.savez(vocab / "texton-1000.npz", centres=centres, recipe=np.array("{}"))
    words = load_words_config(CONFIG_DIR / "paper.yaml", [f"words.vocabulary_dir={vocab}"])
    with pytest.raises(CuriosityError, match=r"texton-1000\.npz: " + message):
        extract_words(load_map(own_map), words, cache_dir=tmp_path / "cache")
    assert not (tmp_path / "cache").exists()


def test_a_missing_vocabulary_says_how_to_build_it(own_map, tmp_path):
    words = load_words_config(CONFIG_DIR / "paper.yaml", ["words.orb_vocabulary=123"])
    with pytest.raises(CuriosityError, match=r"orb-123\.npz: vocabulary not found; vocab build builds the orb vocabulary of 123 words"):
        extract_words(load_map(own_map), words, cache_dir=tmp_path)


def test_a_failure_mid_extraction_leaves_no_store(own_map, tmp_path, monkeypatch):
    import curiosity_cli.words.hamming as hamming

    def broken(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(hamming, "nearest_binary_words", broken)
    with pytest.raises(KeyboardInterrupt):
        extract_words(load_map(own_map), WORDS, cache_dir=tmp_path / "cache")
    assert not (tmp_path / "cache").exists() or list((tmp_path / "cache").iterdir()) == []


def test_the_cached_file_is_a_store(own_map, tmp_path):
    result = extract_words(load_map(own_map), WORDS, cache_dir=tmp_path)
    assert np.array_equal(load_store(result.path).words, result.store.words)
    assert result.store.params["dataset"] == "own" and result.store.params["stride"] == 1


def test_a_change_of_orb_settings_gets_its_own_store(own_map, tmp_path):
    m = load_map(own_map)
    settings = [
        [],
        ["words.orb_per_tile=2"],
        ["words.orb_per_tile=2", "words.orb_fill_threshold=1"],
        ["words.orb_per_tile=2", "words.orb_fill_threshold=5"],
        ["words.orb_fast_threshold=30"],
        ["words.orb_tile=32", "words.orb_per_tile=2"],
        ["words.orb_max_features=50"],
    ]
    paths = [
        extract_words(m, load_words_config(CONFIG_DIR / "paper.yaml", overrides), cache_dir=tmp_path).path
        for overrides in settings
    ]
    assert len(set(paths)) == len(settings)
    assert extract_words(m, WORDS, cache_dir=tmp_path).reused


def test_the_orb_share_counts_orb_words_among_all(own_map, tmp_path):
    result = extract_words(load_map(own_map), WORDS, cache_dir=tmp_path)
    n_orb = result.store.count_by_type()["orb"]
    assert 0 < n_orb and result.orb_share == n_orb / len(result.store.words)
    capped = load_words_config(CONFIG_DIR / "paper.yaml", ["words.orb_per_tile=1"])
    assert extract_words(load_map(own_map), capped, cache_dir=tmp_path).orb_share < result.orb_share


# --- grid ORB (issue 32) and the store's name from the words settings (issue 34) -------


def test_the_default_store_names_are_todays(own_map):
    # the names before words.orb_detector existed: old caches and old runs' recipes stay valid
    m = load_map(own_map)
    assert store_name(m, WORDS)[0] == "own-e270caf4de777d2e.npz"
    capped = load_words_config(CONFIG_DIR / "paper.yaml", ["words.orb_per_tile=2", "words.orb_fill_threshold=1"])
    assert store_name(m, capped)[0] == "own-8628354b94992909.npz"
    # the grid's step is read by the grid only: under the keypoints detector another one is refused (issue 63)
    with pytest.raises(ConfigError, match="words.orb_grid_step: got 7, but words.orb_detector keypoints reads no grid step"):
        load_words_config(CONFIG_DIR / "paper.yaml", ["words.orb_grid_step=7"])


def test_the_grid_and_its_step_name_their_own_stores(own_map):
    m = load_map(own_map)

    def name(*overrides):
        return store_name(m, load_words_config(CONFIG_DIR / "paper.yaml", list(overrides)))[0]

    grid = name("words.orb_detector=grid")
    assert grid not in (name(), name("words.orb_detector=grid", "words.orb_grid_step=2"))
    # keypoint settings the grid does not read leave its store alone
    assert grid == name("words.orb_detector=grid", "words.orb_fast_threshold=30", "words.orb_tile=32")


def _another_value(config, field):
    """A valid value of ``field`` other than ``config``'s."""
    value = getattr(config, field.name)
    choices = field.metadata.get("choices")
    if choices:
        return next(c for c in choices if c != value)
    if isinstance(value, bool):
        return not value
    if value is None:
        return 2
    return value + 1


def test_every_words_key_names_the_store_or_is_excluded(own_map):
    import dataclasses

    from curiosity_cli.config import _READ_BY, _VOCABULARY_KEYS, WordsConfig

    m = load_map(own_map)
    for field in dataclasses.fields(WordsConfig):
        if field.name in _VOCABULARY_KEYS:  # recorded by the vocabularies' hashes
            continue
        base = WORDS
        if _READ_BY.get(field.name) == "grid":
            base = dataclasses.replace(WORDS, orb_detector="grid")
        changed = dataclasses.replace(base, **{field.name: _another_value(base, field)})
        assert store_name(m, changed)[0] != store_name(m, base)[0], field.name


def test_grid_words_sit_on_the_grid(own_map, tmp_path):
    grid = load_words_config(CONFIG_DIR / "paper.yaml", ["words.orb_detector=grid", "words.orb_grid_step=4"])
    result = extract_words(load_map(own_map), grid, cache_dir=tmp_path)
    store = result.store
    orb = store.words < 5000
    # 96 x 128 px, step 4: rows 2, 6, ..., 94 and cols 2, 6, ..., 126; 16 words in every 16 px cell
    assert orb.sum() == 24 * 32
    assert set(store.rows[orb] % 4) == {2} and set(store.cols[orb] % 4) == {2}
    orb_per_cell = np.add.reduceat(orb.astype(int), store.cell_start[:-1])
    assert store.n_cells == 6 * 8 and set(orb_per_cell.tolist()) == {16}
    assert result.orb_share == 24 * 32 / (24 * 32 + 96 * 128)
    assert not extract_words(load_map(own_map), WORDS, cache_dir=tmp_path).reused
