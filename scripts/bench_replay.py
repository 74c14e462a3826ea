"""Benchmark a bag replay's speed, frames per second, at two commits side by side.

One ROS 2 MCAP bag of 640 x 480 frames is written once (``sensor_msgs/msg/CompressedImage``,
JPEG, cut from the reef mosaic along a diagonal, 10 frames a second of bag time). Each
commit is checked out with ``git worktree`` into a temporary folder and replays it with
``curiosity drive --dry-run --camera BAG`` in its own process, imported ahead of this
checkout's package (``PYTHONPATH``), with this virtual environment and the commit's own configs
and data (linked into its shipped package, as a study's clone does). The commits take
turns, the order swapped each repeat, after an untimed replay each that compiles their
kernels. A replay's speed is read from its log: frames after the first ``--skip`` (the
model's arrays grow over the first frames) over the log's seconds between them, so the
start-up is not counted. Prints each replay, then the medians and their ratio; never asserts.

    python scripts/bench_replay.py --reference dd09732~1              # against HEAD, 300 frames, 3 repeats
    python scripts/bench_replay.py --reference HEAD~5 --candidate HEAD --frames 1000 --repeats 5
    python scripts/bench_replay.py --smoke                           # 6 frames of HEAD against itself, once
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ROWS, COLS = 480, 640
PERIOD_NS = 100_000_000
START_NS = 1_700_000_000_000_000_000


def write_bag(path: Path, frames: int) -> Path:
    """A ROS 2 MCAP bag of ``frames`` (480, 640) JPEG frames on /camera/image."""
    import cv2
    import numpy as np
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    from curiosity_cli.maps.map_data import load_map

    image = load_map("reef-mosaic").image
    span_rows, span_cols = image.shape[0] - ROWS, image.shape[1] - COLS
    store = get_typestore(Stores.ROS2_HUMBLE)
    t = store.types
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        camera = writer.add_connection("/camera/image", "sensor_msgs/msg/CompressedImage", typestore=store)
        for i in range(frames):
            row, col = (7 * i) % span_rows, (11 * i) % span_cols
            ok, jpeg = cv2.imencode(".jpg", np.ascontiguousarray(image[row : row + ROWS, col : col + COLS, ::-1]))
            stamp = START_NS + i * PERIOD_NS
            header = t["std_msgs/msg/Header"](
                stamp=t["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id="camera"
            )
            message = t["sensor_msgs/msg/CompressedImage"](header=header, format="jpeg", data=np.frombuffer(jpeg, np.uint8))
            writer.write(camera, stamp, store.serialize_cdr(message, "sensor_msgs/msg/CompressedImage"))
    return path


def replay(code: Path, bag: Path, out: Path, frames: int, skip: int) -> float:
    """Frames per second of one replay by the package in ``code``, from its log."""
    env = {**os.environ, "PYTHONPATH": str(code)}
    done = subprocess.run(
        [sys.executable, "-m", "curiosity_cli", "drive", "--dry-run", "--camera", str(bag), "--out", str(out),
         "--max-frames", str(frames)],
        cwd=out.parent, env=env, capture_output=True, text=True,
    )
    if done.returncode != 0:
        sys.exit(f"the replay by {code} failed: {done.stderr.strip().splitlines()[-1]}")
    with (out / "log.jsonl").open() as log:
        times = [record["time"] for record in map(json.loads, log) if record["event"] == "frame"]
    timed = times[skip:]
    return (len(timed) - 1) / (timed[-1] - timed[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference", default="HEAD", help="the commit to compare against")
    parser.add_argument("--candidate", default="HEAD")
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--skip", type=int, default=20, help="frames left out at the start")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--smoke", action="store_true", help="6 frames, skip 1, once")
    args = parser.parse_args()
    if args.smoke:
        args.frames, args.skip, args.repeats = 6, 1, 1
    if args.skip < 0 or args.frames < args.skip + 2 or args.repeats < 1:
        parser.error("--skip must be at least 0, --frames at least --skip + 2 and --repeats at least 1")
    commits = []
    for given in (args.reference, args.candidate):
        found = subprocess.run(["git", "rev-parse", "--short", "--verify", "--quiet", f"{given}^{{commit}}"], cwd=ROOT,
                               capture_output=True, text=True)
        if found.returncode != 0:
            parser.error(f"{given!r} is not a commit of {ROOT}")
        commits.append(found.stdout.strip())
    with tempfile.TemporaryDirectory(prefix="bench-replay-") as tmp:
        bag = write_bag(Path(tmp) / "bag", args.frames)
        versions, worktrees = {}, {}
        try:
            for role, commit in zip(("reference", "candidate"), commits):
                if commit in worktrees:  # a commit against itself (the noise): one checkout, compiled once
                    versions[f"{role} {commit}"] = worktrees[commit]
                    continue
                versions[f"{role} {commit}"] = worktrees[commit] = Path(tmp) / role
                subprocess.run(["git", "worktree", "add", "--detach", str(Path(tmp) / role), commit], cwd=ROOT,
                               check=True, capture_output=True)
                # its own configs and data: an editable install maps the shipped ones to this checkout's
                for shipped in ("configs", "data"):
                    (Path(tmp) / role / "curiosity_cli" / "shipped" / shipped).symlink_to(Path("..", "..", shipped))
            runs = iter(range(10**6))
            for code in worktrees.values():  # each checkout's kernels compiled, untimed
                replay(code, bag, Path(tmp) / f"run-{next(runs)}", args.skip + 2, 0)
            speeds = {name: [] for name in versions}
            for repeat in range(args.repeats):
                order = list(versions) if repeat % 2 == 0 else list(versions)[::-1]
                for name in order:
                    fps = replay(versions[name], bag, Path(tmp) / f"run-{next(runs)}", args.frames, args.skip)
                    speeds[name].append(fps)
                    print(f"{name:<22} {fps:6.2f} frames/s", flush=True)
        finally:
            for code in worktrees.values():
                subprocess.run(["git", "worktree", "remove", "--force", str(code)], cwd=ROOT, check=False)
    medians = {name: statistics.median(values) for name, values in speeds.items()}
    (ref_name, ref), (new_name, new) = medians.items()
    print(f"\nreplay of {args.frames} frames of {COLS} x {ROWS} (the first {args.skip} not timed), medians of "
          f"{args.repeats}: {ref_name} {ref:.2f} frames/s, {new_name} {new:.2f} frames/s, ratio {new / ref:.2f}")


if __name__ == "__main__":
    main()
