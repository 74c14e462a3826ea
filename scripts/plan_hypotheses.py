"""What a declared hypothesis's plan takes from earlier seeds: its per-map scales, the lead it expects, its power.

Reads the recorded ``mi.csv`` of a study's earlier seeds of one specification
(``<record>/seed-<S>/<specification>/mi.csv``), takes the walker's signed lead over each comparator on a
measure at a path length, pair by pair (the same map, seed and restart), and prints, per map, the pairs, the
scale a plan declares (:func:`curiosity_cli.evaluate.confirmation.plan_scales`: the standard deviation of the
leads, pooled over the comparators) and the mean lead over each comparator; pooled over the maps, the scaled
lead expected over each comparator with its 95 % interval; the power of the intersection-union test on
``--pairs`` new pairs per map at the observed lead, at half of it and at none (which must stay at or below
``--alpha``: :func:`~curiosity_cli.evaluate.confirmation.planned_power`); and the ``scale:`` line to declare.

    python scripts/plan_hypotheses.py studies/validated --specification candidates-8 --seeds 0 1 2 \\
        --measure time_to_find --maps zurich-zh17 aerial-mosaic sentinel-coast reef-mosaic geonrw-essen --alpha 0.0125
    python scripts/plan_hypotheses.py --smoke     # the multiverse's default seeds on mean recall, few replicates
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from curiosity_cli.errors import CuriosityError

ROOT = Path(__file__).resolve().parents[1]
WALKERS = ["random-walk", "stochastic-coverage", "word-perplexity"]


def leads_of(record: Path, specification: str, seeds: list[int], measure: str, against: str, maps: list[str] | None,
             walker: str, comparators: list[str], length: int) -> dict:
    """Per map, the walker's signed lead over each comparator: a row per (seed, restart), a column per comparator."""
    import pandas as pd

    from curiosity_cli.evaluate.measures import measure_named
    from curiosity_cli.evaluate.tables import read_table

    chosen = measure_named(measure)
    if against not in chosen.columns:
        raise CuriosityError(f"--against: got {against!r}, expected one of {', '.join(chosen.columns)} for {measure}")
    if walker in comparators:
        raise CuriosityError(f"--comparators: {walker} is the walker itself; expected the walkers it is compared with")
    if not record.is_dir():
        raise CuriosityError(f"{record}: not a folder; expected a study's record, e.g. studies/validated")
    column = chosen.columns[against]
    tables = []
    for seed in seeds:
        path = record / f"seed-{seed}" / specification / "mi.csv"
        mi = read_table(path)
        if column not in mi:
            raise CuriosityError(f"{path}: no {column} (recorded before {measure} was measured)")
        tables.append(mi)
    mi = pd.concat(tables, ignore_index=True)
    mi = mi[(mi["path_length"] == length) & mi["weight_function"].isin([walker, *comparators])]
    if mi.empty:
        raise CuriosityError(f"{record}: no runs of {walker} or {', '.join(comparators)} at {length} steps (--path-length)")
    leads = {}
    for name in maps or list(dict.fromkeys(mi["dataset"])):
        block = mi[mi["dataset"] == name].pivot_table(index=["replicate", "restart"], columns="weight_function",
                                                       values=column)
        if block.empty or not {walker, *comparators} <= set(block.columns):
            raise CuriosityError(f"{record}: no runs of {walker} and {', '.join(comparators)} on {name} at {length} steps")
        block = block[[walker, *comparators]].dropna()
        ours, theirs = block[walker].to_numpy()[:, None], block[comparators].to_numpy()
        leads[name] = theirs - ours if chosen.lower_is_better else ours - theirs
    return leads


def plan(args: argparse.Namespace) -> int:
    from curiosity_cli.evaluate.confirmation import Stratified, plan_scales, planned_power, stratified_t

    leads = leads_of(args.record, args.specification, args.seeds, args.measure, args.against, args.maps, args.walker,
                     args.comparators, args.path_length)
    scales = plan_scales(leads)
    print(f"{args.specification}, seeds {' '.join(map(str, args.seeds))}: {args.walker}'s lead on {args.measure} "
          f"({args.against}) at {args.path_length} steps, positive where it is ahead")
    print(f"{'map':<16} {'pairs':>5} {'scale':>8}  " + "  ".join(f"{c:>20}" for c in args.comparators))
    for name, values in leads.items():
        print(f"{name:<16} {len(values):>5} {scales[name]:>8.4f}  " + "  ".join(f"{v:>20.4f}" for v in values.mean(axis=0)))
    strata = np.concatenate([[name] * len(values) for name, values in leads.items()])
    print("pooled, scaled (the mean over maps), with its 95 % interval (stratified t):")
    for c, comparator in enumerate(args.comparators):
        result = stratified_t(Stratified.of(np.concatenate([v[:, c] / scales[n] for n, v in leads.items()]), strata))
        print(f"  over {comparator}: {result.statistic:+.3f} [{result.ci_low:+.3f}, {result.ci_high:+.3f}], "
              f"one-sided p {result.p_value:.3g}")
    rng = np.random.default_rng(args.power_seed)
    for effect in (1.0, 0.5, 0.0):
        power = planned_power(leads, scales, args.pairs, args.alpha, args.replicates, rng, effect)
        print(f"power at {effect:.0%} of the observed leads, {args.pairs} new pairs a map, alpha {args.alpha}: "
              f"{power:.3f} ({args.replicates} replicates)")
    print("scale: {" + ", ".join(f"{name}: {scales[name]:.4g}" for name in leads) + "}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("record", nargs="?", type=Path, help="a study's record folder, e.g. studies/validated")
    parser.add_argument("--specification", default="default")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--measure", default="time_to_find")
    parser.add_argument("--against", default="human")
    parser.add_argument("--maps", nargs="+", help="default: every map of the tables")
    parser.add_argument("--walker", default="topic-perplexity")
    parser.add_argument("--comparators", nargs="+", default=WALKERS)
    parser.add_argument("--path-length", type=int, default=80)
    parser.add_argument("--pairs", type=int, default=50, help="new pairs per map the plan runs")
    parser.add_argument("--alpha", type=float, default=0.0125, help="the level the hypothesis's p is held to")
    parser.add_argument("--replicates", type=int, default=2000)
    parser.add_argument("--power-seed", type=int, default=0)
    parser.add_argument("--smoke", action="store_true", help="the multiverse's default seeds on mean recall")
    args = parser.parse_args(argv)
    if not 0 < args.alpha <= 0.5:  # NaN too
        parser.error(f"--alpha: got {args.alpha}, expected a one-sided level above 0 and at most 0.5")
    if args.pairs < 2 or args.replicates < 1:
        parser.error(f"--pairs, --replicates: got {args.pairs} and {args.replicates}, expected at least 2 and 1")
    if args.smoke:
        args.record, args.measure, args.replicates = ROOT / "studies" / "multiverse", "mean_recall", 20
    elif args.record is None:
        parser.error("a record folder is needed (or --smoke)")
    try:
        return plan(args)
    except CuriosityError as exc:
        print(f"Error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
