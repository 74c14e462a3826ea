"""How many frozen-Φ Gibbs sweeps Z_p needs: chains from two starts, and warm-started chains.

Labels a sample of the runs of an explored and labelled experiment (it needs the runs and
each map's batch reference Z_b) with the sampler of ``curiosity label``, and prints the
mean MI of Z_p against the human labels (Z_h) and against Z_b:

- uniform: each checkpoint from uniformly random topics (what ``label`` does), after 0,
  1, 2, 4, ... --max-sweeps sweeps (one chain per checkpoint: its labels after s sweeps
  are exactly those of an s-sweep labelling with the same seed);
- placed: the same chains from a placed start (``TopicModel.place``: each word drawn
  from eq. 5 given the words placed before it). Its labels begin smooth where the
  uniform ones begin as noise, so the two come at the chain's fixed point from opposite
  sides;
- warm: a path's checkpoints in order, the first from random topics with --first
  sweeps, each later one starting from the topics the one before left, with w sweeps,
  for each w of --warm (what ``label`` does with ``label.warm_sweeps``).

The reference for every schedule is the mean of the two starts after --max-sweeps
sweeps, paired by run and length. Two checks, against Z_h and against Z_b, on every map
and path length, each passed by a mean within --tolerance bits (default 0.01) or within
twice the standard error over runs (the chains' own noise):

- two starts: the uniform and the placed chain end at the same mean MI;
- doubling: doubling a schedule's sweeps no longer changes its mean MI. A chain that
  forgets its start slowly passes this one long before it gets there, which is why the
  two-start check comes first.

    python scripts/study_label_sweeps.py results/paper-grid --restarts 1 --max-sweeps 256 --first 256 --warm 8 16 32
    python scripts/study_label_sweeps.py --smoke   # a tiny experiment made in a temporary folder, 2 sweeps: seconds
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.evaluate.information import contingency, mutual_information
from curiosity_cli.label.sampling import label_paths, map_chains, pixel_labels
from curiosity_cli.label.sampling import path_seed
from curiosity_cli.evaluate.statistics import CONVERGENCE_TOLERANCE, within_noise
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.explore.runs import read_run
from curiosity_cli.paths import DEFAULT_CACHE
from curiosity_cli.words.store import load_store

#: What pairs one labelling with another of the same checkpoint.
RUN_KEYS = ["dataset", "weight_function", "restart", "path_length"]
#: --smoke's experiment: two walkers, one restart of 10 steps on the smallest map, labelled with one sweep.
SMOKE = [
    "datasets=[rare-patches]", "explore.weight_functions=[random-walk, topic-perplexity]", "explore.restarts=1",
    "explore.path_length=10", "explore.checkpoints=[5, 10]", "label.sweeps=1", "label.warm_sweeps=1",
    "label.batch_sweeps=1", "name=smoke",
]


def mi_pair(store, words, shape, human, n_classes, batch, k):
    pixels = pixel_labels(store, words, shape)
    return (
        mutual_information(contingency(pixels, human, k, n_classes)) if human is not None else np.nan,
        mutual_information(contingency(pixels, batch, k, k)),
    )


def study_map(folder: Path, config, dataset: str, entry: str, store_file: Path, args) -> list[dict]:
    store = load_store(store_file)
    map_data = load_map(entry)
    human = map_data.labels
    n_classes = max(c.id for c in map_data.legend) + 1 if human is not None else 0
    with np.load(ExperimentFolder(folder).batch(dataset)) as npz:
        batch = npz["labels"]
    shape, k = map_data.image.shape[:2], config.model.topics
    chains = map_chains(store, config.model)
    record = [0] + [2**i for i in range(int(np.log2(args.max_sweeps)) + 1)]
    rows = []
    for weight in config.explore.weight_functions:
        for restart in range(args.restarts):
            run = read_run(ExperimentFolder(folder).run(dataset, weight, restart))
            lengths = run.meta["checkpoints"]
            phis = [run.phi(n) for n in lengths]
            seed = path_seed(run.meta["seed"])
            base = {"dataset": dataset, "weight_function": weight, "restart": restart}
            # every cold start of the run (checkpoint x schedule) in lock-step
            cold = [
                (length, schedule, phi, (seed + j) % 2**64)
                for j, (length, phi) in enumerate(zip(lengths, phis))
                if not args.cold_lengths or length in args.cold_lengths
                for schedule in args.starts
            ]
            if cold:
                chains.start([c[2] for c in cold], [c[3] for c in cold], [c[1] == "placed" for c in cold])
                done = 0
                for s in record:
                    chains.sweep(s - done)
                    done = s
                    labels = chains.ml_topics()
                    for column, (length, schedule, _, _) in enumerate(cold):
                        human_mi, batch_mi = mi_pair(store, labels[:, column], shape, human, n_classes, batch, k)
                        rows.append({**base, "path_length": length, "schedule": schedule, "sweeps": s,
                                     "mi_human": human_mi, "mi_batch": batch_mi})
            for w in args.warm:
                for j, _, labels in label_paths(store, config.model, [phis], [seed], sweeps=args.first, warm_sweeps=w):
                    human_mi, batch_mi = mi_pair(store, labels[:, 0], shape, human, n_classes, batch, k)
                    rows.append({**base, "path_length": lengths[j], "schedule": "warm", "sweeps": w,
                                 "mi_human": human_mi, "mi_batch": batch_mi})
            print(f"  {dataset} {weight} restart {restart}: done", flush=True)
    return rows


def smallest_converged(table: pd.DataFrame, tolerance: float):
    """Per schedule: the smallest sweeps s whose doubling changes the mean MI by less than
    ``tolerance`` or by less than twice the change's standard error over runs (so is not
    told apart from the chain's own noise), against Z_h and Z_b on every map and length;
    and per s, the largest change with its standard error."""
    out = {}
    for schedule, block in table.groupby("schedule"):
        sweeps = sorted(block["sweeps"].unique())
        found, worst = None, {}
        for s in sweeps:
            if s == 0 or 2 * s not in sweeps:
                continue
            a = block[block.sweeps == s].set_index(RUN_KEYS)
            b = block[block.sweeps == 2 * s].set_index(RUN_KEYS)
            passed, largest = True, (0.0, 0.0)
            for against in ("mi_human", "mi_batch"):
                change = (b[against] - a[against]).dropna().groupby(level=["dataset", "path_length"]).agg(["mean", "sem"])
                for _, row in change.iterrows():
                    if not within_noise(row["mean"], row["sem"], tolerance):
                        passed = False
                    if abs(row["mean"]) > abs(largest[0]):
                        largest = (row["mean"], row["sem"])
            worst[s] = largest
            if found is None and passed:
                found = s
        out[schedule] = (found, worst)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("experiment", type=Path, nargs="?", help="an explored and labelled experiment folder")
    parser.add_argument("--config", type=Path, default=CONFIG_DIR / "paper-grid.yaml",
                        help="K, α, β and weight functions (the experiment's own); its datasets entries name the maps")
    parser.add_argument("--maps", nargs="*", help="datasets to study; default all of the experiment's")
    parser.add_argument("--restarts", type=int, default=2, help="restarts per weight function (0 .. N-1)")
    parser.add_argument("--max-sweeps", type=int, default=64)
    parser.add_argument("--cold-lengths", type=int, nargs="*", help="path lengths of the placed and uniform chains; default every checkpoint")
    parser.add_argument("--starts", nargs="*", choices=["uniform", "placed"], default=["uniform", "placed"],
                        help="starts of the chains of each checkpoint")
    parser.add_argument("--first", type=int, default=64, help="sweeps of the first checkpoint of a warm chain")
    parser.add_argument("--warm", type=int, nargs="+", default=[1, 2, 4, 8, 16])
    parser.add_argument("--tolerance", type=float, default=CONVERGENCE_TOLERANCE)
    parser.add_argument("--cache-dir", type=Path, default=DEFAULT_CACHE)
    parser.add_argument("--out", type=Path, help="CSV of every labelling (default EXPERIMENT/label-sweeps.csv)")
    parser.add_argument("--smoke", action="store_true", help="a tiny experiment made and studied in a temporary "
                        "folder, seconds (what tests/test_scripts.py runs)")
    args = parser.parse_args()
    if args.smoke:
        with tempfile.TemporaryDirectory() as tmp:
            args.experiment = smoke_experiment(Path(tmp))
            args.config, args.restarts, args.max_sweeps, args.first, args.warm = (
                args.experiment / "config.yaml", 1, 2, 1, [1]
            )
            study(args)
    elif args.experiment is None:
        parser.error("expected an experiment folder")
    else:
        study(args)


def smoke_experiment(folder: Path) -> Path:
    """An experiment in ``folder``, explored and labelled (:data:`SMOKE`)."""
    from curiosity_cli import api

    experiment = api.explore("quick", overrides=SMOKE, results_dir=folder, jobs=1).folder
    api.label(experiment, jobs=1)
    return experiment


def study(args) -> None:
    """Label the sample of runs, write the CSV and print the tables (module docstring)."""
    config = load_config(args.config)
    maps = pd.read_csv(args.experiment / "maps.csv")
    entries = dict(zip([load_map(e).config.name for e in config.datasets], config.datasets))
    started = time.perf_counter()
    rows = []
    for m in maps.itertuples():
        if args.maps and m.dataset not in args.maps:
            continue
        rows += study_map(args.experiment, config, m.dataset, entries[m.dataset], args.cache_dir / m.store, args)
    table = pd.DataFrame(rows)
    out = args.out or args.experiment / "label-sweeps.csv"
    table.to_csv(out, index=False)

    means = table.groupby(["dataset", "path_length", "schedule", "sweeps"])[["mi_human", "mi_batch"]].mean().reset_index()
    pd.set_option("display.width", 200)
    pd.set_option("display.max_rows", 500)
    for against in ("mi_human", "mi_batch"):
        print(f"\nmean {against} (bits) by sweeps; {args.restarts} restarts x {len(config.explore.weight_functions)} weight functions per map")
        print(means.pivot_table(index=["dataset", "path_length"], columns=["schedule", "sweeps"], values=against).round(3).to_string())

    def chain(schedule, sweeps):
        return table[(table.schedule == schedule) & (table.sweeps == sweeps)].set_index(RUN_KEYS)[["mi_human", "mi_batch"]]

    def flag(mean, sem):
        return "" if within_noise(mean, sem, args.tolerance) else "*"

    ends = {start: chain(start, args.max_sweeps) for start in args.starts}
    reference = sum(ends.values()) / len(ends)
    if len(ends) == 2:
        print(f"\ntwo starts: uniform minus placed after {args.max_sweeps} sweeps, mean (standard error) over runs, bits; "
              f"'*' where it is >= {args.tolerance} and >= twice its standard error")
        gap = (ends["uniform"] - ends["placed"]).dropna().groupby(level=["dataset", "path_length"]).agg(["mean", "sem"])
        for (dataset, length), r in gap.iterrows():
            print(f"  {dataset:>16} {length:>4}: " + ", ".join(
                f"{a} {r[(a, 'mean')]:+.3f} ({r[(a, 'sem')]:.3f}){flag(r[(a, 'mean')], r[(a, 'sem')])}" for a in ("mi_human", "mi_batch")))

    print(f"\neach schedule minus the mean of the {' and '.join(args.starts)} chains after {args.max_sweeps} sweeps, "
          "mean over runs, bits (against Z_h / against Z_b); '*' as above")
    columns = {}
    for schedule, block in table.groupby("schedule"):
        for s in sorted(block.sweeps.unique()):
            diff = (chain(schedule, s) - reference).dropna().groupby(level=["dataset", "path_length"]).agg(["mean", "sem"])
            columns[f"{schedule} {s}"] = pd.Series({
                at: "/".join(f"{r[(a, 'mean')]:+.3f}{flag(r[(a, 'mean')], r[(a, 'sem')])}" for a in ("mi_human", "mi_batch"))
                for at, r in diff.iterrows()})
    print(pd.DataFrame(columns).fillna("").rename_axis(["dataset", "path_length"]).to_string())

    print(f"\ndoubling: the mean MI changes by < {args.tolerance} bits, or by less than twice its standard error over "
          "runs, against Z_h and Z_b, every map and length")
    for schedule, (found, worst) in smallest_converged(table, args.tolerance).items():
        steps = ", ".join(f"{s}->{2 * s}: {c:+.4f} ({e:.4f})" for s, (c, e) in worst.items())
        print(f"  {schedule}: smallest passing sweeps {found}; largest change per doubling {steps}")
    print(f"\n{time.perf_counter() - started:.0f} s; wrote {out}")
    print(json.dumps({"maps": sorted(table.dataset.unique()), "restarts": args.restarts}))


if __name__ == "__main__":
    main()
