"""sentinel-coast: a true-colour Sentinel-2 crop, labelled from bands the image does not show.

The labels are thresholds on spectral indices that all involve near- or short-wave
infrared bands (B08, B11), which the RGB image, and so the visual words, never see.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .label_cleanup import majority_merge_small, open_classes
from .legend import MapClass, legend_entries
from .sources import sentinel_scene, true_colour
from .texture import to_uint8

#: The sentinel-coast crop, (row, col) of its top-left corner in the 10 m scene: sea,
#: barrier beach, inlet, salt marsh, lagoon and farmland with a hamlet in one frame.
COAST_ORIGIN = (300, 480)
COAST_SHAPE = (1024, 1024)

COAST_CLASSES = [
    MapClass("water", "#1f78b4", "sea, inlet, lagoon and tidal channels; MNDWI (B03, B11) at least 0.72"),
    MapClass("salt-marsh", "#cab2d6", "salt marsh and wet shrub; NDVI below 0.30 and dark in SWIR (B11 below 0.12)"),
    MapClass("sand", "#ffe34d", "beach, dunes and sand flats; NDVI below 0.17, MNDWI above -0.38, B11 above 0.12"),
    MapClass("bare-soil", "#bf812d", "ploughed or bare fields, roads and buildings; other pixels with NDVI below 0.35"),
    MapClass(
        "crops-grass", "#a6d96a", "green crops and pasture; NDVI at least 0.35 and bright in SWIR (B11 at least 0.11)"
    ),
    MapClass("woodland", "#1a7837", "woods and hedgerows; NDVI at least 0.35 and dark in SWIR (B11 below 0.11)"),
]

# Label thresholds, all on top-of-atmosphere reflectance (DN / 10000). Each rule uses at
# least one band outside the RGB image (B08 NIR, B11 SWIR); rules later in
# `classify_coast` override earlier ones. The values come from the histograms of pixels
# picked by eye in each cover type (sea, lagoon, marsh, beach, dunes, bare and green
# fields, woods, hamlet) and were then checked against the image side by side.
#: MNDWI = (B03 - B11) / (B03 + B11): sea and lagoon 0.87-0.90, surf 0.78, but flooded
#: marsh reaches 0.5-0.65 (dry marsh 0.1-0.45), so only open water passes 0.72.
COAST_WATER_MNDWI_MIN = 0.72
#: NDVI = (B08 - B04) / (B08 + B04): winter-dormant marsh -0.25-0.0, bare fields
#: 0.15-0.34, green fields 0.5-0.75, woods 0.45-0.7.
COAST_MARSH_NDVI_MAX = 0.30
#: Wet marsh is dark in SWIR (B11 0.03-0.06); bare fields and sand are bright (0.15-0.4).
COAST_MARSH_B11_MAX = 0.12
#: Beach and dune sand: little vegetation (NDVI 0.03-0.16) and, unlike bare fields
#: (MNDWI -0.47 to -0.3), bright in green relative to SWIR (MNDWI -0.37 to -0.07).
COAST_SAND_NDVI_MAX = 0.17
COAST_SAND_MNDWI_MIN = -0.38
COAST_SAND_B11_MIN = 0.12
#: Below this NDVI a pixel that is neither water, marsh nor sand is bare soil or built-up.
COAST_VEGETATION_NDVI_MIN = 0.35
#: Woods (shadowed canopy) are dark in SWIR (B11 0.07-0.09); green crops are 0.15-0.24.
COAST_WOODLAND_B11_MAX = 0.11
#: Clean-up: open each class with a disk of this radius (drops 1-2 px slivers)…
COAST_OPEN_RADIUS = 1
#: …then merge regions smaller than this many pixels (0.64 ha) into their surroundings.
COAST_MIN_REGION = 64


def classify_coast(scene: dict[str, np.ndarray]) -> np.ndarray:
    """Label every pixel of the scene with a `COAST_CLASSES` index by index thresholds.

    Parameters
    ----------
    scene : dict band -> reflectance array, from `sentinel_scene`

    Returns
    -------
    (rows, cols) uint8 array
    """
    b03, b04, b08, b11 = (scene[b] for b in ("B03", "B04", "B08", "B11"))
    ndvi = (b08 - b04) / (b08 + b04)
    mndwi = (b03 - b11) / (b03 + b11)
    k = {c.name: i for i, c in enumerate(COAST_CLASSES)}
    # From the most general rule to the most specific: each overrides the ones above.
    labels = np.full(b08.shape, k["crops-grass"], dtype=np.uint8)
    labels[(ndvi >= COAST_VEGETATION_NDVI_MIN) & (b11 < COAST_WOODLAND_B11_MAX)] = k["woodland"]
    labels[ndvi < COAST_VEGETATION_NDVI_MIN] = k["bare-soil"]
    labels[(ndvi < COAST_MARSH_NDVI_MAX) & (b11 < COAST_MARSH_B11_MAX)] = k["salt-marsh"]
    labels[(ndvi < COAST_SAND_NDVI_MAX) & (mndwi > COAST_SAND_MNDWI_MIN) & (b11 > COAST_SAND_B11_MIN)] = k["sand"]
    labels[mndwi >= COAST_WATER_MNDWI_MIN] = k["water"]
    return labels


def clean_coast_labels(labels: np.ndarray) -> np.ndarray:
    """Apply the `COAST_OPEN_RADIUS` opening and the `COAST_MIN_REGION` merge."""
    opened = open_classes(labels, len(COAST_CLASSES), COAST_OPEN_RADIUS)
    return majority_merge_small(opened, COAST_MIN_REGION, len(COAST_CLASSES))


def build_sentinel_coast(cache: Path) -> tuple[np.ndarray, np.ndarray, list[dict]]:
    """Build sentinel-coast: a true-colour crop and its NIR/SWIR-derived labels.

    The labels are computed on a margin around the crop, so the clean-up near the
    crop's edge sees the same neighbourhood as anywhere else.
    """
    scene = sentinel_scene(str(cache))
    (r0, c0), (rows, cols) = COAST_ORIGIN, COAST_SHAPE
    margin = 32
    window = (slice(r0 - margin, r0 + rows + margin), slice(c0 - margin, c0 + cols + margin))
    labels = clean_coast_labels(classify_coast({b: a[window] for b, a in scene.items()}))
    labels = labels[margin : margin + rows, margin : margin + cols]
    image = true_colour(scene)[r0 : r0 + rows, c0 : c0 + cols]
    return to_uint8(image), labels, legend_entries(COAST_CLASSES)
