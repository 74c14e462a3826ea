"""Clean-up of label maps: merging small regions, opening thin features away."""

from __future__ import annotations

import numpy as np


def majority_merge_small(labels: np.ndarray, min_area: int, n_classes: int) -> np.ndarray:
    """Merge every connected region smaller than `min_area` pixels into its neighbours' majority.

    Regions are visited from the smallest up and each takes the most common label on
    its one-pixel outer ring; a few passes settle chains of small regions.

    Parameters
    ----------
    labels : (rows, cols) integer array
    min_area : int
    n_classes : int

    Returns
    -------
    (rows, cols) array, same dtype
    """
    from scipy import ndimage as ndi

    labels = labels.copy()
    ring_structure = np.ones((3, 3), dtype=bool)
    for _ in range(4):
        small = []
        for k in range(n_classes):
            components, count = ndi.label(labels == k)
            if count == 0:
                continue
            sizes = np.bincount(components.ravel())
            for index, box in enumerate(ndi.find_objects(components), start=1):
                if sizes[index] < min_area:
                    small.append((sizes[index], k, index, box, components))
        if not small:
            break
        small.sort(key=lambda item: item[:3])
        for _, k, index, box, components in small:
            # Grow the bounding box by one pixel so the ring fits inside it.
            box = tuple(slice(max(0, s.start - 1), s.stop + 1) for s in box)
            region = components[box] == index
            ring = ndi.binary_dilation(region, ring_structure) & ~region
            around = labels[box][ring]
            if around.size:
                labels[box][region] = np.bincount(around, minlength=n_classes).argmax()
    return labels


def open_classes(labels: np.ndarray, n_classes: int, radius: int) -> np.ndarray:
    """Morphologically open each class, then give the freed pixels their nearest class.

    Opening removes features thinner than ``2 * radius + 1`` pixels (single noisy
    pixels, mixed-pixel fringes) without shifting the boundaries of larger regions.

    Parameters
    ----------
    labels : (rows, cols) integer array
    n_classes : int
    radius : int
        Radius of the disk structuring element.

    Returns
    -------
    (rows, cols) array, same dtype
    """
    from scipy import ndimage as ndi

    r, c = np.mgrid[-radius : radius + 1, -radius : radius + 1]
    disk = r**2 + c**2 <= radius**2
    kept = np.zeros(labels.shape, dtype=bool)
    for k in range(n_classes):
        kept |= ndi.binary_opening(labels == k, disk)
    _, (near_r, near_c) = ndi.distance_transform_edt(~kept, return_indices=True)
    return labels[near_r, near_c]
