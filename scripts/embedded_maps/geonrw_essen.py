"""geonrw-essen: a real 1 m aerial photograph of forest crossed by roads, from GeoNRW.

One GeoNRW tile (Baier et al. 2021), ``essen_360_5693``: 1000 x 1000 px at 1 m, the
square kilometre east 360-361 km, north 5693-5694 km of ETRS89 / UTM zone 32N, which
GeoNRW files under Essen. The photograph is an official orthophoto of North
Rhine-Westphalia (Geobasis NRW). The labels are NOT drawn on these pixels: GeoNRW
rasterised official land-cover vector data of North Rhine-Westphalia, refined with
OpenStreetMap, onto the photograph's grid; roads are fixed-width bands along their
centrelines, so where trees hang over a road the label says road and the photograph shows
canopy.

The tile is read from the sample folder ``geonrw_samples/`` of the public repository
``aniketqxp/carbon-sequestration-index`` at a pinned commit, and each file is checked
against its SHA-256 before use. The JPEG 2000 photograph is lossy (9/7 wavelet), so
another OpenJPEG version may decode it a grey level differently here and there; the
committed PNG is the reference (see data/README.md).
"""

from __future__ import annotations

import hashlib
import io

import numpy as np

from curiosity_cli.errors import DatasetError

from .legend import MapClass, legend_entries

#: The map's name in configs/datasets and data/maps.
NAME = "geonrw-essen"

#: Where the source files are: repository, commit, folder, and tile name.
SOURCE_REPOSITORY = "aniketqxp/carbon-sequestration-index"
SOURCE_COMMIT = "90b45c3af94fa39009eb220531d54133817581ed"
SOURCE_FOLDER = "geonrw_samples"
TILE = "essen_360_5693"

#: The two source files and their SHA-256.
SOURCE_FILES = {
    f"{TILE}_rgb.jp2": "f2ee8b33ac4849ee3e9ee05de0c4d31070bcb982b8e39015eea52ea88014d67d",
    f"{TILE}_seg.tif": "5cb303dcbba30041aec1a72fc0acc6bdcd27ee5cbec8f6378a66ed779267ff4b",
}

#: The crop: the centred 992 x 992 px (62 x 62 cells of 16 px) of the 1000 x 1000 tile.
CROP_ORIGIN = (4, 4)
CROP_SHAPE = (992, 992)

#: GeoNRW's class ids (0 is unused background) -> this map's classes, for the classes
#: present in the crop, in GeoNRW's order. Railway (6), highway (7) and airport (8) do not
#: occur in it.
GEONRW_CLASSES = {
    1: MapClass("forest", "#1b7837", "forest (GeoNRW class 1)"),
    2: MapClass("water", "#2166ac", "water: a river along the top edge and ponds (GeoNRW class 2)"),
    3: MapClass("agricultural", "#dfc27d", "fields and pasture (GeoNRW class 3, agricultural)"),
    4: MapClass(
        "residential",
        "#969696",
        "settlement land around the buildings (GeoNRW class 4, residential, commercial, industrial)",
    ),
    5: MapClass("grassland", "#a6dba0", "grassland, swamp and shrubbery (GeoNRW class 5)"),
    9: MapClass(
        "roads",
        "#d73027",
        "roads and forest roads (GeoNRW class 9): fixed-width bands, about 4-7 px across, along the map "
        "data's road centrelines, labelled road even where canopy hides it",
    ),
    10: MapClass("buildings", "#762a83", "building footprints (GeoNRW class 10)"),
}


def check_source(filename: str, data: bytes) -> None:
    """Refuse a source file whose SHA-256 is not the pinned one.

    Raises
    ------
    DatasetError
    """
    digest = hashlib.sha256(data).hexdigest()
    if digest != SOURCE_FILES[filename]:
        raise DatasetError(f"{filename}: SHA-256 {digest}, expected {SOURCE_FILES[filename]}")


def build_geonrw_essen(sources: dict[str, bytes]) -> tuple[np.ndarray, np.ndarray, list[dict]]:
    """Build the map from the bytes of its two source files.

    Parameters
    ----------
    sources : dict
        File name (the keys of `SOURCE_FILES`) -> file content.

    Returns
    -------
    image : (992, 992, 3) uint8 RGB
    labels : (992, 992) uint8 class ids 0..6
    legend : list of dict with keys id, name, colour, description

    Raises
    ------
    DatasetError
        A file is missing, has another SHA-256, or decodes to something unexpected.
    """
    import imagecodecs
    import tifffile

    for filename in SOURCE_FILES:
        if filename not in sources:
            raise DatasetError(f"source file {filename} is missing")
        check_source(filename, sources[filename])
    photo = imagecodecs.jpeg2k_decode(sources[f"{TILE}_rgb.jp2"])
    classes = tifffile.imread(io.BytesIO(sources[f"{TILE}_seg.tif"]))
    if photo.shape != (1000, 1000, 4) or photo.dtype != np.uint8:
        raise DatasetError(f"{TILE}_rgb.jp2 decodes to {photo.dtype} {photo.shape}, expected uint8 (1000, 1000, 4)")
    if classes.shape != (1000, 1000) or classes.dtype != np.uint8:
        raise DatasetError(f"{TILE}_seg.tif is {classes.dtype} {classes.shape}, expected uint8 (1000, 1000)")
    rows = slice(CROP_ORIGIN[0], CROP_ORIGIN[0] + CROP_SHAPE[0])
    cols = slice(CROP_ORIGIN[1], CROP_ORIGIN[1] + CROP_SHAPE[1])
    # Bands 0-2 are red, green, blue (8-bit, used as they are); band 3 is near infrared
    # (brightest over vegetation, darker than green and blue over water) and is dropped.
    image = np.ascontiguousarray(photo[rows, cols, :3])
    crop = classes[rows, cols]
    present = sorted(np.unique(crop).tolist())
    if present != sorted(GEONRW_CLASSES):
        raise DatasetError(f"{TILE}_seg.tif: classes {present} in the crop, expected {sorted(GEONRW_CLASSES)}")
    lookup = np.zeros(256, np.uint8)
    for new_id, geonrw_id in enumerate(GEONRW_CLASSES):
        lookup[geonrw_id] = new_id
    labels = lookup[crop]
    return image, labels, legend_entries(list(GEONRW_CLASSES.values()))
