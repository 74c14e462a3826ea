"""The validation table: a graded oracle lead and a sham at the nominal rate pass; a sham that leads, or oracles
that do not, fail; a time is better lower."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from curiosity_cli.evaluate.measures import MI, TIME_TO_FIND
from curiosity_cli.evaluate.tables import EvaluationError
from curiosity_cli.evaluate.validation import BLOCK, MIN_REPLICATIONS, merge_runs, readings_table, validation_table

SEEDS, RESTARTS = 4, 60  # 4 x 60 / 5 = 48 sham replications


def table(oracle_step: float, sham_lead: float, ours_lead: float, noise: float = 0.05, seed: int = 0) -> pd.DataFrame:
    """mi.csv rows of stochastic coverage, the oracles (lead ``oracle_step`` per 0.1 of P), the sham and topic
    perplexity, with independent normal noise per run."""
    rng = np.random.default_rng(seed)
    leads = {"stochastic-coverage": 0.0, "oracle-0.1": oracle_step, "oracle-0.2": 2 * oracle_step,
             "oracle-0.3": 3 * oracle_step, "sham": sham_lead, "topic-perplexity": ours_lead}
    rows = []
    for replicate in range(SEEDS):
        for restart in range(RESTARTS):
            base = rng.normal(1.0, 0.2)  # a restart's own level, shared by its walkers: what pairing removes
            for walker, lead in leads.items():
                rows.append({"dataset": "planted", "weight_function": walker, "replicate": replicate,
                             "restart": restart, "path_length": 80, "mi_human": base + lead + rng.normal(0, noise)})
    return pd.DataFrame(rows)


def only(result: pd.DataFrame) -> pd.Series:
    assert len(result) == 1
    return result.iloc[0]


def test_a_graded_oracle_lead_and_a_null_sham_validate_the_measure_and_place_topic_perplexity_on_the_scale():
    row = only(validation_table(table(0.02, 0.0, 0.03), 80, (MI,)))
    assert row["n"] == SEEDS * RESTARTS and row["sham_replications"] == SEEDS * RESTARTS // BLOCK >= MIN_REPLICATIONS
    assert row["lead_0.1"] == pytest.approx(0.02, abs=0.01) and row["lead_0.3"] == pytest.approx(0.06, abs=0.01)
    assert row["slope"] == pytest.approx(0.2, abs=0.05) and row["slope_p"] < 1e-6 and row["top_p"] < 1e-6
    assert row["sham_rate_low"] <= 0.05 and row["sham_rate"] < 0.2
    assert row["ours_low"] < 0.03 < row["ours_high"] and row["ours_p_equivalent"] == pytest.approx(0.15, abs=0.05)
    assert row["graded"] and row["sham_null"] and row["validated"]


def test_a_sham_that_leads_or_oracles_that_do_not_fail_the_measure():
    leading_sham = only(validation_table(table(0.02, 0.06, 0.0), 80, (MI,)))
    assert leading_sham["graded"] and not leading_sham["sham_null"] and not leading_sham["validated"]
    assert leading_sham["sham_rate_low"] > 0.05
    flat = only(validation_table(table(0.0, 0.0, 0.0, seed=1), 80, (MI,)))
    assert not flat["graded"] and not flat["validated"] and flat["slope_p"] > 0.01


def test_too_few_sham_replications_decide_nothing_and_a_time_is_better_lower():
    rows = table(-2.0, 0.0, -1.0, noise=1.0)
    rows = rows.rename(columns={"mi_human": "time_to_find"})
    few = rows[rows["replicate"] == 0]
    row = only(validation_table(few, 80, (TIME_TO_FIND,)))
    assert row["sham_replications"] == RESTARTS // BLOCK < MIN_REPLICATIONS and not row["sham_null"]
    assert row["lead_0.3"] == pytest.approx(6.0, abs=0.6), "two steps sooner per 0.1 of P is a lead"
    assert row["graded"] and not row["validated"]


def test_a_run_two_experiments_share_is_taken_once_and_only_when_both_give_it_the_same_values():
    rows = table(0.02, 0.0, 0.0)
    oracles = rows[rows["weight_function"] != "sham"]
    sham = rows[rows["weight_function"].isin(["sham", "stochastic-coverage"])]
    merged = merge_runs({"results/validation": oracles, "results/validation-sham": sham})
    assert len(merged) == len(rows) and "_folder" not in merged
    pd.testing.assert_frame_equal(
        merged.sort_values(list(merged.columns)).reset_index(drop=True),
        rows.sort_values(list(rows.columns)).reset_index(drop=True),
    )
    edited = sham.copy()
    edited.loc[edited.index[0], "mi_human"] += 1e-9
    with pytest.raises(EvaluationError, match="^results/validation and results/validation-sham: run planted/"
                       "stochastic-coverage/0/0 has other values in each"):
        merge_runs({"results/validation": oracles, "results/validation-sham": edited})


def test_the_kept_validation_gives_its_table_again_from_its_kept_runs():
    from pathlib import Path

    kept = Path(__file__).resolve().parents[2] / "studies" / "validation"
    names = ["validation", *(f"validation-sham-{m}" for m in ("planted-disjoint", "planted-shared", "rare-patches"))]
    table = validation_table(merge_runs({n: pd.read_csv(kept / f"{n}-mi.csv") for n in names}), 80)
    pd.testing.assert_frame_equal(table, pd.read_csv(kept / "validation.csv"), check_dtype=False)
    passes = table[table["validated"]]
    assert set(passes.loc[passes["measure"] == "time_to_find", "dataset"]) == {"planted-shared", "rare-patches"}


def test_each_reading_is_validated_on_its_own_runs():
    graded, flat = table(0.02, 0.0, 0.03), table(0.0, 0.0, 0.0, seed=1)
    both = readings_table({"frozen": graded, "unseen-topic": flat}, 80, (MI,))
    assert list(both["reading"]) == ["frozen", "unseen-topic"] and list(both.columns[:2]) == ["reading", "dataset"]
    assert list(both["validated"]) == [True, False]
    pd.testing.assert_frame_equal(
        both.iloc[1:].drop(columns="reading").reset_index(drop=True), validation_table(flat, 80, (MI,)),
    )


def test_the_kept_readings_give_their_table_again_from_their_kept_runs():
    """studies/validation/readings/READING/ holds the four mi.csv of the validation labelled under each reading but
    frozen (whose are studies/validation's own); readings.csv is the table scripts/validate_measures.py made of all."""
    from pathlib import Path

    kept = Path(__file__).resolve().parents[2] / "studies" / "validation"
    names = ["validation", *(f"validation-sham-{m}" for m in ("planted-disjoint", "planted-shared", "rare-patches"))]
    folders = {"frozen": kept, **{path.name: path for path in sorted((kept / "readings").iterdir())}}
    groups = {title: merge_runs({n: pd.read_csv(folder / f"{n}-mi.csv") for n in names}) for title, folder in folders.items()}
    table = readings_table(groups, 80)
    expected = pd.read_csv(kept / "readings.csv")
    assert list(dict.fromkeys(expected["reading"])) == list(folders)
    pd.testing.assert_frame_equal(table, expected, check_dtype=False)
    frozen = table[table["reading"] == "frozen"].drop(columns="reading").reset_index(drop=True)
    pd.testing.assert_frame_equal(frozen, pd.read_csv(kept / "validation.csv"), check_dtype=False)


def test_a_restart_whose_oracles_all_lead_alike_has_a_slope_of_exactly_0_which_the_test_leaves_out():
    rows = table(0.0, 0.0, 0.0, noise=0.0)  # every walker of a restart equal: each oracle's lead is exactly 0
    lifted = rows["weight_function"].str.startswith("oracle") & (rows["restart"] < 10)
    rows.loc[lifted, "mi_human"] += 0.1  # ten restarts where every oracle leads alike: still no rise with P
    row = only(validation_table(rows, 80, (MI,)))
    assert row["lead_0.1"] == row["lead_0.3"] > 0 and row["slope"] == 0.0 and row["slope_p"] == 1.0
    assert row["top_p"] < 0.05 and not row["graded"]
