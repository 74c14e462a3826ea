"""Benchmark `curiosity drive` in the closed loop with `curiosity simrobot` over a real pty.

Each scenario starts `curiosity simrobot --map reef-mosaic` and `curiosity drive --serial
<pty> --camera sim`, two processes as on a hardware bench, with 640 x 480 camera frames
(drive.sim_view_rows/cols) and the default per-frame budget (drive.samples_per_frame),
and reads the run's log. Scenarios:

  1 core, unpaced   drive pinned to one core (numba/BLAS/OpenCV one thread), frames as
                    fast as the loop runs: latency at full load and the sustained fps
  1 core, 5 fps     the same at the paper's frame rate (drive.sim_frame_interval 0.2)
  2 cores, unpaced  no pinning: what the machine gives

Per scenario, side by side: frame-to-command latency (frame rendered -> VEL written),
median and 95th percentile; the median of each stage (words, model = add + refine,
score); ACK latency (VEL written -> ACK read) median and p95; frames per second over the
run. The first --skip frames are left out (the first frames grow the model's arrays).
The simulated robot runs on the other core when there are two. The script prints and
never asserts: the numbers depend on the machine.

    python scripts/bench_drive.py                 # 300 frames per scenario, about 2 minutes
    python scripts/bench_drive.py --frames 100    # quicker
    python scripts/bench_drive.py --smoke         # 3 frames of the first scenario: seconds
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

CURIOSITY = str(Path(sys.executable).parent / "curiosity")
ONE_THREAD = {v: "1" for v in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
FRAME = ["--set", "drive.sim_view_rows=480", "--set", "drive.sim_view_cols=640"]

# (label, cores for the driver, seconds between frames)
SCENARIOS = [("1 core, unpaced", 1, 0.0), ("1 core, 5 fps", 1, 0.2), ("2 cores, unpaced", None, 0.0)]


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q / 100 * (len(ordered) - 1)))]


def run_scenario(folder: Path, frames: int, cores: int | None, interval: float, skip: int) -> dict:
    available = sorted(os.sched_getaffinity(0))
    driver_cores = set(available[:cores]) if cores else set(available)
    robot_cores = set(available[1:2]) if cores and len(available) > 1 else set(available)
    robot = subprocess.Popen(
        [CURIOSITY, "simrobot", "--map", "reef-mosaic", "--start", "1700,600"],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        preexec_fn=lambda: os.sched_setaffinity(0, robot_cores),
    )
    try:
        port = robot.stdout.readline().strip()
        env = {**os.environ, **(ONE_THREAD if cores == 1 else {})}
        out = folder / "run"
        result = subprocess.run(
            [CURIOSITY, "drive", "--serial", port, "--camera", "sim", "--sim-map", "reef-mosaic", "--out", str(out),
             "--max-frames", str(frames + skip), *FRAME, "--set", f"drive.sim_frame_interval={interval}"],
            env=env, capture_output=True, text=True,
            preexec_fn=lambda: os.sched_setaffinity(0, driver_cores),
        )
        if result.returncode != 0:
            sys.exit(f"curiosity drive failed ({result.returncode}): {result.stderr.strip().splitlines()[-1]}")
    finally:
        robot.terminate()
        robot.communicate(timeout=30)
    log = [json.loads(line) for line in (out / "log.jsonl").read_text().splitlines()]
    rows = [r for r in log if r["event"] == "frame"][skip:]
    acks = [r["ack_ms"] for r in rows if r["ack_ms"] is not None]
    span = rows[-1]["time"] - rows[0]["time"]
    return {
        "frames": len(rows),
        "latency": [r["latency_ms"] for r in rows],
        "words": [1000 * r["seconds"]["words"] for r in rows],
        "model": [1000 * r["seconds"]["model"] for r in rows],
        "score": [1000 * r["seconds"]["score"] for r in rows],
        "ack": acks,
        "fps": (len(rows) - 1) / span if span > 0 else float("nan"),
        "words_per_frame": statistics.median(r["words"] for r in rows),
        "end": log[-1],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=300, help="frames measured per scenario")
    parser.add_argument("--skip", type=int, default=10, help="first frames left out")
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.frames, args.skip = 3, 1
    scenarios = SCENARIOS[:1] if args.smoke else SCENARIOS  # the others differ only in their cores and pace

    print(f"640 x 480 frames from the simulated camera, reef-mosaic, {args.frames} frames per scenario, "
          f"first {args.skip} skipped; {len(os.sched_getaffinity(0))} cores available\n")
    header = (f"{'scenario':<18} {'latency ms':>17} {'words':>6} {'model':>6} {'score':>6} "
              f"{'ACK ms':>13} {'fps':>6} {'words/frame':>12}")
    print(header)
    print(f"{'':<18} {'median':>8} {'p95':>8} {'median':>6} {'median':>6} {'median':>6} {'median':>6} {'p95':>6}")
    print("-" * len(header))
    for label, cores, interval in scenarios:
        with tempfile.TemporaryDirectory() as folder:
            r = run_scenario(Path(folder), args.frames, cores, interval, args.skip)
        print(
            f"{label:<18} {statistics.median(r['latency']):8.1f} {percentile(r['latency'], 95):8.1f} "
            f"{statistics.median(r['words']):6.1f} {statistics.median(r['model']):6.1f} {statistics.median(r['score']):6.2f} "
            f"{statistics.median(r['ack']):6.2f} {percentile(r['ack'], 95):6.2f} {r['fps']:6.1f} {r['words_per_frame']:12.0f}",
            flush=True,
        )
    print("\nlatency: frame rendered -> VEL written; words/model/score: the pipeline's stages; "
          "ACK: VEL written -> its ACK read (pty round trip through the simulated robot)")


if __name__ == "__main__":
    main()
