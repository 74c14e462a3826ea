"""Benchmark the labelling pipeline, and the full paper grid end to end.

Part 1, one process (numba compiled first, untimed), on --map (default aerial-mosaic):
- labelling one checkpoint: Z_p of the whole map from a path model's Φ (label.sweeps
  frozen-Φ sweeps, ML topics, pixel labels, contingency tables), median of --repeats,
  beside its reference in the same run: the frozen sweeps alone;
- the batch reference Z_b of each map of --config (label.batch_sweeps sweeps on
  --threads threads), once each.
Part 2 (--full-grid): `curiosity reproduce CONFIG --jobs N` in a fresh process, words
already cached, into --results-dir (a temporary folder unless given): wall time, and the
seconds per stage from its REPORT.md.

    python scripts/bench_pipeline.py                                   # part 1, a few minutes
    python scripts/bench_pipeline.py --full-grid --results-dir results # and the paper grid

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

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.data import load_map
from curiosity_cli.evaluate.information import contingency
from curiosity_cli.evaluate.labeling import _whole_map_model, batch_labels, label_with_phi, pixel_labels
from curiosity_cli.explore.walker import explore
from curiosity_cli.words.extract import extract_words


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--config", type=Path, default=CONFIG_DIR / "paper-grid.yaml")
    parser.add_argument("--map", default="aerial-mosaic")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--full-grid", action="store_true")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--results-dir", type=Path, default=None)
    args = parser.parse_args()

    config = load_config(args.config)
    map_data = load_map(args.map)
    store = extract_words(map_data, config.words).store
    sweeps = config.label.sweeps
    # a path model to label with: 80 steps of topic-perplexity exploration
    settings = dataclasses.replace(config.explore, path_length=80, checkpoints=(80,))
    phi = explore(store, "topic-perplexity", 0, model=config.model, settings=settings, seed=0).checkpoints[80].dense()
    label_with_phi(store, phi, config.model, sweeps=1, seed=0)

    whole, alone = [], []
    for repeat in range(args.repeats):
        began = time.perf_counter()
        words = label_with_phi(store, phi, config.model, sweeps=sweeps, seed=repeat)
        pixels = pixel_labels(store, words, map_data.image.shape[:2])
        contingency(pixels, map_data.labels, config.model.topics, int(map_data.labels.max()) + 1)
        whole.append(time.perf_counter() - began)
        model = _whole_map_model(store, config.model, repeat, frozen_counts=phi)
        began = time.perf_counter()
        model.refine_batch(sweeps, threads=1)
        alone.append(time.perf_counter() - began)
    n = len(store.words)
    print(f"{args.map}: {n:,} words; label.sweeps = {sweeps}, one core, median of {args.repeats}")
    print(f"  labelling one checkpoint   {statistics.median(whole):6.2f} s")
    print(f"  its frozen sweeps alone    {statistics.median(alone):6.2f} s  "
          f"({sweeps * n / statistics.median(alone) / 1e6:.1f} M words/s; ratio {statistics.median(whole) / statistics.median(alone):.2f})")

    print(f"\nbatch reference, {config.label.batch_sweeps} sweeps on {args.threads} threads:")
    for entry in config.datasets:
        m = load_map(entry)
        s = extract_words(m, config.words).store
        began = time.perf_counter()
        _, trace = batch_labels(s, config.model, sweeps=config.label.batch_sweeps, seed=0, threads=args.threads)
        seconds = time.perf_counter() - began
        print(f"  {m.config.name:<16} {len(s.words):>10,} words {seconds:7.1f} s   log-likelihood "
              f"{trace[0]:.3f} -> {trace[len(trace) // 2]:.3f} -> {trace[-1]:.3f} (first, middle, last sweep)")

    if args.full_grid:
        with tempfile.TemporaryDirectory() as tmp:
            results = args.results_dir or Path(tmp)
            command = [sys.executable, "-m", "curiosity_cli", "reproduce", str(args.config), "--jobs", str(args.jobs),
                       "--results-dir", str(results)]
            began = time.perf_counter()
            subprocess.run(command, check=True)
            minutes = (time.perf_counter() - began) / 60
            report = (results / config.name / "REPORT.md").read_text()
        print(f"\nfull grid, `curiosity reproduce {args.config.name} --jobs {args.jobs}`: {minutes:.1f} min end to end")
        times = report[report.index("## Time"):report.index("## Config")]
        print(times.strip())


if __name__ == "__main__":
    main()
