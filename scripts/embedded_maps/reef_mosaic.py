"""reef-mosaic: a synthetic underwater reef built from real textures, tinted and blurred.

Coral heads, seagrass beds, rubble and rare sponges on rippled sand, shaded as relief
and then seen through water.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .aerial_mosaic import AERIAL_S2_WINDOWS
from .legend import MapClass, legend_entries
from .quilting import quilt
from .seeding import stage_rng
from .sources import sentinel_scene, skimage_photo
from .texture import colour_ramp, halve, random_crop, robust_unit, smooth_noise, to_uint8

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
