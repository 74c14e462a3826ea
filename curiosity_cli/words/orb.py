"""ORB words: the map's ORB keypoints, and exact nearest-word assignment.

Paper section 5.1 describes local features with ORB words from a 5000-word vocabulary.
:func:`detect_orb` finds every ORB keypoint (OpenCV) of the map, so their density follows
the image content as in the paper's Table 1 (many on roofs and roads, few on water), or
optionally at most a few per tile, topped up with weak corners so smooth regions get some
too. :func:`curiosity_cli.words.hamming.nearest_binary_words` maps each 256-bit descriptor
to its nearest vocabulary word by Hamming distance. Vocabularies are learned with
:func:`curiosity_cli.words.binary_kmeans.binary_kmeans`.

Positions are (row, col) image pixels; OpenCV's (x, y) appears only inside
:func:`_detect_window`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from curiosity_cli.checks import as_uint8, check_float, check_int
from curiosity_cli.errors import ParameterError
from curiosity_cli.words.hamming import DESCRIPTOR_BYTES

# OpenCV ORB's oriented-BRIEF sampling pattern is defined on a 31 x 31 patch; its edge
# threshold (border where nothing is detected) must cover the patch, so both stay at 31.
PATCH_SIZE = 31
EDGE_THRESHOLD = 31

# Map side (pixels) detected in one OpenCV call: bounds memory on big maps (at FAST
# threshold 1 a textured megapixel yields ~2e5 raw keypoints over 8 pyramid levels).
_BLOCK_SIDE = 2048

# Largest scale of the coarsest pyramid level (OpenCV's defaults: 1.2 ** 7 = 3.6).
_MAX_LEVEL_SCALE = 16.0


class OrbFeatures(NamedTuple):
    """ORB keypoints of a map, sorted by (row, col).

    Attributes
    ----------
    rows : (N,) int32
        Keypoint row, rounded to the nearest pixel, in ``0 .. H-1``.
    cols : (N,) int32
        Keypoint column, rounded to the nearest pixel, in ``0 .. W-1``.
    descriptors : (N, 32) uint8
        Oriented-BRIEF descriptors, one 256-bit string per keypoint.
    """

    rows: np.ndarray
    cols: np.ndarray
    descriptors: np.ndarray


def pad_for_levels(n_levels: int, scale_factor: float) -> int:
    """Pixels of padding around a window so every pyramid level can reach its edge.

    ORB drops keypoints within ``edgeThreshold`` pixels of the border of each pyramid
    level, i.e. ``31 * scale_factor ** level`` pixels of the original image.
    """
    return math.ceil(EDGE_THRESHOLD * scale_factor ** (n_levels - 1)) + 2


def _orb_keypoints(window: np.ndarray, fast_threshold: int, n_levels: int, scale_factor: float):
    """Every ORB keypoint of a grey window (no cap) and its descriptor, from OpenCV."""
    # nfeatures caps keypoints per level by Harris response; above the window's pixel
    # count (level 0 gets the largest share, ~(1 - 1/scale) of it) it never binds, so
    # every keypoint comes back and any selection is ours (per tile) rather than
    # OpenCV's (global).
    area = window.shape[0] * window.shape[1]
    share = (1 - 1 / scale_factor) / (1 - scale_factor**-n_levels) if n_levels > 1 else 1.0
    nfeatures = min(2**30, math.ceil(area / share) + 16)
    orb = orb_extractor(nfeatures=nfeatures, scale_factor=scale_factor, n_levels=n_levels, fast_threshold=fast_threshold)
    return orb.detectAndCompute(window, None)


def orb_extractor(*, nfeatures: int = 1, scale_factor: float = 1.2, n_levels: int = 1, fast_threshold: int = 20):
    """OpenCV's ORB with the settings every ORB word here shares: the 31 px patch and border, the
    two-point BRIEF tests, Harris ranking, from level 0. The other arguments only matter for
    detection (OpenCV's defaults); describing given points needs none of them."""
    import cv2

    return cv2.ORB_create(
        nfeatures=nfeatures,
        scaleFactor=scale_factor,
        nlevels=n_levels,
        edgeThreshold=EDGE_THRESHOLD,
        firstLevel=0,
        WTA_K=2,
        scoreType=cv2.ORB_HARRIS_SCORE,
        patchSize=PATCH_SIZE,
        fastThreshold=fast_threshold,
    )


def _detect_window(
    window: np.ndarray, fast_threshold: int, fill_threshold: int | None, n_levels: int, scale_factor: float
):
    """ORB keypoints of a grey window, each tagged strong (FAST >= ``fast_threshold``)
    or weak (found only at ``fill_threshold``).

    Returns
    -------
    rows, cols : (M,) float64
        Sub-pixel positions in window pixels.
    response : (M,) float32
        Harris response (ORB's ranking score).
    octave : (M,) int32
        Pyramid level.
    weak : (M,) bool
    descriptors : (M, 32) uint8
    """
    import cv2

    lowest = fast_threshold if fill_threshold is None else fill_threshold
    keypoints, descriptors = _orb_keypoints(window, lowest, n_levels, scale_factor)
    m = len(keypoints)
    if m == 0:
        empty = np.empty(0, np.float64)
        return (
            empty,
            empty,
            np.empty(0, np.float32),
            np.empty(0, np.int32),
            np.empty(0, bool),
            np.empty((0, DESCRIPTOR_BYTES), np.uint8),
        )
    weak = np.zeros(m, bool)
    if fill_threshold is not None:
        # FAST at a lower threshold finds a superset of the corners (same positions,
        # orientations, responses and descriptors), so a strong keypoint is one the
        # higher threshold also finds.
        strong, _ = _orb_keypoints(window, fast_threshold, n_levels, scale_factor)
        strong_keys = {(kp.octave, kp.pt) for kp in strong}
        weak = np.fromiter(((kp.octave, kp.pt) not in strong_keys for kp in keypoints), bool, m)
    xy = cv2.KeyPoint_convert(keypoints).astype(np.float64)
    response = np.fromiter((kp.response for kp in keypoints), np.float32, m)
    octave = np.fromiter((kp.octave for kp in keypoints), np.int32, m)
    descriptors = np.asarray(descriptors, np.uint8).reshape(m, DESCRIPTOR_BYTES)
    return xy[:, 1], xy[:, 0], response, octave, weak, descriptors


def _select_per_tile(rows, cols, weak, response, octave, row_sub, col_sub, tile, per_tile):
    """Indices of the ``per_tile`` best keypoints of each tile (all of them for None;
    strong before weak, then by Harris response), and each one's rank within its tile."""
    tile_id = (rows // tile) * (1 << 31) + cols // tile
    # lexsort: the last key sorts first. Sub-pixel positions make the order total.
    order = np.lexsort((col_sub, row_sub, octave, -response, weak, tile_id))
    sorted_tiles = tile_id[order]
    starts = np.flatnonzero(np.r_[True, sorted_tiles[1:] != sorted_tiles[:-1]])
    rank = np.arange(order.size) - np.repeat(starts, np.diff(np.r_[starts, order.size]))
    if per_tile is None:
        return order, rank
    keep = rank < per_tile
    return order[keep], rank[keep]


def detect_orb(
    image_gray,
    *,
    tile: int = 16,
    per_tile: int | None = None,
    max_features: int | None = None,
    fast_threshold: int = 20,
    fill_threshold: int | None = None,
    n_levels: int = 8,
    scale_factor: float = 1.2,
) -> OrbFeatures:
    """ORB keypoints and descriptors of a map: all of them, or at most a few per tile.

    By default (``per_tile`` None) every keypoint OpenCV's ORB finds is kept, at every
    pyramid level, with no cap on their number (OpenCV's own ``nfeatures`` cap keeps
    only the globally strongest): their density follows the image content, dense on
    roofs and roads, sparse or nil on water and sand, as the paper's words were. With
    the other defaults (FAST threshold 20, 8 levels, scale 1.2, 31 px patch and edge,
    Harris score) these are OpenCV's ORB defaults.

    With ``per_tile`` set, the map is cut into ``tile`` x ``tile`` tiles and each tile
    keeps its ``per_tile`` best keypoints: first the corners standard ORB finds (FAST
    threshold ``fast_threshold``), strongest Harris response first; with
    ``fill_threshold`` set, a tile with too few of them is topped up with weaker corners
    found at FAST threshold ``fill_threshold``, again strongest first, so smooth tiles
    (water, sand) still get keypoints; only a perfectly flat tile, with no corner at
    all, gets none. All ``n_levels`` pyramid levels compete in the same tile.

    The image is padded by reflection (OpenCV ``BORDER_REFLECT_101``) before detection,
    so pixels at the map border get keypoints at every pyramid level like the
    interior; keypoints found in the padding are dropped. Patches of keypoints near
    the border partly see mirrored pixels. Maps wider or taller than 2048 px are
    detected in 2048 px blocks with a margin, to bound memory; each keypoint is kept by
    the one block holding its pixel. Level-0 keypoints are those of a single call, but a
    block's coarser pyramid levels are resampled from the block's own origin, so their
    keypoints can differ slightly from a single call's.

    Parameters
    ----------
    image_gray : (H, W) uint8 array_like
        Grey image, H, W >= 1.
    tile : int, default 16
        Side of the tiles in pixels; tiles start at (0, 0). They hold the ``per_tile``
        cap and rank keypoints for ``max_features``. Matching the cell width spreads
        capped keypoints over cells: on the embedded 1024 x 1024 maps, 16 px tiles with
        a top-up put a keypoint in 100 % of 16 px cells, 64 px tiles (16 per tile) in
        about 30 %.
    per_tile : int or None, default None
        Most keypoints kept per tile; None: every keypoint.
    max_features : int or None, default None
        Most keypoints kept in total. When there are more, keypoints are dropped by
        rank within their tile, the best of every tile kept first, so the cap thins
        the densest tiles and keeps the few keypoints of sparse ones: without
        ``per_tile`` it is as if the largest per-tile cap that fits were applied, the
        last rank filled by response. Among equal ranks, strong before weak, then the
        stronger response wins.
    fast_threshold : int, default 20
        FAST intensity threshold (1..255) of the keypoints (with a top-up: of the
        preferred ones); OpenCV's default.
    fill_threshold : int or None, default None
        With ``per_tile``: FAST threshold (1..``fast_threshold``) of the weaker corners
        that top up tiles with fewer than ``per_tile`` preferred ones; None: no top-up.
        Needs ``per_tile``: without a cap there is nothing to top up.
    n_levels : int, default 8
        ORB pyramid levels (1..16, with ``scale_factor ** (n_levels - 1) <= 16``);
        OpenCV's default.
    scale_factor : float, default 1.2
        Pyramid decimation ratio, in (1, 2]; OpenCV's default.

    Returns
    -------
    OrbFeatures
        ``(rows, cols, descriptors)``: (N,) int32 rows, (N,) int32 cols (each keypoint's
        position rounded to the nearest pixel, inside the image) and (N, 32) uint8
        descriptors, sorted by row, then col (then pyramid level and sub-pixel
        position). Several keypoints may share a pixel (different pyramid levels).
        Identical for identical inputs, whatever OpenCV's thread count.

    Raises
    ------
    ValueError
        Naming the parameter, for a wrong image shape or dtype or an out-of-range
        setting.
    """
    image = as_uint8("image_gray", image_gray, 2, "(H, W)")
    height, width = image.shape
    if height == 0 or width == 0:
        raise ParameterError(f"image_gray: got shape {image.shape}, expected (H, W) with H, W >= 1")
    tile = check_int("tile", tile, 1)
    if per_tile is not None:
        per_tile = check_int("per_tile", per_tile, 1)
    if max_features is not None:
        max_features = check_int("max_features", max_features, 1)
    fast_threshold = check_int("fast_threshold", fast_threshold, 1, 255)
    if fill_threshold is not None:
        fill_threshold = check_int("fill_threshold", fill_threshold, 1, fast_threshold)
        if per_tile is None:
            raise ParameterError(
                f"fill_threshold: got {fill_threshold} with per_tile None, expected None: "
                "the top-up only fills tiles capped by per_tile"
            )
        if fill_threshold == fast_threshold:
            fill_threshold = None
    n_levels = check_int("n_levels", n_levels, 1, 16)
    scale_factor = check_float("scale_factor", scale_factor, 1, 2, low_open=True)
    if scale_factor ** (n_levels - 1) > _MAX_LEVEL_SCALE:
        # The padding grows with the coarsest level's scale; past this it dwarfs the map.
        raise ParameterError(
            f"n_levels: got {n_levels} with scale_factor {scale_factor}, expected "
            f"scale_factor ** (n_levels - 1) <= {_MAX_LEVEL_SCALE}"
        )

    import cv2

    pad = pad_for_levels(n_levels, scale_factor)
    padded = cv2.copyMakeBorder(image, pad, pad, pad, pad, cv2.BORDER_REFLECT_101)
    # Blocks are whole tiles, so tile selection can run block by block.
    block = max(tile, (_BLOCK_SIDE // tile) * tile)
    parts = []
    for r0 in range(0, height, block):
        r1 = min(r0 + block, height)
        for c0 in range(0, width, block):
            c1 = min(c0 + block, width)
            window = padded[r0 : r1 + 2 * pad, c0 : c1 + 2 * pad]
            row_sub, col_sub, response, octave, weak, descriptors = _detect_window(
                window, fast_threshold, fill_threshold, n_levels, scale_factor
            )
            row_sub = row_sub + (r0 - pad)
            col_sub = col_sub + (c0 - pad)
            rows = np.rint(row_sub).astype(np.int64)
            cols = np.rint(col_sub).astype(np.int64)
            idx = np.flatnonzero((rows >= r0) & (rows < r1) & (cols >= c0) & (cols < c1))
            chosen, rank = _select_per_tile(
                rows[idx], cols[idx], weak[idx], response[idx], octave[idx], row_sub[idx], col_sub[idx], tile, per_tile
            )
            idx = idx[chosen]
            parts.append(
                (rows[idx], cols[idx], rank, weak[idx], response[idx], octave[idx], row_sub[idx], col_sub[idx], descriptors[idx])
            )
    rows, cols, rank, weak, response, octave, row_sub, col_sub, descriptors = (
        np.concatenate([part[i] for part in parts]) for i in range(9)
    )
    if max_features is not None and rows.size > max_features:
        keep = np.lexsort((col_sub, row_sub, octave, -response, weak, rank))[:max_features]
        rows, cols, octave, row_sub, col_sub, descriptors = (
            a[keep] for a in (rows, cols, octave, row_sub, col_sub, descriptors)
        )
    order = np.lexsort((col_sub, row_sub, octave, cols, rows))
    return OrbFeatures(
        rows=rows[order].astype(np.int32),
        cols=cols[order].astype(np.int32),
        descriptors=np.ascontiguousarray(descriptors[order]),
    )
