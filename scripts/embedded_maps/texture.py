"""Texture helpers shared by the map builders: smooth noise, tone and colour, shrinking, random crops."""

from __future__ import annotations

import numpy as np


def bspline_upsampler(length: int, scale: float) -> np.ndarray:
    """Matrix that samples a cubic B-spline through coarse nodes at every output pixel.

    Output pixel ``i`` sits at coarse coordinate ``1 + i / scale``; the coarse grid has
    ``ceil(length / scale) + 3`` nodes, one spare each side for the spline's support.

    Returns
    -------
    (length, nodes) float64 array whose rows sum to 1
    """
    nodes = int(np.ceil(length / scale)) + 3
    x = 1.0 + np.arange(length) / scale
    base = np.floor(x).astype(int)
    t = x - base
    weights = [(1 - t) ** 3 / 6, (3 * t**3 - 6 * t**2 + 4) / 6, (-3 * t**3 + 3 * t**2 + 3 * t + 1) / 6, t**3 / 6]
    matrix = np.zeros((length, nodes))
    for k, w in enumerate(weights):
        matrix[np.arange(length), base - 1 + k] = w
    return matrix


def smooth_noise(shape: tuple[int, int], scale: float, rng: np.random.Generator) -> np.ndarray:
    """Return a smooth random field with zero mean and unit standard deviation.

    White noise on a coarse grid (one node per `scale` pixels) is blurred a little and
    then interpolated by a cubic B-spline, which is far cheaper than blurring full-size
    noise with a kernel `scale` pixels wide.

    Parameters
    ----------
    shape : (rows, cols)
    scale : float
        Typical feature size in pixels.
    rng : numpy.random.Generator

    Returns
    -------
    (rows, cols) float64 array
    """
    from scipy import ndimage as ndi

    up_rows, up_cols = bspline_upsampler(shape[0], scale), bspline_upsampler(shape[1], scale)
    coarse = ndi.gaussian_filter(rng.standard_normal((up_rows.shape[1], up_cols.shape[1])), 0.6, mode="wrap")
    field = up_rows @ coarse @ up_cols.T
    return (field - field.mean()) / field.std()


def robust_unit(image: np.ndarray, low: float = 1.0, high: float = 99.0) -> np.ndarray:
    """Stretch an array linearly so its `low` and `high` percentiles map to 0 and 1, clipped.

    Parameters
    ----------
    image : ndarray
    low, high : float
        Percentiles, in percent.

    Returns
    -------
    float64 ndarray, same shape, values in [0, 1]
    """
    lo, hi = np.percentile(image, [low, high])
    return np.clip((image.astype(np.float64) - lo) / (hi - lo), 0.0, 1.0)


def colour_ramp(gray: np.ndarray, stops: list[tuple[float, tuple[int, int, int]]]) -> np.ndarray:
    """Tint a gray image in [0, 1] by piecewise-linear interpolation between RGB colours.

    Parameters
    ----------
    gray : (rows, cols) float array in [0, 1]
    stops : list of (position, (r, g, b))
        Increasing positions in [0, 1] and 0-255 colours.

    Returns
    -------
    (rows, cols, 3) float64 array in [0, 1]
    """
    positions = np.array([p for p, _ in stops])
    colours = np.array([c for _, c in stops], dtype=np.float64) / 255.0
    return np.stack([np.interp(gray, positions, colours[:, k]) for k in range(3)], axis=-1)


def to_uint8(image: np.ndarray) -> np.ndarray:
    """Convert a float image in [0, 1] to uint8 with rounding.

    All the arithmetic before this is float64, so the last-bit differences between
    machines' vectorised maths stay some 1e-13 away from moving a value across a
    rounding boundary, and the PNGs come out bit for bit the same.
    """
    return np.rint(np.clip(image, 0.0, 1.0) * 255.0).astype(np.uint8)


def halve(image: np.ndarray) -> np.ndarray:
    """Shrink an image by 2 in rows and cols by averaging 2 x 2 blocks (no aliasing)."""
    rows, cols = image.shape[0] // 2 * 2, image.shape[1] // 2 * 2
    blocks = image[:rows, :cols].reshape(rows // 2, 2, cols // 2, 2, *image.shape[2:])
    return blocks.mean(axis=(1, 3))


def random_orientation(patch: np.ndarray, rng: np.random.Generator, transpose: bool = True) -> np.ndarray:
    """Apply one of the 8 (or 4 without `transpose`) flips/rotations of a square lattice."""
    if transpose and rng.random() < 0.5:
        patch = np.swapaxes(patch, 0, 1)
    if rng.random() < 0.5:
        patch = patch[::-1]
    if rng.random() < 0.5:
        patch = patch[:, ::-1]
    return patch


def random_crop(
    source: np.ndarray, shape: tuple[int, int], rng: np.random.Generator, transpose: bool = True
) -> np.ndarray:
    """Cut a `shape` window at a random offset from a randomly oriented `source`.

    A source smaller than the window is first extended by mirror reflection, which
    leaves no seam (at worst a line of symmetry).

    Parameters
    ----------
    source : (rows, cols[, channels]) array
    shape : (rows, cols)
    rng : numpy.random.Generator
    transpose : bool
        Whether the orientation may swap rows and columns.

    Returns
    -------
    array of shape `shape` (+ channels)
    """
    source = random_orientation(source, rng, transpose)
    rows, cols = shape
    pad_r, pad_c = max(0, rows - source.shape[0]), max(0, cols - source.shape[1])
    if pad_r or pad_c:
        pad = [(0, pad_r), (0, pad_c)] + [(0, 0)] * (source.ndim - 2)
        source = np.pad(source, pad, mode="symmetric")
    r0 = int(rng.integers(0, source.shape[0] - rows + 1))
    c0 = int(rng.integers(0, source.shape[1] - cols + 1))
    return source[r0 : r0 + rows, c0 : c0 + cols]
