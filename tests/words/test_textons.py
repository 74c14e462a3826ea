"""Nearest-centre assignment and texton words."""

from __future__ import annotations

import cv2
import numba
import numpy as np
import pytest
from naive import nearest_centres_naive

from curiosity_cli.errors import ParameterError
from curiosity_cli.words._texton_kernels import nearest_centres_kernel
from curiosity_cli.words.filterbank import mr8_responses, normalise_responses
from curiosity_cli.words.textons import nearest_centres, texton_words


def brute_force(vectors, centres):
    """The definition, as one numpy expression in float64."""
    v = np.asarray(vectors, np.float32).astype(np.float64)
    c = np.asarray(centres, np.float32).astype(np.float64)
    # in slices of rows to bound the (rows, K, D) temporary
    return np.concatenate(
        [np.argmin(((v[i : i + 256, None, :] - c[None]) ** 2).sum(-1), axis=1) for i in range(0, len(v), 256)]
        or [np.empty(0, np.intp)]
    )


def texture(shape, seed):
    rng = np.random.default_rng(seed)
    image = cv2.GaussianBlur(rng.standard_normal(shape), (0, 0), 1.5)
    rows, cols = np.mgrid[0 : shape[0], 0 : shape[1]]
    image[:, shape[1] // 2 :] += np.sin(rows[:, shape[1] // 2 :] * 0.9)  # a striped half
    return image


# --- kernel against its twin --------------------------------------------------------


@pytest.mark.parametrize(
    ("n", "k", "d", "seed"),
    [(1, 1, 1, 0), (700, 37, 3, 1), (1500, 1000, 8, 2), (300, 9, 13, 3), (1029, 64, 8, 4)],
)
def test_kernel_matches_naive_twin_on_random_data(n, k, d, seed):
    # sizes straddle the 512-row chunks and the padding of K to a multiple of 8
    rng = np.random.default_rng(seed)
    vectors = rng.standard_normal((n, d)).astype(np.float32)
    centres = rng.standard_normal((k, d)).astype(np.float32)
    got = nearest_centres_kernel(vectors, centres)
    assert got.dtype == np.int32
    np.testing.assert_array_equal(got, nearest_centres_naive(vectors, centres))


def test_public_function_equals_float64_brute_force():
    rng = np.random.default_rng(5)
    vectors = rng.random((3000, 8), dtype=np.float32) * 2 - 1
    centres = rng.random((1000, 8), dtype=np.float32) * 2 - 1
    np.testing.assert_array_equal(nearest_centres(vectors, centres), brute_force(vectors, centres))


def test_near_ties_within_float32_screen_error_are_decided_exactly():
    # centres one float32 ulp apart, and vectors halfway between neighbours: the float32
    # screen cannot separate them, the exact float64 distances must
    rng = np.random.default_rng(6)
    base = rng.standard_normal((50, 8)).astype(np.float32)
    nudged = np.nextafter(base, np.float32(np.inf))
    centres = np.concatenate([base, nudged, base + np.float32(1e-6)])
    vectors = np.concatenate(
        [base, nudged, (base + nudged) / 2, base + rng.standard_normal(base.shape).astype(np.float32) * 1e-5]
    ).astype(np.float32)
    got = nearest_centres(vectors, centres)
    np.testing.assert_array_equal(got, nearest_centres_naive(vectors, centres))
    np.testing.assert_array_equal(got, brute_force(vectors, centres))


def test_ties_go_to_the_lowest_index():
    rng = np.random.default_rng(7)
    unique = rng.standard_normal((20, 8)).astype(np.float32)
    # every centre three times, the copies interleaved at higher indices
    centres = np.concatenate([unique, unique[::-1], unique])
    vectors = np.concatenate([unique, rng.standard_normal((500, 8)).astype(np.float32)])
    got = nearest_centres(vectors, centres)
    np.testing.assert_array_equal(got, brute_force(vectors, centres))
    assert (got < 20).all()
    np.testing.assert_array_equal(got[:20], np.arange(20))


def test_exact_ties_on_a_lattice():
    # integer coordinates: many centres at exactly the same distance from a vector
    rng = np.random.default_rng(8)
    centres = rng.integers(-2, 3, size=(60, 4)).astype(np.float32)
    vectors = rng.integers(-3, 4, size=(2000, 4)).astype(np.float32)
    got = nearest_centres(vectors, centres)
    np.testing.assert_array_equal(got, nearest_centres_naive(vectors, centres))
    np.testing.assert_array_equal(got, brute_force(vectors, centres))
    # all-equal centres: everything is a tie
    same = np.zeros((5, 4), np.float32)
    assert (nearest_centres(vectors, same) == 0).all()


@pytest.mark.parametrize("scale", [1e-30, 1e-12, 1e6, 1e16, 1e18])
def test_extreme_scales_stay_exact(scale):
    # tiny values underflow the float32 screen, huge ones would overflow it (such rows
    # take the float64 path); either way the answer is the brute-force one
    rng = np.random.default_rng(9)
    vectors = (rng.standard_normal((400, 8)) * scale).astype(np.float32)
    centres = (rng.standard_normal((30, 8)) * scale).astype(np.float32)
    got = nearest_centres(vectors, centres)
    np.testing.assert_array_equal(got, nearest_centres_naive(vectors, centres))


def test_result_does_not_depend_on_thread_count():
    rng = np.random.default_rng(10)
    vectors = rng.standard_normal((5000, 8)).astype(np.float32)
    centres = rng.standard_normal((300, 8)).astype(np.float32)
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        single = nearest_centres(vectors, centres)
    finally:
        numba.set_num_threads(threads)
    np.testing.assert_array_equal(nearest_centres(vectors, centres), single)


def test_real_mr8_responses_against_the_twin():
    # structured data: normalised MR8 responses of a small image, with centres drawn from
    # the responses themselves (so many vectors sit exactly on a centre) plus noise
    responses = normalise_responses(mr8_responses(texture((60, 70), seed=11))).reshape(-1, 8)
    rng = np.random.default_rng(12)
    picked = responses[rng.choice(len(responses), 150, replace=False)]
    jittered = picked + rng.normal(0, 0.05, picked.shape).astype(np.float32)
    centres = np.concatenate([picked, jittered, picked[:10]])  # the last 10 duplicate
    got = nearest_centres(responses, centres)
    np.testing.assert_array_equal(got, nearest_centres_naive(responses, centres))
    np.testing.assert_array_equal(got, brute_force(responses, centres))
    assert (got < 300).all()


def test_inputs_of_any_real_dtype_and_layout_are_accepted():
    rng = np.random.default_rng(13)
    vectors = rng.standard_normal((8, 300)).T  # float64, not C-contiguous
    centres = rng.integers(-2, 3, size=(20, 8))
    np.testing.assert_array_equal(nearest_centres(vectors, centres), brute_force(vectors, centres))
    assert nearest_centres(np.zeros((0, 8)), centres).shape == (0,)
    assert nearest_centres(np.zeros((0, 8)), centres).dtype == np.int32


@pytest.mark.parametrize(
    ("vectors", "centres", "message"),
    [
        (np.zeros(8), np.zeros((3, 8)), r"vectors: got shape \(8,\), expected a 2-D \(N, D\)"),
        (np.zeros((4, 8)), np.zeros(8), r"centres: got shape \(8,\), expected a 2-D \(K, D\)"),
        (np.zeros((4, 8)), np.zeros((0, 8)), r"centres: got shape \(0, 8\), expected at least one centre"),
        (np.zeros((4, 8)), np.zeros((3, 7)), r"centres: got 7 columns, expected D = 8"),
        (np.zeros((4, 0)), np.zeros((3, 0)), r"vectors: got shape \(4, 0\), expected D >= 1"),
        (np.zeros((4, 8), complex), np.zeros((3, 8)), "vectors: got dtype complex128"),
        (np.zeros((4, 8)), np.zeros((3, 8), bool), "centres: got dtype bool"),
        (np.full((4, 8), np.nan), np.zeros((3, 8)), "vectors: got NaN or infinite values .*, expected finite numbers"),
        (np.zeros((4, 8)), np.full((3, 8), np.inf), "centres: got NaN or infinite values"),
        (np.zeros((4, 8)), np.full((3, 8), 1e300), r"centres: got .*too large for float32\), expected finite numbers"),
    ],
)
def test_bad_arguments_are_named(vectors, centres, message):
    with pytest.raises(ParameterError, match=f"^{message}"):
        nearest_centres(vectors, centres)


# --- texton words ------------------------------------------------------------------


@pytest.mark.parametrize("stride", [1, 2, 3])
def test_texton_words_samples_every_stride_th_pixel_in_row_major_order(stride):
    image = (texture((23, 30), seed=14) * 40 + 128).clip(0, 255).astype(np.uint8)
    rng = np.random.default_rng(15)
    centres = rng.standard_normal((40, 8)).astype(np.float32)
    rows, cols, words = texton_words(image, centres, stride)
    n_rows, n_cols = -(-23 // stride), -(-30 // stride)
    assert rows.shape == cols.shape == words.shape == (n_rows * n_cols,)
    assert rows.dtype == cols.dtype == words.dtype == np.int32
    grid_rows, grid_cols = np.meshgrid(np.arange(0, 23, stride), np.arange(0, 30, stride), indexing="ij")
    np.testing.assert_array_equal(rows, grid_rows.ravel())
    np.testing.assert_array_equal(cols, grid_cols.ravel())
    # filtered at full resolution, then sampled
    responses = normalise_responses(mr8_responses(image))[rows, cols]
    np.testing.assert_array_equal(words, nearest_centres_naive(responses, centres))


def test_texton_words_validates_its_arguments():
    image = np.zeros((10, 10))
    centres = np.zeros((5, 8))
    with pytest.raises(ParameterError, match="stride: got 0, expected an integer >= 1"):
        texton_words(image, centres, 0)
    with pytest.raises(ParameterError, match=r"centres: got shape \(5, 7\), expected \(K, 8\)"):
        texton_words(image, np.zeros((5, 7)), 1)
    with pytest.raises(ParameterError, match=r"centres: got shape \(0, 8\), expected at least one centre"):
        texton_words(image, np.zeros((0, 8)), 1)
    with pytest.raises(ParameterError, match=r"image: got shape \(10, 10, 3\).*grayscale"):
        texton_words(np.zeros((10, 10, 3)), centres, 1)
