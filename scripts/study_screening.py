"""Screening the readings of issue 32 before the specification-curve study: which of the
paper's open choices move topic perplexity's steering at all.

For each map and each reading changed alone from the default (and ``rost``, all of the
authors' readings together: configs/rost.yaml), explore ``--restarts`` topic-perplexity paths of ``--length`` steps
(no labelling: steering needs only the walker's own records) and report, per reading:

- steering: the total-variation distance between topic perplexity's step distribution and
  stochastic coverage's on the same candidates (the recorded coverage potential U),
  averaged over the scored steps; 0 means topic perplexity steps as coverage would;
- spread: the median over steps of the largest / smallest finite candidate perplexity;
- infinite: the share of candidates with an infinite perplexity (counts-only P(k | path));
- seconds per run.

Usage: python scripts/study_screening.py [--maps M ...] [--restarts 4] [--length 80]
       python scripts/study_screening.py --smoke    # two readings, one path of 5 steps on the smallest map: seconds
"""

from __future__ import annotations

import argparse
import time

import numpy as np

READINGS = {
    "default": [],
    "candidates-8": ["explore.candidates=8"],
    "context-own": ["explore.candidate_context=own"],
    "context-own-10-sweeps": ["explore.candidate_context=own", "explore.candidate_sweeps=10"],
    "sweeps-10": ["explore.candidate_sweeps=10"],
    "path-topics-counts": ["explore.path_topics=counts"],
    "revisits-again": ["explore.revisits=again"],
    "picks-recent": ["explore.refine_picks=recent"],
    "coverage-clamp": ["explore.coverage=clamp"],
    "coverage-others": ["explore.coverage=others"],
    "beta-1": ["model.beta=1.0"],
    "topics-16": ["model.topics=16"],
    "orb-grid": ["words.orb_detector=grid"],
    "colour-words": ["words.colour_words=true"],
    "rost": "rost",
}


def steering(run) -> tuple[float, float, float]:
    from curiosity_cli.evaluate.steering import step_distances

    _, distances = step_distances(run.candidate_step, run.coverage, run.weight)
    spreads = []
    for step in np.unique(run.candidate_step):
        here = run.candidate_step == step
        finite = run.topic_perplexity[here][np.isfinite(run.topic_perplexity[here])]
        if finite.size > 1:
            spreads.append(finite.max() / finite.min())
    return float(np.mean(distances)), float(np.median(spreads)), float(np.mean(np.isinf(run.topic_perplexity)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maps", nargs="+", default=["zurich-zh17", "aerial-mosaic", "sentinel-coast", "reef-mosaic"])
    parser.add_argument("--readings", nargs="+", default=list(READINGS))
    parser.add_argument("--restarts", type=int, default=4)
    parser.add_argument("--length", type=int, default=80)
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.maps, args.readings, args.restarts, args.length = ["rare-patches"], ["default", "rost"], 1, 5

    from curiosity_cli.api import load, word_store
    from curiosity_cli.explore.walker import explore

    print(f"{'reading':24s} {'map':16s} steering  spread  infinite  s/run")
    for name in args.readings:
        base, overrides = ("rost", []) if READINGS[name] == "rost" else ("quick", READINGS[name])
        config = load(base, overrides + [f"explore.path_length={args.length}", f"explore.checkpoints=[{args.length}]"])
        for dataset in args.maps:
            store = word_store(dataset, config)
            starts = np.random.default_rng(0).choice(store.n_cells, args.restarts, replace=False)
            rows, took = [], []
            for restart, start in enumerate(starts):
                began = time.perf_counter()
                run = explore(store, "topic-perplexity", int(start), model=config.model, settings=config.explore,
                              seed=(0, restart))
                took.append(time.perf_counter() - began)
                rows.append(steering(run))
            s, spread, infinite = np.mean(rows, axis=0)
            print(f"{name:24s} {dataset:16s} {s:8.3f} {spread:7.2f} {infinite:9.3f} {np.median(took):6.1f}", flush=True)


if __name__ == "__main__":
    main()
