"""rare-patches: the positive control, a meadow with a few small patches of terrain found nowhere else.

A walker gathers mutual information with the human labels on this map only by finding
the patches: the meadow is one class over 95 % of the pixels, so a labelling that splits
it into topics tells nothing about the labels, and a patch's texture gets a topic of its
own only in a model that has seen it. This is the paper's trail through forest (its
Montreal1) made the whole point of the map, so that a walker steered by surprise has
every chance to lead: if topic perplexity leads nowhere else but here, the pipeline can
see a lead; if not even here, no map of ours could show one.

The design was fixed before any walker ran on it: 512 x 512 px, 32 x 32 cells of
16 px (the paper's aerial cell width), 12 patches of 2 x 2 cells on the cell grid, four
each of gravel, brick and stained tissue (three of scikit-image's permitted photos, the
meadow the fourth), at random cells at least 3 cells from one another and 2 from the
edge.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .legend import MapClass, legend_entries
from .quilting import quilt
from .seeding import stage_rng
from .sources import skimage_photo
from .texture import colour_ramp, halve, random_crop, robust_unit, to_uint8

PATCHES_SHAPE = (512, 512)
PATCHES_CELL = 16
#: Each patch's side in cells, how many of each patch class, and the cells kept free
#: between two patches and from the edge.
PATCH_CELLS = 2
PATCHES_PER_CLASS = 4
PATCH_GAP = 3
PATCH_MARGIN = 2
PATCHES_CLASSES = [
    MapClass("meadow", "#33a02c", "grass photo (scikit-image grass, CC0) quilted and tinted green: 95 % of the map"),
    MapClass("gravel", "#bdbdbd", "4 patches of 2 x 2 cells: gravel photo (scikit-image gravel, CC0) tinted stone grey"),
    MapClass("brick", "#8c510a", "4 patches of 2 x 2 cells: brick photo (scikit-image brick, CC0) tinted terracotta"),
    MapClass("tissue", "#984ea3", "4 patches of 2 x 2 cells: stained tissue micrograph (scikit-image "
             "immunohistochemistry, no known copyright restrictions), grey, tinted violet"),
]
PATCHES_RAMPS = {
    "meadow": [(0.0, (26, 44, 16)), (0.5, (72, 104, 40)), (1.0, (156, 180, 100))],
    "gravel": [(0.0, (52, 50, 48)), (0.5, (138, 134, 126)), (1.0, (222, 218, 208))],
    "brick": [(0.0, (58, 26, 18)), (0.45, (150, 72, 46)), (1.0, (226, 196, 170))],
    "tissue": [(0.0, (40, 20, 56)), (0.5, (120, 80, 150)), (1.0, (230, 210, 240))],
}
PATCHES_PHOTOS = {"meadow": "grass", "gravel": "gravel", "brick": "brick", "tissue": "immunohistochemistry"}

# Stages of rare-patches' random stream (see `stage_rng`).
_PLACES, _TEXTURES = range(2)


def patch_corners(rng: np.random.Generator) -> list[tuple[int, int]]:
    """The top-left cells (row, col) of the patches: drawn one by one, each at least `PATCH_GAP` cells from the others."""
    cells = PATCHES_SHAPE[0] // PATCHES_CELL
    low, high = PATCH_MARGIN, cells - PATCH_MARGIN - PATCH_CELLS
    corners: list[tuple[int, int]] = []
    while len(corners) < PATCHES_PER_CLASS * (len(PATCHES_CLASSES) - 1):
        row, col = (int(v) for v in rng.integers(low, high + 1, size=2))
        # the cells between two patches' nearest edges, along rows or columns
        if all(max(abs(row - r), abs(col - c)) - PATCH_CELLS >= PATCH_GAP for r, c in corners):
            corners.append((row, col))
    return corners


def build_rare_patches(cache: Path) -> tuple[np.ndarray, np.ndarray, list[dict]]:
    """Build rare-patches (module docstring); ``cache`` is unused: every source is bundled with scikit-image."""
    name = "rare-patches"
    rng = stage_rng(name, _TEXTURES)
    tinted = {
        cls: colour_ramp(robust_unit(halve(skimage_photo(photo))), PATCHES_RAMPS[cls])
        for cls, photo in PATCHES_PHOTOS.items()
    }
    image = quilt(tinted["meadow"], PATCHES_SHAPE, rng, patch=128, overlap=32)
    labels = np.zeros(PATCHES_SHAPE, np.uint8)
    side = PATCH_CELLS * PATCHES_CELL
    for index, (row, col) in enumerate(patch_corners(stage_rng(name, _PLACES))):
        cls = 1 + index % (len(PATCHES_CLASSES) - 1)
        r0, c0 = row * PATCHES_CELL, col * PATCHES_CELL
        source = tinted[PATCHES_CLASSES[cls].name]
        image[r0 : r0 + side, c0 : c0 + side] = random_crop(source, (side, side), rng, transpose=cls != 2)
        labels[r0 : r0 + side, c0 : c0 + side] = cls
    return to_uint8(image), labels, legend_entries(PATCHES_CLASSES)
