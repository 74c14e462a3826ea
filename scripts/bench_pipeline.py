"""Benchmark the labelling pipeline, and the full paper grid end to end.

Part 1, one process (numba compiled first, untimed), on --map (default aerial-mosaic):
- labelling one run: Z_p of the whole map at each of its 6 checkpoints (the label
  settings of --config: a random start with label.sweeps, then label.warm_sweeps from
  the checkpoint before; pixel labels; contingency tables), median of --repeats, beside
  its reference in the same run: building a whole-map model per checkpoint and sweeping
  it from a random start with label.sweeps (how labelling worked before a run's
  checkpoints shared one model), and the frozen sweeps alone;
- the batch reference Z_b of each map of --config (label.batch_sweeps sweeps on
  --threads threads), once each.
Part 2 (--full-grid): `curiosity reproduce CONFIG --jobs N` in a fresh process, words
already cached, into --results-dir (a temporary folder unless given), for the grids of
--grids: ``paper``, the paper's own grid (the three embedded maps of --config x the
paper's four weight functions), and ``config``, the whole of --config as it stands: wall
time, and the seconds per stage from its REPORT.md, beside the figures of commit 1903b17
(the paper's grid labelled one single chain at a time, 64 sweeps then 16 warm per
checkpoint, with the two-start check, on a 2-core machine: explore 4.9, label 28.9, all
34.2 minutes). --grid-only skips part 1. --device cuda labels on a CUDA GPU (part 1's
run, and the grids: ``--set label.device=cuda``); the label files are the same bytes.

    python scripts/bench_pipeline.py                                   # part 1, a few minutes
    python scripts/bench_pipeline.py --full-grid                       # and both grids
    python scripts/bench_pipeline.py --full-grid --grid-only --grids paper
    python scripts/bench_pipeline.py --full-grid --grid-only --grids paper --jobs 16 --device cuda
    python scripts/bench_pipeline.py --smoke    # part 1 on the smallest map, 10 steps, one sweep: seconds

Prints and never asserts: timings depend on the machine.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from curiosity_cli.config import CONFIG_DIR, LABEL_DEVICES, load_config
from curiosity_cli.maps.datasets import dataset_path, load_dataset_config
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.evaluate.information import contingency
from curiosity_cli.topics.devices import resolve_device
from curiosity_cli.label.sampling import batch_labels, label_paths, pixel_labels, whole_map_model
from curiosity_cli.explore.walker import explore
from curiosity_cli.words.extract import extract_words


#: Minutes per stage of the paper's grid at commit 1903b17 (README, issue 14), 2 cores.
BEFORE = {"explore": 4.9, "label": 28.9, "all": 34.2}
#: The weight functions of the paper's own grid (its section 5.1).
PAPER_WEIGHT_FUNCTIONS = ("random-walk", "stochastic-coverage", "word-perplexity", "topic-perplexity")
#: --smoke's config: part 1 on the smallest map, a short path, one sweep of each kind.
SMOKE = ["datasets=[rare-patches]", "explore.path_length=10", "explore.checkpoints=[5, 10]", "label.sweeps=1",
         "label.warm_sweeps=1", "label.batch_sweeps=1"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--config", type=Path, default=CONFIG_DIR / "paper-grid.yaml")
    parser.add_argument("--map", default="aerial-mosaic")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--full-grid", action="store_true")
    parser.add_argument("--grids", nargs="+", choices=["paper", "config"], default=["paper", "config"],
                        help="with --full-grid: the paper's grid, the whole --config, or both")
    parser.add_argument("--grid-only", action="store_true", help="with --full-grid: skip part 1")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--results-dir", type=Path, default=None)
    parser.add_argument("--device", choices=LABEL_DEVICES, default="cpu", help="label.device: where Z_p's chains run")
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.map, args.repeats, args.threads, args.full_grid, args.grid_only = "rare-patches", 1, 1, False, False

    config = load_config(args.config, SMOKE if args.smoke else ())
    if not (args.full_grid and args.grid_only):
        part_one(config, args)

    if args.full_grid:
        embedded = [e for e in config.datasets if load_dataset_config(dataset_path(e)).fetch is None]
        grids = {
            "paper": ("the paper's grid: 3 embedded maps x the paper's 4 weight functions", args.config, [
                "--set", f"datasets={embedded}", "--set", f"explore.weight_functions={list(PAPER_WEIGHT_FUNCTIONS)}",
                "--set", f"name={config.name}-paper-grid",
            ]),
            "config": (f"{args.config.name} as it stands", args.config, []),
        }
        if args.device != "cpu":  # before the name, which stays last
            grids = {key: (title, path, [*sets[:-2], "--set", f"label.device={args.device}", *sets[-2:]] if sets else
                           ["--set", f"label.device={args.device}"]) for key, (title, path, sets) in grids.items()}
        grids = [grids[name] for name in args.grids]
        print(f"\nbefore (commit 1903b17, paper's grid, 2 cores): explore {BEFORE['explore']} min, "
              f"label {BEFORE['label']} min, all {BEFORE['all']} min")
        for title, path, sets in grids:
            with tempfile.TemporaryDirectory() as tmp:
                results = args.results_dir or Path(tmp)
                command = [sys.executable, "-m", "curiosity_cli", "reproduce", str(path), *sets, "--jobs", str(args.jobs),
                           "--results-dir", str(results), "--no-reuse"]  # computed: no labels taken from a run before
                began = time.perf_counter()
                subprocess.run(command, check=True)
                minutes = (time.perf_counter() - began) / 60
                name = sets[-1].split("=", 1)[1] if sets and sets[-1].startswith("name=") else config.name
                report = (results / name / "REPORT.md").read_text()
            print(f"\n{title}, `curiosity reproduce {path.name} {' '.join(sets)} --jobs {args.jobs}`: "
                  f"{minutes:.1f} min end to end")
            times = report[report.index("## Time"):report.index("## Config")]
            print(times.strip())


def part_one(config, args) -> None:
    """Labelling one run, three ways, and each map's batch reference (module docstring, part 1)."""
    map_data = load_map(args.map)
    store = extract_words(map_data, config.words).store
    label = config.label
    # a path's checkpoints to label: 320 steps of topic-perplexity exploration
    run = explore(store, "topic-perplexity", 0, model=config.model, settings=config.explore, seed=0)
    phis = [run.checkpoints[n].dense() for n in config.explore.checkpoints]
    for _ in label_paths(store, config.model, [phis[:1]], [0], sweeps=1, warm_sweeps=None, device=resolve_device(args.device)):
        pass  # compiled
    n_classes = int(map_data.labels.max()) + 1

    def tables(words):
        pixels = pixel_labels(store, words, map_data.image.shape[:2])
        contingency(pixels, map_data.labels, config.model.topics, n_classes)

    ours, rebuilt, alone = [], [], []
    for repeat in range(args.repeats):
        began = time.perf_counter()
        for _, _, labels in label_paths(store, config.model, [phis], [repeat], sweeps=label.sweeps,
                                        warm_sweeps=label.warm_sweeps, device=resolve_device(args.device)):
            tables(labels[:, 0])
        ours.append(time.perf_counter() - began)
        began = time.perf_counter()
        for j, phi in enumerate(phis):
            model = whole_map_model(store, config.model, repeat + j, frozen_counts=phi)
            model.refine_batch(label.sweeps, threads=1)
            tables(model.ml_topics())
        rebuilt.append(time.perf_counter() - began)
        model = whole_map_model(store, config.model, repeat, frozen_counts=phis[-1])
        began = time.perf_counter()
        model.refine_batch(label.sweeps, threads=1)
        alone.append(time.perf_counter() - began)
    n, median = len(store.words), statistics.median
    warm = "random start each" if label.warm_sweeps is None else f"then {label.warm_sweeps} warm"
    print(f"{args.map}: {n:,} words; one run of {len(phis)} checkpoints, label.sweeps = {label.sweeps} ({warm}); "
          f"one core, median of {args.repeats}")
    print(f"  labelling the run, one chain               {median(ours):6.2f} s")
    print(f"  a model per checkpoint, {label.sweeps} sweeps each      {median(rebuilt):6.2f} s  (x {median(rebuilt) / median(ours):.2f})")
    print(f"  {label.sweeps} frozen sweeps alone                     {median(alone):6.2f} s  "
          f"({label.sweeps * n / median(alone) / 1e6:.1f} M words/s)")

    print(f"\nbatch reference, {config.label.batch_sweeps} sweeps on {args.threads} threads:")
    for entry in config.datasets:
        m = load_map(entry)
        s = extract_words(m, config.words).store
        began = time.perf_counter()
        _, trace = batch_labels(s, config.model, sweeps=config.label.batch_sweeps, seed=0, threads=args.threads)
        seconds = time.perf_counter() - began
        print(f"  {m.config.name:<16} {len(s.words):>10,} words {seconds:7.1f} s   log-likelihood "
              f"{trace[0]:.3f} -> {trace[len(trace) // 2]:.3f} -> {trace[-1]:.3f} (first, middle, last sweep)")


if __name__ == "__main__":
    main()
