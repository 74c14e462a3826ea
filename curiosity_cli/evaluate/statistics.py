"""The statistics of the evaluation tables: means with their confidence intervals, the paired
tests and effects between walkers, and whether two labelling chains have met.

Runs of two walkers are paired by :data:`PAIR_KEYS`: the same start cell and streams of one
seed's experiment. Ceilings (:data:`~curiosity_cli.explore.weights.CEILINGS`) are not
walkers, and the validation walkers test the measures, not curiosity: neither takes part in
the tests (:func:`walkers_only`).
"""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING

import numpy as np

from curiosity_cli.evaluate.measures import MI, Measure
from curiosity_cli.explore.weights import in_verdict

if TYPE_CHECKING:
    import pandas as pd

#: Significance level of "beats": a higher mean and a paired Wilcoxon p below it.
ALPHA = 0.05
CONFIDENCE = 0.95
#: Bits within which two labelling chains from far-apart starts count as having met.
CONVERGENCE_TOLERANCE = 0.01
#: What identifies a row of mi.csv.
KEYS = ["dataset", "weight_function", "restart", "path_length"]
#: What pairs two walkers' runs: the same start cell and streams of one seed's experiment.
PAIR_KEYS = ["replicate", "restart"]


def _mean_ci(grouped) -> pd.DataFrame:
    """``n``, ``mean``, ``std`` and the 95 % Student-t CI of the mean, per group of a grouped Series."""
    from scipy import stats

    summary = grouped.agg(n="count", mean="mean", std="std").reset_index()
    half = stats.t.ppf(0.5 + CONFIDENCE / 2, np.maximum(summary["n"] - 1, 1)) * summary["std"].fillna(0) / np.sqrt(summary["n"])
    summary["ci_low"] = summary["mean"] - half
    summary["ci_high"] = summary["mean"] + half
    return summary


def summarise(mi, measure: Measure = MI):
    """Mean, standard deviation and 95 % CI of a measure (MI unless told) per (dataset, weight function, length,
    against), against each labelling whose column ``mi`` has."""
    import pandas as pd

    present = {column: against for against, column in measure.columns.items() if column in mi}
    long = mi.melt(id_vars=KEYS, value_vars=list(present), var_name="against", value_name="value").dropna(subset=["value"])
    long["against"] = long["against"].map(present)
    return pd.DataFrame(_mean_ci(long.groupby(["dataset", "weight_function", "path_length", "against"], sort=False)["value"]))


def summarise_classes(mi):
    """Mean, standard deviation and 95 % CI of ``classes_found`` and ``mean_recall``
    (``measure``) per (dataset, weight function, length), with the map's ``classes``."""
    import pandas as pd

    columns = ["dataset", "weight_function", "path_length", "measure", "classes", "n", "mean", "std", "ci_low", "ci_high"]
    if "classes_found" not in mi:
        return pd.DataFrame(columns=columns)
    long = mi.melt(
        id_vars=[*KEYS, "classes"], value_vars=["classes_found", "mean_recall"], var_name="measure", value_name="value",
    ).dropna(subset=["value"])
    grouped = long.groupby(["dataset", "weight_function", "path_length", "measure", "classes"], sort=False)["value"]
    return pd.DataFrame(_mean_ci(grouped), columns=columns)


def summarise_revisits(mi):
    """Mean, standard deviation and 95 % CI of each revisit column (``measure``:
    :data:`~curiosity_cli.evaluate.revisits.REVISIT_COLUMNS`) per (dataset, weight function, length)."""
    import pandas as pd

    from curiosity_cli.evaluate.revisits import REVISIT_COLUMNS

    long = mi.melt(
        id_vars=KEYS, value_vars=list(REVISIT_COLUMNS), var_name="measure", value_name="value",
    ).dropna(subset=["value"])
    grouped = long.groupby(["dataset", "weight_function", "path_length", "measure"], sort=False)["value"]
    return pd.DataFrame(_mean_ci(grouped))


def summarise_steering(steering):
    """Mean, standard deviation and 95 % CI of ``steering.csv``'s ``steering`` per (dataset,
    weight function, length) (:mod:`~curiosity_cli.evaluate.steering`)."""
    import pandas as pd

    grouped = steering.dropna(subset=["steering"]).groupby(["dataset", "weight_function", "path_length"], sort=False)
    return pd.DataFrame(_mean_ci(grouped["steering"]))


def within_noise(mean: float, sem: float, tolerance: float = CONVERGENCE_TOLERANCE) -> bool:
    """Whether a mean difference in bits is within ``tolerance``, or within twice its
    standard error over runs (not told apart from the chains' own noise)."""
    return bool(abs(mean) < tolerance or abs(mean) < 2 * sem)


def label_convergence(mi):
    """The two-start check of Z_p, per (dataset, path length, against), over the runs labelled twice.

    ``uniform`` and ``placed`` are the mean MI of the runs' two chains, ``difference``
    the mean of uniform minus placed, ``sem`` its standard error (NaN for one run), and
    ``converged`` :func:`within_noise`. Empty when no run was labelled twice.
    """
    import pandas as pd

    columns = ["dataset", "path_length", "against", "n", "uniform", "placed", "difference", "sem", "converged"]
    rows = []
    for against in ("human", "batch"):
        pairs = mi.dropna(subset=[f"mi_{against}", f"placed_mi_{against}"])
        for (dataset, length), block in pairs.groupby(["dataset", "path_length"], sort=False):
            diff = (block[f"mi_{against}"] - block[f"placed_mi_{against}"]).to_numpy()
            sem = float(diff.std(ddof=1) / np.sqrt(diff.size)) if diff.size > 1 else np.nan
            rows.append({
                "dataset": dataset, "path_length": int(length), "against": against, "n": int(diff.size),
                "uniform": float(block[f"mi_{against}"].mean()), "placed": float(block[f"placed_mi_{against}"].mean()),
                "difference": float(diff.mean()), "sem": sem, "converged": within_noise(diff.mean(), np.nan_to_num(sem)),
            })
    return pd.DataFrame(rows, columns=columns)


def walkers_only(mi):
    """The rows of the walkers the verdict compares (:func:`~curiosity_cli.explore.weights.in_verdict`): ceilings
    and validation walkers left out."""
    return mi[mi["weight_function"].map(in_verdict).astype(bool)]


def paired_blocks(mi, measure: Measure = MI):
    """Per (against, dataset, path length): a measure of the walkers (ceilings left out), MI unless told,
    a row per restart and a column per walker; none against a labelling whose column ``mi`` lacks."""
    mi = walkers_only(mi)
    for against, column in measure.columns.items():
        if column not in mi:
            continue
        table = mi.dropna(subset=[column]).pivot_table(
            index=["dataset", "path_length", *PAIR_KEYS], columns="weight_function", values=column
        )
        for (dataset, length), block in table.groupby(level=["dataset", "path_length"]):
            yield against, dataset, length, block


def paired_tests(mi, measure: Measure = MI):
    """Wilcoxon signed-rank test between every pair of walkers on a measure (MI unless told), paired by restart
    (ceilings left out)."""
    import pandas as pd

    rows = []
    for against, dataset, length, block in paired_blocks(mi, measure):
        for a, b in itertools.combinations(block.columns, 2):
            pair = block[[a, b]].dropna()
            diff = pair[a] - pair[b]
            p = wilcoxon_pair_p(diff.to_numpy()) if len(pair) else np.nan
            rows.append({
                "dataset": dataset, "path_length": length, "against": against, "a": a, "b": b,
                "n": len(pair), "median_difference": float(diff.median()) if len(pair) else np.nan, "p_value": p,
            })
    return pd.DataFrame(rows, columns=["dataset", "path_length", "against", "a", "b", "n", "median_difference", "p_value"])


#: Pairs up to which scipy's Wilcoxon test of differences with ties or zeros enumerates every sign flip
#: (2 ** 13 is below its 9,999 resamples): its p is then exact, and costly to get from scipy.
_ENUMERATED = 13


def wilcoxon_pair_p(differences: np.ndarray) -> float:
    """Two-sided Wilcoxon signed-rank p of paired differences, as ``scipy.stats.wilcoxon(differences)`` gives it.

    Differences with tied magnitudes or zeros (counts, such as classes found), 13 or
    fewer, are scipy's exact permutation test, computed here at once over every sign flip
    (:func:`_sign_flip_p`): scipy takes about 75 ms a test to enumerate them.

    Parameters
    ----------
    differences : (n,) float ndarray

    Returns
    -------
    float
        1 where every difference is 0.
    """
    from scipy import stats

    d = np.asarray(differences, np.float64)
    if not d.any():
        return 1.0
    magnitude = np.sort(np.abs(d))
    if d.size <= _ENUMERATED and (magnitude[0] == 0 or (np.diff(magnitude) == 0).any()):
        return _sign_flip_p(d)
    return float(stats.wilcoxon(d).pvalue)


def _sign_flip_p(d: np.ndarray) -> float:
    """The exact two-sided permutation p of Wilcoxon's W+ (the midranks of the non-zero magnitudes where the
    difference is positive) over every sign flip of the non-zero differences, with scipy's tolerance for ties
    of the statistic (``scipy.stats.permutation_test``)."""
    from scipy.stats import rankdata

    nonzero = d[d != 0]
    ranks = rankdata(np.abs(nonzero))
    flips = (np.arange(2**nonzero.size)[:, None] >> np.arange(nonzero.size)) & 1
    null = flips @ ranks
    observed = ranks[nonzero > 0].sum()
    tolerance = abs(np.finfo(np.float64).eps * 100 * observed)
    below = np.count_nonzero(null <= observed + tolerance) / null.size
    above = np.count_nonzero(null >= observed - tolerance) / null.size
    return float(min(1.0, 2 * min(below, above)))


def smallest_wilcoxon_p(pairs: int) -> float:
    """The smallest two-sided p an exact Wilcoxon signed-rank test of ``pairs`` pairs can give: ``2 ** (1 - pairs)``.

    Every difference of one sign is the most extreme outcome, of chance ``2 ** -pairs``
    each way; with 5 pairs or fewer no test reaches p < 0.05 whatever the data.
    """
    return 2.0 ** (1 - pairs) if pairs >= 1 else 1.0


def paired_difference(a: np.ndarray, b: np.ndarray, confidence: float = CONFIDENCE) -> tuple[float, float, float]:
    """Mean of ``a - b`` and its Student-t confidence interval, as ``scipy.stats.ttest_rel(a, b)``.

    Parameters
    ----------
    a, b : (n,) float ndarrays
        Paired values (the same restart of two walkers).
    confidence : float
        Of the interval, in (0, 1).

    Returns
    -------
    (float, float, float)
        Mean difference, lower and upper bound. The bounds are NaN for fewer than two
        pairs, and both the mean when every difference is the same.
    """
    return mean_interval(np.asarray(a, np.float64) - np.asarray(b, np.float64), confidence)


def mean_interval(values: np.ndarray, confidence: float = CONFIDENCE) -> tuple[float, float, float]:
    """Mean of ``values`` and its Student-t confidence interval.

    Parameters
    ----------
    values : (n,) float ndarray
    confidence : float
        Of the interval, in (0, 1).

    Returns
    -------
    (float, float, float)
        Mean, lower and upper bound: all NaN for no values, the bounds NaN for one.
    """
    from scipy import stats

    values = np.asarray(values, np.float64)
    if values.size == 0:
        return np.nan, np.nan, np.nan
    mean = float(values.mean())
    if values.size < 2:
        return mean, np.nan, np.nan
    half = float(stats.t.ppf(0.5 + confidence / 2, values.size - 1) * values.std(ddof=1) / np.sqrt(values.size))
    return mean, mean - half, mean + half


def wilcoxon_p(tests, dataset: str, length: int, against: str, a: str, b: str) -> tuple[float, int]:
    """The Wilcoxon p and pairs of ``a`` against ``b`` in ``tests`` (either order); ``(NaN, 0)`` if absent."""
    pair = tests[
        (tests["dataset"] == dataset) & (tests["path_length"] == length) & (tests["against"] == against)
        & (((tests["a"] == a) & (tests["b"] == b)) | ((tests["a"] == b) & (tests["b"] == a)))
    ]
    return (float(pair["p_value"].iloc[0]), int(pair["n"].iloc[0])) if len(pair) else (np.nan, 0)
