"""Image quilting: a large texture grown from random crops of a small photo (Efros & Freeman, 2001)."""

from __future__ import annotations

import numpy as np

from .texture import random_crop


def min_cut(error: np.ndarray) -> np.ndarray:
    """Find the cheapest top-to-bottom seam through an error strip by dynamic programming.

    Parameters
    ----------
    error : (rows, width) float array
        Squared difference between two overlapping patches.

    Returns
    -------
    (rows,) int array: for each row, the column where the seam passes
    """
    rows, width = error.shape
    # Infinite columns either side spare the edge cases of the three-way minimum.
    cost = np.full((rows, width + 2), np.inf)
    cost[:, 1:-1] = error
    for r in range(1, rows):
        prev = cost[r - 1]
        cost[r, 1:-1] += np.minimum(np.minimum(prev[:-2], prev[1:-1]), prev[2:])
    seam = np.empty(rows, dtype=int)
    seam[-1] = int(np.argmin(cost[-1, 1:-1]))
    for r in range(rows - 2, -1, -1):
        c = seam[r + 1] + 1  # column in the padded array
        seam[r] = c - 2 + int(np.argmin(cost[r, c - 1 : c + 2]))
    return seam


def quilt(
    source: np.ndarray,
    shape: tuple[int, int],
    rng: np.random.Generator,
    patch: int,
    overlap: int,
    transpose: bool = True,
    candidates: int = 16,
) -> np.ndarray:
    """Synthesise a large texture from random crops of `source` by image quilting.

    Patches are laid in raster order, overlapping their upper and left neighbours by
    `overlap` pixels. Each is the best of `candidates` random crops (randomly flipped or
    rotated) at matching what is already there, and is joined along the cheapest seam
    through the overlap, softened over a pixel or two (Efros & Freeman, 2001). Matching
    keeps structures such as brick courses continuous; the seams avoid both the ghosting
    of feathered blends and the visible repetition of tiling a small source.

    Parameters
    ----------
    source : (rows, cols[, channels]) float array, at least `patch` on each side
    shape : (rows, cols)
    rng : numpy.random.Generator
    patch, overlap : int
        Patch side and overlap in pixels.
    transpose : bool
        Whether patches may be transposed (off for textures with a preferred direction).
    candidates : int
        Random crops tried per patch.

    Returns
    -------
    float64 array of shape `shape` (+ channels)
    """
    from scipy import ndimage as ndi

    rows, cols = shape
    step = patch - overlap
    n_r, n_c = max(1, int(np.ceil((rows - overlap) / step))), max(1, int(np.ceil((cols - overlap) / step)))
    canvas = np.zeros((n_r * step + overlap, n_c * step + overlap) + source.shape[2:])
    for i in range(n_r):
        for j in range(n_c):
            window = (slice(i * step, i * step + patch), slice(j * step, j * step + patch))
            existing = canvas[window]
            known = np.zeros((patch, patch), dtype=bool)
            known[:overlap, :] |= i > 0
            known[:, :overlap] |= j > 0
            best, best_error = None, np.inf
            for _ in range(candidates if known.any() else 1):
                piece = random_crop(source, (patch, patch), rng, transpose)
                error = float(np.sum((piece - existing)[known] ** 2))
                if error < best_error:
                    best, best_error = piece, error
            take = np.ones((patch, patch))
            diff = (best - existing) ** 2
            if diff.ndim == 3:
                diff = diff.sum(axis=2)
            if j > 0:  # keep the old pixels left of the seam through the left overlap
                seam = min_cut(diff[:, :overlap])
                take[:, :overlap][np.arange(overlap)[None, :] < seam[:, None]] = 0.0
            if i > 0:  # and above the seam through the top overlap
                seam = min_cut(diff[:overlap, :].T)
                take[:overlap, :][np.arange(overlap)[:, None] < seam[None, :]] = 0.0
            # Soften the seam, but only where there is something to blend with.
            take = np.where(known, ndi.gaussian_filter(take, 1.0, mode="nearest"), 1.0)
            if take.ndim < best.ndim:
                take = take[..., None]
            canvas[window] = take * best + (1.0 - take) * existing
    return canvas[:rows, :cols]
