"""The table of measures and what each walker found: every measure compared as MI is."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from curiosity_cli.errors import ParameterError
from curiosity_cli.evaluate.information import mutual_information
from curiosity_cli.evaluate.found import found_effects, found_leads, missing_measures, summarise_found
from curiosity_cli.evaluate.measures import MEASURES, Checkpoint, measure_named, measure_values
from curiosity_cli.explore.weights import CEILINGS

WALKERS = ["topic-perplexity", "stochastic-coverage", "word-perplexity", "random-walk"]


def found_mi(lead: float, seed: int = 0, datasets=("a", "b", "c")) -> pd.DataFrame:
    """mi.csv rows of 4 walkers and a ceiling, 12 restarts at 80 steps: every measure but MI noise around a
    walker-free centre, topic perplexity's classes found, recall and NMI raised by ``lead`` times a scale."""
    rng = np.random.default_rng(seed)
    rows = []
    for dataset in datasets:
        for restart in range(12):
            shared = rng.standard_normal()  # what the restart's start cell gives every walker
            for weight in (*WALKERS, CEILINGS[0]):
                ahead = lead if weight == "topic-perplexity" else 0.0
                noise = 0.3 * rng.standard_normal()
                rows.append({
                    "dataset": dataset, "weight_function": weight, "restart": restart, "path_length": 80,
                    "mi_human": 0.3, "mi_batch": 0.5, "nmi_human": 0.2 + 0.02 * (shared + noise + ahead),
                    "nmi_batch": 0.3, "ami_human": 0.2 + 0.02 * (shared + noise), "ami_batch": 0.3,
                    "classes_found": 3 + shared + noise + ahead, "classes": 6,
                    "mean_recall": 0.4 + 0.05 * (shared + noise + ahead), "replicate": 0,
                    "time_to_find": 40 + 5 * (shared + noise - ahead),  # sooner is better
                    "mi_visited_human": 0.4 + 0.02 * (shared + noise), "mi_visited_batch": 0.6,
                    "mi_unvisited_human": 0.3 + 0.02 * (shared + noise), "mi_unvisited_batch": 0.5,
                    "heldout": -7.0 + 0.1 * (shared + noise), "heldout_unvisited": -7.5 + 0.1 * (shared + noise),
                })
    return pd.DataFrame(rows)


def test_a_planted_lead_on_what_a_path_finds_is_found_and_a_sham_one_is_not():
    for lead, expected in ((2.0, True), (0.0, False)):
        mi = found_mi(lead)
        leads = found_leads(found_effects(mi)).query("against == 'human'").set_index(["measure", "dataset"])
        for measure in ("classes_found", "mean_recall", "nmi", "time_to_find"):
            rows = leads.loc[measure]
            assert (rows["beats_all"] & (rows["p_each_holm"] < 0.05)).all() == expected, (lead, measure)
            assert rows["walkers"].eq(3).all()  # the ceiling is not a walker
        # AMI, MI by part and the held-out log-likelihood were left without a lead in both
        for measure in ("ami", "mi_visited", "mi_unvisited"):
            assert not (leads.loc[measure]["p_each_holm"] < 0.05).any(), measure
        words = found_leads(found_effects(mi)).query("against == 'words'")
        assert set(words["measure"]) == {"heldout", "heldout_unvisited"} and not (words["p_each_holm"] < 0.05).any()


def test_effects_are_the_paired_differences_with_their_intervals():
    mi = found_mi(1.0)
    effects = found_effects(mi)
    row = effects[(effects.measure == "classes_found") & (effects.dataset == "a") & (effects.other == "random-walk")].iloc[0]
    block = mi[(mi.dataset == "a")].pivot_table(index="restart", columns="weight_function", values="classes_found")
    diff = block["topic-perplexity"] - block["random-walk"]
    assert row["n"] == 12
    assert row["mean_difference"] == pytest.approx(diff.mean())
    assert row["ci_low"] < diff.mean() < row["ci_high"]
    assert row["ratio"] == pytest.approx(block["topic-perplexity"].mean() / block["random-walk"].mean())
    # human-only measures are never compared against Z_b
    assert set(effects.loc[effects.measure == "mean_recall", "against"]) == {"human"}
    assert set(effects.loc[effects.measure == "nmi", "against"]) == {"human", "batch"}


def test_the_summary_holds_every_walker_and_ceiling_of_every_measure():
    mi = found_mi(0.0)
    summary = summarise_found(mi)
    assert set(summary["measure"]) == {m.name for m in MEASURES if m.found}
    row = summary[(summary.measure == "mean_recall") & (summary.dataset == "b") & (summary.weight_function == CEILINGS[0])]
    values = mi[(mi.dataset == "b") & (mi.weight_function == CEILINGS[0])]["mean_recall"]
    assert row["n"].item() == 12 and row["mean"].item() == pytest.approx(values.mean())


def test_a_table_from_before_a_measure_says_it_lacks_it_and_invents_nothing():
    mi = found_mi(1.0).drop(columns=["ami_human", "ami_batch"])
    assert [m.name for m in missing_measures(mi)] == ["ami"]
    assert "ami" not in set(found_effects(mi)["measure"]) | set(summarise_found(mi)["measure"])
    assert missing_measures(found_mi(1.0)) == []


def test_a_checkpoint_gives_every_measure_column_in_order():
    human = np.array([[30, 0, 5], [0, 20, 0], [0, 0, 0], [2, 1, 0]])  # 4 topics, 3 classes (the third unseen in pixels)
    human[:, 2] = [0, 0, 0, 0]
    batch = np.array([[20, 5, 0, 0], [0, 15, 3, 0], [0, 0, 10, 0], [1, 0, 0, 4]])
    values = measure_values(Checkpoint(40, batch, human, np.array([3, 50, -1])))
    columns = [c for m in MEASURES for c in m.columns.values()]
    assert [c for c in values if c in columns] == columns
    assert values["classes_found"] == 1 and values["classes"] == 2  # class 1 first reached at step 50 > 40
    assert values["mean_recall"] == pytest.approx((30 / 32 + 20 / 21) / 2)
    assert values["topics_used"] == 4
    assert values["time_to_find"] == (3 + 40) / 2  # class 1 not found by step 40: censored there
    assert values["ami_human"] < values["nmi_human"]
    unlabelled = measure_values(Checkpoint(40, batch, None, None))
    assert np.isnan(unlabelled["mi_human"]) and np.isnan(unlabelled["classes_found"]) and np.isfinite(unlabelled["ami_batch"])


def test_mi_where_the_path_went_and_where_it_did_not_is_taken_from_the_two_parts_of_the_map():
    rng = np.random.default_rng(3)
    seen_human, rest_human = rng.integers(0, 30, (4, 3)), rng.integers(0, 30, (4, 3))
    seen_batch, rest_batch = rng.integers(0, 30, (4, 4)), rng.integers(0, 30, (4, 4))
    point = Checkpoint(40, seen_batch + rest_batch, seen_human + rest_human, None, seen_batch, seen_human)
    values = measure_values(point)
    for against, seen, rest in (("human", seen_human, rest_human), ("batch", seen_batch, rest_batch)):
        assert values[f"mi_visited_{against}"] == pytest.approx(mutual_information(seen))
        assert values[f"mi_unvisited_{against}"] == pytest.approx(mutual_information(rest))
    assert values["mi_human"] == pytest.approx(mutual_information(seen_human + rest_human))
    # a path that visited every cell leaves no pixels elsewhere: no MI there, not 0 bits
    whole = measure_values(Checkpoint(40, seen_batch, seen_human, None, seen_batch, seen_human))
    assert np.isnan(whole["mi_unvisited_human"]) and np.isnan(whole["mi_unvisited_batch"])
    # a label file without the visited tables gives neither part
    older = measure_values(Checkpoint(40, seen_batch, seen_human, None))
    assert all(np.isnan(older[c]) for c in ("mi_visited_human", "mi_unvisited_human", "mi_visited_batch"))


def test_the_held_out_log_likelihood_is_its_bits_per_word_over_all_cells_and_over_the_unvisited():
    batch = np.eye(3, dtype=int) * 10
    point = Checkpoint(40, batch, None, None, heldout_bits=np.array([-700.0, -300.0]), heldout_words=np.array([100, 40]))
    values = measure_values(point)
    assert (values["heldout"], values["heldout_unvisited"]) == (-7.0, -7.5)
    # a path that visited every cell leaves no held-out word elsewhere: no likelihood there, not 0 bits
    whole = measure_values(Checkpoint(40, batch, None, None, heldout_bits=np.array([-700.0, 0.0]),
                                      heldout_words=np.array([100, 0])))
    assert whole["heldout"] == -7.0 and np.isnan(whole["heldout_unvisited"])
    older = measure_values(Checkpoint(40, batch, None, None))
    assert np.isnan(older["heldout"]) and np.isnan(older["heldout_unvisited"])
    assert measure_named("heldout").columns == {"words": "heldout"} and measure_named("heldout").unit == "bits/word"


def test_a_measure_is_named_or_the_names_are_listed():
    assert measure_named("ami").title == "AMI"
    with pytest.raises(ParameterError, match="measure: got 'auc', expected one of mi, nmi, ami"):
        measure_named("auc")


def test_a_study_counts_each_measures_leads_over_its_points_after_holm():
    from types import SimpleNamespace

    from curiosity_cli.evaluate.found_curve import found_curve_lines, found_curve_table

    specifications = [
        ({"specification": "ahead"}, SimpleNamespace(found_effects=found_effects(found_mi(2.0, seed=1)), seeds=(0, 1))),
        ({"specification": "level"}, SimpleNamespace(found_effects=found_effects(found_mi(0.0, seed=2)), seeds=(0, 1))),
    ]
    table = found_curve_table(specifications)
    assert len(table) == 9 * 2 * 3  # measures x specifications x maps
    # a measure of no labelling is read against the map's held-out words
    assert (table.loc[table.measure.str.startswith("heldout"), "against"] == "words").all()
    recall = table[table.measure == "mean_recall"].set_index(["specification", "dataset"])
    assert (recall.loc["ahead", "p_each_holm"] < 0.05).all() and not (recall.loc["level", "p_each_holm"] < 0.05).any()
    assert (recall["against"] == "human").all() and (recall["path_length"] == 80).all()
    # Holm over the measure's six points: never below the point's own p
    assert (recall["p_each_holm"] >= recall["p_each"]).all()
    time = table[table.measure == "time_to_find"].set_index(["specification", "dataset"])
    assert (time.loc["ahead", "p_each_holm"] < 0.05).all() and (time.loc["ahead", "closest_difference"] < 0).all()
    lines = "\n".join(found_curve_lines(table, ["ami"]))
    assert "| mean recall | 6 | 3 |" in lines
    assert "Not pooled (AMI)" in lines


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(-3, 3), min_size=1, max_size=16))
def test_the_wilcoxon_p_of_counts_is_scipys_exact_permutation_p(differences):
    # counts tie and hit zero: scipy enumerates every sign flip up to 13 pairs, slowly; we do it at once
    from scipy import stats

    from curiosity_cli.evaluate.statistics import wilcoxon_pair_p

    d = np.array(differences, float)
    expected = stats.wilcoxon(d).pvalue if d.any() else 1.0
    assert wilcoxon_pair_p(d) == pytest.approx(expected, rel=1e-12, abs=1e-15)


def test_each_class_is_timed_censored_at_the_length_and_paired_by_restart():
    from curiosity_cli.evaluate.found import class_times

    rows = []
    for restart in range(6):
        for weight, first in (("topic-perplexity", 5 + restart), ("random-walk", None if restart < 3 else 30), (CEILINGS[0], 0)):
            rows.append({
                "dataset": "m", "weight_function": weight, "restart": restart, "path_length": 40, "class_id": 2,
                "class_name": "rock", "pixels": 10, "found": first is not None, "first_step": first, "topic": 0,
                "recall": 0.5,
            })
    times = class_times(pd.DataFrame(rows))
    assert len(times) == 1  # the ceiling is not a walker
    row = times.iloc[0]
    assert row["other"] == "random-walk" and row["n"] == 6
    assert row["topic_perplexity_steps"] == pytest.approx(np.mean([5, 6, 7, 8, 9, 10]))
    assert row["other_steps"] == pytest.approx((3 * 40 + 3 * 30) / 6)  # never found: 40, the length
    assert row["mean_difference"] == pytest.approx(7.5 - 35) and row["ci_high"] < 0
    assert (row["topic_perplexity_found"], row["other_found"]) == (1.0, 0.5)
