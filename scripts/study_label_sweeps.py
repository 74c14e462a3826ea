"""How many frozen-Φ Gibbs sweeps Z_p needs, from a placed start and warm-started.

Labels a sample of the runs of an explored and labelled experiment (it needs the runs and
each map's batch reference Z_b) with the sampler of ``curiosity label``, and prints the
mean MI of Z_p against the human labels (Z_h) and against Z_b:

- placed: each checkpoint from a placed start (``TopicModel.place``, what ``label``
  does), after 0, 1, 2, 4, ... --max-sweeps sweeps (one chain per checkpoint: its labels
  after s sweeps are exactly those of an s-sweep labelling with the same seed);
- uniform: the same chains from uniformly random topics, the far-off start;
- warm: a path's checkpoints in order, the first placed with --first sweeps, each later
  one starting from the topics the one before left, with w sweeps, for each w of --warm;
- down (with --down S): the same from the longest path to the shortest, the longest
  placed with S sweeps.

Two checks, against Z_h and against Z_b, on every map and path length:

- doubling: a schedule is converged when doubling its sweeps changes the mean MI by less
  than --tolerance bits (default 0.01), or by less than twice the standard error of that
  change over runs (the chain's own noise);
- two starts: chains from the placed and the uniform start must end at the same mean MI
  (within the same bounds) after --max-sweeps. A chain that forgets its start slowly
  passes the doubling check long before it gets there; the two starts come at the fixed
  point from opposite sides.

The script prints the smallest sweeps that pass the doubling check per schedule, the gap
between the two starts, and how far each warm schedule's mean lies from the placed
reference (--max-sweeps) beside the run-to-run standard error of that difference.

    python scripts/study_label_sweeps.py results/paper-grid --restarts 2
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import pandas as pd

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.data import load_map
from curiosity_cli.evaluate.information import contingency, mutual_information
from curiosity_cli.evaluate.label_sampling import PathLabeller, pixel_labels
from curiosity_cli.evaluate.label_stage import path_seed
from curiosity_cli.explore.runs import read_run
from curiosity_cli.layout import DEFAULT_CACHE, ExperimentFolder
from curiosity_cli.words.store import load_store

#: What pairs one labelling with another of the same checkpoint.
RUN_KEYS = ["dataset", "weight_function", "restart", "path_length"]


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
    labeller = PathLabeller(store, config.model)
    record = [0] + [2**i for i in range(int(np.log2(args.max_sweeps)) + 1)]
    rows = []
    for weight in config.explore.weight_functions:
        for restart in range(args.restarts):
            run = read_run(ExperimentFolder(folder).run(dataset, weight, restart))
            lengths = run.meta["checkpoints"]
            phis = [run.phi(n) for n in lengths]
            seed = path_seed(run.meta["seed"])
            base = {"dataset": dataset, "weight_function": weight, "restart": restart}
            for j, (length, phi) in enumerate(zip(lengths, phis)):
                if args.cold_lengths and length not in args.cold_lengths:
                    continue
                for schedule in args.starts:
                    labeller.start(phi, seed + j, uniform=schedule == "uniform")
                    done = 0
                    for s in record:
                        labeller.sweep(s - done, args.threads)
                        done = s
                        human_mi, batch_mi = mi_pair(store, labeller.labels(), shape, human, n_classes, batch, k)
                        rows.append({**base, "path_length": length, "schedule": schedule, "sweeps": s,
                                     "mi_human": human_mi, "mi_batch": batch_mi})
            for w in args.warm:
                labels = labeller.label_path(phis, seed=seed, sweeps=args.first, warm_sweeps=w, threads=args.threads)
                if args.down is not None:
                    down = labeller.label_path(phis[::-1], seed=seed, sweeps=args.down, warm_sweeps=w, threads=args.threads)
                for schedule, chain in [("warm", labels)] + ([("down", down[::-1])] if args.down is not None else []):
                    for length, words in zip(lengths, chain):
                        human_mi, batch_mi = mi_pair(store, words, shape, human, n_classes, batch, k)
                        rows.append({**base, "path_length": length, "schedule": schedule, "sweeps": w,
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
                    if abs(row["mean"]) >= tolerance and abs(row["mean"]) >= 2 * row["sem"]:
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
    parser.add_argument("experiment", type=Path)
    parser.add_argument("--config", type=Path, default=CONFIG_DIR / "paper-grid.yaml",
                        help="K, α, β and weight functions (the experiment's own); its datasets entries name the maps")
    parser.add_argument("--maps", nargs="*", help="datasets to study; default all of the experiment's")
    parser.add_argument("--restarts", type=int, default=2, help="restarts per weight function (0 .. N-1)")
    parser.add_argument("--max-sweeps", type=int, default=64)
    parser.add_argument("--cold-lengths", type=int, nargs="*", help="path lengths of the placed and uniform chains; default every checkpoint")
    parser.add_argument("--starts", nargs="*", choices=["placed", "uniform"], default=["placed", "uniform"],
                        help="starts of the chains of each checkpoint")
    parser.add_argument("--first", type=int, default=64, help="sweeps of the first checkpoint of a warm chain")
    parser.add_argument("--warm", type=int, nargs="+", default=[1, 2, 4, 8, 16])
    parser.add_argument("--down", type=int, help="also warm chains from the longest path down, the longest with this many sweeps")
    parser.add_argument("--tolerance", type=float, default=0.01)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--cache-dir", type=Path, default=DEFAULT_CACHE)
    parser.add_argument("--out", type=Path, help="CSV of every labelling (default EXPERIMENT/label-sweeps.csv)")
    args = parser.parse_args()

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
        return table[(table.schedule == schedule) & (table.sweeps == sweeps)].set_index(RUN_KEYS)

    reference = chain("placed", args.max_sweeps)
    for schedule in ("warm", "down"):
        if schedule not in set(table.schedule):
            continue
        print(f"\n{schedule} minus placed after {args.max_sweeps} sweeps, mean over runs and lengths (standard error), bits")
        for w in args.warm:
            for against in ("mi_human", "mi_batch"):
                diff = (chain(schedule, w)[against] - reference[against]).dropna()
                by_map = diff.groupby(level="dataset").agg(["mean", "sem"])
                text = ", ".join(f"{d} {r['mean']:+.4f} ({r['sem']:.4f})" for d, r in by_map.iterrows())
                print(f"  w = {w:>2} {against}: {text}")

    print(f"\nrule: doubling the sweeps changes the mean MI by < {args.tolerance} bits, or by less than twice its "
          "standard error over runs, against Z_h and Z_b, every map and length")
    for schedule, (found, worst) in smallest_converged(table, args.tolerance).items():
        steps = ", ".join(f"{s}->{2 * s}: {c:+.4f} ({e:.4f})" for s, (c, e) in worst.items())
        print(f"  {schedule}: smallest converged sweeps {found}; largest change per doubling {steps}")
    if {"placed", "uniform"} <= set(table.schedule):
        print(f"\ntwo starts: uniform minus placed after {args.max_sweeps} sweeps, mean (standard error), bits; "
              f"'*' where it is >= {args.tolerance} and >= twice its standard error")
        for against in ("mi_human", "mi_batch"):
            diff = (chain("uniform", args.max_sweeps)[against] - reference[against]).dropna()
            by = diff.groupby(level=["dataset", "path_length"]).agg(["mean", "sem"])
            text = ", ".join(
                f"{d} {n}: {r['mean']:+.3f} ({r['sem']:.3f}){'*' if abs(r['mean']) >= max(args.tolerance, 2 * r['sem']) else ''}"
                for (d, n), r in by.iterrows())
            print(f"  {against}: {text}")
    print(f"\n{time.perf_counter() - started:.0f} s; wrote {out}")
    print(json.dumps({"maps": sorted(table.dataset.unique()), "restarts": args.restarts}))


if __name__ == "__main__":
    main()
