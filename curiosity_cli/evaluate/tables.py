"""``curiosity evaluate``: mutual information per run and checkpoint, its summary and tests.

Written under ``results/<experiment>/``:

- ``mi.csv`` and ``mi.parquet``: one row per (dataset, weight function, restart, path
  length): ``mi_human``, ``mi_batch`` (bits), ``nmi_human``, ``nmi_batch`` and the run's
  ``seed``; the human columns are NaN for a map without labels.
- ``summary.csv``: per (dataset, weight function, path length, against): ``n``, ``mean``,
  ``std``, and the 95 % confidence interval of the mean (Student's t).
- ``tests.csv``: per (dataset, path length, against) and pair of weight functions, the
  Wilcoxon signed-rank test over the restarts both have (paired by restart, which
  share start cells).
- ``headline.csv``: per dataset, topic-perplexity MI against human labels at 80 steps
  divided by the next best weight function's, with the paired Wilcoxon p of the two
  and the paper's ratio for the map the dataset stands in for (1.51, 1.20 and 1.05).
"""

from __future__ import annotations

import itertools
import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from curiosity_cli.errors import CuriosityError
from curiosity_cli.files import atomic_path, display_path

if TYPE_CHECKING:
    import pandas as pd

HEADLINE_LENGTH = 80
HEADLINE_WEIGHT = "topic-perplexity"


class EvaluationError(CuriosityError):
    """Results that cannot be evaluated: missing, corrupt, or not from the same maps."""


@dataclass(frozen=True)
class Evaluation:
    """The tables of an experiment, and the runs that had to be left out (each with why)."""

    mi: pd.DataFrame
    summary: pd.DataFrame
    tests: pd.DataFrame
    headline: pd.DataFrame
    skipped: list[str]
    maps: pd.DataFrame | None  # maps.csv, None for folders from before it existed


def mi_rows(folder: Path) -> tuple[list[dict], list[str]]:
    """One row per run and checkpoint from the label files; and the files left out, with why.

    Raises
    ------
    EvaluationError
        No label files at all, or a label file whose run or batch reference was made
        from another word store (naming both stores).
    """
    from curiosity_cli.evaluate.information import mutual_information, normalised_mutual_information
    from curiosity_cli.evaluate.labels import batch_path, read_meta
    from curiosity_cli.explore.runs import RunError, read_run, run_folder

    folder = Path(folder)
    files = sorted((folder / "labels").glob("*/*/restart-*.npz"))
    if not files:
        raise EvaluationError(f"{display_path(folder / 'labels')}: no label files; run `curiosity label` first")
    rows, skipped = [], []
    batch_stores = {}
    for path in files:
        try:
            with np.load(path) as npz:
                meta = read_meta(npz)
                lengths = npz["lengths"].tolist()
                human = npz["human"] if "human" in npz.files else None
                batch = npz["batch"]
        except (OSError, ValueError, KeyError, EOFError) as exc:
            skipped.append(f"{display_path(path)}: corrupt ({type(exc).__name__}); run `curiosity label --force`")
            continue
        run_path = run_folder(folder, meta["dataset"], meta["weight_function"], meta["restart"])
        try:
            run = read_run(run_path)
        except RunError as exc:
            skipped.append(str(exc))
            continue
        if (run.meta["store"], run.meta["vocabulary_hashes"]) != (meta["store"], meta["vocabulary_hashes"]):
            raise EvaluationError(
                f"{display_path(path)}: labels made from word store {meta['store']}, but the run "
                f"{display_path(run_path)} from {run.meta['store']}; run `curiosity label --force`"
            )
        if meta["dataset"] not in batch_stores:
            with np.load(batch_path(folder, meta["dataset"])) as npz:
                batch_stores[meta["dataset"]] = read_meta(npz)["store"]
        if batch_stores[meta["dataset"]] != meta["store"]:
            raise EvaluationError(
                f"{display_path(path)}: labels made from word store {meta['store']}, but the batch reference "
                f"{display_path(batch_path(folder, meta['dataset']))} from {batch_stores[meta['dataset']]}; "
                "run `curiosity label --force`"
            )
        for i, length in enumerate(lengths):
            rows.append({
                "dataset": meta["dataset"],
                "weight_function": meta["weight_function"],
                "restart": meta["restart"],
                "path_length": length,
                "mi_human": mutual_information(human[i]) if human is not None else np.nan,
                "mi_batch": mutual_information(batch[i]),
                "nmi_human": normalised_mutual_information(human[i]) if human is not None else np.nan,
                "nmi_batch": normalised_mutual_information(batch[i]),
                "seed": " ".join(map(str, meta["run_seed"])),
            })
    return rows, skipped


def summarise(mi):
    """Mean, standard deviation and 95 % CI of MI per (dataset, weight function, length, against)."""
    import pandas as pd
    from scipy import stats

    long = mi.melt(
        id_vars=["dataset", "weight_function", "restart", "path_length"],
        value_vars=["mi_human", "mi_batch"], var_name="against", value_name="mi",
    ).dropna(subset=["mi"])
    long["against"] = long["against"].str.removeprefix("mi_")
    grouped = long.groupby(["dataset", "weight_function", "path_length", "against"], sort=False)["mi"]
    summary = grouped.agg(n="count", mean="mean", std="std").reset_index()
    half = stats.t.ppf(0.975, np.maximum(summary["n"] - 1, 1)) * summary["std"].fillna(0) / np.sqrt(summary["n"])
    summary["ci_low"] = summary["mean"] - half
    summary["ci_high"] = summary["mean"] + half
    return pd.DataFrame(summary)


def paired_tests(mi):
    """Wilcoxon signed-rank test between every pair of weight functions, paired by restart."""
    import pandas as pd
    from scipy import stats

    rows = []
    for against in ("human", "batch"):
        column = f"mi_{against}"
        table = mi.dropna(subset=[column]).pivot_table(
            index=["dataset", "path_length", "restart"], columns="weight_function", values=column
        )
        for (dataset, length), block in table.groupby(level=["dataset", "path_length"]):
            for a, b in itertools.combinations(block.columns, 2):
                pair = block[[a, b]].dropna()
                diff = pair[a] - pair[b]
                if len(pair) == 0 or not diff.any():
                    p = np.nan if len(pair) == 0 else 1.0
                else:
                    p = float(stats.wilcoxon(pair[a], pair[b]).pvalue)
                rows.append({
                    "dataset": dataset, "path_length": length, "against": against, "a": a, "b": b,
                    "n": len(pair), "median_difference": float(diff.median()) if len(pair) else np.nan, "p_value": p,
                })
    return pd.DataFrame(rows, columns=["dataset", "path_length", "against", "a", "b", "n", "median_difference", "p_value"])


def headline(summary, tests, stands_in_for: dict[str, str]):
    """Per dataset: topic-perplexity mean MI vs human labels at 80 steps over the next best's.

    With the paired Wilcoxon p of topic perplexity against that next best, and the
    paper's ratio for the map the dataset stands in for (``stands_in_for``: dataset name
    to paper map name; datasets without one get no paper ratio).
    """
    import pandas as pd

    from curiosity_cli.paper import PAPER_MAPS

    rows = []
    at = summary[(summary["against"] == "human") & (summary["path_length"] == HEADLINE_LENGTH)]
    for dataset, block in at.groupby("dataset", sort=False):
        means = block.set_index("weight_function")["mean"]
        if HEADLINE_WEIGHT not in means or len(means) < 2:
            continue
        others = means.drop(HEADLINE_WEIGHT)
        next_best = others.idxmax()
        pair = tests[
            (tests["dataset"] == dataset) & (tests["path_length"] == HEADLINE_LENGTH) & (tests["against"] == "human")
            & (((tests["a"] == HEADLINE_WEIGHT) & (tests["b"] == next_best)) | ((tests["a"] == next_best) & (tests["b"] == HEADLINE_WEIGHT)))
        ]
        paper = PAPER_MAPS.get(stands_in_for.get(dataset, ""))
        rows.append({
            "dataset": dataset, "topic_perplexity": means[HEADLINE_WEIGHT], "next_best": next_best,
            "next_best_mi": others.max(), "ratio": means[HEADLINE_WEIGHT] / others.max(),
            "p_value": float(pair["p_value"].iloc[0]) if len(pair) else np.nan,
            "pairs": int(pair["n"].iloc[0]) if len(pair) else 0,
            "paper_map": paper.name if paper else "", "paper_ratio": paper.headline_ratio if paper else np.nan,
        })
    columns = ["dataset", "topic_perplexity", "next_best", "next_best_mi", "ratio", "p_value", "pairs", "paper_map", "paper_ratio"]
    return pd.DataFrame(rows, columns=columns)


def read_maps(folder: Path):
    """``maps.csv`` of an experiment (each map's words and the paper map it stands in
    for, written by ``explore``), or None for a folder from before it existed."""
    import pandas as pd

    path = Path(folder) / "maps.csv"
    if not path.is_file():
        return None
    try:
        return pd.read_csv(path, keep_default_na=False, na_values=[""])
    except (ValueError, OSError) as exc:
        raise EvaluationError(f"{display_path(path)}: cannot read the table of maps: {exc}") from None


def evaluate_experiment(folder: Path) -> Evaluation:
    """Compute and write every table of an experiment folder (module docstring).

    Raises
    ------
    EvaluationError
        No usable label files, or labels from another word store than their runs.
    """
    import pandas as pd

    folder = Path(folder)
    rows, skipped = mi_rows(folder)
    if not rows:
        raise EvaluationError(f"{display_path(folder / 'labels')}: every label file was left out: " + "; ".join(skipped))
    mi = pd.DataFrame(rows).sort_values(["dataset", "weight_function", "restart", "path_length"], ignore_index=True)
    summary = summarise(mi)
    tests = paired_tests(mi)
    maps = read_maps(folder)
    stands_in_for = {} if maps is None else {r.dataset: r.stands_in_for for r in maps.itertuples() if isinstance(r.stands_in_for, str)}
    top = headline(summary, tests, stands_in_for)
    for name, table in (("mi", mi), ("summary", summary), ("tests", tests), ("headline", top)):
        with atomic_path(folder / f"{name}.csv") as tmp:
            table.to_csv(tmp, index=False)
    with atomic_path(folder / "mi.parquet") as tmp:
        mi.to_parquet(tmp, index=False)
    with atomic_path(folder / "skipped.json") as tmp:
        tmp.write_text(json.dumps(skipped, indent=2) + "\n")
    return Evaluation(mi, summary, tests, top, skipped, maps)
