"""aerial-mosaic's trail: one rare, narrow, winding class that must stay on land."""

from __future__ import annotations

import numpy as np

from curiosity_cli.errors import DatasetError

from .texture import smooth_noise

#: Trail geometry: `steps` segments of `step` px. The turn per segment itself does a
#: random walk (N(0, bend_sd) per step, capped at max_turn radians), so the trail bends
#: in long meanders rather than jittering; corner cutting then smooths the polyline.
TRAIL_WALK = {"steps": 30, "step": 32.0, "bend_sd": 0.12, "max_turn": 0.35}
#: Trail half-width in pixels: the trail is 2 * 2 + 1 = 5 px wide.
TRAIL_HALF_WIDTH = 2
#: Light sandy dirt, clearly brighter than every region texture except bright gravel.
TRAIL_COLOUR = (226, 196, 148)


def chaikin(points: np.ndarray, iterations: int) -> np.ndarray:
    """Smooth an open polyline by Chaikin corner cutting (keeps both end points)."""
    for _ in range(iterations):
        a, b = points[:-1], points[1:]
        cut = np.empty((2 * len(a), 2))
        cut[0::2] = 0.75 * a + 0.25 * b
        cut[1::2] = 0.25 * a + 0.75 * b
        points = np.vstack([points[:1], cut, points[-1:]])
    return points


def densify(points: np.ndarray, spacing: float) -> np.ndarray:
    """Resample a polyline so consecutive points are at most `spacing` pixels apart."""
    out = [points[:1]]
    for a, b in zip(points[:-1], points[1:]):
        n = max(1, int(np.ceil(np.hypot(*(b - a)) / spacing)))
        t = (np.arange(1, n + 1) / n)[:, None]
        out.append(a + t * (b - a))
    return np.vstack(out)


def trail_candidate(shape: tuple[int, int], rng: np.random.Generator) -> np.ndarray:
    """Walk a smooth random trail in from a random map edge.

    Returns
    -------
    (n, 2) float64 array of (row, col) points, at most half a pixel apart
    """
    rows, cols = shape
    side = int(rng.integers(4))
    along = rng.uniform(0.25, 0.75)
    start = [(0.0, along * cols), (along * rows, cols - 1.0), (rows - 1.0, along * cols), (along * rows, 0.0)][side]
    centre = np.array([rows / 2, cols / 2])
    to_centre = centre - start
    heading = np.arctan2(to_centre[0], to_centre[1]) + rng.normal(0, 0.4)
    points = [np.array(start)]
    turn = 0.0
    for _ in range(TRAIL_WALK["steps"]):
        turn = np.clip(
            turn + rng.normal(0.0, TRAIL_WALK["bend_sd"]),
            -TRAIL_WALK["max_turn"],
            TRAIL_WALK["max_turn"],
        )
        heading += turn
        step = TRAIL_WALK["step"] * np.array([np.sin(heading), np.cos(heading)])
        nxt = points[-1] + step
        if not (0 <= nxt[0] < rows and 0 <= nxt[1] < cols):
            break
        points.append(nxt)
    return densify(chaikin(np.array(points), 4), 0.5)


def path_mask(shape: tuple[int, int], points: np.ndarray, half_width: int) -> np.ndarray:
    """Rasterise a dense polyline as a band `2 * half_width + 1` pixels wide.

    Returns
    -------
    (rows, cols) bool array
    """
    from scipy import ndimage as ndi

    centre = np.zeros(shape, dtype=bool)
    idx = np.rint(points).astype(int)
    keep = (idx[:, 0] >= 0) & (idx[:, 0] < shape[0]) & (idx[:, 1] >= 0) & (idx[:, 1] < shape[1])
    centre[idx[keep, 0], idx[keep, 1]] = True
    r, c = np.mgrid[-half_width : half_width + 1, -half_width : half_width + 1]
    return ndi.binary_dilation(centre, r**2 + c**2 <= half_width**2 + half_width)


def choose_trail(wet: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Pick the first random trail that stays off `wet` ground and crosses 40-75 % of the map.

    Parameters
    ----------
    wet : (rows, cols) bool array
        Where a trail does not run (water, marsh); a trail may touch it on under 3 % of
        its pixels.
    rng : numpy.random.Generator

    Returns
    -------
    (rows, cols) bool mask of the trail
    """
    for _ in range(500):
        points = trail_candidate(wet.shape, rng)
        span = max(np.ptp(points, axis=0) / wet.shape)
        if not 0.4 <= span <= 0.75:
            continue
        mask = path_mask(wet.shape, points, TRAIL_HALF_WIDTH)
        if wet[mask].mean() < 0.03:
            return mask
    raise DatasetError("no trail candidate stayed on land; change SEED or the trail settings")


def trail_texture(mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Light dirt: a sandy colour with fine grain and mottling, darker toward the edges."""
    from scipy import ndimage as ndi

    grain = 0.07 * rng.standard_normal(mask.shape) + 0.06 * smooth_noise(mask.shape, 6.0, rng)
    edge = ndi.distance_transform_edt(mask)
    shade = 0.86 + 0.14 * np.clip(edge / (TRAIL_HALF_WIDTH + 1), 0.0, 1.0)
    base = np.array(TRAIL_COLOUR) / 255.0
    return np.clip(base * (shade * (1.0 + grain))[..., None], 0.0, 1.0)
