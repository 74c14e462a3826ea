"""The MR8 filter bank: a rotation-invariant texture descriptor at every pixel.

The Root Filter Set (RFS) of Varma & Zisserman, derived from the Leung–Malik set, holds
38 filters:

* edge filters (first derivative of an anisotropic Gaussian) and bar filters (second
  derivative) at three scales ``(sigma_long, sigma_short) = (3, 1), (6, 2), (12, 4)``
  pixels, each at six orientations ``0°, 30°, …, 150°`` — 36 filters;
* a Gaussian and a Laplacian of Gaussian, both isotropic with ``sigma = 10`` pixels.

MR8 ("maximum response 8") filters an image with all 38 and keeps, for each of the six
anisotropic groups (edge or bar × scale), only the largest response over orientations,
plus the two isotropic responses: 8 numbers per pixel that do not change when the image
is rotated.

Conventions
-----------
* An orientation ``theta`` is the direction of a filter's long axis, counter-clockwise from
  the column axis as the image is displayed (row 0 at the top); the derivative is taken
  across the long axis, so the ``theta = 0`` edge filter responds to edges that run
  along the rows.
* Responses are correlations, ``response[row, col] = sum kernel[dr + h, dc + h] *
  image[row + dr, col + dc]`` with ``h = support // 2``; the image is mirrored at its
  border (OpenCV's ``BORDER_REFLECT``, ``fedcba|abcdef``).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import cv2
import numpy as np

from curiosity_cli.checks import check_float
from curiosity_cli.errors import ParameterError

#: ``(sigma_long, sigma_short)`` of the three anisotropic scales, in pixels.
SCALES: tuple[tuple[float, float], ...] = ((3.0, 1.0), (6.0, 2.0), (12.0, 4.0))
#: Number of orientations per anisotropic scale, spread evenly over 180°.
N_ORIENTATIONS = 6
#: Sigma of the isotropic Gaussian and Laplacian of Gaussian, in pixels.
ISOTROPIC_SIGMA = 10.0
#: Names of the 8 MR8 channels, in the order of the last axis of :func:`mr8_responses`.
MR8_CHANNELS: tuple[str, ...] = (
    "edge_3x1",
    "edge_6x2",
    "edge_12x4",
    "bar_3x1",
    "bar_6x2",
    "bar_12x4",
    "gaussian_10",
    "log_10",
)
#: Weber-law constant of :func:`normalise_responses` (Varma & Zisserman).
CONTRAST_SCALE = 0.03


@dataclass(frozen=True, eq=False)
class FilterBank:
    """The 38 filters of the Root Filter Set, all read-only float32.

    Attributes
    ----------
    edge : (3, 6, S, S) ndarray
        First-derivative filters, ``edge[scale, orientation]``; zero mean, L1 norm 1.
    bar : (3, 6, S, S) ndarray
        Second-derivative filters, indexed like ``edge``; zero mean, L1 norm 1.
    gaussian : (S, S) ndarray
        Isotropic Gaussian, ``sigma = 10``; non-negative, sums to 1.
    log : (S, S) ndarray
        Isotropic Laplacian of Gaussian, ``sigma = 10``; zero mean, L1 norm 1.
    scales : tuple of (float, float)
        ``(sigma_long, sigma_short)`` of each anisotropic scale, in pixels.
    orientations : (6,) ndarray
        Long-axis orientation of each anisotropic filter, radians, ``k * pi / 6``.
    support : int
        Side ``S`` of every kernel (odd).
    """

    edge: np.ndarray
    bar: np.ndarray
    gaussian: np.ndarray
    log: np.ndarray
    scales: tuple[tuple[float, float], ...]
    orientations: np.ndarray
    support: int

    def stack(self) -> np.ndarray:
        """All 38 kernels as one ``(38, S, S)`` array.

        Order: the 18 edge filters (scale-major, then orientation), the 18 bar filters
        likewise, the Gaussian, the Laplacian of Gaussian.
        """
        s = self.support
        return np.concatenate(
            [
                self.edge.reshape(-1, s, s),
                self.bar.reshape(-1, s, s),
                self.gaussian[None],
                self.log[None],
            ]
        )

    def __len__(self) -> int:
        return self.edge.shape[0] * self.edge.shape[1] * 2 + 2


def mr8_filters(support: int = 49, *, circular: bool = True) -> FilterBank:
    """Build the 38 Root Filter Set kernels from which MR8 is computed.

    Parameters
    ----------
    support : int, default 49
        Side of every (square) kernel in pixels; odd, at least 3. Varma & Zisserman use 49.
    circular : bool, default True
        Zero every kernel outside the disc inscribed in its square. A square support
        truncates an oriented filter's long axis at a different length for every
        orientation (the corners reach further than the sides), so with the disc the six
        orientations of a group are rotations of one another and MR8 is closer to
        rotation invariant. ``False`` keeps the full square, as in the original bank.

    Returns
    -------
    FilterBank
        Read-only float32 kernels.

    Notes
    -----
    Normalisation: the edge, bar and LoG kernels have their mean (over the support)
    subtracted, so a constant image gives zero response, then are divided by their L1
    norm (sum of absolute values), so every kernel has ``sum(abs(k)) == 1`` and its
    response to an image of values in ``[a, b]`` lies within ``[-(b-a)/2, (b-a)/2]``
    for the zero-mean ones. The Gaussian, a smoothing filter, is divided by its sum
    (equal to its L1 norm) and not made zero mean, so its response is a local average.
    """
    if isinstance(support, bool) or not isinstance(support, (int, np.integer)):
        raise ParameterError(f"support: got {support!r}, expected an odd integer >= 3")
    if support < 3 or support % 2 == 0:
        raise ParameterError(f"support: got {support}, expected an odd integer >= 3")
    return _build_filters(int(support), bool(circular))


@functools.lru_cache(maxsize=8)
def _build_filters(support: int, circular: bool) -> FilterBank:
    half = support // 2
    offsets = np.arange(-half, half + 1, dtype=np.float64)
    rows, cols = np.meshgrid(offsets, offsets, indexing="ij")
    if circular:
        inside = rows**2 + cols**2 <= half**2
    else:
        inside = np.ones_like(rows, dtype=bool)

    orientations = np.arange(N_ORIENTATIONS) * (math.pi / N_ORIENTATIONS)
    edge = np.empty((len(SCALES), N_ORIENTATIONS, support, support), np.float32)
    bar = np.empty_like(edge)
    for i, (sigma_long, sigma_short) in enumerate(SCALES):
        for j, theta in enumerate(orientations):
            cos_t, sin_t = _exact_cos_sin(theta)
            # rows point down on screen, so a counter-clockwise angle subtracts row offsets
            along = cols * cos_t - rows * sin_t
            across = cols * sin_t + rows * cos_t
            gauss = np.exp(-0.5 * ((along / sigma_long) ** 2 + (across / sigma_short) ** 2))
            first = -across / sigma_short**2 * gauss
            second = (across**2 / sigma_short**4 - 1.0 / sigma_short**2) * gauss
            edge[i, j] = _zero_mean_unit_l1(first, inside)
            bar[i, j] = _zero_mean_unit_l1(second, inside)

    radius2 = rows**2 + cols**2
    sigma2 = ISOTROPIC_SIGMA**2
    gauss_iso = np.exp(-0.5 * radius2 / sigma2) * inside
    gaussian = (gauss_iso / gauss_iso.sum()).astype(np.float32)
    log = _zero_mean_unit_l1((radius2 / sigma2 - 2.0) / sigma2 * gauss_iso, inside)

    for array in (edge, bar, gaussian, log, orientations):
        array.flags.writeable = False
    return FilterBank(
        edge=edge,
        bar=bar,
        gaussian=gaussian,
        log=log,
        scales=SCALES,
        orientations=orientations,
        support=support,
    )


def _exact_cos_sin(theta: float) -> tuple[float, float]:
    # cos(pi / 2) is 6e-17, not 0: rounding multiples of 90° makes the 90° kernels exact
    # 90° rotations of the 0° ones, hence MR8 exactly invariant under np.rot90.
    quarter = theta / (math.pi / 2)
    if abs(quarter - round(quarter)) < 1e-12:
        return [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)][round(quarter) % 4]
    return math.cos(theta), math.sin(theta)


def _zero_mean_unit_l1(kernel: np.ndarray, inside: np.ndarray) -> np.ndarray:
    kernel = np.where(inside, kernel, 0.0)
    kernel = np.where(inside, kernel - kernel[inside].mean(), 0.0)
    return (kernel / np.abs(kernel).sum()).astype(np.float32)


def mr8_responses(
    image: np.ndarray,
    *,
    standardise: bool = True,
    filters: FilterBank | None = None,
) -> np.ndarray:
    """Filter a grayscale image with the Root Filter Set and keep the 8 MR8 responses.

    Parameters
    ----------
    image : (H, W) ndarray
        Grayscale image, any integer or floating dtype (finite values). Colour images must
        be converted to grayscale by the caller (e.g. ``cv2.cvtColor``).
    standardise : bool, default True
        First shift and scale the image to zero mean and unit standard deviation, as
        Varma & Zisserman do, so responses do not depend on the image's brightness and
        contrast (or on whether it is stored as 0..255 or 0..1) and are on the scale that
        :func:`normalise_responses` assumes. A constant image is only shifted.
    filters : FilterBank, optional
        The bank to use; default ``mr8_filters()`` (49 x 49 kernels).

    Returns
    -------
    (H, W, 8) ndarray of float32
        Per pixel, in the order of :data:`MR8_CHANNELS`: for each edge scale the largest
        absolute response over the six orientations, for each bar scale the largest
        (signed) response over the six orientations, then the Gaussian and the LoG
        responses.

    Notes
    -----
    An edge (odd) filter turned by 180° is the same filter negated, so the six
    orientations over 180° stand for twelve over the full circle, and the maximum
    response over the full circle is the maximum *absolute* response over the six. This
    makes the edge channels invariant to all rotations, including 180°, which a plain
    maximum over the six would not be. A bar (even) filter turned by 180° is unchanged, so
    its maximum is taken on signed responses and keeps the bar's contrast polarity.

    Filtering uses ``cv2.filter2D`` in float32 (OpenCV switches to a DFT for kernels of
    this size): about 0.7 s for a 1024 x 1024 image on one core.
    """
    image = check_image(image)
    if filters is None:
        filters = mr8_filters()
    elif not isinstance(filters, FilterBank):
        raise ParameterError(f"filters: got {type(filters).__name__}, expected a FilterBank from mr8_filters()")
    if standardise:
        # in float64: float32 sums over millions of pixels lose digits
        work = image.astype(np.float64)
        work -= work.mean()
        std = work.std()
        if std > 0:
            work /= std
        work = work.astype(np.float32)
    else:
        work = np.ascontiguousarray(image, dtype=np.float32)

    height, width = work.shape
    out = np.empty((height, width, 8), np.float32)
    scratch = np.empty((height, width), np.float32)
    for group, (bank, absolute) in enumerate(((filters.edge, True), (filters.bar, False))):
        for scale in range(bank.shape[0]):
            best = out[:, :, 3 * group + scale]
            for orientation in range(bank.shape[1]):
                response = _correlate(work, bank[scale, orientation], scratch)
                if absolute:
                    np.abs(response, out=response)
                if orientation == 0:
                    best[...] = response
                else:
                    np.maximum(best, response, out=best)
    out[:, :, 6] = _correlate(work, filters.gaussian, scratch)
    out[:, :, 7] = _correlate(work, filters.log, scratch)
    return out


def _correlate(image: np.ndarray, kernel: np.ndarray, out: np.ndarray) -> np.ndarray:
    # filter2D's default anchor is the centre of an odd kernel and it correlates (does
    # not flip the kernel), as the module docstring states. Its BORDER_REFLECT repeats the
    # reflection as often as needed, so images narrower than the kernel are fine too.
    return cv2.filter2D(image, cv2.CV_32F, kernel, dst=out, borderType=cv2.BORDER_REFLECT)


def normalise_responses(responses: np.ndarray, *, scale: float = CONTRAST_SCALE) -> np.ndarray:
    """Varma & Zisserman's contrast normalisation of filter responses (Weber's law).

    Each pixel's response vector ``F`` of Euclidean norm ``L = ||F||_2`` becomes
    ``F * log(1 + L / scale) / L``: its direction is kept and its length compressed
    logarithmically, so a texture seen at twice the contrast moves only a little in
    response space. A zero vector stays zero (the limit as ``L -> 0``).

    Parameters
    ----------
    responses : (..., C) ndarray
        Filter responses, the last axis being the channels, e.g. ``(H, W, 8)`` from
        :func:`mr8_responses`.
    scale : float, default 0.03
        Weber-law constant, in response units; 0.03 assumes a standardised image and
        L1-normalised filters, as :func:`mr8_responses` produces by default.

    Returns
    -------
    (..., C) ndarray of float32
        The normalised responses (a new array).
    """
    responses = np.asarray(responses)
    if responses.ndim < 1 or responses.shape[-1] < 1:
        raise ParameterError(f"responses: got shape {responses.shape}, expected (..., C) with C >= 1")
    if not (np.issubdtype(responses.dtype, np.floating) or np.issubdtype(responses.dtype, np.integer)):
        raise ParameterError(f"responses: got dtype {responses.dtype}, expected a real numeric dtype")
    scale = check_float("scale", scale, 0, low_open=True)
    # norms in float64 so the log factor is accurate; the result is stored as float32
    work = responses.astype(np.float64)
    length = np.sqrt(np.einsum("...c,...c->...", work, work))[..., None]
    safe = np.where(length > 0, length, 1.0)
    factor = np.where(length > 0, np.log1p(length / scale) / safe, 0.0)
    return (work * factor).astype(np.float32)


def check_image(image: object) -> np.ndarray:
    """Return ``image`` as an ndarray, or raise ParameterError naming it unless it is a finite 2-D real array."""
    image = np.asarray(image)
    if image.ndim != 2:
        hint = " (convert colour images to grayscale first)" if image.ndim == 3 else ""
        raise ParameterError(f"image: got shape {image.shape}, expected a 2-D (H, W) grayscale array{hint}")
    if image.size == 0:
        raise ParameterError(f"image: got shape {image.shape}, expected a non-empty array")
    if image.dtype == bool or not (
        np.issubdtype(image.dtype, np.integer) or np.issubdtype(image.dtype, np.floating)
    ):
        raise ParameterError(f"image: got dtype {image.dtype}, expected an integer or floating dtype")
    if np.issubdtype(image.dtype, np.floating) and not np.isfinite(image).all():
        raise ParameterError("image: contains NaN or infinite values")
    return image
