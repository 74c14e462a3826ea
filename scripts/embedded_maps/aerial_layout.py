"""aerial-mosaic's layout: terrain regions on a warped power diagram, one class each."""

from __future__ import annotations

import numpy as np

from .label_cleanup import majority_merge_small
from .texture import smooth_noise


def poisson_sites(shape: tuple[int, int], count: int, min_distance: float, rng: np.random.Generator) -> np.ndarray:
    """Draw up to `count` points at least `min_distance` apart by dart throwing.

    Returns
    -------
    (n, 2) float64 array of (row, col)
    """
    sites: list[np.ndarray] = []
    for _ in range(count * 200):
        candidate = rng.uniform((0.0, 0.0), shape)
        if all(np.hypot(*(candidate - s)) >= min_distance for s in sites):
            sites.append(candidate)
            if len(sites) == count:
                break
    return np.array(sites)


def warped_power_diagram(
    shape: tuple[int, int], sites: np.ndarray, weights: np.ndarray, warps, rng: np.random.Generator
) -> np.ndarray:
    """Partition the map into the power cells of weighted sites, seen through a smooth warp.

    Warping the coordinates (not the cells) bends every border the same smooth way,
    which gives the lobed, irregular outlines of terrain instead of straight edges.

    Parameters
    ----------
    shape : (rows, cols)
    sites : (n, 2) array of (row, col)
    weights : (n,) array
        Power weights in squared pixels; a larger weight grows a larger cell.
    warps : sequence of (scale, amplitude)
    rng : numpy.random.Generator

    Returns
    -------
    (rows, cols) int32 array of site indices
    """
    rows, cols = np.mgrid[0 : shape[0], 0 : shape[1]].astype(np.float64)
    for scale, amplitude in warps:
        rows += amplitude * smooth_noise(shape, scale, rng)
        cols += amplitude * smooth_noise(shape, scale, rng)
    best = np.full(shape, np.inf)
    region = np.zeros(shape, dtype=np.int32)
    for index, ((r, c), w) in enumerate(zip(sites, weights)):
        power = (rows - r) ** 2 + (cols - c) ** 2 - w
        closer = power < best
        best[closer] = power[closer]
        region[closer] = index
    return region


def split_regions(region: np.ndarray, min_area: int) -> np.ndarray:
    """Make every region one connected piece: drop small fragments, renumber from 0.

    Returns
    -------
    (rows, cols) int32 array of region ids 0..n-1
    """
    from scipy import ndimage as ndi

    n = int(region.max()) + 1
    region = majority_merge_small(region, min_area, n)
    pieces = np.zeros(region.shape, dtype=np.int32)
    next_id = 0
    for k in range(n):
        components, count = ndi.label(region == k)
        pieces[components > 0] = components[components > 0] + next_id - 1
        next_id += count
    return pieces


def region_adjacency(region: np.ndarray) -> set[tuple[int, int]]:
    """Return the pairs (a, b), a < b, of regions that share a border."""
    pairs = set()
    for a, b in ((region[:, :-1], region[:, 1:]), (region[:-1, :], region[1:, :])):
        differ = a != b
        for p, q in zip(a[differ].tolist(), b[differ].tolist()):
            pairs.add((min(p, q), max(p, q)))
    return pairs


def assign_classes(region: np.ndarray, n_classes: int, rng: np.random.Generator) -> np.ndarray:
    """Give each region a class, balancing class areas and never repeating a neighbour's.

    Regions are taken from the largest down; each gets, among the classes none of its
    already assigned neighbours has, the one with the least area so far (ties broken at
    random). Neighbours never merge, so every region stays visible as its own patch.

    Returns
    -------
    (n_regions,) int array of class ids
    """
    n = int(region.max()) + 1
    area = np.bincount(region.ravel(), minlength=n)
    neighbours: dict[int, set[int]] = {i: set() for i in range(n)}
    for a, b in region_adjacency(region):
        neighbours[a].add(b)
        neighbours[b].add(a)
    classes = np.full(n, -1)
    class_area = np.zeros(n_classes)
    jitter = rng.random(n_classes) * 1e-3
    for i in np.argsort(-area, kind="stable"):
        taken = {classes[j] for j in neighbours[i] if classes[j] >= 0}
        free = [k for k in range(n_classes) if k not in taken] or list(range(n_classes))
        k = min(free, key=lambda k: class_area[k] + jitter[k])
        classes[i] = k
        class_area[k] += area[i]
    return classes
