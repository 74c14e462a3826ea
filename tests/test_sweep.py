"""``curiosity reproduce --sweep``: parsing, naming, validation first, real sweeps that resume."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
import yaml
from small_maps import edit_yaml, tiny_yaml
from typer.testing import CliRunner

from curiosity_cli.cli import app
from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.errors import ConfigError
from curiosity_cli.study.sweep import combination_name, combinations, parse_sweeps, plan_sweep, split_values
from curiosity_cli.study.types import SweepAxis, SweepSyntaxError

runner = CliRunner()


def sweep(config: Path, results: Path, *options: str):
    common = ["--jobs", "1", "--cache-dir", str(results / "cache"), "--results-dir", str(results)]
    return runner.invoke(app, ["reproduce", str(config), *options, *common])


# --------------------------------------------------------------------------- parsing and names


def test_combinations_are_the_product_with_the_first_option_slowest():
    axes = parse_sweeps(["model.topics=16,32,64", "explore.restarts=20", "seed= 0 , 1"])
    assert axes[2] == SweepAxis("seed", ("0", "1"))
    assert combinations(axes) == [
        (f"model.topics={k}", "explore.restarts=20", f"seed={s}") for k in (16, 32, 64) for s in (0, 1)
    ]


def test_values_split_on_commas_outside_brackets():
    assert split_values("[a,b],[c, d],e") == ["[a,b]", "[c, d]", "e"]
    assert split_values("{a: 1, b: [2, 3]},null") == ["{a: 1, b: [2, 3]}", "null"]
    (axis,) = parse_sweeps(["explore.checkpoints=[10,20],[10, 80]"])
    assert axis.values == ("[10,20]", "[10, 80]")


@pytest.mark.parametrize(
    ("options", "sets", "message"),
    [
        (["model.topics"], [], "'model.topics': expected KEY=V1,V2,..., e.g. model.topics=16,32"),
        (["=16,32"], [], "'=16,32': expected KEY=V1,V2"),
        (["model.topics="], [], "'model.topics=': no values"),
        (["model.topics=16,,32"], [], "'model.topics=16,,32': an empty value; write null for null"),
        (["model.topics=16", "model.topics=32"], [], "'model.topics=32': model.topics is already swept"),
        (["model=16", "model.topics=32"], [], "'model.topics=32': model is already swept"),
        (["model.topics=16"], ["model.topics=8"], "model.topics is also among the overrides"),
        (["datasets=[a,b"], [], "'[a,b': a bracket is not closed"),
        (["datasets=a],b"], [], "a closing ']' without its opening bracket"),
        (["model.topics=16,32,16"], [], "'16' is the same value as '16'; give each value once"),
        (["datasets=[a,b],[a, b]"], [], "'[a, b]' is the same value as '[a,b]'"),
        (["name=a,b"], [], "name cannot be swept"),
    ],
)
def test_a_malformed_sweep_is_a_usage_error(options, sets, message, tmp_path):
    with pytest.raises(SweepSyntaxError, match=None) as caught:
        parse_sweeps(options, sets)
    assert message in str(caught.value)
    args = [arg for text in options for arg in ("--sweep", text)] + [arg for text in sets for arg in ("--set", text)]
    result = runner.invoke(app, ["reproduce", "--quick", *args, "--results-dir", str(tmp_path / "results")])
    assert result.exit_code == 2
    flat = " ".join(result.output.replace("│", " ").split())
    assert "Invalid value for --sweep" in flat and " ".join(message.split()) in flat
    assert not (tmp_path / "results").exists()


def test_names_are_readable_valid_experiment_names_and_never_shared():
    assert combination_name(["model.topics=16", "explore.restarts=20"]) == "model.topics-16_explore.restarts-20"
    assert combination_name(["label.warm_sweeps=null"]) == "label.warm_sweeps-null"
    bracketed = combination_name(["datasets=[zurich-zh17]"])
    assert bracketed.startswith("datasets-zurich-zh17-") and len(bracketed) == len("datasets-zurich-zh17-") + 6
    # the hash is of the parsed value: spelled differently, the same list names the same folder
    assert combination_name(["datasets=[a, b]"]) == combination_name(["datasets=[a,b]"])
    names = {combination_name([f"datasets={v}"]) for v in ("[a,b]", "[a/b]", "[a b]", "a-b", "[a-b]")}
    assert len(names) == 5
    long = combination_name([f"datasets=[{'x' * 80}]", f"words.vocabulary_dir={'y' * 80}"])
    assert len(long) <= 120
    for name in (bracketed, long, *names):
        assert load_config(CONFIG_DIR / "quick.yaml", [f"name={name}"]).name == name


def test_every_combination_is_loaded_with_its_values_and_named_by_them():
    planned = plan_sweep(CONFIG_DIR / "quick.yaml", parse_sweeps(["model.topics=16,32", "seed=3"]), ["explore.restarts=2"])
    assert planned.name == "quick" and planned.folder(Path("results")) == Path("results/quick-sweep")
    assert [c.name for c in planned.combinations] == ["model.topics-16_seed-3", "model.topics-32_seed-3"]
    assert [c.label for c in planned.combinations] == ["model.topics=16, seed=3", "model.topics=32, seed=3"]
    assert [(c.config.model.topics, c.config.seed, c.config.explore.restarts) for c in planned.combinations] == [
        (16, 3, 2), (32, 3, 2),
    ]
    assert planned.combinations[0].config.name == "model.topics-16_seed-3"
    assert planned.command().endswith("--set explore.restarts=2 --sweep model.topics=16,32 --sweep seed=3")


def test_a_bad_swept_value_is_refused_like_an_override_naming_the_sweeps():
    axes = parse_sweeps(["model.topics=16,300"])
    with pytest.raises(ConfigError, match=r"^sweeps: model.topics: got 300 \(int\), expected an integer >= 2 and <= 127$") as bad:
        plan_sweep(CONFIG_DIR / "quick.yaml", axes)
    assert bad.value.parameter == "sweeps"
    with pytest.raises(ConfigError, match=r"^sweeps: model.topicz: unknown key; expected one of topics,"):
        plan_sweep(CONFIG_DIR / "quick.yaml", parse_sweeps(["model.topicz=16"]))
    # a rule tying keys together names the key it checks, and the combination that broke it
    with pytest.raises(ConfigError, match=r"explore.checkpoints: .* \(with the sweep's explore.path_length=50\)$"):
        plan_sweep(CONFIG_DIR / "quick.yaml", parse_sweeps(["explore.path_length=160,50"]))


# --------------------------------------------------------------------------- through the CLI


def test_a_bad_value_anywhere_fails_before_any_folder_is_written(own_map, tmp_path):
    config = tiny_yaml(own_map, tmp_path)
    results = tmp_path / "results"
    result = sweep(config, results, "--sweep", "model.topics=4,6", "--sweep", "explore.restarts=2,0")
    assert result.exit_code == 1
    assert result.stderr.strip() == "Error: --sweep: explore.restarts: got 0 (int), expected an integer >= 1 and <= 10000"
    assert not results.exists()
    result = runner.invoke(app, ["reproduce", "--quick", "--sweep", "model.topics=200", "--results-dir", str(results)])
    assert result.exit_code == 1 and result.stderr.startswith("Error: --sweep: model.topics: got 200")
    assert not results.exists()
    # a value of the config's own sweep: the file is named, not --sweep, which was not given
    edit_yaml(config, sweep={"seed": [0, -5]})
    result = sweep(config, results)
    assert result.exit_code == 1 and result.stderr.startswith(f"Error: {config}: sweep.seed: got -5 (int), expected")
    # given with --sweep, the same key is --sweep's
    result = sweep(config, results, "--sweep", "seed=-6")
    assert result.exit_code == 1 and result.stderr.startswith("Error: --sweep: seed: got -6 (int)")
    assert not results.exists()


@pytest.mark.slow
def test_a_sweep_writes_a_folder_per_combination_and_one_report_and_resumes(own_map, tmp_path):
    config = tiny_yaml(own_map, tmp_path)
    results = tmp_path / "results"
    options = ("--sweep", "model.topics=4,6", "--sweep", "seed=1")
    result = sweep(config, results, *options)
    assert result.exit_code == 0, result.output
    folder = results / "tiny-sweep"
    assert result.stdout.strip() == f"wrote {folder / 'SWEEP.md'}"
    assert "combination 1/2: model.topics=4, seed=1" in result.stderr
    assert "combination 2/2: model.topics=6, seed=1" in result.stderr
    names = ["model.topics-4_seed-1", "model.topics-6_seed-1"]
    assert sorted(p.name for p in folder.iterdir() if p.is_dir()) == names
    for name, topics in zip(names, (4, 6)):
        saved = yaml.safe_load((folder / name / "config.yaml").read_text())
        assert (saved["name"], saved["model"]["topics"], saved["seed"]) == (name, topics, 1)
        assert (folder / name / "REPORT.md").is_file()

    plan = yaml.safe_load((folder / "sweep.yaml").read_text())
    assert plan["sweep"] == {"model.topics": ["4", "6"], "seed": ["1"]}
    assert [c["folder"] for c in plan["combinations"]] == names
    assert plan["combinations"][1]["overrides"] == ["model.topics=6", "seed=1"]

    report = (folder / "SWEEP.md").read_text()
    assert report.startswith("# Parameter sweep of `tiny`: 2 combinations")
    for name, label in zip(names, ("model.topics=4, seed=1", "model.topics=6, seed=1")):
        assert f"## {names.index(name) + 1}. {label}" in report
        assert f"[{name}/REPORT.md]({name}/REPORT.md)" in report
    table = pd.read_csv(folder / "sweep.csv")
    assert list(table.columns) == [
        "combination", "folder", "model.topics", "seed", "dataset", "topic_perplexity", "next_best", "next_best_mi",
        "ratio", "p_value", "pairs", "paper_map", "paper_ratio", "ratio_ci_low", "ratio_ci_high", "detectable_ratio",
        "pairs_for_lead",
    ]
    assert table["model.topics"].tolist() == [4, 6] and table["dataset"].tolist() == ["own", "own"]
    assert (table["next_best"] == "random-walk").all() and (table["pairs"] == 2).all()
    for name, row in zip(names, table.itertuples()):
        headline = pd.read_csv(folder / name / "headline.csv")
        assert row.ratio == pytest.approx(headline["ratio"].item())
        assert f"| own | {headline['topic_perplexity'].item():.3f} | random-walk |" in report

    finished = sorted(folder.glob("*/runs/*/*/restart-*/*")) + sorted(folder.glob("*/labels/*/*/*.npz"))
    assert len(finished) > 2 * 4 * 2
    mtimes = {path: path.stat().st_mtime_ns for path in finished}
    (folder / "SWEEP.md").unlink()
    result = sweep(config, results, *options)
    assert result.exit_code == 0, result.output
    assert result.stderr.count("exploring (4 runs already done)") == 2
    assert {path: path.stat().st_mtime_ns for path in finished} == mtimes
    assert (folder / "SWEEP.md").read_text().startswith("# Parameter sweep of `tiny`")


def test_a_failing_combination_does_not_stop_the_others(own_map, tmp_path):
    config = tiny_yaml(own_map, tmp_path)
    results = tmp_path / "results"
    # 192 cells: 200 restarts have no start cells; the config is valid, the grid is not
    result = sweep(config, results, "--sweep", "explore.restarts=200,2")
    assert result.exit_code == 1
    assert "Error: 1 of 2 combinations failed" in result.stderr
    assert "combination 1 (explore.restarts=200): explore.restarts: got 200, but own has only 192 cells" in result.stderr
    folder = results / "tiny-sweep"
    assert (folder / "explore.restarts-2" / "REPORT.md").is_file()
    report = (folder / "SWEEP.md").read_text()
    assert "## 1. explore.restarts=200\n\nFailed: explore.restarts: got 200" in report
    assert "[explore.restarts-2/REPORT.md](explore.restarts-2/REPORT.md)" in report
    assert pd.read_csv(folder / "sweep.csv")["explore.restarts"].tolist() == [2]


@pytest.mark.slow
def test_a_readings_sweep_declared_in_its_config_pools_the_seeds_into_the_sensitivity_table_and_resumes(own_map, tmp_path):
    config = tiny_yaml(own_map, tmp_path)
    text = yaml.safe_load(config.read_text())
    text["explore"]["weight_functions"] = ["stochastic-coverage", "topic-perplexity"]
    text["sweep"] = {"explore.coverage": ["literal", "clamp"], "seed": [1, 2]}
    config.write_text(yaml.safe_dump(text, sort_keys=False))
    results = tmp_path / "results"
    result = sweep(config, results)
    assert result.exit_code == 0, result.output
    assert "4 combinations" in result.stderr
    folder = results / "tiny-sweep"
    report = (folder / "SWEEP.md").read_text()
    assert report.index("## Sensitivity (seeds pooled)") < report.index("## Headlines")
    pooled = pd.read_csv(folder / "sensitivity.csv", dtype={"seeds": str})
    assert pooled["explore.coverage"].tolist() == ["literal", "clamp"]
    assert (pooled["seeds"] == "1 2").all() and (pooled["pairs"] == 4).all(), "2 restarts of each of 2 seeds"
    for reading, row in zip(("literal", "clamp"), pooled.to_dict("records")):
        # the pooled ratio is over both seeds' runs: the mean of topic perplexity's 4 runs over the other's
        mi = pd.concat(
            pd.read_csv(folder / f"explore.coverage-{reading}_seed-{seed}" / "mi.csv") for seed in (1, 2)
        )
        means = mi[mi["path_length"] == 80].groupby("weight_function")["mi_human"].mean()
        assert row["ratio"] == pytest.approx(means["topic-perplexity"] / means["stochastic-coverage"])
        assert row["ratio_ci_low"] <= row["ratio"] <= row["ratio_ci_high"]
        distinct = mi[(mi["path_length"] == 80) & (mi["weight_function"] == "stochastic-coverage")]["distinct_cells"]
        assert row["distinct_stochastic-coverage"] == pytest.approx(distinct.mean())
        assert f"| `{reading}` | own | 1 2 | 4 | {row['ratio']:.2f} [" in report
    # the literal reading never steps back while a neighbour is open: more distinct cells than the clamp
    assert pooled["distinct_stochastic-coverage"][0] > pooled["distinct_stochastic-coverage"][1]
    assert "Distinct cells seen in 80 steps" in report

    finished = sorted(folder.glob("*/runs/*/*/restart-*/*")) + sorted(folder.glob("*/labels/*/*/*.npz"))
    mtimes = {path: path.stat().st_mtime_ns for path in finished}
    (folder / "sensitivity.csv").unlink()
    result = sweep(config, results, "--sweep", "explore.coverage=literal")  # replaces the declared values
    assert result.exit_code == 0, result.output
    assert "2 combinations" in result.stderr and result.stderr.count("exploring (4 runs already done)") == 2
    assert {path: path.stat().st_mtime_ns for path in finished} == mtimes
    assert pd.read_csv(folder / "sensitivity.csv")["explore.coverage"].tolist() == ["literal"]


def test_a_declared_sweep_that_is_not_a_mapping_of_lists_is_refused_naming_the_file(own_map, tmp_path):
    config = tiny_yaml(own_map, tmp_path)
    text = yaml.safe_load(config.read_text())
    for declared, message in (
        ([1, 2], "tiny.yaml: sweep: expected a mapping of dotted keys to lists of values"),
        ({"seed": 3}, "tiny.yaml: sweep.seed: expected a list of one or more values"),
    ):
        config.write_text(yaml.safe_dump({**text, "sweep": declared}, sort_keys=False))
        result = sweep(config, tmp_path / "results")
        assert result.exit_code == 1 and message in result.stderr, result.output
    assert not (tmp_path / "results").exists()


def test_a_declared_sweep_reads_as_sweep_options_and_the_command_line_replaces_a_key_in_place(tmp_path):
    from curiosity_cli.study.sweep import declared_sweeps, merge_sweeps

    config = tmp_path / "exp.yaml"
    config.write_text(
        "base: paper.yaml\nname: exp\nseed: 0\ndatasets: [zurich-zh17]\nsweep:\n  explore.coverage: [literal, clamp]\n  datasets: [[zurich-zh17], [aerial-mosaic]]\n"
        "  seed: [0, 1]\n  name_like: ['null', 'a b']\n"
    )
    declared = declared_sweeps(config)
    assert declared == [
        "explore.coverage=literal,clamp", 'datasets=["zurich-zh17"],["aerial-mosaic"]', "seed=0,1",
        'name_like="null",a b',
    ]
    # each value reads back as the YAML value it was: the string 'null' stays a string
    plan = plan_sweep(config, parse_sweeps(declared[:3]))
    assert plan.combinations[0].config.datasets == ("zurich-zh17",) and plan.combinations[-1].config.seed == 1
    assert parse_sweeps(declared)[3].values == ('"null"', "a b")
    # a key given on the command line takes the declared key's place, so combinations keep their folders
    merged = merge_sweeps(declared[:3], ["seed=2", "model.topics=8"])
    assert merged == [declared[0], declared[1], "seed=2", "model.topics=8"]
    assert merge_sweeps([], ["seed=1"]) == ["seed=1"] and declared_sweeps(CONFIG_DIR / "quick.yaml") == []


def test_a_swept_key_that_nothing_reads_under_the_other_settings_is_refused_before_anything_runs(tmp_path):
    # issue 44: the grid step with the keypoints detector gave two identical treatments reported as two; issue 63:
    # a step the keypoints detector does not read is refused by the config itself, as a single experiment's is
    with pytest.raises(ConfigError, match=(
        r"^sweeps: words.orb_grid_step: got 2, but words.orb_detector keypoints reads no grid step; expected 1"
    )):
        plan_sweep(CONFIG_DIR / "quick.yaml", parse_sweeps(["words.orb_grid_step=1,2"]))
    # a floor on d^2 the reading does not read: the same experiment twice
    with pytest.raises(ConfigError, match=(
        r"^sweeps: explore.min_d2=0.25 and explore.min_d2=0.5 make the same experiment: "
        r"explore.min_d2 changes nothing under the other settings; sweep only values that are read$"
    )):
        plan_sweep(CONFIG_DIR / "quick.yaml", parse_sweeps(["explore.min_d2=0.25,0.5"]), ["explore.coverage=others"])
    # under the grid detector it is read: two experiments
    sweep = plan_sweep(
        CONFIG_DIR / "quick.yaml", parse_sweeps(["words.orb_grid_step=1,2"]),
        ["words.orb_detector=grid", "words.orb_per_tile=null", "words.orb_max_features=null"],
    )
    assert len(sweep.combinations) == 2
    assert not list(tmp_path.iterdir()), "nothing written"
