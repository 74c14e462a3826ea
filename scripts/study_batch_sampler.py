"""Whether the batch reference Z_b changes when the word-topic counts are synchronised once per colour.

A batch sweep (``label.sampling.batch_labels``) refines the observed cells in phases and
brings every thread's word-topic counts up to date once per phase: each cell sees the
counts of its phase's start plus its own changes. Today a phase holds at most 1/16 of
the cells (``batch_sweeps._PHASES = 16``: the sampler ``phases-16``). With
``_PHASES = 1`` a phase is one whole colour of the cell colouring (the sampler
``colours``): fewer synchronisations and staler counts, an AD-LDA-style approximation
(issue 42; its speed: ``scripts/bench_batch_threads.py --colours``). The staleness does
not depend on the threads, so one thread measures it as well as many.

For each map, each sampler and each seed (0 .. --seeds - 1) this computes Z_b as the
label stage does (--sweeps batch sweeps, default the config's ``label.batch_sweeps``)
and spreads it over the pixels, then records its mutual information with the human
labels (bits), the final mean per-word log-likelihood (the trace's last value, nats)
and the seconds of ``batch_labels`` (after one untimed compiling sweep in each worker
process; with --jobs > 1 the tasks share the machine, so compare seconds only within
one run). Per map it prints:

- per sampler, the mean and standard deviation over seeds of MI(Z_b; human) and of the
  final log-likelihood, and the mean seconds;
- chain agreement: MI(Z_b,i; Z_b,j) over the seed pairs i < j within each sampler, and
  over the pairs (phases-16 seed i, colours seed j), i != j, across them (mean and
  standard deviation over pairs);
- the difference of the MI-to-human means, colours minus phases-16, its standard error
  and the p value of Welch's t-test;
- a verdict: whether that difference is within two of its standard errors, and whether
  the mean across-sampler chain MI lies within the spread of the within-sampler chain MI
  (the mean of both samplers' within pairs, pooled, plus or minus two standard
  deviations). Two samplers that draw from the same distribution pass both.

    python scripts/study_batch_sampler.py --maps aerial-mosaic sentinel-coast reef-mosaic --seeds 5 --jobs 2 --threads 1
    python scripts/study_batch_sampler.py --smoke     # the smallest map, 2 seeds, one sweep: seconds

Prints and never asserts: the answer is read from the table.
"""

from __future__ import annotations

import argparse
import itertools
import os
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

import numpy as np

#: Sampler name -> ``batch_sweeps._PHASES``.
SAMPLERS = {"phases-16": 16, "colours": 1}

_compiled = False


def task(name: str, store_path: Path, sampler: str, seed: int, sweeps: int, threads: int) -> dict:
    """One map's Z_b with one sampler and seed, in this process: pixel labels, MI to human, trace end, seconds."""
    global _compiled
    from curiosity_cli.config import load_config
    from curiosity_cli.evaluate.information import contingency, mutual_information
    from curiosity_cli.label.sampling import batch_labels, pixel_labels
    from curiosity_cli.maps.map_data import load_map
    from curiosity_cli.topics import batch_sweeps
    from curiosity_cli.words.store import load_store

    batch_sweeps._PHASES = SAMPLERS[sampler]  # a module global: set in the process that samples
    config = load_config("quick", overrides=[f"datasets=[{name}]"])
    store = load_store(store_path)
    map_data = load_map(name)
    if not _compiled:
        batch_labels(store, config.model, sweeps=1, seed=seed, threads=threads)
        _compiled = True
    began = time.perf_counter()
    words, trace = batch_labels(store, config.model, sweeps=sweeps, seed=seed, threads=threads)
    seconds = time.perf_counter() - began
    pixels = pixel_labels(store, words, map_data.image.shape[:2])
    human = map_data.labels
    mi_human = (
        mutual_information(contingency(pixels, human, config.model.topics, map_data.n_classes))
        if human is not None else np.nan
    )
    return {"map": name, "sampler": sampler, "seed": seed, "pixels": pixels, "mi_human": mi_human,
            "log_likelihood": float(trace[-1]), "seconds": seconds, "topics": config.model.topics}


def chain_mi(a: np.ndarray, b: np.ndarray, k: int) -> float:
    from curiosity_cli.evaluate.information import contingency, mutual_information

    return mutual_information(contingency(a, b, k, k))


def mean_sd(values) -> tuple[float, float]:
    values = np.asarray(values, float)
    return float(values.mean()), float(values.std(ddof=1)) if values.size > 1 else np.nan


def report(name: str, results: list[dict]) -> None:
    """Print one map's table and verdict (module docstring)."""
    from scipy.stats import ttest_ind

    by = {s: sorted((r for r in results if r["sampler"] == s), key=lambda r: r["seed"]) for s in SAMPLERS}
    k = results[0]["topics"]
    print(f"\n{name}")
    print(f"{'sampler':>10}  {'MI(Z_b; human) bits':>21}  {'final log-lik (nats)':>22}  {'seconds':>8}")
    for sampler, rows in by.items():
        mi, mi_sd = mean_sd([r["mi_human"] for r in rows])
        ll, ll_sd = mean_sd([r["log_likelihood"] for r in rows])
        print(f"{sampler:>10}  {mi:>10.4f} ± {mi_sd:<8.4f}  {ll:>11.5f} ± {ll_sd:<8.5f}  "
              f"{np.mean([r['seconds'] for r in rows]):>8.1f}")
    print("  per seed MI(Z_b; human): " + "; ".join(
        f"{s} " + " ".join(f"{r['mi_human']:.4f}" for r in rows) for s, rows in by.items()))

    within = {s: [chain_mi(a["pixels"], b["pixels"], k) for a, b in itertools.combinations(rows, 2)]
              for s, rows in by.items()}
    first, second = list(SAMPLERS)
    across = [chain_mi(a["pixels"], b["pixels"], k)
              for a in by[first] for b in by[second] if a["seed"] != b["seed"]]
    print("  chain MI(Z_b,i; Z_b,j) bits: " + ", ".join(
        f"within {s} {mean_sd(v)[0]:.4f} ± {mean_sd(v)[1]:.4f} ({len(v)} pairs)" for s, v in within.items())
        + f", across {mean_sd(across)[0]:.4f} ± {mean_sd(across)[1]:.4f} ({len(across)} pairs)")

    a = np.array([r["mi_human"] for r in by[first]])
    b = np.array([r["mi_human"] for r in by[second]])
    difference = b.mean() - a.mean()
    se = np.sqrt(a.var(ddof=1) / a.size + b.var(ddof=1) / b.size)
    p = ttest_ind(b, a, equal_var=False).pvalue
    print(f"  MI to human, {second} minus {first}: {difference:+.4f} bits (standard error {se:.4f}), "
          f"Welch p = {p:.3g}")

    pooled_mean, pooled_sd = mean_sd(within[first] + within[second])
    low, high = pooled_mean - 2 * pooled_sd, pooled_mean + 2 * pooled_sd
    across_mean = mean_sd(across)[0]
    human_ok = bool(abs(difference) <= 2 * se)
    chains_ok = bool(low <= across_mean <= high)
    print(f"  verdict: MI-to-human difference {'within' if human_ok else 'NOT within'} two standard errors "
          f"(|{difference:+.4f}| vs {2 * se:.4f}); across-sampler chain MI {across_mean:.4f} "
          f"{'within' if chains_ok else 'NOT within'} the within-sampler spread [{low:.4f}, {high:.4f}]")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--maps", nargs="+", default=["aerial-mosaic", "sentinel-coast", "reef-mosaic"])
    parser.add_argument("--seeds", type=int, default=5, help="seeds 0 .. N-1 per map and sampler")
    parser.add_argument("--sweeps", type=int, help="batch sweeps; default the config's label.batch_sweeps")
    parser.add_argument("--threads", type=int, default=2, help="threads of each batch_labels")
    parser.add_argument("--jobs", type=int, default=1, help="processes computing (map, sampler, seed) tasks at once")
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.maps, args.seeds, args.sweeps, args.threads, args.jobs = ["rare-patches"], 2, 1, 1, 1

    from curiosity_cli.config import load_config
    from curiosity_cli.experiment.maps import prepare_stores
    from curiosity_cli.paths import DEFAULT_CACHE

    started = time.perf_counter()
    stores, sweeps = {}, args.sweeps
    for name in args.maps:  # here, once: workers preparing one store at once would race
        config = load_config("quick", overrides=[f"datasets=[{name}]"])
        stores[name] = next(iter(prepare_stores(config, DEFAULT_CACHE).values())).path
        sweeps = sweeps or config.label.batch_sweeps
    print(f"logical CPUs {os.cpu_count()}; {sweeps} batch sweeps, seeds 0..{args.seeds - 1}, "
          f"{args.threads} thread(s) per chain, {args.jobs} job(s); samplers "
          + ", ".join(f"{s} (_PHASES = {p})" for s, p in SAMPLERS.items()), flush=True)

    # seeds outermost within a map, the samplers side by side: both see the same load
    tasks = [(name, stores[name], sampler, seed, sweeps, args.threads)
             for name in args.maps for seed in range(args.seeds) for sampler in SAMPLERS]
    results: dict[str, list[dict]] = {name: [] for name in args.maps}
    # spawn, not fork: a forked child inherits the parent's numba and thread state
    with ProcessPoolExecutor(args.jobs, mp_context=get_context("spawn")) as pool:
        futures = [pool.submit(task, *t) for t in tasks]
        for future in futures:
            r = future.result()
            results[r["map"]].append(r)
            print(f"  {r['map']} {r['sampler']} seed {r['seed']}: MI to human {r['mi_human']:.4f} bits, "
                  f"log-lik {r['log_likelihood']:.5f}, {r['seconds']:.1f} s", flush=True)
            if len(results[r["map"]]) == args.seeds * len(SAMPLERS):
                report(r["map"], results[r["map"]])
    print(f"\n{time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()
