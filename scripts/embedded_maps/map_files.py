"""A map's three files: writing them atomically, and comparing them with committed ones."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from curiosity_cli.errors import DatasetError
from curiosity_cli.files import atomic_path
from curiosity_cli.maps.images import read_raster

from .build import build_map, validate_map
from .legend import legend_yaml


def encode_png(array: np.ndarray) -> bytes:
    """Encode an RGB or single-channel uint8 array as a maximally compressed PNG."""
    import cv2

    bgr = array[..., ::-1] if array.ndim == 3 else array  # OpenCV stores colour as BGR
    ok, buffer = cv2.imencode(".png", np.ascontiguousarray(bgr), [cv2.IMWRITE_PNG_COMPRESSION, 9])
    if not ok:
        raise DatasetError("OpenCV could not encode a PNG")
    return buffer.tobytes()


def write_map(name: str, out_dir: Path, cache: Path) -> dict[str, float]:
    """Build one map and write its three files into ``out_dir / name``, each atomically.

    Returns
    -------
    dict class name -> pixel fraction
    """
    image, labels, legend = build_map(name, cache)
    return write_map_files(name, out_dir, image, labels, legend)


def write_map_files(
    name: str,
    out_dir: Path,
    image: np.ndarray,
    labels: np.ndarray,
    legend: list[dict],
    script: str = "scripts/make_maps.py",
) -> dict[str, float]:
    """Check a built map against the data format and write its three files into ``out_dir / name``, each atomically.

    Parameters
    ----------
    script : str
        The script that makes the map, named in the header of ``legend.yaml``.

    Returns
    -------
    dict class name -> pixel fraction
    """
    validate_map(name, image, labels, legend)
    folder = out_dir / name
    files = {
        "image.png": encode_png(image),
        "labels.png": encode_png(labels),
        "legend.yaml": legend_yaml(name, legend, script).encode("utf-8"),
    }
    try:
        for filename, data in files.items():
            with atomic_path(folder / filename) as tmp:
                tmp.write_bytes(data)
    except OSError as exc:
        raise DatasetError(f"cannot write {folder}: {exc.strerror or exc}") from exc
    counts = np.bincount(labels.ravel(), minlength=len(legend)) / labels.size
    return {c["name"]: float(counts[c["id"]]) for c in legend}


def decoded_pixels(path: Path) -> np.ndarray | None:
    """The pixels of an image file as (rows, cols, bands), RGB order; None if it is missing or unreadable."""
    try:
        return read_raster(path, "map").pixels
    except DatasetError:
        return None


def compare_maps(name: str, fresh_dir: Path, committed_dir: Path) -> str | None:
    """Compare a regenerated map with a committed one by decoded pixels and legend text.

    Returns
    -------
    None if identical, else a short description of what differs
    """
    problems = []
    for filename in ("image.png", "labels.png"):
        new, old = decoded_pixels(fresh_dir / name / filename), decoded_pixels(committed_dir / name / filename)
        if old is None:
            problems.append(f"{filename} missing or unreadable")
        elif old.shape != new.shape or old.dtype != new.dtype:
            problems.append(f"{filename} is {old.dtype} {old.shape}, regenerated {new.dtype} {new.shape}")
        elif not np.array_equal(old, new):
            problems.append(f"{filename} ({int(np.any(old != new, axis=2).sum())} pixels)")
    legend_path = committed_dir / name / "legend.yaml"
    if not legend_path.is_file():
        problems.append("legend.yaml missing")
    elif legend_path.read_text(encoding="utf-8").replace("\r\n", "\n") != (fresh_dir / name / "legend.yaml").read_text(
        encoding="utf-8"
    ):
        problems.append("legend.yaml")
    return ", ".join(problems) or None
