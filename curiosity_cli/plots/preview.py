"""A dataset preview: each map's image beside its colour-coded label map."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from curiosity_cli.maps.map_data import MapClass, MapData
from curiosity_cli.errors import CuriosityError
from curiosity_cli.files import atomic_path
from curiosity_cli.plots import missing_glyphs_noted

#: Pixels per side a map is shrunk to before drawing: keeps figures small, and a huge map
#: from taking gigabytes in matplotlib.
MAX_SIDE = 800


def _step(shape) -> int:
    return max(1, -(-max(shape[:2]) // MAX_SIDE))


def shrink_labels(labels: np.ndarray) -> np.ndarray:
    """(H, W) → every ``step``-th pixel, so at most :data:`MAX_SIDE` per side (labels must not blend)."""
    step = _step(labels.shape)
    return labels[::step, ::step]


def shrink_image(image: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 → area-averaged to the size :func:`shrink_labels` gives."""
    import cv2

    step = _step(image.shape)
    if step == 1:
        return image
    rows, cols = -(-image.shape[0] // step), -(-image.shape[1] // step)
    return cv2.resize(image, (cols, rows), interpolation=cv2.INTER_AREA)  # OpenCV takes (width, height)


def colour_labels(labels: np.ndarray, legend: tuple[MapClass, ...]) -> np.ndarray:
    """Paint a label map with its legend's colours.

    Parameters
    ----------
    labels : (H, W) integer ndarray
        Class ids, each present in ``legend``.
    legend : tuple of MapClass

    Returns
    -------
    (H, W, 3) uint8 ndarray
        RGB.
    """
    palette = np.zeros((max(c.id for c in legend) + 1, 3), dtype=np.uint8)
    for c in legend:
        palette[c.id] = c.colour
    return palette[labels]


def write_preview(maps: list[MapData], out: Path) -> None:
    """Write one row per map, image left and labels right, with a legend, to PNG or PDF.

    Raises
    ------
    CuriosityError
        ``out`` has a suffix matplotlib cannot write.
    """
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    out = Path(out)
    if out.suffix.lower() not in (".png", ".pdf"):
        raise CuriosityError(f"out: got {str(out)!r}, expected a .png or .pdf file name", parameter="out")
    fig = Figure(figsize=(11, 5.2 * len(maps)), layout="constrained")
    axes = fig.subplots(len(maps), 2, squeeze=False)
    for (ax_image, ax_labels), m in zip(axes, maps):
        ax_image.imshow(shrink_image(m.image), interpolation="antialiased")
        ax_image.set_title(f"{m.config.name}: image ({m.image.shape[0]} x {m.image.shape[1]} px)")
        if m.labels is not None:
            # nearest keeps thin classes (a trail a few px wide) visible when the map is shrunk
            ax_labels.imshow(colour_labels(shrink_labels(m.labels), m.legend), interpolation="nearest")
            ax_labels.set_title("labels")
            ax_labels.legend(
                handles=[Patch(color=np.array(c.colour) / 255, label=c.name) for c in m.legend],
                loc="center left",
                bbox_to_anchor=(1.01, 0.5),
                frameon=False,
            )
        else:
            ax_labels.text(0.5, 0.5, "no labels", ha="center", va="center")
        for ax in (ax_image, ax_labels):
            ax.set_xticks([])
            ax.set_yticks([])
    with missing_glyphs_noted(), atomic_path(out) as tmp:  # a class name may hold an emoji
        fig.savefig(tmp, dpi=110, format=out.suffix.lower()[1:])
