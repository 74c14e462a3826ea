"""Steering: each move's total-variation distance from stochastic coverage's, by hand and on real runs."""

from __future__ import annotations

import dataclasses
from fractions import Fraction

import numpy as np
import pandas as pd
import pytest
from small_maps import grid_config

from curiosity_cli.label.stage import label_experiment
from curiosity_cli.evaluate.steering import STEERING_COLUMNS, step_distances, steering_at, steering_rows
from curiosity_cli.evaluate.stage import evaluate_experiment
from curiosity_cli.explore.grid import run_grid

INF = float("inf")

#: A run of 5 steps (moves 0 .. 3) of topic perplexity, its candidates as candidates.csv has them,
#: rows of a step not together (the reader must not rely on order).
CANDIDATES = pd.DataFrame(
    [
        # move 0: U = 1, 2, 4 and perplexities 2, 1, 1: weights 2, 1/2, 1/4
        (0, 1.0, 2.0), (0, 2.0, 0.5),
        # move 2, boxed in under the literal reading: U recorded as the visit counts 1 and 3,
        # perplexities 1 and 6: weights 1 and 2
        (2, 1.0, 1.0), (2, 3.0, 2.0),
        (0, 4.0, 0.25),
        # move 1: a visited neighbour (U = inf, weight 0) beside an open one
        (1, INF, 0.0), (1, 2.0, 1.5),
        # move 3: an infinitely surprising neighbour takes every chance
        (3, 1.0, INF), (3, 1.0, 1.0), (3, 2.0, 0.5),
    ],
    columns=["step", "coverage", "weight"],
)


def _tv(p, q) -> Fraction:
    return sum((abs(a - b) for a, b in zip(p, q)), Fraction(0)) / 2


# by hand, in exact fractions: the walker's chances p against coverage's q = (1/U) / Σ (1/U)
MOVE_0 = _tv([Fraction(8, 11), Fraction(2, 11), Fraction(1, 11)], [Fraction(4, 7), Fraction(2, 7), Fraction(1, 7)])
MOVE_1 = _tv([0, 1], [0, 1])
MOVE_2 = _tv([Fraction(1, 3), Fraction(2, 3)], [Fraction(3, 4), Fraction(1, 4)])
MOVE_3 = _tv([1, 0, 0], [Fraction(2, 5), Fraction(2, 5), Fraction(1, 5)])


def test_each_moves_distance_against_a_hand_computation():
    assert (MOVE_0, MOVE_1, MOVE_2, MOVE_3) == (Fraction(12, 77), 0, Fraction(5, 12), Fraction(3, 5))
    steps, distances = step_distances(CANDIDATES["step"], CANDIDATES["coverage"], CANDIDATES["weight"])
    assert steps.tolist() == [0, 1, 2, 3]
    np.testing.assert_allclose(distances, [float(MOVE_0), 0.0, float(MOVE_2), float(MOVE_3)], rtol=1e-12)


def test_a_path_of_length_l_averages_its_moves_0_to_l_minus_2():
    steps, distances = step_distances(CANDIDATES["step"], CANDIDATES["coverage"], CANDIDATES["weight"])
    assert steering_at(steps, distances, 3) == (2, pytest.approx(float((MOVE_0 + MOVE_1) / 2)))
    assert steering_at(steps, distances, 5) == (4, pytest.approx(float((MOVE_0 + MOVE_1 + MOVE_2 + MOVE_3) / 4)))
    count, mean = steering_at(steps, distances, 1)
    assert count == 0 and np.isnan(mean)
    run = {"dataset": "own", "weight_function": "topic-perplexity", "restart": 3, "replicate": 7, "path_length": 0}
    rows = steering_rows(run, CANDIDATES, [3, 5])
    assert [tuple(r) for r in rows] == [STEERING_COLUMNS] * 2
    assert [(r["restart"], r["replicate"], r["path_length"], r["steps"]) for r in rows] == [(3, 7, 3, 2), (3, 7, 5, 4)]


def test_stochastic_coverages_own_moves_and_a_plan_that_scores_nothing():
    coverage = CANDIDATES.assign(weight=1.0 / CANDIDATES["coverage"])
    _, distances = step_distances(coverage["step"], coverage["coverage"], coverage["weight"])
    assert (distances == 0).all()
    run = {"dataset": "own", "weight_function": "lawnmower", "restart": 0, "replicate": 0}
    assert steering_rows(run, CANDIDATES.iloc[:0], [5, 12]) == []
    # a lone visited cell under `others` has U = 0: its coverage weight is infinite, as the walker's
    _, distances = step_distances([0, 0], [0.0, 1.0], [INF, 1.0])
    assert distances.tolist() == [0.0]


@pytest.mark.slow
@pytest.mark.parametrize("coverage", ["literal", "others"])
def test_steering_csv_agrees_with_every_runs_candidates_csv(own_map, tmp_path, coverage):
    walkers = ("random-walk", "stochastic-coverage", "topic-perplexity", "lawnmower")
    config = grid_config(own_map, path_length=40, checkpoints=(10, 40), coverage=coverage, weight_functions=walkers)
    config = dataclasses.replace(config, label=dataclasses.replace(config.label, sweeps=2, batch_sweeps=4))
    run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    folder = tmp_path / config.name
    label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1)
    evaluation = evaluate_experiment(folder)
    steering = pd.read_csv(folder / "steering.csv")
    assert list(steering.columns) == list(STEERING_COLUMNS)
    assert set(steering["weight_function"]) == {"random-walk", "stochastic-coverage", "topic-perplexity"}
    assert len(steering) == 3 * 2 * 2, "3 walkers that score x 2 restarts x 2 lengths; the lawnmower has no rows"
    for row in steering.itertuples():
        run = folder / "runs" / row.dataset / row.weight_function / f"restart-{row.restart:03d}"
        table = pd.read_csv(run / "candidates.csv")
        made = table[table["step"] <= row.path_length - 2]
        distances = []
        for _, move in made.groupby("step"):
            with np.errstate(divide="ignore"):
                q = 1 / move["coverage"].to_numpy()
            w = move["weight"].to_numpy()
            p = np.isinf(w) / np.isinf(w).sum() if np.isinf(w).any() else w / w.sum()
            q = np.isinf(q) / np.isinf(q).sum() if np.isinf(q).any() else q / q.sum()
            distances.append(np.abs(p - q).sum() / 2)
        assert row.steps == row.path_length - 1 == len(distances)
        assert row.steering == pytest.approx(np.mean(distances), abs=1e-12)
    by_walker = steering.groupby("weight_function")["steering"]
    assert (by_walker.get_group("stochastic-coverage") == 0).all()
    assert (by_walker.get_group("random-walk") > 0).all() and (by_walker.get_group("topic-perplexity") > 0).any()
    pd.testing.assert_frame_equal(evaluation.steering, steering, check_dtype=False)
    report_lines = (folder / "tables.json").read_text()
    assert '"steering.csv"' in report_lines and "candidates.csv" in report_lines
