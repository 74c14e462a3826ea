"""Colours for topic label maps, and matching one labelling's topics to another's.

Topic ids are arbitrary: topic 3 of a path's model Z_p has nothing to do with topic 3 of
the batch model Z_b. To make two label maps comparable by eye, Z_b's topics take palette
slots in order of size (the largest topic gets the first, most distinct colour), and each
Z_p topic takes the slot of the Z_b topic it is matched to: pairs are matched one to one
so that the matched pairs share as many pixels as can be (the optimal assignment, not a
greedy one). A Z_p topic left without a partner (the path's model split a batch topic in
two, or found one the batch model did not) gets a slot no Z_b topic uses, so splits and
merges stay visible instead of being painted over.

The palette is glasbey-like: colours picked one at a time from a grid of sRGB colours,
each the farthest (in CIELAB) from all colours picked before, so the first colours are the
most distinct. It is computed, not stored, and the same on every machine.
"""

from __future__ import annotations

import functools

import numpy as np

from curiosity_cli.errors import ParameterError

#: Slots the palette offers: enough for a 127-topic Z_b plus 127 unmatched Z_p topics.
PALETTE_SIZE = 256


def _srgb_to_lab(rgb: np.ndarray) -> np.ndarray:
    """(N, 3) sRGB in 0..1 → (N, 3) CIELAB (D65 white)."""
    linear = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    to_xyz = np.array(
        [[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750], [0.0193339, 0.1191920, 0.9503041]]
    )
    xyz = linear @ to_xyz.T / np.array([0.95047, 1.0, 1.08883])
    eps, kappa = 216 / 24389, 24389 / 27
    f = np.where(xyz > eps, np.cbrt(xyz), (kappa * xyz + 16) / 116)
    return np.stack([116 * f[:, 1] - 16, 500 * (f[:, 0] - f[:, 1]), 200 * (f[:, 1] - f[:, 2])], axis=1)


@functools.lru_cache(maxsize=1)
def _palette() -> np.ndarray:
    levels = np.linspace(0, 255, 18).round()  # steps of 15: 5832 candidate colours
    grid = np.stack(np.meshgrid(levels, levels, levels, indexing="ij"), axis=-1).reshape(-1, 3)
    lab = _srgb_to_lab(grid / 255)
    # very dark and very light colours are hard to tell apart from each other and from a page
    keep = (lab[:, 0] >= 25) & (lab[:, 0] <= 92)
    grid, lab = grid[keep], lab[keep]
    # start as if white and black were already picked, as Glasbey et al. seed with the background
    anchors = _srgb_to_lab(np.array([[1.0, 1.0, 1.0], [0.0, 0.0, 0.0]]))
    nearest = np.min(((lab[:, None, :] - anchors[None, :, :]) ** 2).sum(-1), axis=1)
    picked = np.empty(PALETTE_SIZE, np.int64)
    for i in range(PALETTE_SIZE):
        picked[i] = int(np.argmax(nearest))  # ties: the lowest index, so the result is fixed
        nearest = np.minimum(nearest, ((lab - lab[picked[i]]) ** 2).sum(-1))
    palette = grid[picked].astype(np.uint8)
    palette.setflags(write=False)
    return palette


def _sizes(labels: np.ndarray, n: int) -> np.ndarray:
    return np.bincount(labels.ravel(), minlength=n)


def _check_labels(labels: np.ndarray, name: str) -> np.ndarray:
    labels = np.asarray(labels)
    if labels.ndim != 2 or labels.dtype.kind not in "iu":
        raise ParameterError(f"{name}: expected an (H, W) integer array, got {labels.dtype} of shape {labels.shape}")
    if labels.size and labels.min() < 0:
        raise ParameterError(f"{name}: topic ids must be >= 0, got {int(labels.min())}")
    return labels.astype(np.int64, copy=False)


def rank_topics(labels: np.ndarray) -> np.ndarray:
    """Palette slots for one labelling on its own: the largest topic first.

    Parameters
    ----------
    labels : (H, W) integer ndarray
        Topic ids >= 0.

    Returns
    -------
    (labels.max() + 1,) int64 ndarray
        ``slots[t]`` is topic ``t``'s palette slot, -1 for an id absent from ``labels``.
        Equal sizes rank by topic id.
    """
    labels = _check_labels(labels, "labels")
    sizes = _sizes(labels, int(labels.max()) + 1 if labels.size else 0)
    order = np.argsort(-sizes, kind="stable")
    slots = np.full(sizes.size, -1, np.int64)
    present = order[sizes[order] > 0]
    slots[present] = np.arange(present.size)
    return slots


def match_topics(z_p: np.ndarray, z_b: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Palette slots that make a path labelling Z_p comparable with the batch labelling Z_b.

    Z_b's topics are ranked by size (:func:`rank_topics`). Z_p's topics are matched one to
    one with Z_b's so that the matched pairs share the most pixels in total: the optimal
    assignment (:func:`scipy.optimize.linear_sum_assignment`) on the contingency table of
    the topics present in each map. Among matchings that share equally many pixels,
    lower ids win: each pair ``(p, b)`` adds a penalty that grows with ``p``, then with
    ``b``, and all penalties together weigh less than one pixel. A pair that shares no
    pixel is no match. A matched Z_p topic takes its partner's slot, an unmatched one the
    next slot no Z_b topic uses, larger unmatched topics first.

    Parameters
    ----------
    z_p, z_b : (H, W) integer ndarray
        Topic ids >= 0 of the same map.

    Returns
    -------
    slots_p : (z_p.max() + 1,) int64 ndarray
        Palette slot of each Z_p topic id, -1 where absent.
    slots_b : (z_b.max() + 1,) int64 ndarray
        Palette slot of each Z_b topic id, -1 where absent.
    agreement : float
        Fraction of pixels painted the same colour in both maps, 0..1.
    """
    from scipy.optimize import linear_sum_assignment

    from curiosity_cli.evaluate.information import contingency

    z_p = _check_labels(z_p, "z_p")
    z_b = _check_labels(z_b, "z_b")
    if z_p.shape != z_b.shape:
        raise ParameterError(f"z_p is {z_p.shape} but z_b is {z_b.shape}; expected label maps of the same map")
    slots_b = rank_topics(z_b)
    n_p = int(z_p.max()) + 1 if z_p.size else 0
    sizes_p = _sizes(z_p, n_p)
    present_p, present_b = np.flatnonzero(sizes_p), np.flatnonzero(slots_b >= 0)
    overlap = contingency(z_p, z_b, n_p, slots_b.size)[np.ix_(present_p, present_b)]
    # pair (i, j) of the present topics costs -overlap * scale + (i * n + j): a matching's
    # penalties (at most min(r, n) pairs, each below r * n) add up to less than scale, the
    # cost of one pixel. All integers, so exact in float64 while pixels * scale is well
    # below 2**53: with 127 topics a side, for maps up to a gigapixel.
    r, n = overlap.shape
    scale = r * n * min(r, n)
    cost = -overlap.astype(np.float64) * scale + np.arange(r * n).reshape(r, n)
    rows, cols = linear_sum_assignment(cost)
    shared = overlap[rows, cols] > 0
    slots_p = np.full(n_p, -1, np.int64)
    slots_p[present_p[rows[shared]]] = slots_b[present_b[cols[shared]]]
    unmatched = [p for p in np.argsort(-sizes_p, kind="stable") if sizes_p[p] > 0 and slots_p[p] < 0]
    first_free = int(slots_b.max()) + 1 if slots_b.size else 0
    slots_p[unmatched] = first_free + np.arange(len(unmatched))
    agreement = float(np.mean(slots_p[z_p] == slots_b[z_b])) if z_p.size else 1.0
    return slots_p, slots_b, agreement


def paint_topics(labels: np.ndarray, slots: np.ndarray) -> np.ndarray:
    """Paint a topic label map with the palette colours of its topics' slots.

    Parameters
    ----------
    labels : (H, W) integer ndarray
        Topic ids, each with a slot >= 0 in ``slots``.
    slots : (n_ids,) int ndarray
        From :func:`rank_topics` or :func:`match_topics`. Slots beyond the palette wrap
        around (only possible with more than 256 topics in view at once).

    Returns
    -------
    (H, W, 3) uint8 ndarray
        RGB.
    """
    labels = _check_labels(labels, "labels")
    return _palette()[np.asarray(slots)[labels] % PALETTE_SIZE]
