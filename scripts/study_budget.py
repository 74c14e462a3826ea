"""Has the default refinement budget converged? MI at 80 and 320 steps for half, once and twice it.

Runs --config (default configs/quick.yaml) to the longest of --lengths (default 80 and 320
steps) three times with explore.samples_per_step at 1/2, 1 and 2 times the config's value,
each as its own experiment (`budget-<samples>` under --results-dir, resumable), labels and
evaluates them, and prints the mean MI against human and batch labels at each of --lengths
with the standard error over restarts. If doubling the budget moves the means by less than their
standard errors, the default has converged. Prints and never asserts.

    python scripts/study_budget.py --jobs 2        # ~15 minutes on 2 cores
    python scripts/study_budget.py --smoke         # two walkers, two restarts of 10 steps on the smallest map: seconds
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from curiosity_cli import api
from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.paths import DEFAULT_RESULTS

LENGTHS = (80, 320)
#: --smoke's config, on top of --config.
SMOKE = [
    "datasets=[rare-patches]", "explore.weight_functions=[random-walk, topic-perplexity]", "explore.restarts=2",
    "label.sweeps=1", "label.warm_sweeps=1", "label.batch_sweeps=1",
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--config", type=Path, default=CONFIG_DIR / "quick.yaml")
    parser.add_argument("--results-dir", type=Path, default=DEFAULT_RESULTS / "studies")
    parser.add_argument("--jobs", type=int, default=None)
    parser.add_argument("--lengths", type=int, nargs="+", default=list(LENGTHS), help="the path lengths compared")
    parser.add_argument("--smoke", action="store_true", help="tiny inputs in a temporary folder, seconds "
                        "(what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        args.lengths, args.jobs = [5, 10], 1
        with tempfile.TemporaryDirectory() as tmp:
            study(load_config(args.config, SMOKE), Path(tmp), args)
    else:
        study(load_config(args.config), args.results_dir, args)


def study(base, results_dir: Path, args) -> None:
    """Reproduce ``base`` at each budget into ``results_dir`` and print the table (module docstring)."""
    default = base.explore.samples_per_step
    tables = []
    for budget in (default // 2, default, default * 2):
        config = dataclasses.replace(
            base, name=f"budget-{budget}",
            explore=dataclasses.replace(
                base.explore, samples_per_step=budget, path_length=max(args.lengths), checkpoints=tuple(args.lengths)
            ),
        )
        # explored, labelled and evaluated, not plotted: mi.csv is all the study reads
        folder = api.explore(config, results_dir=results_dir, jobs=args.jobs).folder
        api.label(folder, jobs=args.jobs)
        api.evaluate(folder)
        mi = pd.read_csv(folder / "mi.csv")
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
