"""Where the label stage's time goes, and how much of it the kernel's rate times the work explains.

Explores CONFIG (default ``quick`` on aerial-mosaic: a shipped map, nothing to fetch) in a
fresh folder, labels it with ``--no-reuse`` (everything computed), and reads the stage's
``label_profile.json`` (:mod:`curiosity_cli.label.profile`). Prints the machine (logical
CPUs and physical cores from ``lscpu``), the stage's segments, the blocks' kernel, table
and reading seconds, the kernel's rate per word sample per block, and the share of the
stage's wall time that ``work x rate / jobs`` explains (the rate: the median block's).

    python scripts/bench_label_profile.py [--config quick] [--set datasets=[aerial-mosaic]] [--jobs N]
    python scripts/bench_label_profile.py --folder results/paper-grid   # an experiment already labelled
    python scripts/bench_label_profile.py --smoke   # one restart of 10 steps on the smallest map, one sweep: seconds
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import tempfile
from pathlib import Path

from curiosity_cli import api


def physical_cores() -> str:
    """Physical cores (distinct core, socket pairs of ``lscpu -p``), or why not."""
    try:
        lines = subprocess.run(["lscpu", "-p=core,socket"], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError) as exc:
        return f"unknown ({exc})"
    return str(len({line for line in lines.splitlines() if line and not line.startswith("#")}))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default="quick")
    parser.add_argument("--set", dest="overrides", action="append", default=None)
    parser.add_argument("--jobs", type=int, default=os.cpu_count())
    parser.add_argument("--folder", type=Path, help="read this experiment's label_profile.json instead")
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.jobs, args.overrides = 1, [
            "datasets=[rare-patches]", "explore.restarts=1", "explore.path_length=10", "explore.checkpoints=[5, 10]",
            "label.sweeps=1", "label.warm_sweeps=1", "label.batch_sweeps=1",
        ]
    print(f"logical CPUs {os.cpu_count()}, physical cores {physical_cores()}")
    if args.folder:
        summarise(json.loads((args.folder / "label_profile.json").read_text()))
        return
    overrides = args.overrides if args.overrides is not None else ["datasets=[aerial-mosaic]"]
    print(f"--jobs {args.jobs}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = api.explore(args.config, overrides=overrides, results_dir=Path(tmp), jobs=args.jobs).folder
        api.label(folder, jobs=args.jobs, reuse=False)
        summarise(json.loads((folder / "label_profile.json").read_text()))


def summarise(profile: dict) -> None:
    """Print a label stage's profile (:mod:`curiosity_cli.label.profile`) and how much of it the kernel explains."""
    wall, jobs, blocks = profile["wall"], profile["jobs"], profile["blocks"]
    print(f"\nlabel stage: {wall:.1f} s wall on {jobs} jobs")
    for name, seconds in profile["segments"].items():
        print(f"  {name:<36} {seconds:7.1f} s  {100 * seconds / wall:5.1f} %")
    for name, batch in profile.get("batches", {}).items():
        print(f"  batch reference of {name} beside the blocks: {batch['seconds']:.1f} s of sweeps, written at {batch['written']:.1f} s")
    if not blocks:
        print("no blocks labelled")
        return
    kernel, tables, reading = (sum(b[k] for b in blocks) for k in ("kernel", "tables", "reading"))
    work = sum(b["work"] for b in blocks)
    rates = [1e9 * b["kernel"] / b["work"] for b in blocks if b["work"]]
    rate = statistics.median(rates)
    print(f"\n{len(blocks)} blocks, {sum(b['chains'] for b in blocks)} chains, {work:.3g} word samples")
    for b in blocks:
        print(f"  {b['dataset']:<16} {b['runs']:>3} runs {b['chains']:>3} chains, began at {b['began']:6.1f} s: "
              f"reading {b['reading']:6.1f} s, "
              f"kernel {b['kernel']:6.1f} s, tables {b['tables']:6.1f} s")
    print(f"  worker seconds: kernel {kernel:.1f}, tables {tables:.1f}, reading {reading:.1f} "
          f"(of {jobs} x {wall:.1f} = {jobs * wall:.1f} core-seconds: kernel {100 * kernel / (jobs * wall):.0f} %, "
          f"tables {100 * tables / (jobs * wall):.0f} %, reading {100 * reading / (jobs * wall):.0f} %)")
    print(f"  kernel rate per word sample per core: median {rate:.1f} ns (blocks {min(rates):.1f} to {max(rates):.1f})")
    print(f"  work x rate / jobs = {work * rate * 1e-9 / jobs:.1f} s: {100 * work * rate * 1e-9 / jobs / wall:.0f} % "
          "of the stage's wall time")


if __name__ == "__main__":
    main()
