"""Mechanism: whether a walker's score points at classes new to its path, by hand, against slow twins, and its figure."""

from __future__ import annotations

import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats

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


def test_ties_at_infinity_new_candidates_and_unseen_words_among_the_finite_by_hand():
    by_length = {r["path_length"]: r for r in rows()}
    # ties: move 0 scores no infinity; move 1's 2 pairs (2 and 4 against 5) are all three infinite
    assert math.isnan(by_length[1]["infinite_ties"])
    assert [by_length[n]["infinite_ties"] for n in (2, 3, 4)] == [0.0, 0.5, 0.5]
    word = {r["path_length"]: r["infinite_ties"] for r in rows(weight_function="word-perplexity", lengths=(4,))}
    assert word == {4: 0.0}, "read under word perplexity, finite at move 1: no tie at infinity"
    # new per candidate: move 0 has 4 of 3 candidates, move 1 has 2 and 4 of 4 (0 visited counts), move 2 none of 3
    assert math.isnan(by_length[1]["new_share"])
    assert [by_length[n]["new_share"] for n in (2, 3, 4)] == [pytest.approx(1 / 3), pytest.approx(3 / 7), 0.3]
    # finite topic perplexity: move 0's 1 [1, 2], 3 [0, 2] and 4 [2, 5] each hold a word the start cell [0, 1] lacks
    # (2 first seen at step 1); move 1's 0 [0, 1] and move 2's 1 [1, 2] hold none the path had not seen
    assert math.isnan(by_length[1]["finite_unseen"])
    assert [by_length[n]["finite_unseen"] for n in (2, 3, 4)] == [1.0, 0.75, 0.6]
    # no candidate of mixed texture whose classes are all seen: 4 holds A and B, but B is new at moves 0 and 1
    assert [by_length[n]["pairs_mixed"] for n in (1, 2, 3, 4)] == [0, 0, 0, 0]
    assert all(math.isnan(by_length[n]["auc_mixed"]) for n in (1, 2, 3, 4))


#: Classes A, B and C: a path [0, 1] has seen A and B; one move, whose candidates are scored by hand.
MIXED_PRESENT = np.zeros((7, 3), bool)
for _cell, _classes in {0: [0, 1], 1: [0], 2: [0, 2], 3: [2], 4: [0, 1], 5: [1], 6: [0, 1]}.items():
    MIXED_PRESENT[_cell, _classes] = True
MIXED_CANDIDATES = pd.DataFrame(
    # cell 0 visited (no negative though mixed); 2 and 3 hold C, new; 4 and 6 mixed, all seen; 5 homogeneous
    [(0, 0, INF, 0.0, 1.0), (0, 2, 1.0, 3.0, 1.0), (0, 3, 1.0, INF, 1.0), (0, 4, 1.0, 2.0, 1.0),
     (0, 5, 1.0, 0.0, 1.0), (0, 6, 1.0, INF, 1.0)],
    columns=["step", "cell", "coverage", "topic_perplexity", "weight"],
)


def test_the_auc_against_mixed_texture_by_hand():
    row, = mechanism_rows(
        RUN, np.array([0, 1]), MIXED_CANDIDATES, MIXED_PRESENT, lambda cell: np.zeros(0, np.int64), [2],
    )
    # against 4, 5 and 6: 2 (3) beats 4 (2) and 5 (0), is below 6 (inf): 2; 3 (inf) beats 4 and 5, ties 6: 2.5
    assert (row["pairs"], row["auc"]) == (6, pytest.approx(4.5 / 6))
    assert row["infinite_ties"] == pytest.approx(1 / 6), "3 against 6"
    # against the mixed 4 and 6 only: 2 wins 1, 3 wins 1.5
    assert (row["pairs_mixed"], row["auc_mixed"]) == (4, pytest.approx(2.5 / 4))
    assert row["new_share"] == pytest.approx(2 / 6)
    # no cell holds a word: none unseen, finite or not
    assert (row["infinite_unseen"], row["finite_unseen"]) == (0.0, 0.0)


def planted_run(score_of, moves: int = 300, seed: int = 0):
    """A path that has seen A and B from its start, and at every move five unvisited candidates: one holding A and C
    (a boundary: mixed, with C new), two holding A or B alone and two holding A and B (mixed, nothing new), each
    scored ``score_of(classes present, holds a new class, uniform noise)``."""
    rng = np.random.default_rng(seed)
    kinds = [([0, 2], True), ([0], False), ([1], False), ([0, 1], False), ([0, 1], False)]
    present = np.zeros((moves + 1 + len(kinds) * moves, 3), bool)
    present[0, [0, 1]] = True
    present[1 : moves + 1, 0] = True
    table = []
    for t in range(moves):
        for k, (classes, new) in enumerate(kinds):
            cell = moves + 1 + len(kinds) * t + k
            present[cell, classes] = True
            table.append((t, cell, 1.0, score_of(len(classes), new, rng.random()), 1.0))
    candidates = pd.DataFrame(table, columns=["step", "cell", "coverage", "topic_perplexity", "weight"])
    path = np.arange(moves + 1)
    row, = mechanism_rows(RUN, path, candidates, present, lambda cell: np.zeros(0, np.int64), [moves + 1])
    return row


def test_a_score_high_on_any_mixed_cell_beats_homogeneous_ones_but_not_mixed_ones():
    # heterogeneity and noise, blind to what the path has seen: the boundary beats the homogeneous candidates
    # always and the mixed ones half the time, 0.75 over all; against the mixed ones alone, a coin
    blind = planted_run(lambda classes, new, noise: classes + noise)
    assert blind["auc"] == pytest.approx(0.75, abs=0.03) and blind["auc"] > 0.7
    assert blind["auc_mixed"] == pytest.approx(0.5, abs=0.05)
    assert (blind["pairs"], blind["pairs_mixed"]) == (4 * 300, 2 * 300)
    # a score that ranks the new first, whatever the texture: above every other candidate in both
    novelty = planted_run(lambda classes, new, noise: new + noise)
    assert novelty["auc"] == novelty["auc_mixed"] == 1.0
    # one that ranks the new first only most of the time keeps the mixed AUC high too
    noisy = planted_run(lambda classes, new, noise: 0.6 * new + noise)
    assert noisy["auc_mixed"] > 0.75 and abs(noisy["auc_mixed"] - noisy["auc"]) < 0.05


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
        wins = pairs = ties = wins_mixed = pairs_mixed = moves = chances = new_candidates = 0
        infinite = unseen = finite = finite_unseen = n = 0
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
            mixed = [o and len(np.flatnonzero(present[c])) >= 2 for c, o in zip(at["cell"], other)]
            for s_i, n_i in zip(at[score], new):
                for s_j, o_j, m_j in zip(at[score], other, mixed):
                    win = 1.0 if s_i > s_j else 0.5 if s_i == s_j else 0.0
                    if n_i and o_j:
                        pairs += 1
                        wins += win
                        ties += s_i == s_j == INF
                    if n_i and m_j:
                        pairs_mixed += 1
                        wins_mixed += win
            new_candidates += sum(new)
            if any(new):
                chances += 1
                p, _ = move_probabilities(at["weight"].to_numpy())
                with np.errstate(divide="ignore"):
                    q, _ = move_probabilities(1.0 / at["coverage"].to_numpy())
                gains.append(sum(pi - qi for pi, qi, nw in zip(p, q, new) if nw))
            for c, tp in zip(at["cell"], at["topic_perplexity"]):
                n += 1
                holds_unseen = any(w not in seen_words for w in words(c))
                if tp == INF:
                    infinite += 1
                    unseen += holds_unseen
                else:
                    finite += 1
                    finite_unseen += holds_unseen
        met, entered = set(), 0
        for c in path[:length]:
            classes = set(np.flatnonzero(present[c]))
            entered += bool(classes - met)
            met |= classes
        out.append({
            **run, "path_length": length, "moves": moves, "pairs": pairs, "auc": wins / pairs if pairs else np.nan,
            "infinite_ties": ties / pairs if pairs else np.nan, "pairs_mixed": pairs_mixed,
            "auc_mixed": wins_mixed / pairs_mixed if pairs_mixed else np.nan,
            "opportunity": chances / moves if moves else np.nan, "new_share": new_candidates / n if n else np.nan,
            "gain": np.mean(gains) if gains else np.nan,
            "new_class_cells": entered, "classes_found": len(met), "candidates": n,
            "infinite_share": infinite / n if n else np.nan, "infinite_unseen": unseen / infinite if infinite else np.nan,
            "finite_unseen": finite_unseen / finite if finite else np.nan,
        })
    return out


def random_run(rng: np.random.Generator, walker: str):
    """A 6 x 6 map, 5 classes, a 40-step walk, its 8-neighbours as candidates, some scores tied or infinite."""
    side, steps = 6, 40
    present = rng.random((side * side, 5)) < 0.25
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
            word = INF if rng.random() < 0.2 else float(rng.integers(1, 4))
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
    assert got[-1]["pairs_mixed"] > 0 and got[-1]["finite_unseen"] > 0


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


def summary_table(runs: list[dict], **keys) -> pd.DataFrame:
    """A mechanism table of runs given by their measures, the rest 1 (restarts 0, 1, ...)."""
    return pd.DataFrame([
        {**RUN, "path_length": 80, **{m: 1.0 for m in MECHANISM_COLUMNS[5:]}, "restart": i, **keys, **run}
        for i, run in enumerate(runs)
    ], columns=list(MECHANISM_COLUMNS))


#: Three runs of one walker: 2 pairs all won, 50 pairs half won, none; pairs against mixed texture 1 won of 1,
#: 3 of 10, none; one tie at infinity, in the first run.
RUNS = [
    {"pairs": 2, "auc": 1.0, "infinite_ties": 0.5, "pairs_mixed": 1, "auc_mixed": 1.0, "gain": 0.1},
    {"pairs": 50, "auc": 0.5, "infinite_ties": 0.0, "pairs_mixed": 10, "auc_mixed": 0.3, "gain": 0.3},
    {"pairs": 0, "auc": np.nan, "infinite_ties": np.nan, "pairs_mixed": 0, "auc_mixed": np.nan, "gain": np.nan},
]


def test_the_summarys_aucs_are_every_runs_wins_over_every_runs_pairs():
    summary = summarise_mechanism(summary_table(RUNS))
    assert list(summary.columns) == list(MECHANISM_SUMMARY_COLUMNS) and summary["n"].tolist() == [3]
    row = summary.iloc[0]
    # (2 + 25) / (2 + 50), not the runs' mean (1 + 0.5) / 2; a run without pairs adds nothing
    assert row["auc"] == pytest.approx(float(Fraction(27, 52)))
    assert row["infinite_ties"] == pytest.approx(float(Fraction(1, 52)))
    assert row["auc_mixed"] == pytest.approx(float(Fraction(4, 11)))
    # the delta method over the 2 runs with pairs, by hand: residuals 2 - 2 R = 50/52 and 25 - 50 R = -50/52,
    # se = sqrt(2 (50/52)^2 / (2 * 1)) / 26 = 25/676, times Student's t with 1 degree of freedom
    half = stats.t.ppf(0.975, 1) * 25 / 676
    assert (row["auc_low"], row["auc_high"]) == pytest.approx((27 / 52 - half, 27 / 52 + half))
    assert row["auc_low"] < row["auc"] < row["auc_high"]
    # a plain mean's interval is Student's over the runs defining it: gain 0.1 and 0.3
    assert row["gain"] == pytest.approx(0.2)
    assert (row["gain_low"], row["gain_high"]) == pytest.approx(stats.t.interval(0.95, 1, loc=0.2, scale=0.1))
    assert (row["moves_low"], row["moves_high"]) == (1.0, 1.0), "the same in every run: no spread"


def test_with_equal_pairs_the_pooled_auc_and_its_interval_are_the_runs_mean_and_its_t_interval():
    aucs = np.array([0.6, 0.65, 0.7, 0.72])
    row = summarise_mechanism(summary_table([{"pairs": 10, "auc": a} for a in aucs])).iloc[0]
    assert row["auc"] == pytest.approx(aucs.mean())
    want = stats.t.interval(0.95, 3, loc=aucs.mean(), scale=stats.sem(aucs))
    assert (row["auc_low"], row["auc_high"]) == pytest.approx(want)
    # clipped to what a share can be
    top = summarise_mechanism(summary_table([{"pairs": 10, "auc": a} for a in (0.9, 1.0)])).iloc[0]
    assert top["auc_high"] == 1.0 and top["auc_low"] < 0.95


def test_an_interval_needs_two_runs_that_define_the_measure():
    one = summarise_mechanism(summary_table(RUNS[:1])).iloc[0]
    assert one["auc"] == 1.0 and one["gain"] == pytest.approx(0.1)
    assert all(math.isnan(one[f"{m}_{end}"]) for m in ("auc", "auc_mixed", "gain", "moves") for end in ("low", "high"))
    # three runs, but only one with pairs or a gain
    sparse = summarise_mechanism(summary_table([RUNS[0], RUNS[2], RUNS[2]])).iloc[0]
    assert sparse["n"] == 3 and sparse["auc"] == 1.0 and math.isnan(sparse["auc_low"]) and math.isnan(sparse["gain_high"])
    none = summarise_mechanism(summary_table(RUNS[2:])).iloc[0]
    assert math.isnan(none["auc"]) and math.isnan(none["auc_mixed"]) and none["pairs"] == 0.0


def test_a_table_from_before_the_new_measures_is_summarised_without_them():
    from curiosity_cli.evaluate.mechanism import ADDED_MEASURES

    new = summary_table(RUNS)
    old = new.drop(columns=list(ADDED_MEASURES))
    summary = summarise_mechanism(old)
    assert list(summary.columns) == list(MECHANISM_SUMMARY_COLUMNS)
    added = [f"{m}{end}" for m in ADDED_MEASURES for end in ("", "_low", "_high")]
    assert summary[added].isna().all(axis=None), "nothing invented"
    kept = [c for c in MECHANISM_SUMMARY_COLUMNS if c not in added]
    pd.testing.assert_frame_equal(summary[kept], summarise_mechanism(new)[kept])
    # pooled with a later table: the group whose runs do not all have them has none; a group of later runs has them
    later = summary_table(RUNS, weight_function="word-perplexity")
    mixed = summarise_mechanism(pd.concat([old, new.assign(restart=[3, 4, 5]), later], ignore_index=True))
    assert mixed["n"].tolist() == [6, 3]
    assert mixed.loc[0, added].isna().all() and mixed.loc[0, "auc"] == pytest.approx(float(Fraction(54, 104)))
    assert mixed.loc[1, "auc_mixed"] == pytest.approx(float(Fraction(4, 11)))
    with pytest.raises(ParameterError, match="^table: pairs: expected numbers") as error:
        summarise_mechanism(new.assign(pairs="many"))
    assert error.value.parameter == "table"


def test_a_recorded_studys_tables_are_summarised_as_they_were_written():
    from curiosity_cli.evaluate.mechanism import ADDED_MEASURES, PAIR_WEIGHTED

    recorded = sorted(Path(__file__).resolve().parents[2].glob("studies/*/seed-*/*/mechanism.csv"))
    if not recorded:
        pytest.skip("no recorded study in this checkout")
    tables = [pd.read_csv(path) for path in recorded]
    # one table written before the added measures existed and one after, where the checkout has both
    older = next((t for t in tables if not set(ADDED_MEASURES) & set(t.columns)), None)
    newer = next((t for t in tables if set(ADDED_MEASURES) <= set(t.columns)), None)
    keys = ["dataset", "weight_function", "path_length"]

    def written(table, m):
        """A group's mean of ``m``, or its share over the pairs pooled, recomputed from the rows."""
        groups = table.groupby(keys, sort=False)
        if m not in PAIR_WEIGHTED:
            return groups[m].mean()
        pairs = table[PAIR_WEIGHTED[m]]
        return (table[m] * pairs).where(pairs > 0).groupby([table[k] for k in keys], sort=False).sum() / groups[
            PAIR_WEIGHTED[m]
        ].sum()

    for table, measures in ((older, ["gain", "infinite_share", "auc"]), (newer, ["gain", "auc", *ADDED_MEASURES])):
        if table is None:
            continue
        summary = summarise_mechanism(table).set_index(keys)
        for m in measures:
            expected = written(table, m)
            assert summary.loc[expected.index, m].to_numpy() == pytest.approx(expected.to_numpy(), nan_ok=True), m
    assert older is not None or newer is not None
    if older is not None:
        assert summarise_mechanism(older)[list(ADDED_MEASURES)].isna().all(axis=None)


def test_the_report_shows_the_new_measures_and_leaves_an_older_tables_empty():
    from curiosity_cli.evaluate.mechanism import ADDED_MEASURES
    from curiosity_cli.evaluate.report import _mechanism_section

    table = pd.DataFrame(rows(lengths=(4,)) + rows(lengths=(4,), restart=3))
    text = "\n".join(_mechanism_section(table, [4]))
    assert text.startswith("## Does surprise point at what is new?") and "against mixed texture" in text
    # two equal runs: AUC 0.625 with an interval of no width, ties 0.5, no mixed pair, 3 of 10 candidates new,
    # unseen words in 3 of 5 infinite candidates and 3 of 5 finite ones
    assert "| own | topic-perplexity | 0.62 [0.62, 0.62] |  | 0.50 | 0.67 | 0.30 | " in text
    assert "| 0.50 | 0.60 | 0.60 |" in text
    older = "\n".join(_mechanism_section(table.drop(columns=list(ADDED_MEASURES)), [4]))
    assert "| own | topic-perplexity | 0.62 [0.62, 0.62] |  |  | 0.67 |  | " in older
    assert "| 0.50 | 0.60 |  |" in older


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
