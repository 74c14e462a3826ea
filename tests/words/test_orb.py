"""ORB keypoints of a map (all of them, or capped per tile), and Hamming nearest-word assignment."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from naive import nearest_words as naive_nearest_words

from curiosity_cli.words import _hamming_kernels, orb
from curiosity_cli.words.hamming import nearest_binary_words
from curiosity_cli.words.orb import detect_orb


def random_descriptors(rng: np.random.Generator, n: int) -> np.ndarray:
    return rng.integers(0, 256, size=(n, 32), dtype=np.uint8)


def flip_bits(rng: np.random.Generator, rows: np.ndarray, n_bits: int) -> np.ndarray:
    """Copies of ``rows`` with ``n_bits`` random bits flipped in each."""
    bits = np.unpackbits(rows, axis=1)
    for r in range(len(bits)):
        flip = rng.choice(256, size=n_bits, replace=False)
        bits[r, flip] ^= 1
    return np.packbits(bits, axis=1)


def textured_and_smooth(rows: int, cols: int, seed: int = 0) -> np.ndarray:
    """Blurred noise in the left half (texture), a gentle gradient with faint noise in
    the right half (smooth: OpenCV's default FAST threshold finds nothing there)."""
    rng = np.random.default_rng(seed)
    noise = rng.normal(128, 60, size=(rows, cols))
    texture = cv2.GaussianBlur(noise, (0, 0), 1.5)
    r, c = np.mgrid[0:rows, 0:cols]
    smooth = 100 + 0.2 * r + 0.1 * c + rng.normal(0, 1.0, size=(rows, cols))
    image = np.where(c < cols // 2, texture, smooth)
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


# --- nearest_binary_words -------------------------------------------------------------


def test_kernel_matches_naive_twin_with_duplicates_and_ties():
    rng = np.random.default_rng(1)
    vocabulary = random_descriptors(rng, 300)
    vocabulary[150] = vocabulary[20]  # duplicate words: ties must go to index 20
    vocabulary[299] = vocabulary[0]
    descriptors = np.concatenate(
        [
            random_descriptors(rng, 200),
            vocabulary[[20, 150, 0, 299, 5]],  # exact copies, distance 0
            flip_bits(rng, vocabulary[:100], 3),  # near copies
            np.zeros((1, 32), np.uint8),
        ]
    )
    index = np.empty(len(descriptors), np.int32)
    distance = np.empty(len(descriptors), np.int32)
    vocabulary_t = np.ascontiguousarray(vocabulary.view(np.uint64).T)
    _hamming_kernels.nearest_words(descriptors.view(np.uint64), vocabulary_t, index, distance)

    want_index, want_distance = naive_nearest_words(descriptors, vocabulary)
    np.testing.assert_array_equal(index, want_index)
    np.testing.assert_array_equal(distance, want_distance)
    np.testing.assert_array_equal(nearest_binary_words(descriptors, vocabulary), want_index)
    assert list(index[200:205]) == [20, 20, 0, 0, 5]


def test_ties_go_to_the_lowest_index():
    # Each word has one bit set, so the zero descriptor is at distance 1 from all.
    vocabulary = np.zeros((40, 32), np.uint8)
    for w in range(40):
        vocabulary[w, w % 32] = 1 << (w // 32)
    descriptors = np.zeros((3, 32), np.uint8)
    descriptors[1, 5] = 1  # equal to word 5
    descriptors[2, 5] = 3  # distance 1 to words 5 and 37 (bits 7 and 6 of byte 5)
    assert nearest_binary_words(descriptors, vocabulary).tolist() == [0, 5, 5]


def test_nearest_words_accepts_other_layouts_and_integer_dtypes():
    rng = np.random.default_rng(2)
    vocabulary = random_descriptors(rng, 50)
    descriptors = random_descriptors(rng, 60)
    want = nearest_binary_words(descriptors, vocabulary)
    assert want.dtype == np.int32 and want.shape == (60,)
    np.testing.assert_array_equal(nearest_binary_words(np.asfortranarray(descriptors), vocabulary), want)
    np.testing.assert_array_equal(nearest_binary_words(descriptors.astype(np.int64), vocabulary.tolist()), want)
    wide = np.zeros((60, 64), np.uint8)
    wide[:, ::2] = descriptors  # a strided view
    np.testing.assert_array_equal(nearest_binary_words(wide[:, ::2], vocabulary), want)


def test_no_descriptors_give_no_words():
    vocabulary = np.zeros((4, 32), np.uint8)
    out = nearest_binary_words(np.zeros((0, 32), np.uint8), vocabulary)
    assert out.shape == (0,) and out.dtype == np.int32


@pytest.mark.parametrize(
    ("descriptors", "vocabulary", "message"),
    [
        (np.zeros((5, 31), np.uint8), np.zeros((4, 32), np.uint8), r"^descriptors: got shape \(5, 31\)"),
        (np.zeros(32, np.uint8), np.zeros((4, 32), np.uint8), r"^descriptors: got shape \(32,\)"),
        (np.zeros((5, 32), np.float32), np.zeros((4, 32), np.uint8), r"^descriptors: got dtype float32"),
        (np.full((5, 32), 256), np.zeros((4, 32), np.uint8), r"^descriptors: got values outside 0\.\.255"),
        (np.zeros((5, 32), np.uint8), np.zeros((0, 32), np.uint8), r"^vocabulary: got 0 words"),
        (np.zeros((5, 32), np.uint8), np.zeros((4, 16), np.uint8), r"^vocabulary: got shape \(4, 16\)"),
        (np.zeros((5, 32), np.uint8), np.zeros((4, 32), bool), r"^vocabulary: got dtype bool"),
    ],
)
def test_nearest_words_rejects_bad_input_naming_the_parameter(descriptors, vocabulary, message):
    with pytest.raises(ValueError, match=message):
        nearest_binary_words(descriptors, vocabulary)


# --- detect_orb -----------------------------------------------------------------------


@pytest.fixture(scope="module")
def image() -> np.ndarray:
    """Non-square on purpose: a rows/cols swap would go out of bounds."""
    return textured_and_smooth(160, 288)


@pytest.fixture(scope="module")
def features(image):
    return detect_orb(image)


def test_detect_orb_returns_sorted_in_bounds_features(image, features):
    rows, cols, descriptors = features
    n = len(rows)
    assert n > 0
    assert rows.dtype == np.int32 and cols.dtype == np.int32
    assert rows.shape == cols.shape == (n,)
    assert descriptors.shape == (n, 32) and descriptors.dtype == np.uint8
    assert rows.min() >= 0 and rows.max() < image.shape[0]
    assert cols.min() >= 0 and cols.max() < image.shape[1]
    keys = rows.astype(np.int64) * image.shape[1] + cols
    assert np.all(np.diff(keys) >= 0)


def test_detect_orb_is_deterministic(image, features):
    again = detect_orb(image.copy())
    for a, b in zip(features, again, strict=True):
        np.testing.assert_array_equal(a, b)


def test_detect_orb_does_not_depend_on_opencv_threads(image, features):
    before = cv2.getNumThreads()
    try:
        cv2.setNumThreads(1)
        single = detect_orb(image)
    finally:
        cv2.setNumThreads(before)
    for a, b in zip(features, single, strict=True):
        np.testing.assert_array_equal(a, b)


def tile_counts(rows, cols, shape, tile):
    counts = np.zeros((-(-shape[0] // tile), -(-shape[1] // tile)), np.int64)
    np.add.at(counts, (rows // tile, cols // tile), 1)
    return counts


def test_capped_keypoints_reach_smooth_tiles_and_the_border(image):
    # The per-tile mode with a top-up, the default before issue 13.
    capped = detect_orb(image, per_tile=2, fill_threshold=1)
    counts = tile_counts(capped.rows, capped.cols, image.shape, 16)
    assert counts.max() <= 2  # per_tile
    assert (counts > 0).mean() >= 0.95
    smooth = counts[:, counts.shape[1] // 2 :]
    assert (smooth > 0).mean() >= 0.9
    # Reflection padding: the outermost tiles get keypoints too.
    for edge in (counts[0], counts[-1], counts[:, 0], counts[:, -1]):
        assert (edge > 0).mean() >= 0.8

    strict = detect_orb(image, per_tile=2)
    strict_smooth = tile_counts(strict.rows, strict.cols, image.shape, 16)[:, counts.shape[1] // 2 :]
    assert (strict_smooth > 0).mean() < 0.5  # what the top-up is for


def test_every_keypoint_by_default_so_density_follows_the_texture(image, features):
    counts = tile_counts(features.rows, features.cols, image.shape, 16)
    textured, smooth = counts[:, : counts.shape[1] // 2], counts[:, counts.shape[1] // 2 :]
    assert smooth.sum() == 0  # faint noise: no corner at FAST threshold 20
    assert textured.mean() > 3 and textured.max() > 2  # more than the old cap of 2 per tile

    capped = detect_orb(image, per_tile=2, fill_threshold=1)
    capped_smooth = tile_counts(capped.rows, capped.cols, image.shape, 16)[:, counts.shape[1] // 2 :]
    assert (capped_smooth > 0).mean() >= 0.9  # the top-up reaches the flat-but-noisy tiles


def test_every_keypoint_is_the_one_opencv_finds_on_the_padded_image():
    image = textured_and_smooth(90, 130, seed=5)
    pad = orb.pad_for_levels(8, 1.2)
    padded = cv2.copyMakeBorder(image, pad, pad, pad, pad, cv2.BORDER_REFLECT_101)
    opencv = cv2.ORB_create(
        nfeatures=10**6,  # far above the keypoints there are: no cap
        scaleFactor=1.2,
        nlevels=8,
        edgeThreshold=31,
        firstLevel=0,
        WTA_K=2,
        scoreType=cv2.ORB_HARRIS_SCORE,
        patchSize=31,
        fastThreshold=20,
    )
    keypoints, descriptors = opencv.detectAndCompute(padded, None)
    row_sub = np.array([kp.pt[1] for kp in keypoints]) - pad
    col_sub = np.array([kp.pt[0] for kp in keypoints]) - pad
    octave = np.array([kp.octave for kp in keypoints])
    rows, cols = np.rint(row_sub).astype(int), np.rint(col_sub).astype(int)
    inside = (rows >= 0) & (rows < image.shape[0]) & (cols >= 0) & (cols < image.shape[1])
    assert inside.sum() > 50 and (~inside).sum() > 0  # some keypoints fall in the padding
    order = np.lexsort((col_sub, row_sub, octave, cols, rows))
    order = order[inside[order]]

    ours = detect_orb(image)
    np.testing.assert_array_equal(ours.rows, rows[order])
    np.testing.assert_array_equal(ours.cols, cols[order])
    np.testing.assert_array_equal(ours.descriptors, descriptors[order])


def test_max_features_without_a_tile_cap_thins_the_densest_tiles_first(image, features):
    counts = tile_counts(features.rows, features.cols, image.shape, 16)
    thinned = detect_orb(image, max_features=int((counts > 0).sum()))
    # Rank within tile: every tile with keypoints keeps its best one.
    np.testing.assert_array_equal(tile_counts(thinned.rows, thinned.cols, image.shape, 16), (counts > 0).astype(int))
    everything = set(zip(features.rows.tolist(), features.cols.tolist(), map(bytes, features.descriptors)))
    assert set(zip(thinned.rows.tolist(), thinned.cols.tolist(), map(bytes, thinned.descriptors))) <= everything
    untouched = detect_orb(image, max_features=len(features.rows))
    for a, b in zip(features, untouched, strict=True):
        np.testing.assert_array_equal(a, b)


def test_blocks_keep_every_keypoint_once(image, monkeypatch):
    # One pyramid level: the block margin covers every patch, so blocking changes nothing.
    whole = detect_orb(image, n_levels=1)
    monkeypatch.setattr(orb, "_BLOCK_SIDE", 64)
    blocked = detect_orb(image, n_levels=1)
    assert len(whole.rows) > 50
    for a, b in zip(whole, blocked, strict=True):
        np.testing.assert_array_equal(a, b)


def test_positions_are_rows_and_cols_not_x_and_y():
    # Texture only in a wide band at the top right of a flat, wide image.
    image = np.full((120, 320), 90, np.uint8)
    band = textured_and_smooth(40, 320, seed=3)[:, :160]
    image[:40, 160:] = band
    rows, cols, _ = detect_orb(image)
    assert len(rows) > 20
    assert rows.max() < 40 + 16  # keypoints hug the textured band's edge at most
    assert cols.min() >= 160 - 16


def test_tile_caps(image):
    rows, cols, _ = detect_orb(image, tile=32, per_tile=3, fill_threshold=1)
    counts = tile_counts(rows, cols, image.shape, 32)
    assert counts.max() == 3

    capped = detect_orb(image, tile=32, per_tile=3, fill_threshold=1, max_features=int((counts > 0).sum()))
    # The overall cap drops by rank within tile: every tile keeps its best keypoint.
    np.testing.assert_array_equal(tile_counts(capped.rows, capped.cols, image.shape, 32), (counts > 0).astype(int))
    assert len(detect_orb(image, max_features=7).rows) == 7


def test_blocks_give_the_same_kind_of_result(image, monkeypatch):
    features = detect_orb(image, per_tile=2, fill_threshold=1)
    monkeypatch.setattr(orb, "_BLOCK_SIDE", 64)
    blocked = detect_orb(image, per_tile=2, fill_threshold=1)
    assert blocked.rows.min() >= 0 and blocked.rows.max() < image.shape[0]
    assert blocked.cols.min() >= 0 and blocked.cols.max() < image.shape[1]
    counts = tile_counts(blocked.rows, blocked.cols, image.shape, 16)
    assert counts.max() <= 2 and (counts > 0).mean() >= 0.95
    # Pixels far from block edges see the same pyramid neighbourhood as the whole image
    # only at level 0, so just ask for broad agreement.
    same = set(zip(blocked.rows.tolist(), blocked.cols.tolist())) & set(
        zip(features.rows.tolist(), features.cols.tolist())
    )
    assert len(same) >= 0.5 * len(features.rows)


@pytest.mark.parametrize("shape", [(1, 1), (3, 5), (40, 17)])
def test_tiny_images(shape):
    rng = np.random.default_rng(4)
    image = rng.integers(0, 256, size=shape, dtype=np.uint8)
    rows, cols, descriptors = detect_orb(image)
    assert len(rows) == len(cols) == len(descriptors)
    assert np.all((rows >= 0) & (rows < shape[0]) & (cols >= 0) & (cols < shape[1]))


def test_flat_image_has_no_keypoints():
    rows, cols, descriptors = detect_orb(np.full((64, 80), 7, np.uint8))
    assert rows.shape == cols.shape == (0,) and descriptors.shape == (0, 32)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"max_features": 0}, r"^max_features: got 0, expected an integer >= 1$"),
        ({"max_features": 2.5}, r"^max_features: got 2\.5, expected an integer >= 1$"),
        ({"tile": 0}, r"^tile: got 0, expected an integer >= 1$"),
        ({"per_tile": True}, r"^per_tile: got True"),
        ({"fast_threshold": 0}, r"^fast_threshold: got 0, expected an integer between 1 and 255$"),
        ({"fill_threshold": 30}, r"^fill_threshold: got 30, expected an integer between 1 and 20$"),
        ({"fill_threshold": 1}, r"^fill_threshold: got 1 with per_tile None, expected None"),
        ({"per_tile": 0}, r"^per_tile: got 0, expected an integer >= 1$"),
        ({"n_levels": 0}, r"^n_levels: got 0"),
        ({"n_levels": 9, "scale_factor": 2}, r"^n_levels: got 9 with scale_factor 2\.0, expected"),
        ({"scale_factor": 1.0}, r"^scale_factor: got 1\.0, expected a number in \(1, 2\]$"),
    ],
)
def test_detect_orb_rejects_bad_settings_naming_the_parameter(kwargs, message):
    with pytest.raises(ValueError, match=message):
        detect_orb(np.zeros((32, 32), np.uint8), **kwargs)


@pytest.mark.parametrize(
    ("image", "message"),
    [
        (np.zeros((32, 32, 3), np.uint8), r"^image_gray: got shape \(32, 32, 3\), expected \(H, W\)$"),
        (np.zeros((0, 32), np.uint8), r"^image_gray: got shape \(0, 32\)"),
        (np.zeros((32, 32), np.float64), r"^image_gray: got dtype float64, expected uint8$"),
        (np.full((32, 32), 1000, np.uint16), r"^image_gray: got values outside 0\.\.255"),
    ],
)
def test_detect_orb_rejects_bad_images(image, message):
    with pytest.raises(ValueError, match=message):
        detect_orb(image)
