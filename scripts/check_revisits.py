"""Does the drive's surprise fall on familiar ground and spike where something changed? Four laps, each reading.

A monitoring robot revisits places: a place it has seen should grow less surprising, and a
change in it should stand out. The frames: a closed loop of ``--frames`` views over a map (a
camera of ``VIEW`` map pixels moving round an ellipse), driven four times, the same frames each
lap; in lap 3, ``PATCH_FRAMES`` consecutive frames carry a patch of a texture the mission never
saw (a crop of another map, ``PATCH_SHARE`` of the frame). Each seed (``--seeds``) runs them
through ``CuriosityPipeline`` with the config's model, words and drive settings, and scores each
frame by every surprise reading of the drive (``drive.surprise``, ``curiosity_cli/drive/surprise.py``), side
by side on the same run (a recorded mission does not steer, so the model is the same for all):

- ``paper``: eq. 12 as the drive computes it, each cell's refined topics under the whole memory's
  topic frequencies, after the frame has joined the model (the drive's surprise before issue 61);
- ``predictive``: each word of the frame scored under the model before the frame joins it,
  ``p(w) = Σ_k θ_k φ_k(w)`` with θ the topic mix of the same image cell's neighbourhood one frame
  earlier, a cell's surprise its words' perplexity;
- ``recent``: eq. 12 against the topic mix of the newest 20 frames
  (``curiosity_cli.drive.surprise.RECENT_FRAMES``) instead of the whole memory's;
- ``bayesian``: how far the frame moves each cell's belief, the KL divergence (bits) of its topic
  mix after the frame from the one predicted before it (Itti & Baldi's Bayesian surprise).

A frame's surprise is the mean over its cells. Per reading, map and seed it prints the median
surprise of each lap, lap 4's over lap 1's (the target: at most ``FALL``), and the patch's
frames: how many stand above the timeline's rule (median + 10 MADs of the mission,
:func:`curiosity_cli.drive.timeline.surprise_threshold`), how many in the top ``TOP`` of laps
2-4, and each one's rank among the frames of laps 2-4 (1: the most surprising). A reading
passes where, in every seed and map, lap 4 falls to ``FALL`` and every patched frame is above
the rule and in the top share. With ``--figure`` it draws each reading's surprise per
frame, the laps overlaid, for seed 0 of each map.

    python scripts/check_revisits.py                     # aerial-mosaic and reef-mosaic, seeds 0-4, 100 frames a lap
    python scripts/check_revisits.py --maps aerial-mosaic --seeds 1 --frames 40
    python scripts/check_revisits.py --smoke             # 12 frames a lap, one map and seed: seconds
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

#: Laps of the loop, and the lap that holds the patch.
LAPS, PATCH_LAP = 4, 3
#: The patch: consecutive frames that carry it, starting at this share of the lap, and its share of a frame's area.
PATCH_FRAMES, PATCH_AT, PATCH_SHARE = 5, 0.4, 0.2
#: The camera's view, in map pixels (rows, columns), as scripts/check_drive_surprise.py's.
VIEW = (240, 320)
#: The target: lap 4's median at most this share of lap 1's; the patch's frames in the top share of laps 2-4.
FALL, TOP = 0.8, 0.05
#: Where each map's patch comes from: a map the mission never sees.
PATCH_SOURCE = {"aerial-mosaic": "reef-mosaic", "reef-mosaic": "aerial-mosaic", "sentinel-coast": "reef-mosaic"}


def loop_frames(name: str, n: int) -> list[np.ndarray]:
    """``n`` (rows, cols, 3) RGB views round an ellipse over map ``name``, the camera's centre a quarter of the map
    from its edges."""
    from curiosity_cli.maps.map_data import load_map

    image = load_map(name).image
    height, width = image.shape[:2]
    rows, cols = VIEW
    frames = []
    for step in range(n):
        angle = 2 * np.pi * step / n
        centre_r = height / 2 + (height / 2 - rows) * 0.6 * np.sin(angle)
        centre_c = width / 2 + (width / 2 - cols) * 0.6 * np.cos(angle)
        top, left = int(round(centre_r - rows / 2)), int(round(centre_c - cols / 2))
        frames.append(np.ascontiguousarray(image[top : top + rows, left : left + cols, :3]))
    return frames


def patched(frames: list[np.ndarray], source: str) -> tuple[list[np.ndarray], list[int]]:
    """The four laps, lap :data:`PATCH_LAP`'s frames from :data:`PATCH_AT` carrying a crop of map ``source``; the
    laps' frames and the patched frames' indices in the mission."""
    from curiosity_cli.maps.map_data import load_map

    texture = load_map(source).image
    rows, cols = VIEW
    side_r, side_c = int(rows * np.sqrt(PATCH_SHARE)), int(cols * np.sqrt(PATCH_SHARE))
    patch = texture[texture.shape[0] // 3 : texture.shape[0] // 3 + side_r, texture.shape[1] // 3 : texture.shape[1] // 3 + side_c, :3]
    n = len(frames)
    first = (PATCH_LAP - 1) * n + int(PATCH_AT * n)
    mission, marked = [], list(range(first, first + PATCH_FRAMES))
    for index in range(LAPS * n):
        frame = frames[index % n]
        if index in marked:
            frame = frame.copy()
            top, left = (rows - side_r) // 2, (cols - side_c) // 2
            frame[top : top + side_r, left : left + side_c] = patch
        mission.append(frame)
    return mission, marked


def run(task: tuple) -> dict:
    """One seed over one map's laps: every reading's surprise per frame (the mean over its cells)."""
    from curiosity_cli.config import DRIVE_SURPRISES, load_config
    from curiosity_cli.drive.pipeline import CuriosityPipeline

    config_name, overrides, name, n, seed = task
    mission, marked = patched(loop_frames(name, n), PATCH_SOURCE[name])
    pipeline = CuriosityPipeline(load_config(config_name, overrides), seed=seed, readings=DRIVE_SURPRISES)
    extract, words = pipeline.words, {}
    series = {reading: [] for reading in DRIVE_SURPRISES}
    for index, frame in enumerate(mission):
        key = index if index in marked else index % n  # a frame's words, extracted once for its four laps
        if key not in words:
            words[key] = extract(frame)
        pipeline.words = lambda _, cell_words=words[key]: cell_words
        decision = pipeline.process(frame)
        for reading in DRIVE_SURPRISES:
            series[reading].append(float(decision.surprises[reading].mean()))
    return {"map": name, "seed": seed, "marked": marked, "series": {r: np.array(v) for r, v in series.items()}}


def verdict(result: dict, reading: str, n: int) -> dict:
    """Lap medians, lap 4 over lap 1, and how many patched frames stand above the rule and in the top share."""
    from curiosity_cli.drive.timeline import surprise_threshold

    values = result["series"][reading]
    medians = [float(np.median(values[lap * n : (lap + 1) * n])) for lap in range(LAPS)]
    marked = result["marked"]
    rule = surprise_threshold(values)
    later = values[n:]
    top = np.quantile(later, 1 - TOP)
    above = int(np.sum(values[marked] > rule))
    in_top = int(np.sum(values[marked] >= top))
    fall = medians[-1] / medians[0]
    # each patched frame's rank among the frames of laps 2-4, 1 the most surprising
    ranks = [int(np.sum(later > values[i])) + 1 for i in marked]
    return {
        "medians": medians, "fall": fall, "above": above, "in_top": in_top, "ranks": ranks,
        "passes": fall <= FALL and above == len(marked) and in_top == len(marked),
    }


def figure(results: list[dict], n: int, out: Path) -> None:
    """Each reading's surprise per frame, the laps overlaid, seed 0 of each map."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from curiosity_cli.config import DRIVE_SURPRISES as READINGS
    from curiosity_cli.files import atomic_path

    first = [r for r in results if r["seed"] == min(x["seed"] for x in results)]
    fig = Figure(figsize=(3.2 * len(READINGS), 2.6 * len(first)), layout="constrained")
    axes = fig.subplots(len(first), len(READINGS), squeeze=False)
    for row, result in zip(axes, first):
        for ax, reading in zip(row, READINGS):
            values = result["series"][reading]
            for lap in range(LAPS):
                ax.plot(np.arange(n), values[lap * n : (lap + 1) * n], linewidth=0.9, label=f"lap {lap + 1}")
            marked = [i - (PATCH_LAP - 1) * n for i in result["marked"]]
            ax.axvspan(min(marked), max(marked), color="0.85", zorder=0, label="patch (lap 3)")
            ax.set_yscale("log")  # a change's spike and a lap's level on one axis
            ax.set_title(f"{result['map']}: {reading}", fontsize=9)
            ax.set_xlabel("frame of the lap", fontsize=8)
            ax.tick_params(labelsize=7)
    axes[0][0].legend(fontsize=7)
    with atomic_path(out) as tmp:
        fig.savefig(tmp, dpi=130, format="png")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--maps", nargs="+", default=["aerial-mosaic", "reef-mosaic"], choices=sorted(PATCH_SOURCE),
                        help="maps whose laps are driven (each has a map of another texture for its patch)")
    parser.add_argument("--frames", type=int, default=100, help="frames a lap (default 100)")
    parser.add_argument("--seeds", type=int, default=5, help="seeds 0 .. N-1 (default 5)")
    parser.add_argument("--config", default="quick", help="the config whose model, words and drive settings run")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a config override")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--figure", type=Path, help="write the laps figure here (a .png)")
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.maps, args.frames, args.seeds, args.jobs = ["aerial-mosaic"], 12, 1, 1
    if args.frames < 2 * PATCH_FRAMES:
        parser.error(f"--frames: expected at least {2 * PATCH_FRAMES}")
    if args.seeds < 1 or args.jobs < 1:
        parser.error(f"--seeds, --jobs: got {args.seeds} and {args.jobs}, expected at least 1 each")

    from curiosity_cli.config import DRIVE_SURPRISES as READINGS
    from curiosity_cli.config import load_config
    from curiosity_cli.errors import CuriosityError

    try:  # refused here in one line, not in each worker
        load_config(args.config, args.set)
    except CuriosityError as exc:
        print(f"Error: {exc}", file=sys.stderr)
        return 1

    tasks = [(args.config, args.set, name, args.frames, seed) for name in args.maps for seed in range(args.seeds)]
    with ProcessPoolExecutor(args.jobs) as pool:
        results = list(pool.map(run, tasks))
    print(f"{LAPS} laps of {args.frames} frames; lap {PATCH_LAP} carries an unseen texture on {PATCH_FRAMES} frames "
          f"({PATCH_SHARE:.0%} of each); target: lap 4's median <= {FALL} x lap 1's, every patched frame above the "
          f"timeline's rule and in the top {TOP:.0%} of laps 2-4")
    passing = {}
    for reading in READINGS:
        print(f"\n{reading}")
        print(f"  {'map':<16}{'seed':>5}  {'median per lap':<40}{'4 / 1':>7}  {'patch: above rule, in top':>26}"
              f"  ranks in laps 2-4 (of {(LAPS - 1) * args.frames})")
        ok = True
        for result in results:
            v = verdict(result, reading, args.frames)
            ok &= v["passes"]
            medians = "  ".join(f"{m:9.4g}" for m in v["medians"])
            print(f"  {result['map']:<16}{result['seed']:>5}  {medians:<40}{v['fall']:>7.3f}  "
                  f"{v['above']:>12} / {PATCH_FRAMES}, {v['in_top']} / {PATCH_FRAMES}  {' '.join(map(str, v['ranks']))}")
        passing[reading] = ok
    print("\npasses: " + ", ".join(r for r, ok in passing.items() if ok) if any(passing.values()) else "\npasses: none")
    if args.figure is not None:
        figure(results, args.frames, args.figure)
        print(f"figure: {args.figure}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
