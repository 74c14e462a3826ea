"""Benchmark a long mission: the stream model's memory and time per frame, and a long replay.

The live model learns for the whole mission (``drive.memory_frames: null``); a memory
bound forgets the oldest frame as each new one arrives. Both run side by side here, on
the reef mosaic's frames: 640 x 480 views along a lawnmower path over it (``--views``
distinct ones, then the path again), resized and cut into words as ``curiosity drive``
does, with the shipped config's model and drive settings (``configs/paper-grid.yaml``).

  model    each setting in a fresh process, one after the other, on the same frames'
           words (extracted once): resident memory (VmRSS) and its peak (VmHWM) as the
           frames arrive, and the median time of ``StreamModel.add_frame`` (add, grow or
           forget, refine within drive.samples_per_frame) over the last 500 frames
           before each checkpoint, and the slowest one since the checkpoint before
           (a frame that grew the table). Default: an hour at 10 Hz, 36 000 frames.
  replay   a ``--replay``-frame MCAP bag of those views (JPEG), replayed through
           ``curiosity drive --dry-run --camera BAG`` once per setting, alternating:
           wall time, frames per second, the median stage times from the log, and the
           replay's surprise timeline (kept with ``--keep DIR``). Needs curiosity-cli[bags].

The script prints and never asserts: the numbers depend on the machine.

    python scripts/bench_long_mission.py                          # an hour of frames, then a 3000-frame replay
    python scripts/bench_long_mission.py --frames 6000 --replay 0 # the model only, 10 minutes of frames
    python scripts/bench_long_mission.py --smoke                  # 20 frames of 2 views, a 3-frame replay: seconds
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

CURIOSITY = str(Path(sys.executable).parent / "curiosity")
VIEW = (480, 640)
STEP = 80  # px between views along the path


def reef_views(count: int) -> list[np.ndarray]:
    """``count`` (480, 640, 3) RGB views of the reef mosaic along a lawnmower path (rows of views, back and forth)."""
    from curiosity_cli.maps.map_data import load_map

    image = load_map("reef-mosaic").image
    rows = range(0, image.shape[0] - VIEW[0], STEP * 3)
    cols = list(range(0, image.shape[1] - VIEW[1], STEP))
    path = [(r, c) for i, r in enumerate(rows) for c in (cols if i % 2 == 0 else cols[::-1])]
    return [np.ascontiguousarray(image[r : r + VIEW[0], c : c + VIEW[1]]) for r, c in path[:count]]


def extract(views: list[np.ndarray], out: Path) -> None:
    """Every view's words per image cell, saved as one array of words and one of counts per cell."""
    from curiosity_cli.config import CONFIG_DIR, load_config
    from curiosity_cli.drive.frame_words import FrameWords

    config = load_config(CONFIG_DIR / "paper-grid.yaml")
    words = FrameWords(config.words, config.drive)
    cells = [cell for view in views for cell in words(view)]
    np.savez(out, words=np.concatenate(cells), counts=np.array([c.size for c in cells]), cells=len(cells) // len(views))


def memory_mb() -> tuple[float, float]:
    """(VmRSS, VmHWM) of this process in MB."""
    fields = dict(line.split(":", 1) for line in Path("/proc/self/status").read_text().splitlines() if ":" in line)
    return tuple(int(fields[key].split()[0]) / 1024 for key in ("VmRSS", "VmHWM"))


def model_child(words_file: Path, memory: int | None, frames: int, checkpoints: list[int]) -> dict:
    """Feed ``frames`` frames (the saved views, cycled) to a StreamModel; what each checkpoint saw."""
    from curiosity_cli.config import CONFIG_DIR, load_config
    from curiosity_cli.drive.stream import StreamModel, newest_share

    config = load_config(CONFIG_DIR / "paper-grid.yaml")
    saved = np.load(words_file)
    per_cell = np.split(saved["words"], np.cumsum(saved["counts"])[:-1])
    n = int(saved["cells"])
    views = [per_cell[i : i + n] for i in range(0, len(per_cell), n)]
    model = StreamModel(
        config.model.topics, config.words.orb_vocabulary + config.words.texton_vocabulary,
        (config.drive.grid_rows, config.drive.grid_cols), memory=memory,
        spatial=config.model.spatial_neighbours, temporal=config.drive.temporal_neighbours,
        alpha=config.model.alpha, beta=config.model.beta, newest_share=newest_share(config),
        budget=config.drive.samples_per_frame, seed=0,
    )
    model.add_frame(views[0])  # compiles the kernels before anything is measured
    start_rss = memory_mb()[0]
    seconds, rows, since = [], [], 0
    for frame in range(1, frames + 1):
        began = time.perf_counter()
        model.add_frame(views[frame % len(views)])
        seconds.append(time.perf_counter() - began)
        if frame + 1 in checkpoints:
            rss, peak = memory_mb()
            rows.append({
                "frames": frame + 1, "rss_mb": rss - start_rss, "peak_mb": peak - start_rss,
                "ms": 1000 * statistics.median(seconds[-500:]), "words": model.model.n_words,
                "longest_ms": 1000 * max(seconds[since:]),
            })
            since = len(seconds)
    return {"rows": rows, "words_per_frame": float(saved["counts"].sum() / len(views))}


def run_model(words_file: Path, settings: list, frames: int) -> None:
    results = {}
    for label, memory in settings:
        command = [sys.executable, __file__, "--child", str(words_file), "--memory", str(memory), "--frames", str(frames)]
        results[label] = json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)
    first = next(iter(results.values()))
    print(f"\nmodel only: {frames} frames of {first['words_per_frame']:.0f} words (memory in MB above the "
          "process after its first frame; ms: median add_frame over the 500 frames before; longest: the slowest "
          "add_frame since the checkpoint before, where the table grew)")
    header = "".join(f"{label + ' MB':>22}{'ms':>8}{'longest':>9}" for label in results)
    print(f"{'frames':>8}{header}")
    for i, checkpoint in enumerate(first["rows"]):
        cells = "".join(
            f"{r['rows'][i]['rss_mb']:>22.0f}{r['rows'][i]['ms']:>8.1f}{r['rows'][i]['longest_ms']:>9.0f}"
            for r in results.values()
        )
        print(f"{checkpoint['frames']:>8}{cells}")
    for label, result in results.items():
        rows = result["rows"]
        per_frame = (rows[-1]["rss_mb"] - rows[0]["rss_mb"]) * 1024 / (rows[-1]["frames"] - rows[0]["frames"])
        print(f"{label}: {per_frame:.1f} kB per frame from frame {rows[0]['frames']} to {rows[-1]['frames']}; "
              f"peak {rows[-1]['peak_mb']:.0f} MB")


def write_bag(path: Path, views: list[np.ndarray], frames: int) -> None:
    import cv2
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types = store.types
    msgtype = "sensor_msgs/msg/CompressedImage"
    start, period = 1_700_000_000_000_000_000, 100_000_000  # 10 Hz
    encoded = [cv2.imencode(".jpg", view[:, :, ::-1], [cv2.IMWRITE_JPEG_QUALITY, 90])[1].ravel() for view in views]
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection("/camera/image_raw/compressed", msgtype, typestore=store)
        for i in range(frames):
            stamp = start + i * period
            header = types["std_msgs/msg/Header"](
                stamp=types["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id="camera"
            )
            message = types[msgtype](header=header, format="jpeg", data=encoded[i % len(encoded)])
            writer.write(connection, stamp, store.serialize_cdr(message, msgtype))


def run_replay(folder: Path, views: list[np.ndarray], settings: list, frames: int) -> None:
    bag = folder / "mission"
    write_bag(bag, views, frames)
    size = sum(p.stat().st_size for p in bag.rglob("*") if p.is_file()) / 2**20
    print(f"\nreplay: {frames} frames at 10 Hz ({frames / 600:.1f} min of mission, bag {size:.0f} MB), "
          "`curiosity drive --dry-run --camera BAG`")
    print(f"{'setting':>22}{'wall s':>9}{'frames/s':>10}{'words ms':>10}{'model ms':>10}{'last 500':>10}")
    for label, memory in settings:
        out = folder / f"run-{label.replace(' ', '-')}"
        began = time.perf_counter()
        subprocess.run(
            [CURIOSITY, "drive", "--dry-run", "--camera", str(bag), "--out", str(out), "--set", f"drive.memory_frames={'null' if memory is None else memory}"],
            check=True, capture_output=True, env={**os.environ, "MPLBACKEND": "Agg"},
        )
        wall = time.perf_counter() - began
        rows = [r for r in map(json.loads, (out / "log.jsonl").read_text().splitlines()) if "words" in r and "frame" in r]
        stage = {k: 1000 * statistics.median(r["seconds"][k] for r in rows) for k in ("words", "model")}
        last = 1000 * statistics.median(r["seconds"]["model"] for r in rows[-500:])
        print(f"{label:>22}{wall:>9.1f}{len(rows) / wall:>10.1f}{stage['words']:>10.1f}{stage['model']:>10.1f}{last:>10.1f}")
        print(f"{'':>22}timeline: {sorted(out.glob('timeline*.png'))}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=36_000, help="frames for the model part (default: an hour at 10 Hz)")
    parser.add_argument("--memory", default="1500", help="the bounded setting's drive.memory_frames (default 1500)")
    parser.add_argument("--views", type=int, default=600, help="distinct views along the path (default 600)")
    parser.add_argument("--replay", type=int, default=3000, help="frames of the replayed bag; 0: no replay")
    parser.add_argument("--keep", type=Path, help="keep the bag and the replays' folders here")
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    parser.add_argument("--child", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.smoke:
        args.frames, args.views, args.replay = 20, 2, 3
    if args.child:
        memory = None if args.memory == "None" else int(args.memory)
        checkpoints = sorted({c for c in (args.frames // 10, args.frames // 4, args.frames // 2, args.frames) if c > 1})
        print(json.dumps(model_child(args.child, memory, args.frames, checkpoints)))
        return
    settings = [("whole mission", None), (f"memory {args.memory}", int(args.memory))]
    views = reef_views(args.views)
    with tempfile.TemporaryDirectory() as scratch:
        folder = args.keep or Path(scratch)
        folder.mkdir(parents=True, exist_ok=True)
        words_file = folder / "words.npz"
        extract(views, words_file)
        if args.frames:
            run_model(words_file, settings, args.frames)
        if args.replay:
            run_replay(folder, views, settings, args.replay)


if __name__ == "__main__":
    main()
