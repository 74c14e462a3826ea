"""What "no difference" gives the headline statistics: simulated walkers whose truth is known.

Four walkers over 10 paired restarts (a per-run coefficient of variation drawn from
0.10-0.25 and a correlation between a restart's walkers from 0-0.5, around 0.3 bits),
the first standing for topic perplexity. Prints, over ``--draws`` draws:

- the ratio of its mean MI to the next best's (the highest of the other three means):
  median and share below 1, when all four are equal;
- how often the null-referenced p of that ratio (:func:`~curiosity_cli.evaluate.comparisons.next_best_null`)
  is below 0.05: with four equal walkers, and with the fourth walker 10, 20 and 50 % worse;
- how often the 95 % interval of the ratio to each walker alone covers the true ratio 1:
  the studentized interval the reports use (:func:`~curiosity_cli.evaluate.comparisons.ratio_interval`)
  and a percentile bootstrap beside it.

    python scripts/null_reference.py [--draws 2000] [--pairs 10]
    python scripts/null_reference.py --smoke    # 2 draws: a second
"""

from __future__ import annotations

import argparse

import numpy as np

from curiosity_cli.evaluate.comparisons import next_best_null, next_best_ratio, ratio_interval


def walkers(rng: np.random.Generator, pairs: int, worse: float = 0.0) -> np.ndarray:
    """(pairs, 4) MI: equal walkers, the last ``worse`` lower."""
    cv, rho = rng.uniform(0.10, 0.25), rng.uniform(0.0, 0.5)
    noise = np.sqrt(rho) * rng.standard_normal((pairs, 1)) + np.sqrt(1 - rho) * rng.standard_normal((pairs, 4))
    mi = 0.3 * (1 + cv * noise)
    mi[:, 3] *= 1 - worse
    return mi


def percentile_interval(a: np.ndarray, b: np.ndarray, rng: np.random.Generator, resamples: int = 1000) -> tuple[float, float]:
    picks = rng.integers(0, a.size, (resamples, a.size))
    low, high = np.quantile(a[picks].mean(axis=1) / b[picks].mean(axis=1), [0.025, 0.975])
    return float(low), float(high)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=2000)
    parser.add_argument("--pairs", type=int, default=10)
    parser.add_argument("--smoke", action="store_true", help="tiny inputs, a second (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.draws = 2
    rng = np.random.default_rng(41)
    ratios, rejected, studentized, percentile = [], 0, 0, 0
    for i in range(args.draws):
        mi = walkers(rng, args.pairs)
        ratios.append(next_best_ratio(mi[:, 0], mi[:, 1:]))
        rejected += next_best_null(mi[:, 0], mi[:, 1:], permutations=1000, seed=i).p_value < 0.05
        for j in (1, 2, 3):
            low, high = ratio_interval(mi[:, 0], mi[:, j], resamples=1000, seed=i)
            studentized += low <= 1 <= high
            low, high = percentile_interval(mi[:, 0], mi[:, j], rng)
            percentile += low <= 1 <= high
    ratios = np.array(ratios)
    print(f"{args.draws} draws of four equal walkers, {args.pairs} pairs:")
    print(f"  ratio to the next best: median {np.median(ratios):.3f}, below 1 in {100 * np.mean(ratios < 1):.1f} %")
    print(f"  null-referenced p < 0.05 in {100 * rejected / args.draws:.1f} %")
    print(f"  95 % interval of the ratio to each walker covers 1: studentized {100 * studentized / (3 * args.draws):.1f} %, "
          f"percentile {100 * percentile / (3 * args.draws):.1f} %")
    for worse in (0.1, 0.2, 0.5):
        hits = 0
        for i in range(args.draws // 2):
            mi = walkers(rng, args.pairs, worse)
            hits += next_best_null(mi[:, 0], mi[:, 1:], permutations=1000, seed=i).p_value < 0.05
        print(f"  one walker {100 * worse:.0f} % worse: null-referenced p < 0.05 in {100 * hits / (args.draws // 2):.1f} %")


if __name__ == "__main__":
    main()
