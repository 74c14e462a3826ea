"""The surprise timeline of a replayed mission: what a scientist skims after a dive.

:func:`write_timeline` reads a replay's ``log.jsonl`` and draws ``timeline.png`` (and
``.pdf``): two panels against time, each frame's topic perplexity (the mean over its image
cells, the paper's surprise, section 5.2) and the decayed curiosity score that steered (the
highest cell's), different quantities on axes of their own, under a strip of the
surprising frames, each linked to its peak. A frame is surprising only when it stands out
from the mission (:func:`surprise_threshold`: above its median by :data:`OUTLIER_MADS`
median absolute deviations, a line on the plot); of those, the :data:`SURPRISING` highest
peaks apart are shown, and a mission where none stands out says so. The time is the bag's
record time, or the messages' header stamps (``clock``); the axis names the clock and the
mission's start (UTC). The surprising frames are written whole as
``surprising/frame-NNNNNN.png``. A frame whose own refinement never sampled its words (log
``refined`` 0) reads its random first topics, not a discovery: it is marked, and never
surprising.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from curiosity_cli.drive.jsonlines import frame_records
from curiosity_cli.files import atomic_path

#: Thumbnails on the timeline: at most this many surprising frames, the highest, at least a share of the mission apart.
SURPRISING = 6
#: A frame is surprising when its perplexity stands above the mission's median by more than this many median
#: absolute deviations (MAD). Why 10: on 400 frames of one steady view (scripts/check_drive_surprise.py's, seeds
#: 0-3) the noise reached 6.7 MADs, so a plateau marks nothing, with a margin for longer missions; a frame whose
#: refinement was luck (a coin per pick, before drive.newest_share) read 40-50, and a new view more still.
OUTLIER_MADS = 10
#: The least spread the rule counts, as a share of the median: a mission whose frames read nearly all the same
#: (a MAD near 0) does not make a frame surprising for standing a hair above them.
MIN_SPREAD = 0.01


#: The clocks a replay's timeline can run on, by name: the log key of each frame's time.
CLOCKS = {"bag": "bag_time", "header": "header_time"}
#: Each clock in words, for the axis.
CLOCK_WORDS = {"bag": "bag time", "header": "header stamps"}


def surprise_series(log: Path, clock: str = "bag") -> dict:
    """Per frame of a replay's log: ``frame``, ``time`` (seconds since the epoch on ``clock``), ``perplexity`` (cell
    mean), ``score`` (cell max), ``refined`` (whether its words were refined in its own frame, or had none; logs
    from before the field: every frame); and ``clock``, the clock used.

    ``bag``: the bag's record times; ``header``: the messages' header stamps. A bag whose
    record times are all equal (a recorder that stamped a batch at once) falls back to
    header stamps, and ``fell_back`` says so.

    A last line cut short (a run stopped while writing it) is left out, with a note.

    Raises
    ------
    CuriosityError
        ``header`` for a log whose frames have no header stamps; a line before the last
        that is not a JSON object, or a frame record without a field the timeline reads,
        naming the line.
    """
    from curiosity_cli.errors import CuriosityError
    from curiosity_cli.files import display_path

    records = frame_records(Path(log), ("frame", "perplexity", "scores", "words"), keep=lambda r: "bag_time" in r)
    headers = all(CLOCKS["header"] in r for r in records)
    if clock == "header" and not headers:
        raise CuriosityError(f"{display_path(Path(log))}: its frames have no header stamps; use the bag's clock")
    fell_back = clock == "bag" and len(records) > 1 and headers and len({r["bag_time"] for r in records}) == 1
    used = "header" if fell_back else clock
    return {
        "frame": np.array([r["frame"] for r in records], np.int64),
        "time": np.array([r[CLOCKS[used]] for r in records], np.float64),
        "perplexity": np.array([np.mean(r["perplexity"]) for r in records], np.float64),
        "score": np.array([np.max(r["scores"]) for r in records], np.float64),
        "refined": np.array([r.get("refined", 1) > 0 or r["words"] == 0 for r in records], bool),
        "clock": used,
        "fell_back": fell_back,
    }


def most_surprising(perplexity: np.ndarray, count: int = SURPRISING, eligible: np.ndarray | None = None) -> list[int]:
    """Indices of the ``count`` highest perplexities (of the ``eligible`` frames, default all), each at least
    ``len / (2 count)`` frames from another, by time."""
    gap = max(1, len(perplexity) // (2 * count))
    chosen = []
    for index in np.argsort(-perplexity, kind="stable"):
        if eligible is not None and not eligible[index]:
            continue
        if all(abs(int(index) - other) >= gap for other in chosen):
            chosen.append(int(index))
        if len(chosen) == count:
            break
    return sorted(chosen)


def surprise_threshold(perplexity: np.ndarray, eligible: np.ndarray | None = None) -> float:
    """The perplexity a frame must exceed to be surprising: the median of the ``eligible`` frames (default all)
    plus :data:`OUTLIER_MADS` times their median absolute deviation, or times :data:`MIN_SPREAD` of the median
    if that is more; infinite without an eligible frame."""
    values = perplexity if eligible is None else perplexity[eligible]
    if values.size == 0:
        return float("inf")
    median = float(np.median(values))
    spread = max(float(np.median(np.abs(values - median))), MIN_SPREAD * median)
    return median + OUTLIER_MADS * spread


def surprising(perplexity: np.ndarray, count: int = SURPRISING, eligible: np.ndarray | None = None) -> list[int]:
    """Indices of the surprising frames (of the ``eligible``, default all): above :func:`surprise_threshold`, at
    most ``count`` of them, the highest, peaks apart (:func:`most_surprising`); none on a plateau."""
    eligible = np.ones(len(perplexity), bool) if eligible is None else np.asarray(eligible, bool)
    above = eligible & (perplexity > surprise_threshold(perplexity, eligible))
    return most_surprising(perplexity, count, above)


def timeline_figure(series: dict, thumbnails: dict[int, np.ndarray], title: str):
    """The figure: a strip of the surprising frames over two panels, each frame's topic perplexity (the cell mean)
    and its curiosity score (decayed, the highest cell), against seconds since the first frame on the series' clock,
    whose absolute start (UTC) the axis names; each thumbnail linked to its peak. The perplexity panel draws the
    line a surprising frame stands above (:func:`surprise_threshold`), its rule in the legend; the strip says so
    when no frame stands above it."""
    from datetime import datetime, timezone

    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    from matplotlib.offsetbox import AnnotationBbox, OffsetImage
    from matplotlib.patches import ConnectionPatch

    seconds = series["time"] - series["time"][0]
    fig = Figure(figsize=(10, 5.6), layout="constrained")
    strip, surprise, score = fig.subplots(3, 1, sharex=True, gridspec_kw={"height_ratios": [1.1, 2, 1.4]})
    fig.suptitle(title, fontsize=10)
    surprise.plot(seconds, series["perplexity"], color="tab:blue", lw=1.2)
    unrefined = ~series["refined"]
    if unrefined.any():
        surprise.plot(seconds[unrefined], series["perplexity"][unrefined], "x", ms=5, color="0.35")
        surprise.set_title(
            f"x: {unrefined.sum()} frame{'s' if unrefined.sum() > 1 else ''} never refined (random topics: "
            "not a discovery)", fontsize=8, loc="right", color="0.35",
        )
    rule = f"the median + {OUTLIER_MADS} median absolute deviations (at least {OUTLIER_MADS * MIN_SPREAD:.0%} above it)"
    threshold = surprise_threshold(series["perplexity"], series["refined"])
    if np.isfinite(threshold):
        surprise.axhline(threshold, color="tab:red", lw=0.8, ls="--", label=f"surprising above {rule}")
        # above the panel, not over the data
        surprise.legend(loc="lower left", bbox_to_anchor=(0, 1), fontsize=7, frameon=False, borderaxespad=0.1)
    if not (series["refined"] & (series["perplexity"] > threshold)).any():
        strip.text(0.5, 0.5, f"no frame stands out: none above {rule}", transform=strip.transAxes, ha="center",
                   va="center", fontsize=9, color="0.35")
    surprise.set_ylabel("topic perplexity\n(mean of the frame's cells)", fontsize=9)
    score.plot(seconds, series["score"], color="tab:orange", lw=1.2)
    score.set_ylabel("curiosity score\n(decayed, highest cell)", fontsize=9)
    for panel in (surprise, score):  # from 1, the least perplexity there is: a steady view's noise looks like noise
        panel.set_ylim(bottom=1)
    start = datetime.fromtimestamp(series["time"][0], timezone.utc).strftime("%Y-%m-%d %H:%M:%S.%f")[:-3]
    fell_back = " (the record times are all equal)" if series.get("fell_back") else ""
    score.set_xlabel(f"{CLOCK_WORDS[series['clock']]}{fell_back}: seconds since the first frame, {start} UTC")
    strip.set_ylim(0, 1)
    strip.set_yticks([])
    strip.tick_params(axis="x", bottom=False)
    for side in ("left", "right", "top", "bottom"):
        strip.spines[side].set_visible(False)
    for index, image in thumbnails.items():
        x, y = seconds[index], series["perplexity"][index]
        zoom = 48 / max(image.shape[:2])  # about 48 points across
        strip.add_artist(AnnotationBbox(OffsetImage(image, zoom=zoom), (x, 0.5), xycoords="data", frameon=True, pad=0.15))
        surprise.plot([x], [y], "o", ms=4, color="tab:red")
        fig.add_artist(ConnectionPatch((x, 0.0), (x, y), coordsA=strip.transData, coordsB=surprise.transData,
                                       color="tab:red", lw=0.6, alpha=0.7))
    return fig


def write_timeline(folder: Path, camera, title: str, count: int = SURPRISING, clock: str = "bag") -> list[Path]:
    """Write ``folder/timeline.png`` and ``.pdf`` from ``folder/log.jsonl``, and the surprising frames as PNGs.

    Parameters
    ----------
    folder : Path
        The replay's run folder.
    camera
        A fresh :class:`~curiosity_cli.drive.bags.BagCamera` on the same topic: the chosen
        frames are read from it again (the run kept no frames in memory).
    title : str
    count : int
        The most surprising frames shown, of those that stand out (:func:`surprising`).
    clock : {"bag", "header"}
        The time axis (:func:`surprise_series`); a fall-back to header stamps is noted on stderr.

    Returns
    -------
    list of Path
        The files written; none for a log without a bag's frames.
    """
    import cv2

    from curiosity_cli.drive.bags import BadMessage
    from curiosity_cli.drive.driver import RUN_LOG

    series = surprise_series(folder / RUN_LOG, clock)
    if series["frame"].size == 0:
        return []
    if series["fell_back"]:
        from curiosity_cli.files import note

        note(f"{folder / RUN_LOG}: every frame has the same bag time; the timeline runs on the messages' header stamps")
    chosen = surprising(series["perplexity"], count, series["refined"])
    wanted = {int(series["frame"][i]): i for i in chosen}
    thumbnails, written = {}, []
    (folder / "surprising").mkdir(exist_ok=True)
    number = 0
    while wanted and number <= max(wanted):
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
