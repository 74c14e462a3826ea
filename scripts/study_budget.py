"""Has the default refinement budget converged? MI at 80 and 320 steps for half, once and twice it.

Runs configs/quick.yaml (aerial-mosaic, 5 restarts, 320 steps) three times with
explore.samples_per_step at 1/2, 1 and 2 times the config's value, each as its own
experiment (`budget-<samples>` under --results-dir, resumable), labels and evaluates
them, and prints the mean MI against human and batch labels at 80 and 320 steps with the
standard error over restarts. If doubling the budget moves the means by less than their
standard errors, the default has converged. Prints and never asserts.

    python scripts/study_budget.py --jobs 2        # ~15 minutes on 2 cores
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.paths import DEFAULT_RESULTS
from curiosity_cli.study.pipeline import reproduce

LENGTHS = (80, 320)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--config", type=Path, default=CONFIG_DIR / "quick.yaml")
    parser.add_argument("--results-dir", type=Path, default=DEFAULT_RESULTS / "studies")
    parser.add_argument("--jobs", type=int, default=None)
    args = parser.parse_args()

    base = load_config(args.config)
    default = base.explore.samples_per_step
    tables = []
    for budget in (default // 2, default, default * 2):
        config = dataclasses.replace(
            base, name=f"budget-{budget}",
            explore=dataclasses.replace(base.explore, samples_per_step=budget, checkpoints=LENGTHS),
        )
        reproduce(config, results_dir=args.results_dir, jobs=args.jobs)
        mi = pd.read_csv(args.results_dir / config.name / "mi.csv")
        mi["budget"] = budget
        tables.append(mi)
    mi = pd.concat(tables)
    long = mi.melt(id_vars=["budget", "weight_function", "restart", "path_length"], value_vars=["mi_human", "mi_batch"],
                   var_name="against", value_name="mi")
    stats = long.groupby(["against", "path_length", "weight_function", "budget"])["mi"].agg(
        mean="mean", se=lambda x: x.std() / np.sqrt(len(x))
    )
    table = stats.unstack("budget")
    pd.set_option("display.width", 160)
    print(f"mean MI (bits) and standard error over {base.explore.restarts} restarts, by word samples per step")
    print(table.round(3).to_string())


if __name__ == "__main__":
    main()
