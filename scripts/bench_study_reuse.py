"""Time a small study with label files and batch references shared between its experiments, and without.

A study of ``--specifications`` of ``configs/multiverse.yaml`` (default: four that change
only how topic perplexity scores candidates, so the other three walkers make the same
paths in each) on one map, seed 0, paths of 80 steps, is reproduced in fresh folders
with ``--reuse`` and with ``--no-reuse``, interleaved, ``--repeats`` times. Each run's
cache folder is its own, with links to the user cache's word stores: no run extracts
words, and none takes what an earlier run stored. Prints each run's seconds, its label
stage's seconds summed over the experiments and the items taken, then the medians and
their ratio.

    python scripts/bench_study_reuse.py [--map aerial-mosaic] [--restarts 4] [--repeats 2] [--jobs 2]
    python scripts/bench_study_reuse.py --smoke   # one specification, paths of 10 steps on the smallest map: seconds
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

import yaml

from curiosity_cli.config import CONFIG_DIR
from curiosity_cli.paths import DEFAULT_CACHE

SHARING = ["default", "path-topics-counts", "labels-argmax", "words-added"]


def study(folder: Path, args) -> Path:
    multiverse = yaml.safe_load((CONFIG_DIR / "multiverse.yaml").read_text())
    declared = multiverse["specifications"]
    text = {
        "base": str(CONFIG_DIR / multiverse["base"]), "name": "bench", "datasets": [args.map],
        "explore": {**multiverse["explore"], "restarts": args.restarts},
        "sweep": {"seed": [0]}, "specifications": {name: declared[name] for name in args.specifications},
    }
    path = folder / "bench.yaml"
    path.write_text(yaml.safe_dump(text, sort_keys=False))
    return path


def run(config: Path, folder: Path, reuse: bool, jobs: int, overrides: list[str]) -> tuple[float, float, dict]:
    """Seconds of one reproduction, its label stages' seconds, and the items its experiments took."""
    cache = folder / "cache"
    cache.mkdir(parents=True)
    for store in DEFAULT_CACHE.glob("*.npz"):
        (cache / store.name).symlink_to(store)
    command = [sys.executable, "-m", "curiosity_cli", "reproduce", str(config), "--jobs", str(jobs),
               "--results-dir", str(folder / "results"), "--cache-dir", str(cache), "--reuse" if reuse else "--no-reuse"]
    command += [option for override in overrides for option in ("--set", override)]
    began = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    seconds = time.perf_counter() - began
    label, taken = 0.0, {"labels": 0, "batches": 0, "labelled": 0}
    for experiment in (folder / "results" / "bench-sweep").glob("specification-*_seed-*"):
        label += json.loads((experiment / "stage_seconds.json").read_text()).get("label", 0.0)
        shared = json.loads((experiment / "shared.json").read_text())
        taken = {key: taken[key] + shared[key] for key in taken}
    return seconds, label, taken


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--map", default="aerial-mosaic")
    parser.add_argument("--restarts", type=int, default=4)
    parser.add_argument("--specifications", nargs="+", default=SHARING)
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--jobs", type=int, default=os.cpu_count())
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="a config override of every run, as --set of curiosity")
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.map, args.restarts, args.specifications, args.repeats, args.jobs = "rare-patches", 1, ["default"], 1, 1
        args.set = ["explore.path_length=10", "explore.checkpoints=[10]", "label.sweeps=1", "label.batch_sweeps=1"]
    times = {True: [], False: []}
    with tempfile.TemporaryDirectory() as tmp:
        config = study(Path(tmp), args)
        for repeat in range(args.repeats):
            for reuse in ((True, False) if repeat % 2 == 0 else (False, True)):
                seconds, label, taken = run(config, Path(tempfile.mkdtemp(dir=tmp)), reuse, args.jobs, args.set)
                times[reuse].append(seconds)
                print(f"{'--reuse' if reuse else '--no-reuse':<11} {seconds:6.1f} s   label stages {label:6.1f} s   taken: "
                      f"{taken['labels']} of {taken['labelled']} label files, {taken['batches']} batch references", flush=True)
    with_reuse, without = statistics.median(times[True]), statistics.median(times[False])
    print(f"\n{len(args.specifications)} specifications x 1 seed on {args.map}, {args.restarts} restarts, median of "
          f"{args.repeats}: --no-reuse {without:.1f} s, --reuse {with_reuse:.1f} s: {without / with_reuse:.2f}x")


if __name__ == "__main__":
    main()
