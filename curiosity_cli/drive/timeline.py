"""The surprise timeline of a replayed mission: what a scientist skims after a dive.

:func:`write_timeline` reads a replay's ``log.jsonl`` and draws ``timeline.png`` (and
``.pdf``): each frame's topic perplexity (the mean over its image cells, the paper's
surprise, section 5.2) and the decayed curiosity score that steered (the highest cell's)
against bag time, with thumbnails of the most surprising frames above their peaks. Those
frames are written whole as ``surprising/frame-NNNNNN.png``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from curiosity_cli.files import atomic_path

#: Thumbnails on the timeline: the most surprising frames, at least a share of the mission apart.
SURPRISING = 6


def surprise_series(log: Path) -> dict[str, np.ndarray]:
    """Per frame of a replay's log: ``frame``, ``time`` (bag seconds), ``perplexity`` (cell mean), ``score`` (cell max)."""
    records = [r for r in map(json.loads, Path(log).read_text().splitlines()) if r.get("event") == "frame" and "bag_time" in r]
    return {
        "frame": np.array([r["frame"] for r in records], np.int64),
        "time": np.array([r["bag_time"] for r in records], np.float64),
        "perplexity": np.array([np.mean(r["perplexity"]) for r in records], np.float64),
        "score": np.array([np.max(r["scores"]) for r in records], np.float64),
    }


def most_surprising(perplexity: np.ndarray, count: int = SURPRISING) -> list[int]:
    """Indices of the ``count`` highest perplexities, each at least ``len / (2 count)`` frames from another, by time."""
    gap = max(1, len(perplexity) // (2 * count))
    chosen = []
    for index in np.argsort(-perplexity, kind="stable"):
        if all(abs(int(index) - other) >= gap for other in chosen):
            chosen.append(int(index))
        if len(chosen) == count:
            break
    return sorted(chosen)


def timeline_figure(series: dict[str, np.ndarray], thumbnails: dict[int, np.ndarray], title: str):
    """The figure: perplexity and score against seconds since the first frame, thumbnails above their peaks."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    from matplotlib.offsetbox import AnnotationBbox, OffsetImage

    seconds = series["time"] - series["time"][0]
    fig = Figure(figsize=(10, 4.2), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(seconds, series["perplexity"], color="tab:blue", lw=1.2, label="topic perplexity (mean over the frame's cells)")
    ax.plot(seconds, series["score"], color="tab:orange", lw=1.2, label="curiosity score (decayed, highest cell)")
    ax.set_xlabel("bag time (s since the first frame)")
    ax.set_ylabel("perplexity")
    ax.set_title(title, fontsize=10)
    top = max(series["perplexity"].max(), series["score"].max())
    ax.set_ylim(top=top * 1.6)  # room above the curves for the thumbnails
    for index, image in thumbnails.items():
        zoom = 42 / max(image.shape[:2])  # about 42 points across
        box = AnnotationBbox(
            OffsetImage(image, zoom=zoom), (seconds[index], series["perplexity"][index]), xybox=(0, 34),
            xycoords="data", boxcoords="offset points", pad=0.15, arrowprops={"arrowstyle": "-", "lw": 0.6},
        )
        ax.add_artist(box)
    ax.legend(loc="lower right", fontsize=8)
    return fig


def write_timeline(folder: Path, camera, title: str, count: int = SURPRISING) -> list[Path]:
    """Write ``folder/timeline.png`` and ``.pdf`` from ``folder/log.jsonl``, and the most surprising frames as PNGs.

    Parameters
    ----------
    folder : Path
        The replay's run folder.
    camera
        A fresh :class:`~curiosity_cli.drive.bags.BagCamera` on the same topic: the chosen
        frames are read from it again (the run kept no frames in memory).
    title : str

    Returns
    -------
    list of Path
        The files written; none for a log without a bag's frames.
    """
    import cv2

    from curiosity_cli.drive.bags import BadMessage
    from curiosity_cli.drive.driver import RUN_LOG

    series = surprise_series(folder / RUN_LOG)
    if series["frame"].size == 0:
        return []
    chosen = most_surprising(series["perplexity"], count)
    wanted = {int(series["frame"][i]): i for i in chosen}
    thumbnails, written = {}, []
    (folder / "surprising").mkdir(exist_ok=True)
    number = 0
    while number <= max(wanted):
        try:
            frame = camera.read()
        except BadMessage:
            continue  # the replay skipped it too: frame numbers count the frames it replayed
        if frame is None:
            break
        if number in wanted:
            thumbnails[wanted[number]] = frame.image
            path = folder / "surprising" / f"frame-{number:06d}.png"
            with atomic_path(path) as tmp:
                if not cv2.imwrite(str(tmp), frame.image[:, :, ::-1]):
                    raise OSError(f"{path}: OpenCV could not write the PNG")
            written.append(path)
        number += 1
    fig = timeline_figure(series, thumbnails, title)
    for suffix in (".png", ".pdf"):
        path = folder / f"timeline{suffix}"
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=150, format=suffix[1:])
        written.append(path)
    return written
