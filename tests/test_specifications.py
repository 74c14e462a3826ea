"""A study's declared specifications: planning, running and resuming, the curve against the mi.csv files, errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from scipy import stats
from small_maps import edit_yaml
from test_sweep import sweep, tiny_yaml

from curiosity_cli.config import CONFIG_DIR
from curiosity_cli.evaluate.comparisons import next_best_interval, next_best_null, ratio_interval
from curiosity_cli.evaluate.multiplicity import benjamini_hochberg, holm
from curiosity_cli.study.specifications import declared_specifications
from curiosity_cli.study.sweep import declared_sweeps, parse_sweeps, plan_sweep
from curiosity_cli.study.types import Specification

WALKERS = ["random-walk", "stochastic-coverage", "topic-perplexity"]
SPECIFICATIONS = {"default": {}, "clamp": {"explore.coverage": "clamp", "explore.min_d2": 0.5}}
FOLDERS = [f"specification-{s}_seed-{seed}" for s in SPECIFICATIONS for seed in (1, 2)]


def study_yaml(own_map: Path, folder: Path, specifications=SPECIFICATIONS) -> Path:
    """The tiny experiment as a study: 3 of the paper's walkers, seeds 1 and 2, two specifications;
    the map stands in for Montreal1, so the curve has the paper's ratio to compare."""
    config = tiny_yaml(own_map, folder)
    edit_yaml(own_map, stands_in_for="Montreal1")
    text = yaml.safe_load(config.read_text())
    text["explore"]["weight_functions"] = WALKERS
    text["sweep"] = {"seed": [1, 2]}
    text["specifications"] = specifications
    config.write_text(yaml.safe_dump(text, sort_keys=False))
    return config


def test_a_study_plans_each_specification_on_each_seed_named_by_them_alone(own_map, tmp_path):
    config = study_yaml(own_map, tmp_path)
    specifications = declared_specifications(config)
    assert specifications == (
        Specification("default", ()), Specification("clamp", ("explore.coverage=clamp", "explore.min_d2=0.5")),
    )
    plan = plan_sweep(config, parse_sweeps(declared_sweeps(config)), (), specifications)
    assert [c.name for c in plan.combinations] == FOLDERS
    assert [(c.config.explore.coverage, c.config.explore.min_d2, c.config.seed) for c in plan.combinations] == [
        ("literal", 0.25, 1), ("literal", 0.25, 2), ("clamp", 0.5, 1), ("clamp", 0.5, 2),
    ]
    assert plan.combinations[2].overrides == ("specification=clamp", "seed=1")
    assert plan.keys == ["specification", "seed"]
    # the command resumes the study from the config alone: the specifications are not --sweep options
    assert "--sweep seed=1,2" in plan.command() and "specification" not in plan.command()
    # reordered, or with another specification declared, the same specifications keep their folders
    reordered = {"others": {"explore.coverage": "others"}, "clamp": SPECIFICATIONS["clamp"], "default": {}}
    again = study_yaml(own_map, tmp_path, reordered)
    names = [c.name for c in plan_sweep(again, parse_sweeps(["seed=1,2"]), (), declared_specifications(again)).combinations]
    assert names == ["specification-others_seed-1", "specification-others_seed-2", *FOLDERS[2:], *FOLDERS[:2]]
    # without a sweep, a combination per specification
    alone = plan_sweep(config, (), (), specifications)
    assert [c.name for c in alone.combinations] == ["specification-default", "specification-clamp"]
    # a config without specifications declares none: readings.yaml runs as before
    assert declared_specifications(CONFIG_DIR / "readings.yaml") == ()


def _pooled(folder: Path, specification: str) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Both seeds' mi.csv and steering.csv of a specification, at 80 steps."""
    mi = pd.concat(pd.read_csv(folder / f"specification-{specification}_seed-{s}" / "mi.csv") for s in (1, 2))
    steering = pd.concat(pd.read_csv(folder / f"specification-{specification}_seed-{s}" / "steering.csv") for s in (1, 2))
    return mi[mi["path_length"] == 80], steering[steering["path_length"] == 80]


@pytest.mark.slow
def test_a_study_runs_leads_its_report_with_the_curve_that_its_mi_csv_files_give_and_resumes(own_map, tmp_path):
    config = study_yaml(own_map, tmp_path)
    text = yaml.safe_load(config.read_text())
    text["hypotheses"] = {"alpha": 0.025, "H1": {  # declared: SWEEP.md leads with it (tests/test_hypotheses.py)
        "claim": "sooner", "specification": "default", "comparators": ["random-walk", "stochastic-coverage"],
        "measure": "time_to_find", "reading": "frozen", "path_length": 80, "label_schedule": {"sweeps": 2, "warm_sweeps": 1},
        "seeds": [1, 2], "scale": {"own": 10.0},
    }}
    config.write_text(yaml.safe_dump(text, sort_keys=False))
    results = tmp_path / "results"
    result = sweep(config, results)
    assert result.exit_code == 0, result.output
    assert "4 combinations (2 specifications x 2 seeds), in" in result.stderr
    folder = results / "tiny-sweep"
    assert sorted(p.name for p in folder.iterdir() if p.is_dir()) == sorted(FOLDERS)
    plan = yaml.safe_load((folder / "sweep.yaml").read_text())
    assert plan["specifications"] == {"default": [], "clamp": ["explore.coverage=clamp", "explore.min_d2=0.5"]}

    report = (folder / "SWEEP.md").read_text()
    assert report.startswith("# Specification curve of `tiny`: 2 specifications x 2 seeds (4 combinations)\n")
    assert report.index("## Declared hypotheses (hypotheses.csv)") < report.index("## Specification curve")
    hypotheses = pd.read_csv(folder / "hypotheses.csv", dtype={"seeds": str})
    mi, _ = _pooled(folder, "default")
    times = mi.pivot_table(index=["replicate", "restart"], columns="weight_function", values="time_to_find")
    for comparator in ("random-walk", "stochastic-coverage"):
        row = hypotheses.query(f"scope == 'pooled' and comparator == '{comparator}'").iloc[0]
        lead = times[comparator] - times["topic-perplexity"]
        assert row["pairs"] == 4 and row["raw_difference"] == pytest.approx(lead.mean())
    head = hypotheses[hypotheses["comparator"].isna() & (hypotheses["scope"] == "pooled")].iloc[0]
    assert head["decision"] in ("confirmed", "not confirmed") and head["status"].startswith("exploratory: no --record")
    assert f"| H1 | sooner | primary | `default` | time to first find (human) at 80 | 1 2 | 4 |" in report
    human = report.index("![specification curve, MI against human labels](specification-curve.png)")
    batch = report.index("![specification curve, MI against Z_b](specification-curve-batch.png)")
    assert report.index("## Specification curve") < human < report.index("### Against Z_b") < batch < report.index("## Headlines")
    assert "## Sensitivity" not in report, "the curve's table has its rows and numbers"
    for suffix in (".png", ".pdf"):
        assert (folder / f"specification-curve{suffix}").stat().st_size > 1000
        assert (folder / f"specification-curve-batch{suffix}").stat().st_size > 1000
    batch_table = pd.read_csv(folder / "specifications-batch.csv", dtype={"seeds": str})
    assert (batch_table["against"] == "batch").all() and len(batch_table) == 2
    table = pd.read_csv(folder / "specifications.csv", dtype={"seeds": str})
    assert (table["against"] == "human").all()
    assert sorted(table["specification"]) == ["clamp", "default"] and (table["dataset"] == "own").all()
    assert table["ratio"].is_monotonic_increasing, "sorted by ratio, as the figure"

    for row in table.to_dict("records"):
        mi, steering = _pooled(folder, row["specification"])
        means = mi.groupby("weight_function")["mi_human"].mean()
        others = means.drop("topic-perplexity")
        next_best = others.idxmax()
        assert row["next_best"] == next_best and row["seeds"] == "1 2"
        assert row["ratio"] == pytest.approx(means["topic-perplexity"] / others.max())
        # paired by seed and restart, never across seeds: 2 restarts x 2 seeds
        pairs = mi.pivot_table(index=["replicate", "restart"], columns="weight_function", values="mi_human")
        assert row["pairs"] == len(pairs) == 4
        assert row["p_value"] == pytest.approx(stats.wilcoxon(pairs["topic-perplexity"], pairs[next_best]).pvalue)
        ours, rest = pairs["topic-perplexity"].to_numpy(), pairs.drop(columns="topic-perplexity").to_numpy()
        low, high = next_best_interval(ours, rest)
        assert (row["ratio_ci_low"], row["ratio_ci_high"]) == pytest.approx((low, high))
        null = next_best_null(ours, rest)
        assert (row["null_median"], row["null_low"], row["null_high"], row["null_p"]) == pytest.approx(
            (null.median, null.low, null.high, null.p_value)
        )
        strict = next_best_null(ours, rest, exchangeable=pairs.columns.drop("topic-perplexity") != "random-walk")
        assert (row["null_no_rw_median"], row["null_no_rw_p"]) == pytest.approx((strict.median, strict.p_value))
        # the lead's p: the largest Wilcoxon p against each walker, 1 where a walker's mean is not below
        p_each = max(stats.wilcoxon(ours, pairs[w]).pvalue for w in others.index)
        assert row["p_each"] == pytest.approx(p_each if (means["topic-perplexity"] > others).all() else 1.0)
        assert row["paper_ratio"] == 1.51 and row["paper_inside"] == (low <= 1.51 <= high)
        for walker in ("random-walk", "stochastic-coverage"):  # each walker compared alone, by its own pairs
            assert row[f"ratio_{walker}"] == pytest.approx(means["topic-perplexity"] / means[walker])
            assert (row[f"ratio_{walker}_low"], row[f"ratio_{walker}_high"]) == pytest.approx(
                ratio_interval(ours, pairs[walker].to_numpy()), nan_ok=True
            )
            assert row[f"p_{walker}"] == pytest.approx(stats.wilcoxon(ours, pairs[walker]).pvalue)
        assert pd.isna(row["ratio_word-perplexity"]), "a paper walker the study did not run"
        # 4 pairs cannot reach p < 0.05 with Wilcoxon's test: no specification leads
        assert not row["beats_all"]
        walker = mi.groupby("weight_function")["distinct_cells"].mean()
        assert row["distinct_topic-perplexity"] == pytest.approx(walker["topic-perplexity"])
        assert row["distinct_stochastic-coverage"] == pytest.approx(walker["stochastic-coverage"])
        ours = steering[steering["weight_function"] == "topic-perplexity"]["steering"]
        assert len(ours) == 4 and row["steering_topic-perplexity"] == pytest.approx(ours.mean())
        mechanism = pd.concat(
            pd.read_csv(folder / f"specification-{row['specification']}_seed-{s}" / "mechanism.csv") for s in (1, 2)
        ).query("path_length == 80 and weight_function == 'topic-perplexity'")
        assert len(mechanism) == 4
        for measure in ("opportunity", "gain", "infinite_share"):
            assert row[measure] == pytest.approx(mechanism[measure].mean(), nan_ok=True)
        # M1 pooled over the runs' pairs: every run's wins over every run's pairs, not the mean of the runs' AUCs
        scored = mechanism[mechanism["pairs"] > 0]
        pooled_auc = (scored["auc"] * scored["pairs"]).sum() / scored["pairs"].sum() if len(scored) else np.nan
        assert row["auc"] == pytest.approx(pooled_auc, nan_ok=True)
        assert (
            f"| `{row['specification']}` | own | {row['ratio_random-walk']:.2f} [" in report
            and f"| {row['ratio']:.2f} [{row['ratio_ci_low']:.2f}, {row['ratio_ci_high']:.2f}] ({next_best}) | "
            f"{row['null_no_rw_median']:.2f} [" in report
        )
    # corrected over the curve's two points
    assert table["p_each_holm"].to_numpy() == pytest.approx(holm(table["p_each"].to_numpy()))
    assert table["null_no_rw_p_bh"].to_numpy() == pytest.approx(benjamini_hochberg(table["null_no_rw_p"].to_numpy()))
    # the study ran no word perplexity: no point has every paper walker, so no joint test
    assert table["p_each_wy"].isna().all()
    assert "No point has every walker's runs: no joint test." in report
    assert "no Westfall-Young correction (no point has every walker's runs)" in report
    inside = int(table["paper_inside"].sum())
    assert "leads every other walker (a higher mean MI at 80 steps" in report and "in **0 of 2** points" in report
    assert "Uncorrected, which is exploratory, in 0 of 2 (0 of 2 on own)" in report
    assert f"The paper's ratio lies inside the 95 % interval in {inside} of 2 on own (Montreal1: 1.51)" in report
    assert "Against its null reference (topic perplexity exchangeable with the walkers that could equal it)" in report
    assert report.index("## Does surprise point at what is new?") < report.index("### Against Z_b")
    assert (folder / "mechanism.png").stat().st_size > 1000

    finished = sorted(folder.glob("*/runs/*/*/restart-*/*")) + sorted(folder.glob("*/labels/*/*/*.npz"))
    assert len(finished) > 4 * 3 * 2
    mtimes = {path: path.stat().st_mtime_ns for path in finished}
    first = (folder / "specifications.csv").read_bytes()
    (folder / "specifications.csv").unlink()
    # every measure beside MI under each specification: the same pairs, the same decision
    found = pd.read_csv(folder / "specifications-found.csv", dtype={"seeds": str})
    assert set(found["measure"]) == {
        "nmi", "ami", "classes_found", "mean_recall", "time_to_find", "mi_visited", "mi_unvisited", "heldout",
        "heldout_unvisited",
    }
    assert len(found) == 18
    for row in found.query("measure == 'mean_recall'").to_dict("records"):
        mi, _ = _pooled(folder, row["specification"])
        pairs = mi.pivot_table(index=["replicate", "restart"], columns="weight_function", values="mean_recall")
        difference = pairs["topic-perplexity"] - pairs["random-walk"]
        assert row["difference_random-walk"] == pytest.approx(difference.mean())
        assert row["closest_difference"] == pytest.approx(
            min(row["difference_random-walk"], row["difference_stochastic-coverage"])
        )
        assert not row["beats_all"]  # 4 pairs
    assert "### What each walker found" in report and "| mean recall | 2 | 0 | 0 |" in report
    assert not (folder / "specification-curve-mean_recall.png").exists()

    # declared in the other order: the same folders, nothing redone, the same curve; and one measure's curve
    study_yaml(own_map, tmp_path, {"clamp": SPECIFICATIONS["clamp"], "default": {}})
    result = sweep(config, results, "--measure", "mean_recall")
    assert result.exit_code == 0, result.output
    assert result.stderr.count("exploring (6 runs already done)") == 4
    assert {path: path.stat().st_mtime_ns for path in finished} == mtimes
    assert (folder / "specifications.csv").read_bytes() == first
    assert "![specification curve, mean recall](specification-curve-mean_recall.png)" in (folder / "SWEEP.md").read_text()
    assert (folder / "specification-curve-mean_recall.png").stat().st_size > 1000


@pytest.mark.parametrize(
    ("specifications", "options", "message"),
    [
        ({"clamp": {"explore.coverage": "clmap"}}, (), "tiny.yaml: specifications.clamp.explore.coverage: got 'clmap'"),
        ({"x": {"explore.nope": 1}}, (), "tiny.yaml: specifications.x.explore.nope: "),
        ({"x": {"model.topics": 0}}, (), "tiny.yaml: specifications.x.model.topics: got 0"),
        ({"x": {"seed": 3}}, (), "tiny.yaml: specifications.x.seed: seed is also swept; give it in one of them"),
        ({"x": {"explore.coverage": "clamp"}}, ("--set", "explore.coverage=others"),
         "tiny.yaml: specifications.x.explore.coverage: explore.coverage is also given with --set"),
        ({"x": {"explore": {"coverage": "clamp"}, "explore.coverage": "others"}}, (),
         "tiny.yaml: specifications.x.explore.coverage: explore is set too; give each key once"),
        ({"x": {"name": "y"}}, (), "tiny.yaml: specifications.x.name: a specification cannot rename"),
        ({"a b": {}}, (), "tiny.yaml: specifications: 'a b': expected a name of 1 to 80 letters"),
        ({"x": [1]}, (), "tiny.yaml: specifications.x: expected a mapping of dotted keys to values"),
        ([1, 2], (), "tiny.yaml: specifications: expected a mapping of names to overrides"),
    ],
)
def test_a_bad_specification_is_refused_in_one_line_before_anything_is_written(own_map, tmp_path, specifications, options, message):
    config = study_yaml(own_map, tmp_path, {"default": {}, **specifications} if isinstance(specifications, dict) else specifications)
    result = sweep(config, tmp_path / "results", *options)
    assert result.exit_code == 1, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("Error: ") and message in lines[0], result.stderr
    assert not (tmp_path / "results").exists()


def test_only_the_study_config_itself_declares_specifications(own_map, tmp_path):
    base = study_yaml(own_map, tmp_path)
    edit_yaml(base, sweep=...)
    child = tmp_path / "child.yaml"
    child.write_text(f"base: {base}\nname: child\n")
    result = sweep(child, tmp_path / "results")
    assert result.exit_code == 1
    assert "tiny.yaml: specifications: only the experiment config itself may declare specifications" in result.stderr


def test_a_gpu_that_is_not_there_is_refused_before_anything_is_explored(own_map, tmp_path):
    """Issue 44: label.device=cuda in a specification, or given with --set, was checked only after exploring."""
    from curiosity_cli.topics.devices import cuda_missing

    if cuda_missing() is None:
        pytest.skip("this machine has a CUDA GPU")
    config = study_yaml(own_map, tmp_path, {"default": {}, "gpu": {"label.device": "cuda"}})
    result = sweep(config, tmp_path / "results")
    assert result.exit_code == 1 and "label.device: cuda, but " in result.stderr
    assert not (tmp_path / "results").exists() or not list((tmp_path / "results").rglob("run.json")), "nothing explored"
    from typer.testing import CliRunner

    from curiosity_cli.cli import app

    single = CliRunner().invoke(app, [
        "reproduce", str(tiny_yaml(own_map, tmp_path)), "--set", "label.device=cuda", "--jobs", "1",
        "--results-dir", str(tmp_path / "single"), "--cache-dir", str(tmp_path / "cache"),
    ])
    assert single.exit_code == 1 and "label.device: cuda, but " in single.stderr
    assert not list((tmp_path / "single").rglob("run.json")), "nothing explored"


def test_config_show_checks_every_experiment_of_a_study_and_says_what_reproduce_runs(own_map, tmp_path):
    from typer.testing import CliRunner

    from curiosity_cli.cli import app

    config = study_yaml(own_map, tmp_path)
    shown = CliRunner().invoke(app, ["config", "show", str(config)])
    assert shown.exit_code == 0, shown.output
    assert shown.stdout.splitlines()[-4:] == [
        "# `curiosity reproduce` runs 4 experiments (2 specifications x 2 seeds): the config above with the overrides "
        "of each, as checked here",
        "#   sweep: seed = 1, 2",
        "#   specifications: default: (none: the config as it is)",
        "#   specifications: clamp: explore.coverage=clamp, explore.min_d2=0.5",
    ]
    # a bad specification or sweep value fails config show as it fails reproduce
    edit_yaml(config, specifications={"x": {"model.topics": 1}})
    bad = CliRunner().invoke(app, ["config", "show", str(config)])
    assert bad.exit_code == 1 and bad.stderr.startswith(f"Error: {config}: specifications.x.model.topics: got 1")
    edit_yaml(config, specifications=..., sweep={"seed": [0, -5]})
    bad = CliRunner().invoke(app, ["config", "show", str(config)])
    assert bad.exit_code == 1 and bad.stderr.startswith(f"Error: {config}: sweep.seed: got -5 (int)")


def test_a_measure_curve_is_only_for_a_study_of_a_measure_there_is(own_map, tmp_path):
    from test_sweep import runner

    from curiosity_cli.cli import app

    config = study_yaml(own_map, tmp_path)
    unknown = sweep(config, tmp_path / "results", "--measure", "auc")
    assert unknown.exit_code == 2 and "--measure: got 'auc', expected one of mi, nmi, ami, classes_found, mean_recall, " in unknown.output
    (tmp_path / "plain").mkdir()
    plain = tiny_yaml(own_map, tmp_path / "plain")
    single = runner.invoke(app, ["reproduce", str(plain), "--measure", "nmi", "--results-dir", str(tmp_path / "r")])
    assert single.exit_code == 2 and "--measure: draws a study's specification curve" in single.output
    swept = sweep(plain, tmp_path / "r", "--sweep", "seed=1,2", "--measure", "nmi")
    assert swept.exit_code == 2 and "this config declares no specifications" in swept.output
    assert not (tmp_path / "results").exists() and not (tmp_path / "r").exists()
