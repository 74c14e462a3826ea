"""Grid ORB: where the grid's points are, their orientation and descriptors, the border."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from curiosity_cli.errors import ParameterError
from curiosity_cli.words import orb_grid
from curiosity_cli.words.orb_grid import _patch_angles, grid_orb, grid_points


def _texture(rows: int, cols: int, seed: int = 0) -> np.ndarray:
    """A smooth random grey texture: corners and gradients everywhere."""
    noise = np.random.default_rng(seed).integers(0, 256, size=(rows, cols), dtype=np.uint8)
    return cv2.GaussianBlur(noise, (7, 7), 2)


def _orb():
    return cv2.ORB_create(
        nfeatures=100_000, nlevels=1, edgeThreshold=31, patchSize=31, scoreType=cv2.ORB_HARRIS_SCORE, fastThreshold=5
    )


def test_grid_points_are_the_centres_of_step_bands():
    # by hand: from step // 2 in steps of step, below the side
    rows, cols = grid_points((10, 7), 3)
    assert rows.tolist() == [1, 4, 7] and cols.tolist() == [1, 4]
    rows, cols = grid_points((40, 40), 8)
    assert rows.tolist() == cols.tolist() == [4, 12, 20, 28, 36]
    rows, cols = grid_points((3, 2), 1)
    assert rows.tolist() == [0, 1, 2] and cols.tolist() == [0, 1]
    # a map narrower than half a step has no point
    assert grid_points((3, 9), 8)[0].size == 0


def test_grid_words_per_cell_by_hand():
    # 40 x 40 px, step 8, 16 px cells: grid rows 4, 12 | 20, 28 | 36 fall 2, 2, 1 in the
    # cell rows 0..15, 16..31, 32..39 (a partial cell), the same for columns
    features = grid_orb(_texture(40, 40), step=8)
    assert features.descriptors.shape == (25, 32) and features.descriptors.dtype == np.uint8
    expected_rows, expected_cols = np.meshgrid([4, 12, 20, 28, 36], [4, 12, 20, 28, 36], indexing="ij")
    assert features.rows.tolist() == expected_rows.ravel().tolist()
    assert features.cols.tolist() == expected_cols.ravel().tolist()
    per_cell = np.zeros((3, 3), int)
    np.add.at(per_cell, (features.rows // 16, features.cols // 16), 1)
    assert per_cell.tolist() == [[4, 4, 2], [4, 4, 2], [2, 2, 1]]


def test_step_one_describes_every_pixel_border_included():
    image = _texture(37, 41)
    features = grid_orb(image, step=1)
    assert len(features.rows) == 37 * 41
    assert features.rows.tolist() == np.repeat(np.arange(37), 41).tolist()
    assert features.cols.tolist() == np.tile(np.arange(41), 37).tolist()


def test_angles_and_descriptors_are_orbs_own():
    # at the corners OpenCV's ORB finds at full resolution, the patch angle is its
    # keypoints' angle and the descriptor its descriptor
    image = _texture(160, 200, seed=1)
    keypoints, descriptors = _orb().detectAndCompute(image, None)
    assert len(keypoints) > 50
    xy = cv2.KeyPoint_convert(keypoints)
    assert np.array_equal(xy, np.rint(xy))  # level 0: whole pixels
    rows, cols = xy[:, 1].astype(np.int64), xy[:, 0].astype(np.int64)
    angles = _patch_angles(image, rows, cols)
    expected = np.array([kp.angle for kp in keypoints], np.float32)
    assert np.allclose(angles, expected, rtol=0, atol=1e-3)
    mine = orb_grid._describe(image, rows, cols, angles)
    assert np.array_equal(mine, descriptors)


def test_the_border_is_mirrored_and_the_interior_is_untouched():
    image = _texture(96, 96, seed=2)
    features = grid_orb(image, step=4)
    index = {(r, c): i for i, (r, c) in enumerate(zip(features.rows.tolist(), features.cols.tolist()))}
    # a border point is described on the reflected map
    padded = cv2.copyMakeBorder(image, 40, 40, 40, 40, cv2.BORDER_REFLECT_101)
    for r, c in [(2, 2), (2, 94), (94, 50)]:
        angle = _patch_angles(padded, np.array([r + 40]), np.array([c + 40]))
        expected = orb_grid._describe(padded, np.array([r + 40]), np.array([c + 40]), angle)
        assert np.array_equal(features.descriptors[index[r, c]], expected[0])
    # a point whose patch and sampling pairs lie inside the map sees no padding: the same
    # descriptor as OpenCV's on the map itself
    r, c = 46, 50
    angle = _patch_angles(image, np.array([r]), np.array([c]))
    assert np.array_equal(features.descriptors[index[r, c]], orb_grid._describe(image, np.array([r]), np.array([c]), angle)[0])


def test_bands_give_the_same_words_as_one_call(monkeypatch):
    image = _texture(70, 90, seed=3)
    whole = grid_orb(image, step=1)
    monkeypatch.setattr(orb_grid, "_BAND_POINTS", 200)  # bands of 2 grid rows
    banded = grid_orb(image, step=1)
    for a, b in zip(whole, banded):
        assert np.array_equal(a, b)


def test_a_map_smaller_than_half_a_step_has_no_grid_words():
    features = grid_orb(np.zeros((3, 3), np.uint8), step=8)
    assert features.rows.size == 0 and features.descriptors.shape == (0, 32)
    one = grid_orb(np.full((1, 1), 9, np.uint8), step=1)
    assert one.rows.tolist() == [0] and one.cols.tolist() == [0]


@pytest.mark.parametrize(
    "image, step, message",
    [
        (np.zeros((8, 8), np.uint8), 0, r"^step: got 0"),
        (np.zeros((8, 8, 3), np.uint8), 1, r"^image_gray: "),
        (np.zeros((0, 8), np.uint8), 1, r"^image_gray: got shape \(0, 8\)"),
    ],
)
def test_bad_arguments_are_named(image, step, message):
    with pytest.raises(ParameterError, match=message):
        grid_orb(image, step=step)


@pytest.mark.slow
def test_a_grid_step_that_places_no_orb_word_is_refused_by_name(tmp_path):
    """Issue 44: orb_grid_step=100000 gave a store without ORB words, and exit 0."""
    from typer.testing import CliRunner

    from curiosity_cli.cli import app

    result = CliRunner().invoke(app, [
        "extract", "aerial-mosaic", "--set", "words.orb_detector=grid", "--set", "words.orb_grid_step=10000",
        "--cache-dir", str(tmp_path),
    ])
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert "words.orb_grid_step: got 10000, but its grid places no ORB word on aerial-mosaic (1024 x 1024 px)" in result.stderr
    assert not list(tmp_path.glob("*.npz")), "no store is cached"


@pytest.mark.slow
def test_a_fast_threshold_that_finds_no_corner_is_refused_by_name(tmp_path):
    """Issue 63: words.orb_fast_threshold=255 gave a store without ORB words, and no warning."""
    from typer.testing import CliRunner

    from curiosity_cli.cli import app

    result = CliRunner().invoke(app, [
        "extract", "aerial-mosaic", "--set", "words.orb_fast_threshold=255", "--cache-dir", str(tmp_path),
    ])
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert "words.orb_fast_threshold: got 255, but FAST finds no corner on aerial-mosaic at it" in result.stderr
    assert not list(tmp_path.glob("*.npz")), "no store is cached"
