"""MR8 filter bank: the 38 kernels, the 8 rotation-invariant responses, normalisation."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from naive import mr8_responses_naive, normalise_responses_naive

from curiosity_cli.words.filterbank import (
    MR8_CHANNELS,
    mr8_filters,
    mr8_responses,
    normalise_responses,
)


def smooth_texture(shape, seed, sigma=2.0):
    """Random texture with structure at every orientation, smooth enough to interpolate."""
    rng = np.random.default_rng(seed)
    image = cv2.GaussianBlur(rng.standard_normal(shape), (0, 0), sigma)
    return image / image.std()


def rotate(image, degrees, flags=cv2.INTER_CUBIC):
    """Rotate counter-clockwise (as displayed) about the image centre, same size."""
    rows, cols = image.shape[:2]
    matrix = cv2.getRotationMatrix2D(((cols - 1) / 2, (rows - 1) / 2), degrees, 1.0)
    return cv2.warpAffine(image, matrix, (cols, rows), flags=flags)


def rotate_channels(responses, degrees):
    return np.stack([rotate(responses[:, :, i], degrees) for i in range(responses.shape[2])], axis=-1)


# --- the filters -------------------------------------------------------------------


def test_root_filter_set_has_38_odd_square_kernels():
    bank = mr8_filters()
    assert len(bank) == 38
    stack = bank.stack()
    assert stack.shape == (38, 49, 49)
    assert stack.dtype == np.float32
    assert bank.edge.shape == bank.bar.shape == (3, 6, 49, 49)
    assert bank.gaussian.shape == bank.log.shape == (49, 49)
    assert bank.scales == ((3.0, 1.0), (6.0, 2.0), (12.0, 4.0))
    np.testing.assert_allclose(np.degrees(bank.orientations), [0, 30, 60, 90, 120, 150])
    small = mr8_filters(25)
    assert small.stack().shape == (38, 25, 25)
    assert small.support == 25


def test_kernels_are_read_only():
    bank = mr8_filters()
    with pytest.raises(ValueError):
        bank.edge[0, 0, 0, 0] = 1.0


@pytest.mark.parametrize("circular", [True, False])
def test_edge_bar_and_log_are_zero_mean_with_unit_l1_norm(circular):
    bank = mr8_filters(circular=circular)
    zero_mean = np.concatenate([bank.edge.reshape(-1, 49, 49), bank.bar.reshape(-1, 49, 49), bank.log[None]])
    for kernel in zero_mean.astype(np.float64):
        assert abs(kernel.sum()) < 1e-6 * np.abs(kernel).sum()
        assert np.abs(kernel).sum() == pytest.approx(1.0, abs=1e-6)
    gaussian = bank.gaussian.astype(np.float64)
    assert (gaussian >= 0).all()
    assert gaussian.sum() == pytest.approx(1.0, abs=1e-6)


def test_circular_kernels_vanish_outside_the_inscribed_disc():
    offsets = np.arange(-24, 25)
    outside = offsets[:, None] ** 2 + offsets[None, :] ** 2 > 24**2
    assert (mr8_filters().stack()[:, outside] == 0).all()
    assert (mr8_filters(circular=False).stack()[:, outside] != 0).any()


def test_edge_filter_at_zero_degrees_detects_edges_along_the_rows():
    # long axis along the columns, derivative across it (down the rows)
    kernel = mr8_filters().edge[0, 0].astype(np.float64)
    step = np.zeros((49, 49))
    step[25:] = 1.0
    along_rows = (kernel * step).sum()
    along_cols = (kernel * step.T).sum()
    assert abs(along_rows) > 0.3
    assert abs(along_cols) < 1e-6


def test_orientations_ninety_degrees_apart_are_exact_rot90s():
    bank = mr8_filters()
    for kernels in (bank.edge, bank.bar):
        for scale in range(3):
            for j in range(3):
                # np.rot90 turns counter-clockwise as displayed, like the orientations
                np.testing.assert_allclose(np.rot90(kernels[scale, j]), kernels[scale, j + 3], rtol=0, atol=1e-7)


# Cubic interpolation cannot reproduce a finely sampled derivative of a sigma = 1
# Gaussian (its profile is barely above the Nyquist limit), so the tolerance grows as the
# scale shrinks; a wrong angle gives errors above 0.7 (checked below).
ROTATION_TOLERANCE = {0: 0.25, 1: 0.08, 2: 0.05}


@pytest.mark.parametrize("scale", [0, 1, 2])
def test_orientations_are_rotations_of_each_other(scale):
    bank = mr8_filters()
    pad = 8  # so the rim does not meet warpAffine's border
    for kernels in (bank.edge, bank.bar):
        base = np.pad(kernels[scale, 0].astype(np.float64), pad)
        for j in range(1, 6):
            turned = rotate(base, 30 * j)[pad:-pad, pad:-pad]
            target = kernels[scale, j]
            error = np.linalg.norm(turned - target) / np.linalg.norm(target)
            assert error < ROTATION_TOLERANCE[scale], (scale, j, error)
            wrong = kernels[scale, (j + 1) % 6]
            assert np.linalg.norm(turned - wrong) / np.linalg.norm(wrong) > 0.7


def test_isotropic_filters_are_rotation_symmetric():
    bank = mr8_filters()
    for kernel in (bank.gaussian, bank.log):
        np.testing.assert_allclose(np.rot90(kernel), kernel, atol=1e-9)
        np.testing.assert_allclose(kernel.T, kernel, atol=1e-9)


@pytest.mark.parametrize("support", [0, 2, 48, -1, 3.0, "49", True])
def test_bad_support_is_named(support):
    with pytest.raises(ValueError, match="support: got"):
        mr8_filters(support)


# --- the responses -----------------------------------------------------------------


@pytest.mark.parametrize("standardise", [True, False])
def test_responses_match_the_naive_twin(standardise):
    image = smooth_texture((37, 52), seed=3) * 40 + 100  # not square: catches row/col swaps
    got = mr8_responses(image, standardise=standardise)
    assert got.shape == (37, 52, 8)
    assert got.dtype == np.float32
    expected = mr8_responses_naive(image, mr8_filters(), standardise=standardise)
    # float32 filtering through a DFT: errors of a few float32 ulps of the image scale
    scale = np.abs(expected).max()
    np.testing.assert_allclose(got, expected, rtol=0, atol=2e-5 * scale)


@pytest.mark.parametrize("shape", [(1, 1), (1, 9), (2, 3), (5, 7), (6, 60), (48, 50)])
def test_images_smaller_than_the_kernels_are_reflected_too(shape):
    # the reflection repeats when the kernel overhangs the image more than once
    image = np.random.default_rng(4).random(shape)
    got = mr8_responses(image, standardise=False)
    np.testing.assert_allclose(got, mr8_responses_naive(image, mr8_filters(), standardise=False), atol=1e-5)


def test_uint8_and_float_images_give_the_same_standardised_responses():
    image = (np.random.default_rng(5).random((30, 30)) * 255).astype(np.uint8)
    as_uint8 = mr8_responses(image)
    as_unit = mr8_responses(image / 255.0)
    np.testing.assert_allclose(as_uint8, as_unit, atol=1e-5)
    # and brightness or contrast changes do not matter
    np.testing.assert_allclose(mr8_responses(image * 3.0 + 7.0), as_uint8, atol=1e-5)


def test_a_constant_image_responds_only_through_the_gaussian():
    flat = mr8_responses(np.full((20, 30), 7.0), standardise=False)
    np.testing.assert_allclose(flat[:, :, :6], 0, atol=1e-5)
    np.testing.assert_allclose(flat[:, :, 6], 7.0, rtol=1e-5)
    np.testing.assert_allclose(flat[:, :, 7], 0, atol=1e-5)
    np.testing.assert_allclose(mr8_responses(np.full((20, 30), 7.0)), 0, atol=1e-6)


def test_responses_do_not_depend_on_opencv_threads():
    image = smooth_texture((200, 260), seed=6)
    threads = cv2.getNumThreads()
    try:
        cv2.setNumThreads(1)
        single = mr8_responses(image)
    finally:
        cv2.setNumThreads(threads)
    np.testing.assert_array_equal(mr8_responses(image), single)


@pytest.mark.parametrize("turns", [1, 2, 3])
def test_responses_are_invariant_to_quarter_turns(turns):
    # np.rot90 moves pixels exactly and maps the six orientations onto themselves (an
    # edge filter turned past 180° onto its negation, which the absolute value absorbs),
    # so the responses must rotate with the image up to float32 DFT rounding.
    image = smooth_texture((64, 80), seed=7)
    responses = mr8_responses(image)
    turned = mr8_responses(np.rot90(image, turns))
    np.testing.assert_allclose(turned, np.rot90(responses, turns), rtol=0, atol=1e-5)


def test_responses_are_invariant_to_mirroring():
    # a mirror maps orientation theta to -theta, again one of the six
    image = smooth_texture((64, 80), seed=8)
    responses = mr8_responses(image)
    np.testing.assert_allclose(mr8_responses(image[:, ::-1]), responses[:, ::-1], atol=1e-5)
    np.testing.assert_allclose(mr8_responses(image[::-1]), responses[::-1], atol=1e-5)


def _rotation_errors(image, degrees):
    """RMS error, relative to RMS response, per channel over the central 48 x 48 pixels.

    Compares the responses of the rotated image with the rotated responses of the image,
    far enough from the border (image half-width 112, kernel radius 24 at up to sqrt 2
    times that after rotation) that neither the rotation's empty corners nor the mirrored
    border reach the compared pixels.
    """
    responses = mr8_responses(image, standardise=False)
    turned = mr8_responses(rotate(image, degrees), standardise=False)
    expected = rotate_channels(responses, degrees)
    centre = image.shape[0] // 2
    window = np.s_[centre - 24 : centre + 24, centre - 24 : centre + 24]
    got, want = turned[window], expected[window]
    return np.sqrt(((got - want) ** 2).mean(axis=(0, 1))) / np.sqrt((want**2).mean(axis=(0, 1)))


def test_responses_are_nearly_invariant_to_a_30_degree_turn():
    # 30° maps the six orientations onto themselves, so only interpolation differs: bicubic
    # resampling of the image before filtering versus of the responses after it. That
    # costs most at the finest scale, whose sigma = 1 derivatives see the interpolation's
    # blur (measured: 8% edge, 16% bar), little at the coarser ones (<= 5%) and under 2%
    # for the isotropic filters.
    image = smooth_texture((224, 224), seed=9)
    errors = _rotation_errors(image, 30)
    tolerance = np.array([0.15, 0.08, 0.05, 0.25, 0.08, 0.05, 0.03, 0.03])
    assert (errors < tolerance).all(), dict(zip(MR8_CHANNELS, errors.round(3)))


def test_responses_are_roughly_invariant_to_a_45_degree_turn_and_single_filters_are_not():
    # 45° falls halfway between the sampled orientations (15° from the nearest), so the
    # maximum over orientations now misses part of the peak: the more elongated and
    # orientation selective the filter, the more (measured up to 33% RMS for the coarsest
    # bar). The isotropic channels stay within interpolation error.
    image = smooth_texture((224, 224), seed=9)
    errors = _rotation_errors(image, 45)
    assert (errors[:6] < 0.4).all(), dict(zip(MR8_CHANNELS, errors.round(3)))
    assert (errors[6:] < 0.03).all(), dict(zip(MR8_CHANNELS, errors.round(3)))

    # a single oriented filter is far from invariant, so the tolerance above is not vacuous
    kernel = mr8_filters().bar[2, 0]
    single = cv2.filter2D(image.astype(np.float32), cv2.CV_32F, kernel, borderType=cv2.BORDER_REFLECT)
    single_turned = cv2.filter2D(
        rotate(image, 45).astype(np.float32), cv2.CV_32F, kernel, borderType=cv2.BORDER_REFLECT
    )
    expected = rotate(single, 45)
    window = np.s_[88:136, 88:136]
    error = np.sqrt(((single_turned[window] - expected[window]) ** 2).mean()) / np.sqrt(
        (expected[window] ** 2).mean()
    )
    assert error > 0.8


# --- normalisation and sampling ----------------------------------------------------


def test_normalisation_is_weber_law_on_the_vector_length():
    responses = np.zeros((2, 3, 8), np.float32)
    responses[0, 0, :2] = [3.0, 4.0]
    out = normalise_responses(responses)
    assert out.dtype == np.float32
    expected = np.array([3.0, 4.0]) * np.log(1 + 5.0 / 0.03) / 5.0
    np.testing.assert_allclose(out[0, 0, :2], expected, rtol=1e-6)
    assert (out[1] == 0).all()  # zero vectors stay zero, no NaN
    np.testing.assert_allclose(np.linalg.norm(out[0, 0]), np.log(1 + 5.0 / 0.03), rtol=1e-6)


def test_normalisation_matches_the_naive_twin():
    responses = mr8_responses(smooth_texture((20, 25), seed=10))
    responses[3, 4] = 0
    np.testing.assert_allclose(
        normalise_responses(responses), normalise_responses_naive(responses), rtol=1e-5, atol=1e-7
    )
    np.testing.assert_allclose(
        normalise_responses(responses, scale=0.5),
        normalise_responses_naive(responses, scale=0.5),
        rtol=1e-5,
        atol=1e-7,
    )


@pytest.mark.parametrize("scale", [0, -0.1, np.nan, "0.03"])
def test_bad_normalisation_scale_is_named(scale):
    with pytest.raises(ValueError, match="scale: got"):
        normalise_responses(np.ones((2, 8)), scale=scale)


# --- validation --------------------------------------------------------------------


def test_colour_images_are_refused_with_a_hint():
    with pytest.raises(ValueError, match=r"image: got shape \(10, 12, 3\).*grayscale"):
        mr8_responses(np.zeros((10, 12, 3)))


@pytest.mark.parametrize(
    ("image", "message"),
    [
        (np.zeros(10), r"image: got shape \(10,\)"),
        (np.zeros((0, 4)), r"image: got shape \(0, 4\), expected a non-empty"),
        (np.zeros((4, 4), bool), "image: got dtype bool"),
        (np.zeros((4, 4), complex), "image: got dtype complex128"),
        (np.full((4, 4), np.nan), "image: contains NaN"),
    ],
)
def test_bad_images_are_named(image, message):
    with pytest.raises(ValueError, match=message):
        mr8_responses(image)


def test_bad_filters_are_named():
    with pytest.raises(ValueError, match="filters: got ndarray"):
        mr8_responses(np.zeros((4, 4)), filters=mr8_filters().stack())
