"""aerial-mosaic: terrain cut from real photographs on a warped Voronoi layout, crossed by a trail.

The textures are scikit-image's CC0 texture photos and patches of the Sentinel-2 scene
(none from the sentinel-coast crop); the one rare class is a winding trail.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .aerial_layout import assign_classes, poisson_sites, split_regions, warped_power_diagram
from .aerial_trail import choose_trail, trail_texture
from .legend import MapClass, legend_entries
from .quilting import quilt
from .seeding import stage_rng
from .sources import sentinel_scene, skimage_photo, true_colour
from .texture import colour_ramp, halve, random_crop, robust_unit, to_uint8

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

# Stages of aerial-mosaic's random stream (see `stage_rng`).
_LAYOUT, _CLASSES, _TEXTURES, _TRAIL = range(4)


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
    names = [c.name for c in AERIAL_CLASSES]
    trail = choose_trail(np.isin(labels, [names.index("water"), names.index("salt-marsh")]), trail_rng)
    image[trail] = trail_texture(trail, trail_rng)[trail]
    labels[trail] = AERIAL_TRAIL
    return to_uint8(image), labels, legend_entries(AERIAL_CLASSES)
