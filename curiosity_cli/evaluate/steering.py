"""Steering: how strongly a walker's choice of the next cell depended on its weights.

A perplexity walker multiplies stochastic coverage's weights ``1 / U`` (eq. 8) by a
perplexity; if the perplexities of a step's candidates are nearly equal, it steps as
stochastic coverage would, and whatever the model learned changed nothing. At each
scored step ``t`` of a run (the move from ``path[t]`` to ``path[t + 1]``), with the
walker's recorded weights ``w`` and coverage potentials ``U`` of the same candidates
(``candidates.csv``; under the literal reading a boxed-in step records the visit counts
as ``U``, the limit the walker used), the step's distance is the total variation

    ``TV_t = 1/2 Σ_i |p_i - q_i|``,  ``p = move_probabilities(w)``,  ``q = move_probabilities(1 / U)``

(:func:`~curiosity_cli.explore.walker.move_probabilities`, the one definition of a
step's chances: NaN counts as 0, infinite weights share every chance, no positive weight
is uniform). A path of length ``L`` made the moves ``0 .. L - 2``; its steering is the
mean of ``TV_t`` over those of them that were scored. 0: the walker stepped exactly as
stochastic coverage would have on every step (stochastic coverage's own runs are 0 by
definition); 1: it always stepped where coverage would never. Random walk, which ignores
coverage, gives a reference for how far from coverage a walker can be on the same kind
of path. Planned walkers (the lawnmower, the ceilings) score nothing and get no rows.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

#: ``steering.csv``'s columns (:func:`steering_rows`).
STEERING_COLUMNS = ("dataset", "weight_function", "restart", "replicate", "path_length", "steps", "steering")


def step_distances(step: np.ndarray, coverage: np.ndarray, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each scored step's total-variation distance from stochastic coverage's step (module docstring).

    Parameters
    ----------
    step, coverage, weight : (M,) ndarrays
        ``candidates.csv``'s columns: a row per scored candidate, the rows of a step together.

    Returns
    -------
    (S,) int64 ndarray, (S,) float64 ndarray
        The scored steps in increasing order, and each one's distance in [0, 1].
    """
    from curiosity_cli.explore.walker import move_probabilities

    step = np.asarray(step, np.int64)
    coverage = np.asarray(coverage, np.float64)
    weight = np.asarray(weight, np.float64)
    order = np.argsort(step, kind="stable")
    step, coverage, weight = step[order], coverage[order], weight[order]
    steps, starts = np.unique(step, return_index=True)
    distances = np.empty(steps.size)
    with np.errstate(divide="ignore"):  # U = 0 (a lone visited cell under `others`): weight +inf, as the walker had it
        inverse = 1.0 / coverage
    for i, (start, end) in enumerate(zip(starts, [*starts[1:], step.size])):
        walker, _ = move_probabilities(weight[start:end])
        coverage_only, _ = move_probabilities(inverse[start:end])
        distances[i] = 0.5 * float(np.abs(walker - coverage_only).sum())
    return steps, distances


def steering_at(steps: np.ndarray, distances: np.ndarray, length: int) -> tuple[int, float]:
    """The mean distance over the moves of a path of ``length`` steps (moves ``0 .. length - 2``).

    Returns
    -------
    (int, float)
        How many of those moves were scored, and their mean distance (NaN for none).
    """
    made = np.asarray(steps) <= length - 2
    count = int(np.count_nonzero(made))
    return count, float(np.asarray(distances)[made].mean()) if count else np.nan


def steering_rows(run: dict, candidates, lengths: Iterable[int]) -> list[dict]:
    """``steering.csv``'s rows of one run: one per checkpoint length, none for a run that scored nothing.

    Parameters
    ----------
    run : dict
        ``dataset``, ``weight_function``, ``restart`` and ``replicate`` of the run.
    candidates : pandas.DataFrame
        Its ``candidates.csv`` (``step``, ``coverage``, ``weight``:
        :meth:`~curiosity_cli.explore.runs.Run.candidates`).
    lengths : iterable of int
        The checkpoint lengths its label file holds.
    """
    if candidates.empty:
        return []
    steps, distances = step_distances(candidates["step"], candidates["coverage"], candidates["weight"])
    rows = []
    for length in lengths:
        count, mean = steering_at(steps, distances, int(length))
        rows.append({**{k: run[k] for k in STEERING_COLUMNS[:4]}, "path_length": int(length), "steps": count, "steering": mean})
    return rows
