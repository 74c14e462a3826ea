"""A synthetic experiment folder with exactly the files `curiosity plot` reads.

The numbers look like a real experiment's (MI growing with path length, topic perplexity
ahead, label maps that follow the ground truth with noise) but come from a seeded
generator, not from the pipeline, so the figure tests need no exploration or labeling.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.config_yaml import to_yaml
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.experiment.experiment import Experiment

WEIGHTS = ("random-walk", "stochastic-coverage", "word-perplexity", "topic-perplexity")
# plateau (bits) and speed (steps) of each weight function's MI curve
_CURVES = {"random-walk": (0.55, 200), "stochastic-coverage": (0.95, 110), "word-perplexity": (0.7, 120), "topic-perplexity": (1.05, 60)}


def truth_of(m) -> np.ndarray:
    """(H, W) classes to derive topics from: the ground truth, or the image's brightness in 5 bands."""
    if m.labels is not None:
        return m.labels.astype(np.int64)
    grey = m.image.mean(axis=2)
    return np.digitize(grey, np.quantile(grey, [0.2, 0.4, 0.6, 0.8]))


def topics_from(truth: np.ndarray, rng: np.random.Generator, n_topics: int, split: float, merge: int, noise: float) -> np.ndarray:
    """(H, W) int16 topic ids: classes split along a diagonal, some merged, permuted, with noise."""
    rows, cols = np.indices(truth.shape)
    band = ((rows + cols) // max(8, int(split * truth.shape[0]))) % 2 if split else 0
    base = (truth // merge) * 2 + band
    perm = rng.permutation(n_topics)
    labels = perm[base % n_topics]
    flip = rng.random(truth.shape) < noise
    labels[flip] = rng.integers(0, n_topics, int(flip.sum()))
    return labels.astype(np.int16)


def walk(grid: tuple[int, int], length: int, rng: np.random.Generator) -> np.ndarray:
    """(length, 2) cells (row, col) of a 4-connected walk repelled from its past, like stochastic coverage."""
    rows, cols = grid
    visits = np.zeros(grid)
    cell = np.array([rng.integers(rows), rng.integers(cols)])
    path = [cell.copy()]
    visits[tuple(cell)] += 1
    for _ in range(length - 1):
        moves = [cell + d for d in ((-1, 0), (1, 0), (0, -1), (0, 1))]
        moves = [c for c in moves if 0 <= c[0] < rows and 0 <= c[1] < cols]
        weights = np.array([1.0 / (1.0 + 4 * visits[tuple(c)]) for c in moves])
        cell = moves[rng.choice(len(moves), p=weights / weights.sum())]
        path.append(cell.copy())
        visits[tuple(cell)] += 1
    return np.array(path)


def make_experiment(
    root: Path,
    datasets: list[str],
    *,
    restarts: int = 5,
    lengths: tuple[int, ...] = (10, 20, 40, 80, 160, 320),
    weights: tuple[str, ...] = WEIGHTS,
    n_topics: int = 64,
    sweeps: int = 60,
    seed: int = 0,
) -> Path:
    """Write ``root/synthetic/`` as `curiosity explore`, `label` and `evaluate` would, sealed (:func:`seal`); returns it.

    Parameters
    ----------
    root : Path
    datasets : list of str
        Registered names or dataset YAML paths.
    """
    rng = np.random.default_rng(seed)
    folder = Path(root) / "synthetic"
    folder.mkdir(parents=True)
    config = load_config(CONFIG_DIR / "quick.yaml", [f"datasets={[str(d) for d in datasets]}", "name=synthetic"])
    (folder / "config.yaml").write_text(to_yaml(config))
    rows = []
    for entry in datasets:
        m = load_map(entry)
        name = m.config.name
        truth = truth_of(m)
        grid = m.grid.shape
        batch = folder / "batch"
        batch.mkdir(exist_ok=True)
        sweep = np.arange(1, sweeps + 1)
        trace = -7.3 + 1.2 * (1 - np.exp(-sweep / 9)) + rng.normal(0, 0.004, sweeps)
        np.savez_compressed(batch / f"{name}.npz", labels=topics_from(truth, rng, n_topics, 0.3, 1, 0.04), log_likelihood=trace)
        examples = folder / "labels" / name / "examples"
        examples.mkdir(parents=True)
        for weight in weights:
            plateau, speed = _CURVES.get(weight, (0.6, 150))
            for restart in range(restarts):
                path = walk(grid, lengths[-1], rng)
                run = folder / "runs" / name / weight / f"restart-{restart:03d}"
                run.mkdir(parents=True)
                pd.DataFrame(
                    {"step": np.arange(len(path)), "row": path[:, 0], "col": path[:, 1], "cell": path[:, 0] * grid[1] + path[:, 1]}
                ).to_csv(run / "path.csv", index=False)
                (run / "run.json").write_text(json.dumps({"grid_shape": list(grid), "path_length": lengths[-1], "checkpoints": list(lengths)}))
                for length in lengths:
                    mi = plateau * (1 - np.exp(-length / speed)) + rng.normal(0, 0.06)
                    mi_batch = 1.3 * mi + rng.normal(0, 0.05)
                    human = m.labels is not None
                    rows.append(
                        dict(dataset=name, weight_function=weight, restart=restart, path_length=length,
                             mi_human=mi if human else np.nan, mi_batch=mi_batch,
                             nmi_human=mi / 2.5 if human else np.nan, nmi_batch=mi_batch / 4, seed=seed,
                             distinct_cells=len(np.unique(path[:length], axis=0)))
                    )
                    if restart == 0 and length in (80, lengths[-1]):
                        merge = 2 if length < 160 else 1
                        z_p = topics_from(truth, rng, n_topics, 0.45, merge, 0.12 if length < 160 else 0.07)
                        np.savez_compressed(examples / f"{weight}-restart-{restart:03d}-{length}.npz", labels=z_p)
    mi = pd.DataFrame(rows)
    mi.to_csv(folder / "mi.csv", index=False)
    summary = []
    for against in ("human", "batch"):
        for (dataset, weight, length), group in mi.groupby(["dataset", "weight_function", "path_length"], sort=False):
            values = group[f"mi_{against}"].dropna().to_numpy()
            n = values.size
            mean = values.mean() if n else np.nan
            std = values.std(ddof=1) if n > 1 else np.nan
            half = 2.776 * std / np.sqrt(n) if n > 1 else np.nan  # t(0.975, 4) for 5 restarts; close enough here
            summary.append(dict(dataset=dataset, weight_function=weight, path_length=length, against=against,
                                n=n, mean=mean, std=std, ci_low=mean - half, ci_high=mean + half))
    pd.DataFrame(summary).to_csv(folder / "summary.csv", index=False)
    seal(folder)
    return folder


def seal(folder: Path) -> None:
    """Record the tables as one set made from the folder's files as they are now (``tables.json``), as evaluate does."""
    experiment = Experiment.open(folder)
    tables = {name: folder / name for name in ("mi.csv", "summary.csv") if (folder / name).is_file()}
    (folder / "tables.json").write_text(experiment.record_tables(tables, experiment.inputs()))
