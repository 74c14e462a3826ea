"""Mechanism: whether a walker's score points at classes new to its path, by hand, against slow twins, and its figure."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pandas as pd
import pytest

from curiosity_cli.errors import ParameterError
from curiosity_cli.evaluate.mechanism import (
    MECHANISM_COLUMNS,
    MECHANISM_SUMMARY_COLUMNS,
    class_presence,
    mechanism_rows,
    step_auc,
    summarise_mechanism,
    walker_score,
)
from curiosity_cli.explore.runs import Run, RunError
from curiosity_cli.explore.walker import move_probabilities

INF = float("inf")
A, B = 0, 1

#: A 3 x 3 map (cells 0 .. 8, row-major) with classes A and B; cell 5 holds neither at 10 %.
PRESENT = np.zeros((9, 2), bool)
for _cell, _classes in {0: [A], 1: [A], 2: [B], 3: [A], 4: [A, B], 6: [A], 7: [B], 8: [B]}.items():
    PRESENT[_cell, _classes] = True
#: Each cell's word ids.
WORDS = {0: [0, 1], 1: [1, 2], 2: [3], 3: [0, 2], 4: [2, 5], 5: [1, 1], 6: [], 7: [7], 8: [8]}
#: A path of 4 steps: moves 0, 1, 2. A is seen from step 0, B from step 2 (cell 4).
PATH = np.array([0, 1, 4, 3])
#: Its candidates as candidates.csv has them (topic perplexity's run: weight = perplexity / U),
#: the rows of a move not together (the reader must not rely on order).
CANDIDATES = pd.DataFrame(
    [
        # move 0 at cell 0 (seen: A): 4 holds B, new (positive); 1 and 3 hold only A (negatives)
        (0, 1, 1.0, 3.0, 2.0, 2.0),
        (1, 0, INF, 1.0, 1.0, 0.0),  # move 1: 0 is visited, neither positive nor negative
        (0, 3, 1.0, 1.0, 5.0, 5.0),
        (0, 4, 2.0, 2.0, 5.0, 2.5),
        # move 1 at cell 1 (seen: A): 2 and 4 hold B (positives), 5 holds nothing (negative);
        # every open candidate infinitely surprising: they tie, and share the walker's chances
        (1, 2, 1.0, 4.0, INF, INF), (1, 4, 1.0, 4.0, INF, INF), (1, 5, 2.0, 2.0, INF, INF),
        # move 2 at cell 4 (seen: A, B): nothing new; 1 visited
        (2, 1, INF, 1.0, 2.0, 0.0), (2, 3, 1.0, 1.0, INF, INF), (2, 7, 1.0, 1.0, INF, INF),
    ],
    columns=["step", "cell", "coverage", "word_perplexity", "topic_perplexity", "weight"],
)
RUN = {"dataset": "own", "weight_function": "topic-perplexity", "restart": 2, "replicate": 5}


def cell_words(cell: int) -> np.ndarray:
    return np.array(WORDS[cell], np.int64)


def rows(candidates=CANDIDATES, lengths=(1, 2, 3, 4), path=PATH, present=PRESENT, **run) -> list[dict]:
    return mechanism_rows({**RUN, **run}, path, candidates, present, cell_words, lengths)


# by hand, in exact fractions
# M1, topic perplexity: move 0: 4 (5) beats 1 (2), ties 3 (5): 3/2 of 2; move 1: inf ties inf twice: 1 of 2
TOPIC_AUC = {2: Fraction(3, 4), 3: Fraction(5, 8), 4: Fraction(5, 8)}
# word perplexity: move 0: 4 (2) below 1 (3), above 3 (1): 1 of 2; move 1: 4 and 4 above 2: 2 of 2
WORD_AUC = {2: Fraction(1, 2), 3: Fraction(3, 4), 4: Fraction(3, 4)}
# M3: move 0: the walker's chance on 4 is 2.5 / 9.5, coverage's (1/U: 1, 1, 1/2) 1/5;
# move 1: infinite weights on 2, 4, 5: 2/3 on the positives, coverage's (0, 1, 1, 1/2) 4/5
GAIN_0 = Fraction(5, 19) - Fraction(1, 5)
GAIN_1 = Fraction(2, 3) - Fraction(4, 5)


def test_the_hand_computation():
    assert GAIN_0 == Fraction(6, 95) and GAIN_1 == Fraction(-2, 15) and (GAIN_0 + GAIN_1) / 2 == Fraction(-2, 57)
    walker, _ = move_probabilities(np.array([2.0, 5.0, 2.5]))
    assert walker[2] == pytest.approx(float(Fraction(5, 19)))


def test_each_measure_against_a_hand_computation():
    by_length = {r["path_length"]: r for r in rows()}
    assert [tuple(r) for r in by_length.values()] == [MECHANISM_COLUMNS] * 4
    one, two, three, four = (by_length[n] for n in (1, 2, 3, 4))
    assert {k: four[k] for k in MECHANISM_COLUMNS[:4]} == RUN
    # M1: pairs within a move only; visited candidates are no negatives
    assert [r["pairs"] for r in (one, two, three, four)] == [0, 2, 4, 4]
    assert math.isnan(one["auc"])
    for length, auc in TOPIC_AUC.items():
        assert by_length[length]["auc"] == pytest.approx(float(auc), abs=1e-15)
    # M2: moves 0 and 1 had something new in reach, move 2 nothing
    assert [r["moves"] for r in (one, two, three, four)] == [0, 1, 2, 3]
    assert math.isnan(one["opportunity"])
    assert (two["opportunity"], three["opportunity"], four["opportunity"]) == (1.0, 1.0, pytest.approx(2 / 3))
    # M3
    assert math.isnan(one["gain"])
    assert two["gain"] == pytest.approx(float(GAIN_0))
    assert four["gain"] == three["gain"] == pytest.approx(float((GAIN_0 + GAIN_1) / 2))
    # M4: A at step 0 (the start cell counts), B at step 2
    assert [(r["new_class_cells"], r["classes_found"]) for r in (one, two, three, four)] == [(1, 1), (1, 1), (2, 2), (2, 2)]


def test_infinite_topic_perplexity_and_the_word_ids_unseen_at_each_move():
    by_length = {r["path_length"]: r for r in rows()}
    # words seen: move 1 (cells 0, 1): {0, 1, 2}; move 2 (cells 0, 1, 4): {0, 1, 2, 5}
    # move 1: 2 [3] unseen, 4 [2, 5] unseen (5 only seen at step 2, later), 5 [1, 1] seen;
    # move 2: 3 [0, 2] seen, 7 [7] unseen (a word on no cell of the path)
    assert [by_length[n]["candidates"] for n in (1, 2, 3, 4)] == [0, 3, 7, 10]
    assert math.isnan(by_length[1]["infinite_share"]) and math.isnan(by_length[1]["infinite_unseen"])
    assert by_length[2]["infinite_share"] == 0.0 and math.isnan(by_length[2]["infinite_unseen"])
    assert by_length[3]["infinite_share"] == pytest.approx(3 / 7)
    assert by_length[3]["infinite_unseen"] == pytest.approx(2 / 3)
    assert by_length[4]["infinite_share"] == 0.5
    assert by_length[4]["infinite_unseen"] == pytest.approx(3 / 5)


def test_each_walker_is_read_under_its_own_score_and_the_others_under_topic_perplexitys():
    assert walker_score("topic-perplexity") == "topic_perplexity"
    assert walker_score("word-perplexity") == "word_perplexity"
    assert walker_score("random-walk") == walker_score("stochastic-coverage") == "topic_perplexity"
    word = {r["path_length"]: r["auc"] for r in rows(weight_function="word-perplexity")}
    assert word == {1: pytest.approx(np.nan, nan_ok=True), **{k: pytest.approx(float(v)) for k, v in WORD_AUC.items()}}
    for walker in ("random-walk", "stochastic-coverage"):
        auc = [r["auc"] for r in rows(weight_function=walker, lengths=(2, 4))]
        assert auc == [pytest.approx(float(TOPIC_AUC[2])), pytest.approx(float(TOPIC_AUC[4]))]
    # a walker needing no word perplexity is read without it
    assert rows(CANDIDATES.drop(columns="word_perplexity"), lengths=(4,))[0]["auc"] == pytest.approx(0.625)


def test_stochastic_coverage_gains_nothing_over_itself_and_a_plan_gets_no_rows():
    coverage = CANDIDATES.assign(weight=1.0 / CANDIDATES["coverage"])
    gains = [r["gain"] for r in rows(coverage, lengths=(2, 4), weight_function="stochastic-coverage")]
    assert gains == [pytest.approx(0.0, abs=1e-15)] * 2
    assert rows(CANDIDATES.iloc[:0], weight_function="lawnmower") == []


def test_classes_met_together_count_one_cell_and_a_start_without_a_class_none():
    # cell 5 holds no class; cell 4 holds A and B, both new at step 1; cell 2 holds only B, no longer new
    candidates = pd.DataFrame(
        [(0, 4, 1.0, 1.0, 1.0, 1.0), (1, 2, 1.0, 1.0, 1.0, 1.0)],
        columns=["step", "cell", "coverage", "word_perplexity", "topic_perplexity", "weight"],
    )
    out = rows(candidates, path=np.array([5, 4, 2]), lengths=(1, 2, 3))
    assert [(r["new_class_cells"], r["classes_found"]) for r in out] == [(0, 0), (1, 2), (1, 2)]
    # move 0: the lone candidate is positive, with no negative: an opportunity without pairs
    assert [r["pairs"] for r in out] == [0, 0, 0]
    assert out[2]["opportunity"] == 0.5 and out[2]["gain"] == 0.0
    assert all(math.isnan(r["auc"]) for r in out)


def test_class_presence_is_the_label_stages_share():
    pixels = np.array([[9, 91], [10, 90], [50, 50], [0, 7]])
    assert class_presence(pixels).tolist() == [[False, True], [True, True], [True, True], [False, True]]


@pytest.mark.parametrize(
    ("change", "parameter", "words"),
    [
        ({"run_info": {"dataset": "own", "weight_function": "random-walk", "restart": 0}}, "run_info", "replicate"),
        ({"run_info": ["own"]}, "run_info", "list"),
        ({"path": np.array([0, 9])}, "path", "0 .. 8"),
        ({"path": np.array([], np.int64)}, "path", "L >= 1"),
        ({"path": np.array([0.0, 1.0])}, "path", "float64"),
        ({"present": PRESENT.astype(int)}, "present", "bool"),
        ({"present": PRESENT[:, 0]}, "present", "(n_cells, C)"),
        ({"candidates": CANDIDATES.drop(columns="topic_perplexity")}, "candidates", "topic_perplexity"),
        ({"candidates": CANDIDATES.to_dict()}, "candidates", "DataFrame"),
        ({"candidates": CANDIDATES.assign(step=CANDIDATES["step"] + 1)}, "candidates", "0 .. 2"),
        ({"candidates": CANDIDATES.assign(cell=CANDIDATES["cell"] + 2)}, "candidates", "cell"),
        ({"candidates": CANDIDATES.assign(step=CANDIDATES["step"].astype(float))}, "candidates", "whole numbers"),
        ({"candidates": CANDIDATES.assign(topic_perplexity=np.nan)}, "candidates", "NaN"),
        ({"lengths": [4, 5]}, "lengths", "4 steps"),
        ({"lengths": [0]}, "lengths", "between 1 and 4"),
        ({"lengths": 4}, "lengths", "checkpoint lengths"),
        ({"cell_words": WORDS}, "cell_words", "callable"),
        ({"cell_words": lambda cell: np.array(WORDS[cell], float) + 0.5}, "cell_words", "integer"),
    ],
)
def test_bad_inputs_are_named(change, parameter, words):
    arguments = {
        "run_info": RUN, "path": PATH, "candidates": CANDIDATES, "present": PRESENT, "cell_words": cell_words,
        "lengths": [2, 4], **change,
    }
    with pytest.raises(ParameterError, match=f"^{parameter}: .*{words}") as error:
        mechanism_rows(**arguments)
    assert error.value.parameter == parameter


def test_step_auc_names_its_bad_inputs():
    with pytest.raises(ParameterError, match="^score: NaN") as error:
        step_auc([0, 0], [np.nan, 1.0], [True, False], [False, True])
    assert error.value.parameter == "score"
    with pytest.raises(ParameterError, match="^negative: "):
        step_auc([0], [1.0], [True], [True])
    with pytest.raises(ParameterError, match=r"^positive: got shape \(1,\)"):
        step_auc([0, 0], [1.0, 2.0], [True], [False, True])
    with pytest.raises(ParameterError, match="^weight_function: "):
        walker_score(None)


# ---- slow, obvious twins ------------------------------------------------------------------


def naive_step_auc(step, score, positive, negative) -> dict[int, tuple[float, int]]:
    """Each move's wins and pairs, a pair at a time."""
    out = {}
    for t in sorted(set(int(s) for s in step)):
        wins, pairs = 0.0, 0
        for i in range(len(step)):
            for j in range(len(step)):
                if step[i] == t and step[j] == t and positive[i] and negative[j]:
                    pairs += 1
                    a, b = float(score[i]), float(score[j])
                    wins += 1.0 if a > b else 0.5 if a == b else 0.0
        out[t] = (wins, pairs)
    return out


def random_candidates(rng: np.random.Generator, moves: int) -> tuple[np.ndarray, ...]:
    per_move = rng.integers(1, 9, moves)
    step = np.repeat(rng.permutation(moves * 3)[:moves], per_move)  # moves not 0 .. S-1, rows shuffled below
    score = rng.integers(0, 4, step.size).astype(float)
    score[rng.random(step.size) < 0.2] = INF
    kind = rng.integers(0, 3, step.size)  # 0 positive, 1 negative, 2 visited
    order = rng.permutation(step.size)
    return step[order], score[order], (kind == 0)[order], (kind == 1)[order]


@pytest.mark.parametrize("seed", range(8))
def test_step_auc_against_its_slow_twin_on_random_moves(seed):
    step, score, positive, negative = random_candidates(np.random.default_rng(seed), 30)
    steps, wins, pairs = step_auc(step, score, positive, negative)
    naive = naive_step_auc(step, score, positive, negative)
    assert steps.tolist() == list(naive)
    assert wins.tolist() == [w for w, _ in naive.values()]
    assert pairs.tolist() == [p for _, p in naive.values()]
    assert step_auc(step[:0], score[:0], positive[:0], negative[:0])[0].size == 0


def naive_rows(run, path, candidates, present, words, lengths) -> list[dict]:
    """mechanism_rows with sets and loops, straight from the definitions."""
    score = walker_score(run["weight_function"])
    out = []
    for length in lengths:
        wins = pairs = moves = chances = infinite = unseen = n = 0
        gains = []
        for t in range(length - 1):
            at = candidates[candidates["step"] == t]
            if at.empty:
                continue
            moves += 1
            visited = {int(c) for c in path[: t + 1]}
            seen_classes = {h for c in visited for h in np.flatnonzero(present[c])}
            seen_words = {w for c in visited for w in words(c)}
            new = [bool(set(np.flatnonzero(present[c])) - seen_classes) for c in at["cell"]]
            other = [int(c) not in visited and not nw for c, nw in zip(at["cell"], new)]
            for s_i, n_i in zip(at[score], new):
                for s_j, o_j in zip(at[score], other):
                    if n_i and o_j:
                        pairs += 1
                        wins += 1.0 if s_i > s_j else 0.5 if s_i == s_j else 0.0
            if any(new):
                chances += 1
                p, _ = move_probabilities(at["weight"].to_numpy())
                with np.errstate(divide="ignore"):
                    q, _ = move_probabilities(1.0 / at["coverage"].to_numpy())
                gains.append(sum(pi - qi for pi, qi, nw in zip(p, q, new) if nw))
            for c, tp in zip(at["cell"], at["topic_perplexity"]):
                n += 1
                if tp == INF:
                    infinite += 1
                    unseen += any(w not in seen_words for w in words(c))
        met, entered = set(), 0
        for c in path[:length]:
            classes = set(np.flatnonzero(present[c]))
            entered += bool(classes - met)
            met |= classes
        out.append({
            **run, "path_length": length, "moves": moves, "pairs": pairs, "auc": wins / pairs if pairs else np.nan,
            "opportunity": chances / moves if moves else np.nan, "gain": np.mean(gains) if gains else np.nan,
            "new_class_cells": entered, "classes_found": len(met), "candidates": n,
            "infinite_share": infinite / n if n else np.nan, "infinite_unseen": unseen / infinite if infinite else np.nan,
        })
    return out


def random_run(rng: np.random.Generator, walker: str):
    """A 6 x 6 map, 3 classes, a 40-step walk, its 8-neighbours as candidates, some scores tied or infinite."""
    side, steps = 6, 40
    present = rng.random((side * side, 3)) < 0.25
    store = {c: rng.integers(0, 30, rng.integers(0, 5)) for c in range(side * side)}
    path, rows_ = [int(rng.integers(side * side))], []
    for t in range(steps - 1):
        r, c = divmod(path[-1], side)
        around = [
            (r + dr) * side + c + dc for dr in (-1, 0, 1) for dc in (-1, 0, 1)
            if (dr or dc) and 0 <= r + dr < side and 0 <= c + dc < side
        ]
        for g in around:
            visited = g in path
            topic = INF if rng.random() < 0.2 else float(rng.integers(1, 4))
            word = float(rng.integers(1, 4))
            coverage = INF if visited else float(rng.integers(1, 4))
            weight = 0.0 if visited else (INF if topic == INF and rng.random() < 0.5 else float(rng.integers(0, 4)))
            rows_.append((t, g, coverage, word, topic, weight))
        path.append(int(rng.choice(around)))
    candidates = pd.DataFrame(rows_, columns=["step", "cell", "coverage", "word_perplexity", "topic_perplexity", "weight"])
    candidates = candidates.sample(frac=1.0, random_state=int(rng.integers(1 << 30))).reset_index(drop=True)
    run = {"dataset": "random", "weight_function": walker, "restart": 0, "replicate": 0}
    return run, np.array(path), candidates, present, lambda cell: store[int(cell)]


@pytest.mark.parametrize("walker", ["topic-perplexity", "word-perplexity", "random-walk"])
@pytest.mark.parametrize("seed", range(3))
def test_rows_against_their_slow_twin_on_random_walks(walker, seed):
    run, path, candidates, present, words = random_run(np.random.default_rng(seed), walker)
    lengths = [1, 2, 10, 25, 40]
    got = mechanism_rows(run, path, candidates, present, words, lengths)
    want = naive_rows(run, path, candidates, present, words, lengths)
    assert len(got) == len(want)
    for g, w in zip(got, want):
        assert list(g) == list(MECHANISM_COLUMNS)
        for key in MECHANISM_COLUMNS:
            assert g[key] == pytest.approx(w[key], nan_ok=True, abs=1e-12), (key, g["path_length"])
    assert got[-1]["pairs"] > 0 and got[-1]["infinite_share"] > 0


# ---- reading a run, summarising, drawing --------------------------------------------------


def test_a_runs_candidates_are_read_with_cells_and_both_perplexities(tmp_path):
    CANDIDATES.assign(row=0, col=0, chosen=False).to_csv(tmp_path / "candidates.csv", index=False)
    run = Run(tmp_path, {}, PATH)
    table = run.candidates()
    pd.testing.assert_frame_equal(table[list(CANDIDATES.columns)], CANDIDATES)
    assert rows(table, lengths=(4,)) == rows(lengths=(4,))
    CANDIDATES.assign(step=CANDIDATES["step"] + 1).to_csv(tmp_path / "candidates.csv", index=False)
    with pytest.raises(RunError, match="step: expected whole numbers 0 .. 2"):
        run.candidates()
    (tmp_path / "candidates.csv").unlink()
    with pytest.raises(RunError, match="not found"):
        run.candidates()


def test_summary_means_each_measure_over_the_runs_that_define_it():
    table = pd.DataFrame(
        rows(lengths=(1, 4)) + rows(lengths=(1, 4), restart=3) + rows(lengths=(4,), weight_function="word-perplexity")
    )
    summary = summarise_mechanism(table)
    assert list(summary.columns) == list(MECHANISM_SUMMARY_COLUMNS)
    assert summary[["weight_function", "path_length", "n"]].values.tolist() == [
        ["topic-perplexity", 1, 2], ["topic-perplexity", 4, 2], ["word-perplexity", 4, 1],
    ]
    assert math.isnan(summary["auc"][0]) and summary["auc"][1] == pytest.approx(0.625)
    assert summary["auc"][2] == pytest.approx(0.75)
    # NaN-aware: a run without a defined measure does not pull the mean down
    one_nan = table.copy()
    one_nan.loc[1, "gain"] = np.nan
    assert summarise_mechanism(one_nan)["gain"][1] == pytest.approx(float((GAIN_0 + GAIN_1) / 2))
    assert summarise_mechanism(table.iloc[:0]).empty
    with pytest.raises(ParameterError, match="^table: no column 'auc'") as error:
        summarise_mechanism(table.drop(columns="auc"))
    assert error.value.parameter == "table"


def _figure_table(ratio: bool) -> pd.DataFrame:
    table = pd.DataFrame({
        "specification": ["paper", "paper", "rost", "rost"], "dataset": ["own", "zurich", "own", "zurich"],
        "auc": [0.62, 0.5, np.nan, 0.71], "opportunity": [0.3, 0.1, 0.0, 0.4], "gain": [0.05, -0.01, np.nan, 0.1],
    })
    if ratio:
        table = table.assign(mi_ratio=[1.1, 0.9, 1.0, 1.3], **{"mi_ratio_random-walk": [1.2, 1.0, 0.95, 1.4]})
    return table


@pytest.mark.slow
@pytest.mark.parametrize("ratio", [False, True])
def test_the_figure_is_written_as_png_and_pdf(tmp_path, ratio):
    from curiosity_cli.plots.mechanism import write_mechanism_figure

    paths = write_mechanism_figure(_figure_table(ratio), tmp_path / "figures" / "mechanism.png")
    assert paths == [tmp_path / "figures" / "mechanism.png", tmp_path / "figures" / "mechanism.pdf"]
    assert all(p.is_file() and p.stat().st_size > 0 for p in paths)
    assert sorted(p.name for p in (tmp_path / "figures").iterdir()) == ["mechanism.pdf", "mechanism.png"]


def test_the_figure_names_a_bad_table(tmp_path):
    from curiosity_cli.plots.mechanism import write_mechanism_figure

    with pytest.raises(ParameterError, match="^table: no column 'gain'") as error:
        write_mechanism_figure(_figure_table(False).drop(columns="gain"), tmp_path / "mechanism")
    assert error.value.parameter == "table"
    with pytest.raises(ParameterError, match="^table: no rows"):
        write_mechanism_figure(_figure_table(False).iloc[:0], tmp_path / "mechanism")
    assert not (tmp_path / "mechanism.png").exists()
