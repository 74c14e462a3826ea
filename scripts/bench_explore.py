"""Benchmark exploration: steps per second per weight function, and the full paper grid's wall time.

Part 1, one core, in this process (numba compiled first, untimed): for each weight
function, --repeats runs of --steps steps on a map at the config's default budget,
each from another start cell; the table gives the median steps per second and, as the
reference measured in the same run, the steps per second of the refinement alone
(realtime refinement with the same budget on a model fed the same path), so the
ratio shows what scoring and bookkeeping cost on top of the sampler.

Part 2 (--full-grid): `curiosity explore configs/paper-grid.yaml --jobs N` into a
temporary results folder: wall time, runs, bytes per run and in total. The paper's
protocol (200 ms per step) would need 240 runs x 320 steps x 0.2 s = 4.3 hours.

    python scripts/bench_explore.py                      # part 1, ~1 minute
    python scripts/bench_explore.py --full-grid --jobs 2  # and part 2, ~7 minutes on 2 cores
    python scripts/bench_explore.py --smoke               # part 1 on the smallest map, 3 steps: seconds

Prints and never asserts: timings depend on the machine.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.explore.walker import explore
from curiosity_cli.config import VALIDATION_WALKERS
from curiosity_cli.explore.weights import WEIGHT_FUNCTIONS
from curiosity_cli.topics.model import TopicModel
from curiosity_cli.words.extract import extract_words


def refinement_alone(store, path: np.ndarray, model, budget: int) -> float:
    """Steps per second of observing and refining along ``path``, nothing else."""
    topic_model = TopicModel(
        model.topics, store.vocabulary_size, store.grid.neighbour_table(model.spatial_neighbours),
        alpha=model.alpha, beta=model.beta, seed=0,
    )
    start = time.perf_counter()
    for step, cell in enumerate(path):
        if not topic_model.is_observed(int(cell)):
            topic_model.add_cell(int(cell), store.cell_words(int(cell)), time=step)
        topic_model.refine_realtime(budget, eta=model.eta)
    return path.size / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--config", type=Path, default=CONFIG_DIR / "paper-grid.yaml")
    parser.add_argument("--map", default="aerial-mosaic")
    parser.add_argument("--steps", type=int, default=320)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--full-grid", action="store_true", help="also time the whole grid of --config")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.map, args.steps, args.repeats = "rare-patches", 3, 1

    config = load_config(args.config)
    settings = dataclasses.replace(config.explore, path_length=args.steps, checkpoints=(args.steps,))
    store = extract_words(load_map(args.map), config.words).store
    budget = settings.samples_per_step
    print(f"map {args.map}: {store.n_cells} cells, {len(store.words):,} words; budget {budget:,} word samples per step")
    explore(store, "topic-perplexity", 0, model=config.model, settings=dataclasses.replace(settings, path_length=3, checkpoints=(3,)), seed=0)

    starts = np.random.default_rng(1).choice(store.n_cells, args.repeats, replace=False)
    print(f"\n{'weight function':<22}{'steps/s':>10}{'sampler alone':>15}{'ratio':>8}   (median of {args.repeats} runs of {args.steps} steps)")
    for name in (n for n in WEIGHT_FUNCTIONS if n not in VALIDATION_WALKERS):  # an oracle needs a map's truth
        ours, alone = [], []
        for repeat, start in enumerate(starts):
            began = time.perf_counter()
            e = explore(store, name, int(start), model=config.model, settings=settings, seed=repeat)
            ours.append(args.steps / (time.perf_counter() - began))
            alone.append(refinement_alone(store, e.path, config.model, budget))
        a, b = statistics.median(ours), statistics.median(alone)
        print(f"{name:<22}{a:>10.1f}{b:>15.1f}{a / b:>8.2f}")

    if args.full_grid:
        with tempfile.TemporaryDirectory() as tmp:
            command = [sys.executable, "-m", "curiosity_cli", "explore", str(args.config), "--jobs", str(args.jobs), "--results-dir", tmp]
            began = time.perf_counter()
            subprocess.run(command, check=True)
            seconds = time.perf_counter() - began
            files = [p for p in Path(tmp).rglob("*") if p.is_file() and "runs" in p.parts]
            runs = len([p for p in files if p.name == "run.json"])
            total = sum(p.stat().st_size for p in files)
        print(f"\nfull grid {args.config.name}, --jobs {args.jobs}: {runs} runs in {seconds / 60:.1f} min "
              f"({seconds / max(runs, 1):.2f} s per run); {total / 1e6:.1f} MB, {total / max(runs, 1) / 1e3:.0f} kB per run")
        print(f"the paper's protocol, 200 ms per step: {runs * settings.path_length * 0.2 / 3600:.1f} hours of robot time")


if __name__ == "__main__":
    main()
