"""A study's declared hypotheses: read and checked against the study, tested on its seeds' tables, confirmatory
only when declared in a commit before their data and on runs no other study recorded; bad ones refused."""

from __future__ import annotations

import subprocess
from datetime import datetime, timedelta
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from naive import sign_flip_p_naive
from scipy import stats
from test_specifications import study_yaml
from test_sweep import sweep

from curiosity_cli.evaluate.multiplicity import holm
from curiosity_cli.study.hypotheses import COLUMNS, declaration, hypothesis_table
from curiosity_cli.study.record import StudyRecord
from curiosity_cli.study.specifications import declared_specifications
from curiosity_cli.study.sweep import declared_sweeps, parse_sweeps, plan_sweep
from curiosity_cli.study.types import Hypothesis, Outcome

COMPARATORS = ["random-walk", "stochastic-coverage"]
RESTARTS = 4  # 2 seeds x 4 restarts: 8 pairs, 256 sign flips to enumerate


def declared(own_map: Path, folder: Path, **changes) -> dict:
    """Two primary hypotheses over the tiny study's one map, and a secondary one; ``changes`` edit H1's fields."""
    name = yaml.safe_load(own_map.read_text())["name"]
    h1 = {
        "claim": "topic perplexity finds the classes sooner", "specification": "default", "comparators": COMPARATORS,
        "measure": "time_to_find", "reading": "frozen", "path_length": 80,
        "label_schedule": {"sweeps": 2, "warm_sweeps": 1}, "seeds": [1, 2], "scale": {name: 10.0}, "draws": 100_000,
    }
    h1.update(changes)
    h2 = {**h1, "specification": "clamp", "claim": "the same under clamp", "test": "stratified-t"}
    h2.pop("draws")
    h3 = {**h1, "role": "secondary", "measure": "mean_recall", "scale": {name: 0.1}, "claim": "a better recall"}
    return {"alpha": 0.025, "H1": {k: v for k, v in h1.items() if v is not ...}, "H2": h2, "H3": h3}


def hypotheses_yaml(own_map: Path, folder: Path, hypotheses=...) -> Path:
    """The tiny study declaring ``hypotheses`` (by default :func:`declared`'s; None: the key left empty)."""
    config = study_yaml(own_map, folder)
    text = yaml.safe_load(config.read_text())
    text["hypotheses"] = hypotheses if hypotheses is not ... else declared(own_map, folder)
    config.write_text(yaml.safe_dump(text, sort_keys=False))
    return config


def planned(config: Path):
    return plan_sweep(config, parse_sweeps(declared_sweeps(config)), (), declared_specifications(config))


def fabricated(plan, folder: Path, started: datetime) -> list[Outcome]:
    """Each combination's evaluated tables, made up: topic perplexity finds the classes 15 steps sooner than
    random walk on average and 10 sooner than stochastic coverage, with noise of 1 step; began at ``started``."""
    rng = np.random.default_rng(5)
    outcomes = []
    for combination in plan.combinations:
        seed = combination.config.seed
        rows = []
        for restart in range(RESTARTS):
            base = rng.uniform(20, 60)
            for walker, ahead in (("topic-perplexity", 0.0), ("random-walk", 15.0), ("stochastic-coverage", 10.0)):
                rows.append({
                    "dataset": "own", "weight_function": walker, "restart": restart, "path_length": 80,
                    "time_to_find": base + ahead + rng.normal(0, 1), "mean_recall": rng.uniform(0, 1),
                    "mi_human": rng.uniform(0, 1), "replicate": seed,
                })
        where = folder / combination.name
        where.mkdir(parents=True)
        pd.DataFrame(rows).to_csv(where / "mi.csv", index=False)
        (where / "provenance.yaml").write_text(yaml.safe_dump({"seed": seed, "started": started.isoformat()}))
        outcomes.append(Outcome(combination, where / "REPORT.md", None, 1.0, where))
    return outcomes


def record_recipes(plan, record: Path, recipe=lambda combination: {"seed": combination.config.seed}) -> None:
    """A record of every combination holding only what the hypotheses read of it: each map's run recipe."""
    kept = StudyRecord(record, plan)
    for combination in plan.combinations:
        folder = kept.folder(combination)
        folder.mkdir(parents=True)
        recipes = {"maps": {"own": {"run": {**recipe(combination), "spec": combination.name}}}}
        (folder / "record.yaml").write_text(yaml.safe_dump({"recipes": recipes}))


def git(folder: Path, *args: str, at: datetime | None = None) -> str:
    """Run git in ``folder``; a commit made ``at`` a given time, if said."""
    import os

    dated = {"GIT_COMMITTER_DATE": at.isoformat(), "GIT_AUTHOR_DATE": at.isoformat()} if at is not None else {}
    done = subprocess.run(
        ["git", "-c", "user.name=t", "-c", "user.email=t@t", "-C", str(folder), *args], capture_output=True, text=True,
        check=True, env={**os.environ, **dated},
    )
    return done.stdout.strip()


def committed(config: Path) -> datetime:
    """Commit the study config in a fresh repository; returns the commit's time."""
    git(config.parent, "init", "-q")
    git(config.parent, "add", config.name)
    git(config.parent, "commit", "-q", "-m", "declared")
    return datetime.fromisoformat(git(config.parent, "log", "-1", "--format=%cI"))


def heads(table: pd.DataFrame) -> pd.DataFrame:
    return table[table["comparator"].isna() & (table["scope"] == "pooled")].set_index("hypothesis")


def test_hypotheses_are_read_with_their_defaults_and_the_study_s_map_names(own_map, tmp_path):
    plan = planned(hypotheses_yaml(own_map, tmp_path))
    assert [h.name for h in plan.hypotheses] == ["H1", "H2", "H3"]
    h1, h2, h3 = plan.hypotheses
    assert h1 == Hypothesis(
        "H1", "topic perplexity finds the classes sooner", True, "default", "topic-perplexity", tuple(COMPARATORS),
        "time_to_find", "human", "frozen", 80, {"sweeps": 2, "warm_sweeps": 1}, "sign-flip", 100_000, (1, 2),
        {"own": 10.0}, 0.025,
    )
    assert (h2.test, h2.draws, h2.primary) == ("stratified-t", 100_000, True) and not h3.primary
    assert h1.maps == ["own"]
    # a study of specifications alone, no seeds swept: its one seed is the config's
    config = hypotheses_yaml(own_map, tmp_path, {"alpha": 0.025, "H1": declared(own_map, tmp_path, seeds=[0])["H1"]})
    text = yaml.safe_load(config.read_text())
    del text["sweep"]
    config.write_text(yaml.safe_dump(text, sort_keys=False))
    alone = plan_sweep(config, (), (), declared_specifications(config))
    assert [h.seeds for h in alone.hypotheses] == [(0,)]


def test_each_hypothesis_is_tested_on_its_seeds_pairs_and_the_primary_ones_adjusted_together(own_map, tmp_path):
    plan = planned(hypotheses_yaml(own_map, tmp_path))
    outcomes = fabricated(plan, tmp_path / "results", datetime.now().astimezone())
    table, declared_at = hypothesis_table(plan, outcomes, None)
    assert list(table.columns) == COLUMNS and declared_at.commit is None
    mi = {
        spec: pd.concat(pd.read_csv(tmp_path / "results" / f"specification-{spec}_seed-{s}" / "mi.csv") for s in (1, 2))
        for spec in ("default", "clamp")
    }
    expected = {}
    for name, spec, column, scale in (("H1", "default", "time_to_find", 10.0), ("H2", "clamp", "time_to_find", 10.0),
                                      ("H3", "default", "mean_recall", 0.1)):
        pairs = mi[spec].pivot_table(index=["replicate", "restart"], columns="weight_function", values=column)
        p_each = []
        for comparator in COMPARATORS:
            lead = pairs[comparator] - pairs["topic-perplexity"] if column == "time_to_find" else (
                pairs["topic-perplexity"] - pairs[comparator]
            )
            row = table.query(f"hypothesis == '{name}' and scope == 'pooled' and comparator == '{comparator}'").iloc[0]
            assert row["pairs"] == 2 * RESTARTS
            assert row["difference"] == pytest.approx(lead.mean() / scale)
            assert row["raw_difference"] == pytest.approx(lead.mean())
            if name == "H2":  # the stratified t of one map is the one-sample t
                p = stats.ttest_1samp(lead / scale, 0.0, alternative="greater").pvalue
                assert row["p_value"] == pytest.approx(p)
            else:  # 100,000 drawn flips against all 256
                p = sign_flip_p_naive((lead / scale).to_numpy(), ["own"] * len(lead))
                assert row["p_value"] == pytest.approx(p, abs=0.005)
            p_each.append(row["p_value"])
        expected[name] = max(p_each)
    head = heads(table)
    assert head["p_value"].to_dict() == pytest.approx(expected)
    # Holm over the two primary hypotheses only; the secondary one is unadjusted and decides nothing
    assert head.loc[["H1", "H2"], "p_holm"].to_numpy() == pytest.approx(holm([expected["H1"], expected["H2"]]))
    assert np.isnan(head.loc["H3", "p_holm"])
    for name in ("H1", "H2"):
        assert head.loc[name, "decision"] == ("confirmed" if head.loc[name, "p_holm"] <= 0.025 else "not confirmed")
    assert head.loc["H3", "decision"] in ("ahead (secondary)", "not ahead (secondary)")
    # leads of 15 and 10 steps in 8 pairs with noise of 1: no flip but the identity reaches them (p = 1/256); H2's t
    # p is smaller, so Holm leaves H1's as it is
    assert head.loc["H1", "decision"] == "confirmed" and head.loc["H1", "p_holm"] == pytest.approx(1 / 256, abs=0.001)
    # per map: its own test (its own draws), Holm over the hypothesis's one map
    own = table.query("hypothesis == 'H1' and scope == 'own'")
    assert own["comparator"].isna().sum() == 1 and own["p_holm"].dropna().tolist() == pytest.approx([1 / 256], abs=0.001)
    # no record and no commit: exploratory, saying why
    assert head["status"].str.startswith("exploratory: no --record").all()
    assert "is not in a git repository" in head.loc["H1", "status"]


def test_a_hypothesis_with_a_seed_missing_is_not_tested_and_no_primary_one_is_decided(own_map, tmp_path):
    plan = planned(hypotheses_yaml(own_map, tmp_path))
    outcomes = fabricated(plan, tmp_path / "results", datetime.now().astimezone())
    failed = outcomes[3]  # clamp, seed 2
    outcomes[3] = Outcome(failed.combination, None, "killed", 1.0)
    head = heads(hypothesis_table(plan, outcomes, None)[0])
    assert head.loc["H2", "decision"] == "not tested: seed 2 not finished"
    # a seed the sweep does not run now is as missing: the hypothesis is never tested on fewer than declared
    config = hypotheses_yaml(own_map, tmp_path, {"alpha": 0.025, "H1": declared(own_map, tmp_path, seeds=[1, 2, 3])["H1"]})
    assert heads(hypothesis_table(planned(config), outcomes, None)[0]).loc["H1", "decision"] == "not tested: seed 3 not in this sweep"
    # Holm over one of the two declared would test H1 at twice the level declared
    assert head.loc["H1", "decision"] == "not decided: H2 not tested" and np.isnan(head.loc["H1", "p_holm"])


def test_a_measure_the_tables_lack_leaves_the_hypothesis_untested_saying_which_table(own_map, tmp_path):
    config = hypotheses_yaml(own_map, tmp_path, {"alpha": 0.025, "H1": declared(own_map, tmp_path, measure="nmi")["H1"]})
    plan = planned(config)
    head = heads(hypothesis_table(plan, fabricated(plan, tmp_path / "results", datetime.now().astimezone()), None)[0])
    assert head.loc["H1", "decision"].startswith("not tested: ")
    assert "mi.csv has no nmi_human (made before nmi was measured)" in head.loc["H1", "decision"]


def test_confirmatory_only_when_declared_in_a_commit_before_its_data_on_runs_no_other_study_recorded(own_map, tmp_path):
    config = hypotheses_yaml(own_map, tmp_path)
    when = committed(config)
    assert declaration(config).commit == git(config.parent, "rev-parse", "HEAD")
    plan = planned(config)
    record = tmp_path / "studies" / "confirmatory"
    record_recipes(plan, record)
    later = fabricated(plan, tmp_path / "results", when + timedelta(hours=1))
    head = heads(hypothesis_table(plan, later, record)[0])
    assert (head["status"] == "confirmatory").all(), head["status"].tolist()

    # another study recorded seed 2 of the default specification's runs: H1 and H3 pool them, H2 does not
    other = tmp_path / "studies" / "multiverse" / "seed-2" / "default"
    other.mkdir(parents=True)
    (other / "record.yaml").write_text((record / "seed-2" / "default" / "record.yaml").read_text())
    head = heads(hypothesis_table(plan, later, record)[0])
    assert head.loc["H2", "status"] == "confirmatory"
    for name in ("H1", "H3"):
        assert head.loc[name, "status"].startswith(
            "exploratory: its runs of own, seed-2 under default's settings were recorded before in "
        ) and head.loc[name, "status"].endswith("studies/multiverse/seed-2/default")
    other.joinpath("record.yaml").unlink()

    # data that began before the declaration's commit
    earlier = fabricated(plan, tmp_path / "earlier", when - timedelta(hours=1))
    status = heads(hypothesis_table(plan, earlier, record)[0]).loc["H1", "status"]
    assert status.startswith("exploratory: specification-default_seed-1, specification-default_seed-2 began before")

    # the declaration edited since its commit
    text = yaml.safe_load(config.read_text())
    text["hypotheses"]["H1"]["claim"] = "changed after the data"
    config.write_text(yaml.safe_dump(text, sort_keys=False))
    assert declaration(config).commit is None and "is not committed as it is now" in declaration(config).why
    # committed again after the data began, it is declared by the new commit: too late
    git(config.parent, "commit", "-q", "-am", "changed", at=when + timedelta(hours=2))
    assert declaration(config).commit == git(config.parent, "rev-parse", "HEAD")
    assert declaration(config).time == when + timedelta(hours=2)
    status = heads(hypothesis_table(planned(config), later, record)[0]).loc["H1", "status"]
    assert "began before its hypotheses were declared as they are" in status


def _error(own_map, tmp_path, hypotheses) -> str:
    config = hypotheses_yaml(own_map, tmp_path, hypotheses)
    result = sweep(config, tmp_path / "results")
    assert result.exit_code == 1, result.output
    assert not (tmp_path / "results").exists(), "refused before anything is written"
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("Error: ") and "Traceback" not in result.output
    return lines[0]


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"claim": ...}, "H1.claim: missing; a hypothesis declares claim, specification"),
        ({"colour": 1}, "H1: 'colour': not a field; expected claim"),
        ({"specification": "nope"}, "H1.specification: got 'nope', expected one of default, clamp"),
        ({"comparators": ["topic-perplexity"]}, "H1.comparators: got ['topic-perplexity'], expected a list of other walkers"),
        ({"comparators": ["word-perplexity"]}, "H1.comparators: got ['word-perplexity'], expected a list of other walkers"),
        ({"measure": "speed"}, "H1.measure: got 'speed', expected one of mi, nmi"),
        ({"against": "batch"}, "H1.against: got 'batch', expected one of human for time_to_find"),
        ({"reading": "thawed"}, "H1.reading: got 'thawed', but default labels 'frozen' (label.reading)"),
        ({"path_length": 40}, "H1.path_length: got 40, expected one of default's checkpoints: 80"),
        ({"label_schedule": {"sweeps": 64, "warm_sweeps": 16}}, "H1.label_schedule: got {'sweeps': 64, 'warm_sweeps': 16}, but default labels with {sweeps: 2, warm_sweeps: 1}"),
        ({"test": "t"}, "H1.test: got 't', expected one of sign-flip, stratified-t"),
        ({"draws": 10}, "H1.draws: got 10, expected a whole number of sign flips from 1000 to 10000000"),
        ({"role": "main"}, "H1.role: got 'main', expected one of primary, secondary"),
        ({"seeds": [1, -1]}, "H1.seeds: got [1, -1], expected a list of seeds (whole numbers >= 0), each once"),
        ({"seeds": [1, 1]}, "H1.seeds: got [1, 1], expected a list of seeds (whole numbers >= 0), each once"),
        ({"scale": {"zurich-zh17": 1.0}}, "H1.scale: 'zurich-zh17': not a map of the study; expected some of own"),
        ({"scale": {"own": -1}}, "H1.scale.own: got -1, expected a number above 1e-09 and at most 1e+09"),
        # the hostile round of issue 64: each took a traceback, or was taken and gave a hypothesis that could never pass
        ({"scale": {"own": float("inf")}}, "H1.scale.own: got inf, expected a number above 1e-09"),
        ({"scale": {"own": 1e-320}}, "H1.scale.own: got 1e-320, expected a number above 1e-09"),
        ({"specification": ["default"]}, "H1.specification: got ['default'], expected one of default, clamp"),
        ({"against": ["human"]}, "H1.against: got ['human'], expected one of human for time_to_find"),
        ({"comparators": [{"a": 1}]}, "H1.comparators: got [{'a': 1}], expected a list of other walkers"),
        ({"reading": ["frozen"]}, "H1.reading: got ['frozen'], expected a labelling reading's name, e.g. frozen"),
        ({"path_length": 80.0}, "H1.path_length: got 80.0, expected one of default's checkpoints: 80"),
        ({"label_schedule": {"sweeps": 2.0, "warm_sweeps": 1}}, "H1.label_schedule: got {'sweeps': 2.0, 'warm_sweeps': 1}"),
        ({"claim": "two\nlines"}, "H1.claim: expected the claim in words, on one line"),
    ],
)
def test_a_bad_hypothesis_is_refused_in_one_line_naming_the_file_the_hypothesis_and_the_field(
    own_map, tmp_path, changes, message,
):
    line = _error(own_map, tmp_path, declared(own_map, tmp_path, **changes))
    assert line.startswith("Error: ") and f"tiny.yaml: hypotheses.{message}" in line, line


def test_a_family_level_out_of_range_and_hypotheses_without_specifications_are_refused(own_map, tmp_path):
    hypotheses = declared(own_map, tmp_path)
    assert "hypotheses.alpha: got 0.9, expected a one-sided family level" in _error(
        own_map, tmp_path, {**hypotheses, "alpha": 0.9}
    )
    config = hypotheses_yaml(own_map, tmp_path)
    text = yaml.safe_load(config.read_text())
    del text["specifications"], text["sweep"]
    config.write_text(yaml.safe_dump(text, sort_keys=False))
    result = sweep(config, tmp_path / "results")
    assert result.exit_code == 1 and "hypotheses: a hypothesis names a specification; declare specifications too" in result.stderr
    assert not (tmp_path / "results").exists()


def test_hypotheses_left_empty_are_refused_not_taken_for_none(own_map, tmp_path):
    line = _error(own_map, tmp_path, None)  # `hypotheses:` with nothing after it
    assert "tiny.yaml: hypotheses: expected alpha and a mapping of names to hypotheses" in line


def test_a_claim_with_a_table_s_bar_keeps_sweep_md_s_table_whole(own_map, tmp_path):
    from curiosity_cli.study.hypotheses import Declaration, hypothesis_lines

    config = hypotheses_yaml(own_map, tmp_path, {"alpha": 0.025, "H1": declared(own_map, tmp_path, claim="a | b")["H1"]})
    plan = planned(config)
    table, _ = hypothesis_table(plan, fabricated(plan, tmp_path / "results", datetime.now().astimezone()), None)
    row = next(line for line in hypothesis_lines(plan, table, Declaration(None, None, "x")) if line.startswith("| H1 |"))
    assert "| a \\| b |" in row and row.count(" | ") == 10


def test_a_declaration_in_a_subfolder_of_its_repository_is_dated_by_its_commit():
    """The study's own configs/confirmatory.yaml read "not committed" (git read the pathspec from configs/, where
    the config's path from the repository's top names nothing), so the confirmatory run was reported exploratory."""
    config = Path(__file__).resolve().parents[1] / "configs" / "confirmatory.yaml"
    if subprocess.run(["git", "-C", str(config.parent), "rev-parse"], capture_output=True).returncode:
        pytest.skip("not a git checkout")
    found = declaration(config)
    first = subprocess.run(
        ["git", "-C", str(config.parents[1]), "log", "--format=%H", "--", "configs/confirmatory.yaml"],
        capture_output=True, text=True, check=True,
    ).stdout.split()
    assert found.why is None and found.commit in first
