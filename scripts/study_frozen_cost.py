"""Where labelling's frozen-Φ sweep spends its time: nanoseconds per word against the number of topics K.

Labelling is most of the grid's time, and its kernel is the frozen-Φ Gibbs sweep
(:func:`curiosity_cli.topics._sampler.gibbs_cell_frozen`). This study times that sweep on
one thread over every word of --map with frozen counts drawn at random, for K = 8 to 128,
and fits ``ns per word = fixed + per_topic * K`` by least squares: the fixed part is what
any K pays per word (the draw's chain of dependent float additions, the topic update,
the random bits), the per-topic part the weights loop and the draw's sums. Median of
--repeats, each --sweeps sweeps after 2 untimed ones.

    python scripts/study_frozen_cost.py                 # about a minute
    python scripts/study_frozen_cost.py --smoke         # the smallest map, one sweep per K: seconds

Prints and never asserts: timings depend on the machine.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import numpy as np

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.label.sampling import whole_map_model
from curiosity_cli.words.extract import extract_words

TOPICS = (8, 16, 32, 64, 128)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--map", default="aerial-mosaic")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--sweeps", type=int, default=8)
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.map, args.repeats, args.sweeps = "rare-patches", 1, 1

    config = load_config(CONFIG_DIR / "paper.yaml", [f"datasets=[{args.map}]", "name=study", "seed=0"])
    store = extract_words(load_map(args.map), config.words).store
    n = len(store.words)
    rng = np.random.default_rng(0)
    print(f"{args.map}: {n:,} words, frozen-Φ sweeps on one thread, median of {args.repeats} x {args.sweeps} sweeps")
    per_word = []
    for k in TOPICS:
        model = whole_map_model(store, dataclasses.replace(config.model, topics=k), 0,
                                 frozen_counts=rng.integers(0, 50, (store.vocabulary_size, k)))
        model.refine_batch(2, threads=1)  # compiled, and past the random start
        times = []
        for _ in range(args.repeats):
            began = time.perf_counter()
            model.refine_batch(args.sweeps, threads=1)
            times.append((time.perf_counter() - began) / args.sweeps)
        seconds = statistics.median(times)
        per_word.append(seconds / n * 1e9)
        print(f"  K = {k:3d}: {seconds * 1e3:6.1f} ms per sweep, {n / seconds / 1e6:5.1f} M words/s, "
              f"{per_word[-1]:5.1f} ns per word")
    per_topic, fixed = np.polyfit(TOPICS, per_word, 1)
    print(f"fit: {fixed:.1f} ns per word for any K + {per_topic:.2f} ns per topic "
          f"(at K = {config.model.topics}: {fixed / (fixed + per_topic * config.model.topics):.0%} fixed)")


if __name__ == "__main__":
    main()
