"""Benchmark labelling's sampler: lock-step chains against the single-chain sampler they replaced.

Z_p is frozen-Φ Gibbs sampling of every word of a map. Until label format 2, each run's
chain was swept alone by the single-chain kernel
(:func:`curiosity_cli.topics._sampler.gibbs_cell_frozen`, through a frozen
:class:`~curiosity_cli.topics.model.TopicModel`), which stays here as the reference. Now
the chains of R runs advance in lock-step (:class:`~curiosity_cli.topics.chains.FrozenChains`).

For each map of --maps: real Φ_p from --runs topic-perplexity runs of --steps steps
(explored here, the config's settings), and both samplers at --threads 1 and 2. One
thread is one process sweeping; two threads are two processes sweeping at once (how
``label`` keeps both cores busy: one block of chains per worker), each timed on its own.
The variants are interleaved in every repeat, after one untimed sweep each; printed:
nanoseconds per word-sample per chain, median of --repeats, and the ratio of the
reference to each.

    python scripts/bench_label.py                      # zurich-zh17 and aerial-mosaic, a few minutes
    python scripts/bench_label.py --smoke              # the smallest map, 3 steps, one sweep: seconds

Prints and never asserts: timings depend on the machine.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.label.sampling import map_chains, whole_map_model
from curiosity_cli.explore.walker import explore
from curiosity_cli.words.extract import extract_words

CHAINS = (1, 8, 16, 32)
#: The issue's goal: lock-step at R = 16 this many times as fast as the single chain, one core.
GOAL = 3.5


def setup(name: str, runs: int, steps: int):
    config = load_config(CONFIG_DIR / "paper.yaml", [f"datasets=[{name}]", "name=bench", "seed=0"])
    store = extract_words(load_map(name), config.words).store
    settings = dataclasses.replace(config.explore, path_length=steps, checkpoints=(steps,))
    phis = [
        explore(store, "topic-perplexity", r, model=config.model, settings=settings, seed=r).checkpoints[steps].dense()
        for r in range(runs)
    ]
    return config, store, phis


def time_variants(name: str, runs: int, steps: int, sweeps: int, repeats: int, chains: tuple[int, ...]) -> dict:
    """Seconds per word-sample per chain of each variant, one list per variant (one process)."""
    config, store, phis = setup(name, runs, steps)
    n = store.words.size
    reference = whole_map_model(store, config.model, 0, frozen_counts=phis[0])
    reference.refine_batch(1)
    blocks = {}
    for r in chains:
        block = map_chains(store, config.model)
        block.start([phis[i % len(phis)] for i in range(r)], list(range(r)))
        block.sweep(1)
        blocks[r] = block
    times = {"single chain": [], **{f"lock-step R = {r}": [] for r in chains}}
    for _ in range(repeats):
        began = time.perf_counter()
        reference.refine_batch(sweeps)
        times["single chain"].append((time.perf_counter() - began) / (sweeps * n))
        for r, block in blocks.items():
            began = time.perf_counter()
            block.sweep(sweeps)
            times[f"lock-step R = {r}"].append((time.perf_counter() - began) / (sweeps * n * r))
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--maps", nargs="+", default=["zurich-zh17", "aerial-mosaic"])
    parser.add_argument("--runs", type=int, default=4, help="runs whose Φ_p the chains take in turn")
    parser.add_argument("--steps", type=int, default=80)
    parser.add_argument("--sweeps", type=int, default=2, help="sweeps per timing")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--chains", type=int, nargs="+", default=list(CHAINS), help="lock-step chains R to time")
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.maps, args.runs, args.steps, args.sweeps, args.repeats, args.chains = ["rare-patches"], 1, 3, 1, 1, [1, 2]

    for name in args.maps:
        rows = {}
        for threads in (1, 2):
            with ProcessPoolExecutor(threads) as pool:
                results = list(pool.map(
                    time_variants,
                    *zip(*[(name, args.runs, args.steps, args.sweeps, args.repeats, tuple(args.chains))] * threads),
                ))
            for variant in results[0]:
                rows.setdefault(variant, {})[threads] = statistics.median(np.concatenate([r[variant] for r in results]))
        print(f"\n{name}: Φ_p of {args.runs} topic-perplexity runs at {args.steps} steps, K = 64; ns per word-sample "
              f"per chain, median of {args.repeats} x {args.sweeps} sweeps (ratio: single chain / this)")
        print(f"  {'sampler':<20} {'1 thread':>16} {'2 threads':>18}")
        reference = rows["single chain"]
        for variant, by_threads in rows.items():
            cells = [f"{by_threads[t] * 1e9:7.1f} ({reference[t] / by_threads[t]:4.2f}x)" for t in (1, 2)]
            print(f"  {variant:<20} {cells[0]:>16} {cells[1]:>18}")
        print(f"  goal: lock-step R = 16 at least {GOAL}x the single chain on one thread")


if __name__ == "__main__":
    main()
