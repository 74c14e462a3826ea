"""Compare the MI of two labelings of the same runs, run by run: two experiment folders' mi.csv.

For two copies of one experiment whose runs are the same but whose labels were made
differently (another sampler, schedule or version), prints per map, path length and
target (Z_h, Z_b) the mean MI of each, the mean paired difference (B minus A) with its
standard error over the runs both have, and whether the difference is within the noise
of the labelling chains by the rule of the convergence check (within 0.01 bits or twice
the standard error, :func:`~curiosity_cli.evaluate.statistics.within_noise`).

    python scripts/compare_mi.py results/paper-grid-before results/paper-grid
    python scripts/compare_mi.py --smoke    # two recorded experiments of studies/multiverse: seconds

Prints and never asserts.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

from curiosity_cli.evaluate.statistics import CONVERGENCE_TOLERANCE, within_noise
from curiosity_cli.experiment.layout import ExperimentFolder

RUN = ["dataset", "weight_function", "restart", "path_length"]
#: --smoke's folders: two specifications of a study's record (its tables, as an experiment folder holds them).
SMOKE = [Path(__file__).resolve().parents[1] / "studies/multiverse/seed-0" / n for n in ("default", "labels-argmax")]
TARGETS = {"mi_human": "Z_h", "mi_batch": "Z_b"}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("a", type=Path, nargs="?", help="experiment folder A (e.g. the labels before)")
    parser.add_argument("b", type=Path, nargs="?", help="experiment folder B (e.g. the labels after)")
    parser.add_argument("--smoke", action="store_true",
                        help="compare two recorded experiments, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.a, args.b = SMOKE
    elif args.b is None:
        parser.error("expected two experiment folders, A and B")
    a, b = (pd.read_csv(ExperimentFolder(folder).table("mi")).set_index(RUN) for folder in (args.a, args.b))
    both = a.merge(b, left_index=True, right_index=True, suffixes=("_a", "_b"))
    print(f"{len(both)} run-lengths in both; MI in bits, B minus A: mean ± standard error over runs, "
          f"✗ where more than {CONVERGENCE_TOLERANCE} and more than 2 standard errors")
    print(f"{'dataset':<16} {'target':<6} {'length':>6} {'n':>4} {'A':>7} {'B':>7} {'B - A':>18}")
    outside = 0
    for (dataset, length), rows in both.groupby(level=["dataset", "path_length"]):
        for column, target in TARGETS.items():
            pair = rows[[f"{column}_a", f"{column}_b"]].dropna()
            if pair.empty:
                continue
            difference = pair[f"{column}_b"] - pair[f"{column}_a"]
            mean, se = difference.mean(), difference.sem()
            ok = within_noise(mean, se, CONVERGENCE_TOLERANCE)
            outside += not ok
            print(f"{dataset:<16} {target:<6} {length:>6} {len(pair):>4} {pair.iloc[:, 0].mean():7.3f} "
                  f"{pair.iloc[:, 1].mean():7.3f} {mean:+8.4f} ± {se:.4f} {'' if ok else '✗'}")
    print(f"outside the noise: {outside}")


if __name__ == "__main__":
    main()
