"""Grid ORB: ORB descriptors at every point of a regular grid, whatever the image holds.

The paper's Table 1 gives Montreal1 (1024 x 1024 px, a texton word at every pixel)
3,239,631 words, so about 2.19 M of them, 68 %, are ORB words: two per pixel. Keypoint
ORB (:func:`curiosity_cli.words.orb.detect_orb`) gives 9 % on a real 1024 x 1024 aerial
photograph, and 13 % even at FAST threshold 2, so Table 1's density cannot come from
keypoints. The authors' word extractor (``rost_vision/src/bow.cpp`` of
yogeshgirdhar/rost-ros) can put ORB words where no corner is: besides keypoint ORB it has
a ``Dense`` detector (``use_dense``, ``bow.cpp:342``, ``feature_detector.hpp:82-83``),
OpenCV 2's ``DenseFeatureDetector(32, 1, 0.1, 16, 32)``: keypoints every 16 px, one
scale, none within 32 px of the image border, oriented by the intensity centroid of
their 31 px patch (``feature_detector.hpp:112-116``, ``:8-62``) and described by ORB
(``bow.cpp:248``). (Its ``grid_orb``, ``visualwords.xml:8-9``, is another thing: ORB
keypoints capped per cell of a 2 x 2 and a 3 x 3 partition of the image,
``GridAdaptedFeatureDetector``, ``feature_detector.hpp:70-77``; our ``orb_per_tile``
is that kind of cap.)

:func:`grid_orb` does what ``Dense`` does, at one scale as it does, with the grid's
step a parameter, so that a map can reach Table 1's density; it differs in two ways,
both so that every cell of a map gets the same number of ORB words:

- the grid starts half a step from the map's corner (a point at the centre of every
  ``step`` x ``step`` tile from (0, 0)), not 32 px in;
- the map is padded by reflection first, as :func:`~curiosity_cli.words.orb.detect_orb`
  pads it, so points near the border get descriptors too; their patches partly see
  mirrored pixels.

Positions are (row, col) image pixels; OpenCV's (x, y) appears only inside
:func:`_describe`.
"""

from __future__ import annotations

import math

import numpy as np

from curiosity_cli.checks import as_uint8, check_int
from curiosity_cli.errors import ParameterError
from curiosity_cli.words.hamming import DESCRIPTOR_BYTES
from curiosity_cli.words.orb import EDGE_THRESHOLD, PATCH_SIZE, OrbFeatures, orb_extractor

# Pixels of reflection around the map: OpenCV's ORB describes no point within its edge
# threshold (31 px) of the image it is given; one more keeps the last row and column in.
_PAD = EDGE_THRESHOLD + 1

# Most grid points described in one OpenCV call: bounds memory (OpenCV keypoint objects).
_BAND_POINTS = 1 << 18


def grid_points(shape: tuple[int, int], step: int) -> tuple[np.ndarray, np.ndarray]:
    """The rows and the columns of a map's grid points.

    Parameters
    ----------
    shape : (int, int)
        The map's rows and columns of pixels, each >= 1.
    step : int
        Pixels between neighbouring points, >= 1.

    Returns
    -------
    rows : (R,) int64
        ``step // 2, step // 2 + step, ...`` below ``shape[0]``: the centre (for an even
        step, the pixel below and right of it) of every ``step``-px band from row 0.
    cols : (C,) int64
        The same for the columns. The grid is every (row, col) pair: ``R * C`` points.
        ``R = ceil((shape[0] - step // 2) / step)``; a partial band at the far border
        has a point when it reaches past ``step // 2``.

    Raises
    ------
    ParameterError
        A step below 1, or an empty shape.
    """
    step = check_int("step", step, 1)
    height, width = (int(n) for n in shape)
    if height < 1 or width < 1:
        raise ParameterError(f"shape: got {tuple(shape)}, expected (rows, cols) with both >= 1")
    return np.arange(step // 2, height, step, dtype=np.int64), np.arange(step // 2, width, step, dtype=np.int64)


def _circle_half_widths(radius: int) -> np.ndarray:
    """Half width (in columns) of ORB's circular patch at each row offset 0..radius.

    ORB's orientation sums a disc of radius 15 (a 31 px patch); OpenCV computes the half
    widths by rounding the circle up to 45 degrees and mirroring the rest so the disc is
    symmetric under a quarter turn. The same rule here, so angles are OpenCV's.
    """
    half_widths = np.zeros(radius + 1, np.int64)
    v_max = math.floor(radius * math.sqrt(2) / 2 + 1)
    v_min = math.ceil(radius * math.sqrt(2) / 2)
    for v in range(v_max + 1):
        half_widths[v] = round(math.sqrt(radius * radius - v * v))
    u = 0
    for v in range(radius, v_min - 1, -1):
        while half_widths[u] == half_widths[u + 1]:
            u += 1
        half_widths[v] = u
        u += 1
    return half_widths


def _patch_angles(image_gray: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """ORB's orientation of the 31 px patch around each point: the angle of its intensity centroid.

    Parameters
    ----------
    image_gray : (H, W) uint8 ndarray
        Grey image; every point's disc of radius 15 lies inside it.
    rows, cols : (N,) int64 ndarray
        Points, at least 15 px from every border.

    Returns
    -------
    (N,) float32 ndarray
        Degrees in [0, 360): ``atan2(m_01, m_10)`` of the disc's first moments about
        the point, ``m_01`` along rows (down is positive), ``m_10`` along columns, by
        OpenCV's ``fastAtan2`` (as its ORB keypoints' ``angle``).
    """
    import cv2

    radius = PATCH_SIZE // 2
    half_widths = _circle_half_widths(radius)
    grey = image_gray.astype(np.int64)
    # prefix sums along each row of I and of col * I, so a row segment's sum and its
    # first moment are two differences each (exact, in integers)
    sums = np.zeros((grey.shape[0], grey.shape[1] + 1), np.int64)
    moments = np.zeros_like(sums)
    np.cumsum(grey, axis=1, out=sums[:, 1:])
    np.cumsum(grey * np.arange(grey.shape[1], dtype=np.int64), axis=1, out=moments[:, 1:])
    m_10 = np.zeros(rows.size, np.int64)
    m_01 = np.zeros(rows.size, np.int64)
    for v in range(-radius, radius + 1):
        d = half_widths[abs(v)]
        r = rows + v
        segment = sums[r, cols + d + 1] - sums[r, cols - d]
        m_10 += moments[r, cols + d + 1] - moments[r, cols - d] - cols * segment
        m_01 += v * segment
    angles = cv2.phase(m_10.astype(np.float32), m_01.astype(np.float32), angleInDegrees=True)
    return angles.reshape(-1)


def _describe(window: np.ndarray, rows: np.ndarray, cols: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """ORB descriptors (N, 32) uint8 of oriented points of a window, one call of OpenCV's ORB."""
    import cv2

    orb = orb_extractor()
    keypoints = [
        cv2.KeyPoint(float(c), float(r), float(PATCH_SIZE), float(a))
        for r, c, a in zip(rows.tolist(), cols.tolist(), angles.tolist())
    ]
    kept, descriptors = orb.compute(window, keypoints)
    if len(kept) != len(keypoints) or descriptors is None:  # the padding keeps every point in
        raise RuntimeError(f"OpenCV's ORB described {len(kept)} of {len(keypoints)} grid points")
    return np.asarray(descriptors, np.uint8).reshape(len(keypoints), DESCRIPTOR_BYTES)


def grid_orb(image_gray, *, step: int) -> OrbFeatures:
    """ORB descriptors of a map at every point of a regular grid, at one scale.

    Every ``step`` px along rows and columns from ``step // 2``
    (:func:`grid_points`), each point is oriented by its patch's intensity centroid
    (:func:`_patch_angles`) and described by OpenCV's ORB at full resolution (pyramid
    level 0, 31 px patch), as the authors' ``Dense`` detector does (see the module
    docstring). The map is padded by 32 px of reflection (OpenCV
    ``BORDER_REFLECT_101``) first, so every grid point gets a descriptor; the
    descriptors of points within 21 px of the border (their orientations: within
    15 px) partly see mirrored pixels. Large maps are described
    in bands of rows; a descriptor sees only its own neighbourhood, so the result is
    the same as one call's.

    Parameters
    ----------
    image_gray : (H, W) uint8 array_like
        Grey image, H, W >= 1.
    step : int
        Pixels between neighbouring grid points, >= 1; 1 describes every pixel.

    Returns
    -------
    OrbFeatures
        ``(rows, cols, descriptors)``: (N,) int32 rows and cols of the ``N = R * C``
        grid points, sorted by row then col, and their (N, 32) uint8 descriptors.

    Raises
    ------
    ParameterError
        Naming the parameter: a wrong image shape or dtype, a step below 1.
    """
    import cv2

    image = as_uint8("image_gray", image_gray, 2, "(H, W)")
    if image.shape[0] == 0 or image.shape[1] == 0:
        raise ParameterError(f"image_gray: got shape {image.shape}, expected (H, W) with H, W >= 1")
    step = check_int("step", step, 1)
    grid_rows, grid_cols = grid_points(image.shape, step)
    if grid_rows.size == 0 or grid_cols.size == 0:  # a map narrower than half a step
        return OrbFeatures(np.empty(0, np.int32), np.empty(0, np.int32), np.empty((0, DESCRIPTOR_BYTES), np.uint8))
    padded = cv2.copyMakeBorder(image, _PAD, _PAD, _PAD, _PAD, cv2.BORDER_REFLECT_101)
    rows_per_band = max(1, _BAND_POINTS // grid_cols.size)
    parts = []
    for first in range(0, grid_rows.size, rows_per_band):
        band = grid_rows[first : first + rows_per_band]
        # window row i is map row band[0] - _PAD + i; a point's map row r is window row r - band[0] + _PAD
        window = padded[band[0] : band[-1] + 1 + 2 * _PAD]
        rows = np.repeat(band, grid_cols.size)
        cols = np.tile(grid_cols, band.size)
        window_rows, window_cols = rows - band[0] + _PAD, cols + _PAD
        angles = _patch_angles(window, window_rows, window_cols)
        parts.append((rows, cols, _describe(window, window_rows, window_cols, angles)))
    return OrbFeatures(
        rows=np.concatenate([p[0] for p in parts]).astype(np.int32),
        cols=np.concatenate([p[1] for p in parts]).astype(np.int32),
        descriptors=np.ascontiguousarray(np.concatenate([p[2] for p in parts])),
    )
