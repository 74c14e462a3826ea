"""Dose-response on generated maps: does a labelling score higher the more rare classes its path has seen?

Issue 58's check before any walker runs. On a generated map (``generate:`` in its YAML,
truth known), for each seed and each k of --ks, a "path" is a set of --cells cells that
has seen exactly k rare classes: one patch cell of each of k rare classes, and --cells - k
background cells. The sets are nested in k within a seed (the same rare classes in the
same order, the same background cells, the last dropped to make room), so a seed is a
paired comparison and the path's length does not change with k. The cells are scattered
(drawn uniformly, not a walk) and visited in an order drawn once per seed.

Φ_p is formed as ``explore`` forms it: each cell added to the map's topic model in turn,
then ``explore.samples_per_step`` word samples of realtime refinement (η, the refinement
picks). The map is then labelled with Φ_p frozen as ``label`` labels Z_p (frozen-Φ Gibbs
chains over every word of the map from random topics, ``label.sweeps`` sweeps, each
word's maximum-likelihood topic; pixels take their word's label), and scored against the
truth: MI, NMI, AMI (:mod:`curiosity_cli.evaluate.information`) and mean recall. Per map and measure it prints
the mean at each k and the slope of the measure against k (least squares within each
seed, then the mean over seeds with its 95 % Student-t interval): positive with an
interval above 0 is the dose-response the pipeline must show. Nothing is tuned: the
settings are the config's (default ``quick``: the paper's K, α, β, η, budget and sweeps).

    python scripts/check_dose_response.py                          # planted-disjoint and planted-shared, 6 seeds
    python scripts/check_dose_response.py --maps planted-shared --seeds 10 --set model.topics=16
    python scripts/check_dose_response.py --smoke                  # tiny settings: seconds
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pandas as pd

from curiosity_cli.config import load_config
from curiosity_cli.evaluate.information import (
    adjusted_mutual_information, mean_recall, mutual_information, normalised_mutual_information,
)
from curiosity_cli.evaluate.statistics import mean_interval
from curiosity_cli.label.pixel_tables import PixelTables
from curiosity_cli.label.sampling import label_paths, pixel_words
from curiosity_cli.maps.generated import cell_classes
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.paths import DEFAULT_CACHE
from curiosity_cli.topics.map_model import map_topic_model
from curiosity_cli.words.extract import extract_words

#: Each measure of a labelling's table against the truth.
MEASURES = {
    "mi": mutual_information, "nmi": normalised_mutual_information, "ami": adjusted_mutual_information,
    "mean_recall": mean_recall,
}
#: --smoke: two seeds of k = 0 and 2 on planted-disjoint, 10 cells, a small model and budget, two sweeps.
SMOKE = dict(maps=["planted-disjoint"], seeds=2, ks=[0, 2], cells=10,
             overrides=["model.topics=8", "explore.samples_per_step=500", "label.sweeps=2"])


def path_sets(classes: np.ndarray, background_topics: int, ks: list[int], cells: int, seed: int) -> dict[int, np.ndarray]:
    """Each k's path: one patch cell of each of k rare classes and ``cells - k`` background cells, in a fixed order.

    Parameters
    ----------
    classes : (n_cells,) int ndarray
        Each cell's true topic; background ``0 .. B - 1``, rare from ``B``.
    background_topics : int
    ks : list of int
        Rare classes seen, each at most the map's rare classes and below ``cells``.
    cells : int
    seed : int

    Returns
    -------
    dict of int to (cells,) int64 ndarray
        The cells of each k's path, in the order they are added to the model.
    """
    rng = np.random.default_rng(seed)
    background = rng.permutation(np.flatnonzero(classes < background_topics))[:cells]
    rare_classes = rng.permutation(np.unique(classes[classes >= background_topics]))
    rare = np.array([rng.choice(np.flatnonzero(classes == c)) for c in rare_classes], np.int64)
    # one visiting order for every k of the seed: the cells a path shares with another are visited in the same order
    key = rng.random(classes.size)
    paths = {}
    for k in ks:
        chosen = np.concatenate([background[: cells - k], rare[:k]])
        paths[k] = chosen[np.argsort(key[chosen], kind="stable")]
    return paths


def path_counts(store, config, path: np.ndarray, *, seed: int) -> np.ndarray:
    """(V, K) int: Φ_p of a path, as ``explore`` forms it (each cell added, then its step's refinement)."""
    topic_model = map_topic_model(store, config.model, seed)
    for step, cell in enumerate(path):
        topic_model.add_cell(int(cell), store.cell_words(int(cell)), time=step)
        topic_model.refine_realtime(config.explore.samples_per_step, eta=config.model.eta, picks=config.explore.refine_picks)
    return topic_model.topic_word_counts()


def check_map(entry: str, config, args) -> pd.DataFrame:
    """One row per seed and k: the measures of its labelling against the truth."""
    map_data = load_map(entry)
    generate = map_data.config.generate
    if generate is None:
        raise SystemExit(f"{entry}: not a generated map (no `generate:`); the check needs its truth by construction")
    if max(args.ks) > generate.rare_topics or max(args.ks) >= args.cells:
        raise SystemExit(f"--ks: got {args.ks}, expected at most {generate.rare_topics} rare classes and below --cells")
    store = extract_words(map_data, config.words, cache_dir=DEFAULT_CACHE).store
    classes = cell_classes(generate)
    tables = PixelTables(pixel_words(store, map_data.image.shape[:2]), map_data.labels, map_data.n_classes)
    runs, counts = [], []
    for seed in range(args.seeds):
        for k, path in path_sets(classes, generate.background_topics, args.ks, args.cells, seed).items():
            runs.append((seed, k))
            counts.append([path_counts(store, config, path, seed=1000 * seed + k)])
    # one checkpoint per path: the first (and only) labels label_paths yields; each chain a stream of its own
    labels = next(
        labels for _, _, labels in label_paths(
            store, config.model, counts, list(range(len(runs))), sweeps=config.label.sweeps, warm_sweeps=None,
        )
    )
    rows = []
    for (seed, k), table in zip(runs, tables.tables(labels, config.model.topics)):
        rows.append({"map": map_data.config.name, "seed": seed, "k": k,
                     **{name: measure(table) for name, measure in MEASURES.items()}})
    return pd.DataFrame(rows)


def slope(frame: pd.DataFrame, measure: str) -> tuple[float, float, float]:
    """Mean over seeds of each seed's least-squares slope of ``measure`` against k, and its 95 % interval."""
    per_seed = [np.polyfit(group["k"], group[measure], 1)[0] for _, group in frame.groupby("seed")]
    return mean_interval(np.array(per_seed))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maps", nargs="+", default=["planted-disjoint", "planted-shared"])
    parser.add_argument("--config", default="quick", help="whose model, explore and label settings to use")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--ks", type=int, nargs="+", default=[0, 2, 4, 8], help="rare classes each path has seen")
    parser.add_argument("--cells", type=int, default=80, help="cells of every path (the headline's 80 steps)")
    parser.add_argument("--csv", help="also write every row here")
    parser.add_argument("--smoke", action="store_true")
    args = parser.parse_args()
    if args.smoke:
        for key, value in SMOKE.items():
            setattr(args, key, value)
    config = load_config(args.config, args.overrides)
    print(
        f"config {args.config} {' '.join(args.overrides)}: K = {config.model.topics}, alpha = {config.model.alpha}, "
        f"beta = {config.model.beta}, eta = {config.model.eta}, {config.explore.samples_per_step:,} samples per cell, "
        f"{config.label.sweeps} sweeps; paths of {args.cells} scattered cells, k = {args.ks}, {args.seeds} seeds"
    )
    frames = []
    for entry in args.maps:
        start = time.perf_counter()
        frame = check_map(entry, config, args)
        frames.append(frame)
        print(f"\n{entry} ({time.perf_counter() - start:.0f} s)")
        means = frame.groupby("k")[list(MEASURES)].agg(["mean", "std"])
        print(means.to_string(float_format=lambda v: f"{v:.4f}"))
        for measure in MEASURES:
            mean, low, high = slope(frame, measure)
            print(f"  slope of {measure} per rare class seen: {mean:+.5f} (95 % CI {low:+.5f} .. {high:+.5f})")
    if args.csv:
        pd.concat(frames).to_csv(args.csv, index=False)
        print(f"wrote {args.csv}")


if __name__ == "__main__":
    main()
