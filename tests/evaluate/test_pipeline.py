"""label, evaluate and reproduce end to end on a small real map, and their bad inputs."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pandas as pd
import pytest
from experiments import small_experiment
from small_maps import grid_config, grid_yaml
from typer.testing import CliRunner

from curiosity_cli.cli import app
from curiosity_cli.label.stage import LabelError, label_experiment
from curiosity_cli.evaluate.stage import evaluate_experiment
from curiosity_cli.evaluate.information import contingency, mutual_information
from curiosity_cli.evaluate.tables import EvaluationError
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.experiment.recipes import Recipe
from curiosity_cli.explore.grid import run_grid
from curiosity_cli.explore.runs import read_run
from curiosity_cli.label.sampling import map_chains, pixel_words
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.words.store import load_store

runner = CliRunner()


@pytest.mark.slow
def test_label_and_evaluate_write_every_table(own_map, tmp_path):
    config, folder = small_experiment(own_map, tmp_path)
    done = label_experiment(config, tmp_path / config.name, cache_dir=tmp_path / "cache", jobs=1)
    assert (done["labelled"], done["skipped"], done["batch_reused"]) == (8, 0, 0)
    with np.load(ExperimentFolder(folder).batch("own")) as npz:
        assert npz["labels"].shape == (96, 128) and npz["log_likelihood"].shape == (8,)
    with np.load(ExperimentFolder(folder).label_file("own", "random-walk", 1)) as npz:
        assert npz["lengths"].tolist() == [5, 12]
        # every pixel counted once per checkpoint, against 2 human classes and K = 8 batch topics
        assert npz["human"].shape == (2, 8, 2) and (npz["human"].sum(axis=(1, 2)) == 96 * 128).all()
        assert npz["batch"].shape == (2, 8, 8) and (npz["batch"].sum(axis=(1, 2)) == 96 * 128).all()
    with np.load(ExperimentFolder(folder).example("own", "topic-perplexity", 0, 12)) as npz:
        assert npz["labels"].shape == (96, 128)

    again = label_experiment(config, tmp_path / config.name, cache_dir=tmp_path / "cache", jobs=1)
    assert (again["labelled"], again["skipped"], again["batch_reused"]) == (0, 8, 1)

    evaluation = evaluate_experiment(folder)
    mi = pd.read_csv(folder / "mi.csv")
    assert list(mi.columns) == [
        "dataset", "weight_function", "restart", "path_length", "mi_human", "mi_batch", "nmi_human", "nmi_batch",
        "ami_human", "ami_batch", "topics_used", "classes_found", "classes", "mean_recall", "time_to_find",
        "mi_visited_human", "mi_visited_batch", "mi_unvisited_human", "mi_unvisited_batch", "heldout", "heldout_unvisited",
        "seed", "replicate",
        "placed_mi_human", "placed_mi_batch", "distinct_cells", "revisit_steps", "boxed_in_steps",
    ]
    # label.check_restarts = 1: restart 0 of each walker is labelled a second time, from a placed start
    checked = mi["restart"] == 0
    assert mi.loc[checked, ["placed_mi_human", "placed_mi_batch"]].notna().all().all()
    assert mi.loc[~checked, ["placed_mi_human", "placed_mi_batch"]].isna().all().all()
    convergence = pd.read_csv(folder / "convergence.csv")
    assert len(convergence) == 2 * 2 and (convergence["n"] == 4).all()
    row = convergence[(convergence.path_length == 12) & (convergence.against == "batch")]
    pairs = mi[checked & (mi.path_length == 12)]
    assert row["difference"].item() == pytest.approx((pairs["mi_batch"] - pairs["placed_mi_batch"]).mean())
    assert len(mi) == 16 and (mi[["mi_human", "mi_batch"]] >= 0).all().all()
    assert (mi[["nmi_human", "nmi_batch"]] <= 1).all().all()
    pd.testing.assert_frame_equal(pd.read_parquet(folder / "mi.parquet"), mi, check_dtype=False)
    summary = pd.read_csv(folder / "summary.csv")
    assert len(summary) == 4 * 2 * 2 and (summary["n"] == 2).all()
    block = mi[(mi.weight_function == "random-walk") & (mi.path_length == 12)]["mi_human"]
    row = summary[(summary.weight_function == "random-walk") & (summary.path_length == 12) & (summary.against == "human")]
    assert row["mean"].item() == pytest.approx(block.mean()) and row["std"].item() == pytest.approx(block.std())
    # t(0.975, 1) = 12.706: the CI half-width of a mean of two
    assert (row["ci_high"] - row["mean"]).item() == pytest.approx(12.7062 * block.std() / np.sqrt(2), rel=1e-4)
    tests = pd.read_csv(folder / "tests.csv")
    assert len(tests) == 2 * 2 * 6 and tests["p_value"].between(0, 1).all()
    # no 80-step checkpoint: the headline is read at the longest path below it, and says so
    assert evaluation.headline["path_length"].tolist() == [12]
    effects = pd.read_csv(folder / "effects.csv")
    assert len(effects) == 2 * 2 * 3 and (effects["ci_low"] <= effects["mean_difference"]).all()


@pytest.mark.slow
def test_the_second_chain_of_a_checked_run_leaves_its_labels_as_they_were(own_map, tmp_path):
    config, folder = small_experiment(own_map, tmp_path)
    label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1)
    path = ExperimentFolder(folder).label_file("own", "word-perplexity", 0)
    with np.load(path) as npz:
        checked = {name: npz[name] for name in npz.files if name != "meta"}
    assert {"placed_batch", "placed_human"} <= set(checked)
    with np.load(ExperimentFolder(folder).label_file("own", "word-perplexity", 1)) as npz:
        assert not {"placed_batch", "placed_human"} & set(npz.files)

    unchecked = dataclasses.replace(config, label=dataclasses.replace(config.label, check_restarts=0))
    done = label_experiment(unchecked, folder, cache_dir=tmp_path / "cache", jobs=1)
    assert (done["labelled"], done["skipped"]) == (4, 4)  # only the checked runs are labelled again
    assert len(done["relabelled"]) == 4 and all("second_start was 'placed', now absent" in r for r in done["relabelled"])
    with np.load(path) as npz:
        assert "placed_batch" not in npz.files
        for name in ("lengths", "batch", "human", "class_first_step"):
            np.testing.assert_array_equal(npz[name], checked[name])
    # the two chains start far apart, and differ after the same sweeps
    assert not np.array_equal(checked["placed_batch"], checked["batch"])


@pytest.mark.slow
def test_labels_record_the_classes_each_path_found(own_map, tmp_path):
    # own_map: class 0 ("sand") in the left 4 of the 8 cell columns, class 1 ("rock") in the right 4
    config, folder = small_experiment(own_map, tmp_path)
    label_experiment(config, tmp_path / config.name, cache_dir=tmp_path / "cache", jobs=1)
    evaluate_experiment(folder)
    mi = pd.read_csv(folder / "mi.csv")
    classes = pd.read_csv(folder / "classes.csv", keep_default_na=False, na_values=[""])
    for weight in config.explore.weight_functions:
        for restart in range(2):
            path = read_run(ExperimentFolder(folder).run("own", weight, restart)).path
            right = path % 8 >= 4
            expected = [int(np.argmax(~right)) if (~right).any() else -1, int(np.argmax(right)) if right.any() else -1]
            with np.load(ExperimentFolder(folder).label_file("own", weight, restart)) as npz:
                assert npz["class_first_step"].tolist() == expected
            for length in (5, 12):
                found = sum(0 <= step < length for step in expected)
                row = mi[(mi.weight_function == weight) & (mi.restart == restart) & (mi.path_length == length)]
                assert (row["classes_found"].item(), row["classes"].item()) == (found, 2)
                rows = classes[(classes.weight_function == weight) & (classes.restart == restart) & (classes.path_length == length)]
                assert rows["class_name"].tolist() == ["sand", "rock"] and rows["found"].sum() == found
                assert row["mean_recall"].item() == pytest.approx(rows["recall"].mean())
    summary = pd.read_csv(folder / "classes_summary.csv")
    assert set(summary["measure"]) == {"classes_found", "mean_recall"} and (summary["classes"] == 2).all()


@pytest.mark.slow
def test_labels_hold_the_tables_of_the_pixels_each_path_visited(own_map, tmp_path):
    config, folder = small_experiment(own_map, tmp_path)
    label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1)
    evaluate_experiment(folder)
    mi = pd.read_csv(folder / "mi.csv")
    store = load_store(tmp_path / "cache" / pd.read_csv(folder / "maps.csv")["store"].item())
    words = pixel_words(store, (96, 128))
    word_cells = np.repeat(np.arange(store.n_cells), store.words_per_cell())
    human = load_map(str(own_map)).labels
    for weight in config.explore.weight_functions:
        path = read_run(ExperimentFolder(folder).run("own", weight, 0)).path
        with np.load(ExperimentFolder(folder).label_file("own", weight, 0)) as npz:
            visited, whole = npz["visited_human"], npz["human"]
            assert "visited_batch" in npz.files and not any(name.startswith("placed_visited") for name in npz.files)
        with np.load(ExperimentFolder(folder).example("own", weight, 0, 12)) as npz:
            labels = npz["labels"]
        # drawn from the example map: the pixels whose word lies in a cell of the path's 12 steps
        seen = np.isin(word_cells[words], path[:12])
        assert 0 < seen.sum() < seen.size
        np.testing.assert_array_equal(visited[-1], contingency(labels[seen], human[seen], 8, 2))
        np.testing.assert_array_equal(whole[-1] - visited[-1], contingency(labels[~seen], human[~seen], 8, 2))
        assert visited[0].sum() < visited[-1].sum()  # 5 steps visit fewer cells than 12
        row = mi[(mi.weight_function == weight) & (mi.restart == 0) & (mi.path_length == 12)]
        assert row["mi_visited_human"].item() == pytest.approx(mutual_information(visited[-1]))
        assert row["mi_unvisited_human"].item() == pytest.approx(mutual_information(whole[-1] - visited[-1]))
    assert mi[["mi_visited_human", "mi_unvisited_human", "mi_visited_batch", "mi_unvisited_batch"]].notna().all().all()


@pytest.mark.slow
def test_labels_hold_the_held_out_log_likelihood_of_one_split_every_walker_shares(own_map, tmp_path, monkeypatch):
    import curiosity_cli.label.heldout as heldout

    config, folder = small_experiment(own_map, tmp_path)
    observed = []  # the words of each block's held-out chains

    def chains_recorded(store, model, device="cpu", kept=None):
        observed.append(kept.copy())
        return map_chains(store, model, device, kept)

    monkeypatch.setattr(heldout, "map_chains", chains_recorded)
    label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1, chains_per_block=1)  # a block per run
    evaluate_experiment(folder)
    mi = pd.read_csv(folder / "mi.csv")
    store = load_store(tmp_path / "cache" / pd.read_csv(folder / "maps.csv")["store"].item())
    held = heldout.map_split(store, config.seed, "own")
    assert len(observed) == 8 and 0 < held.sum() < store.words.size
    for words in observed:  # every walker's and restart's chains ran over the same observed half, never a held-out word
        np.testing.assert_array_equal(words, ~held)
    held_cells = np.repeat(np.arange(store.n_cells), store.words_per_cell())[held]
    for weight in config.explore.weight_functions:
        for restart in range(2):
            path = read_run(ExperimentFolder(folder).run("own", weight, restart)).path
            with np.load(ExperimentFolder(folder).label_file("own", weight, restart)) as npz:
                bits, words, lengths = npz["heldout_bits"], npz["heldout_words"], npz["lengths"]
            assert bits.dtype == np.float64 and words.dtype == np.int64 and bits.shape == words.shape == (2, 2)
            rows = mi[(mi.weight_function == weight) & (mi.restart == restart)].set_index("path_length")
            for j, length in enumerate(lengths.tolist()):
                unvisited = ~np.isin(held_cells, path[:length])
                assert words[j].tolist() == [held.sum(), unvisited.sum()]
                assert rows.loc[length, "heldout"] == bits[j, 0] / words[j, 0]
                assert rows.loc[length, "heldout_unvisited"] == bits[j, 1] / words[j, 1]
    # Φ_p has seen some of the map's terrain: its words are predicted better than by a uniform model
    assert (mi[["heldout", "heldout_unvisited"]] > np.log2(1 / store.vocabulary_size)).all().all()


@pytest.mark.slow
def test_a_corrupt_label_file_is_reported_and_left_out(own_map, tmp_path):
    config, folder = small_experiment(own_map, tmp_path)
    label_experiment(config, tmp_path / config.name, cache_dir=tmp_path / "cache", jobs=1)
    ExperimentFolder(folder).label_file("own", "word-perplexity", 0).write_bytes(b"garbage")
    evaluation = evaluate_experiment(folder, partial=True)
    assert len(evaluation.skipped) == 1 and "word-perplexity/restart-000.npz: corrupt" in evaluation.skipped[0]
    assert len(evaluation.mi) == 14
    assert json.loads((folder / "skipped.json").read_text()) == evaluation.skipped


@pytest.mark.slow
@pytest.mark.parametrize("table", ["batch", "placed_batch"])
def test_a_label_file_with_a_table_short_of_its_lengths_is_reported_and_left_out(own_map, tmp_path, table):
    config, folder = small_experiment(own_map, tmp_path)
    label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1)
    path = ExperimentFolder(folder).label_file("own", "word-perplexity", 0)
    with np.load(path) as npz:
        arrays = {name: npz[name] for name in npz.files}
    arrays[table] = arrays[table][:1]  # 1 table, 2 checkpoint lengths
    with open(path, "wb") as handle:
        np.savez_compressed(handle, **arrays)
    evaluation = evaluate_experiment(folder, partial=True)
    assert len(evaluation.skipped) == 1 and "word-perplexity/restart-000.npz: corrupt or truncated" in evaluation.skipped[0]
    assert f"{table} has shape (1, 8, 8), expected one table for each of 2 lengths" in evaluation.skipped[0]
    assert len(evaluation.mi) == 14
    # and label, as the note advises, makes it again
    done = label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1)
    assert (done["labelled"], done["skipped"]) == (1, 7)
    assert not evaluate_experiment(folder).skipped


def test_labels_of_a_run_made_again_from_other_words_are_refused_naming_what_changed(own_map, tmp_path):
    config, folder = small_experiment(own_map, tmp_path)
    label_experiment(config, tmp_path / config.name, cache_dir=tmp_path / "cache", jobs=1)
    meta_path = ExperimentFolder(folder).run("own", "random-walk", 0) / "run.json"
    meta = json.loads(meta_path.read_text())
    real, other = meta["store"], "own-0000000000000000.npz"
    # the run as explored again from another word store: its recipe records that store
    meta["store"] = other
    meta["recipe"] = Recipe({**meta["recipe"]["inputs"], "store": other}).record()
    meta_path.write_text(json.dumps(meta))
    with pytest.raises(EvaluationError, match=f"1 label files or runs were made otherwise .*restart-000/run.json: store was "
                                              f"'{other}', now '{real}'\\); label makes the label files again"):
        evaluate_experiment(folder)
    with pytest.raises(LabelError, match=f"1 runs were made otherwise .*restart-000/run.json: store was '{other}', "
                                         f"now '{real}'\\); restore the config, or run explore with force=True to redo the runs"):
        label_experiment(config, tmp_path / config.name, cache_dir=tmp_path / "cache", jobs=1, force=True)


def test_a_corrupt_checkpoint_is_named_and_the_other_runs_are_labelled(own_map, tmp_path):
    config, folder = small_experiment(own_map, tmp_path)
    (ExperimentFolder(folder).run("own", "random-walk", 1) / "checkpoints.npz").write_bytes(b"garbage")
    with pytest.raises(LabelError, match=r"1 of 8 runs could not be labelled .*random-walk/restart-001/checkpoints.npz: corrupt"):
        label_experiment(config, tmp_path / config.name, cache_dir=tmp_path / "cache", jobs=1)
    assert len(list((folder / "labels" / "own").glob("*/restart-*.npz"))) == 7


def test_the_headline_is_the_ratio_to_the_next_best_with_its_paired_p():
    from curiosity_cli.evaluate.statistics import paired_tests, summarise
    from curiosity_cli.evaluate.headline import headline

    rng = np.random.default_rng(3)
    rows = []
    for weight, centre in (("random-walk", 0.2), ("stochastic-coverage", 0.3), ("topic-perplexity", 0.45)):
        for restart in range(10):
            mi = centre + 0.01 * rng.standard_normal()
            rows.append({"dataset": "zurich-zh17", "weight_function": weight, "restart": restart, "path_length": 80,
                         "mi_human": mi, "mi_batch": mi, "nmi_human": mi, "nmi_batch": mi, "seed": restart,
                         "replicate": 0})
    mi = pd.DataFrame(rows)
    top = headline(summarise(mi), paired_tests(mi), {"zurich-zh17": "Montreal1"})
    row = top.iloc[0]
    means = mi.groupby("weight_function")["mi_human"].mean()
    assert row["next_best"] == "stochastic-coverage"
    assert row["ratio"] == pytest.approx(means["topic-perplexity"] / means["stochastic-coverage"])
    # every one of 10 pairs favours topic perplexity: the exact two-sided p is 2 / 2**10
    assert row["p_value"] == pytest.approx(2 / 2**10) and row["pairs"] == 10
    assert (row["paper_map"], row["paper_ratio"]) == ("Montreal1", 1.51)
    assert np.isnan(headline(summarise(mi), paired_tests(mi), {})["paper_ratio"].item())


def test_nothing_to_label_or_evaluate_says_which_command_comes_first(own_map, tmp_path):
    config = grid_config(own_map)
    with pytest.raises(LabelError, match=r"grid/runs: none of the runs of the grid of .*config.yaml is explored .*"
                                         r"restart-000: not explored.*; explore makes them"):
        label_experiment(config, tmp_path / config.name, cache_dir=tmp_path / "cache", jobs=1)
    with pytest.raises(EvaluationError, match="grid/labels: no label files; label makes them"):
        evaluate_experiment(tmp_path / "grid")


@pytest.mark.slow
def test_the_commands_through_the_cli(own_map, tmp_path):
    config = grid_yaml(own_map, tmp_path)
    common = ["--jobs", "1", "--cache-dir", str(tmp_path / "cache")]
    folder = tmp_path / "results" / "grid"
    result = runner.invoke(app, ["label", str(folder)])
    assert result.exit_code == 1 and "grid/config.yaml: not found; `curiosity explore` makes the experiment" in result.stderr

    sets = ["--set", "label.sweeps=2", "--set", "label.batch_sweeps=5"]
    result = runner.invoke(app, ["reproduce", str(config), *sets, *common, "--results-dir", str(tmp_path / "results")])
    assert result.exit_code == 0, result.output
    assert "wrote" in result.stdout and "REPORT.md" in result.stdout
    report = (folder / "REPORT.md").read_text()
    assert "## Mutual information" in report and "| own | topic-perplexity |" in report and "](figures/" in report
    assert report.splitlines()[4] == "## Verdict"  # right after the title and one line of context
    assert "- own: topic perplexity" in report and " at 12 steps (its longest path; the paper reads 80); against each alone, MI ratio " in report
    # the labels' settings (the --set above) and the convergence rule are stated
    assert "Labels: a run's first checkpoint's Z_p is 2 frozen-Φ Gibbs sweeps from random topics" in report
    assert "end at the same mean MI" in report
    for section in ("## Paired effect sizes", "## What each walker found at 12 steps"):
        assert section in report
    # the held-out log-likelihood's columns are scored against the map's words, not its labels
    assert "**own** (against Z_h and its held-out words):" in report
    # every measure beside MI compared as MI is, from the same pairs
    found, effects = pd.read_csv(folder / "found_effects.csv"), pd.read_csv(folder / "effects.csv")
    assert set(found["measure"]) == {
        "nmi", "ami", "classes_found", "mean_recall", "time_to_find", "mi_visited", "mi_unvisited", "heldout",
        "heldout_unvisited",
    }
    nmi = found[(found["measure"] == "nmi")].drop(columns="measure").reset_index(drop=True)
    assert nmi[["dataset", "path_length", "against", "other", "n"]].equals(effects[["dataset", "path_length", "against", "other", "n"]])
    assert (mi_table := pd.read_csv(folder / "mi.csv"))["ami_human"].le(mi_table["nmi_human"] + 1e-12).all()
    assert "| leads each |" in report
    # the mechanism: a row per run of a scoring walker and length; its classes found are mi.csv's, counted apart
    mechanism, mi = pd.read_csv(folder / "mechanism.csv"), pd.read_csv(folder / "mi.csv")
    assert len(mechanism) == len(mi) == 4 * 2 * 2, "the paper's 4 walkers all score their moves: 2 restarts, 2 lengths"
    both = mechanism.merge(mi, on=["weight_function", "restart", "path_length"], suffixes=("", "_mi"))
    assert len(both) == len(mechanism) and (both["classes_found"] == both["classes_found_mi"]).all()
    assert mechanism["auc"].dropna().between(0, 1).all() and mechanism["opportunity"].between(0, 1).all()
    assert (mechanism.loc[mechanism["weight_function"] == "stochastic-coverage", "gain"].dropna().abs() < 1e-12).all()
    assert "## Does surprise point at what is new?" in report
    maps = pd.read_csv(folder / "maps.csv")
    store = load_store(tmp_path / "cache" / maps["store"].item())
    counts = store.count_by_type()
    assert maps["words"].item() == store.words.size == sum(counts.values())
    assert maps["orb_share"].item() == pytest.approx(counts["orb"] / store.words.size)
    assert f"| own | 48 | {store.words.size:,} | {100 * counts['orb'] / store.words.size:.1f} % | | | |" in report

    result = runner.invoke(app, ["label", str(folder), *sets, *common])
    assert result.exit_code == 0, result.output
    assert "labelled 0 runs" in result.stdout and "8 were up to date" in result.stdout
    result = runner.invoke(app, ["evaluate", str(folder)])
    assert result.exit_code == 0 and "wrote" in result.stdout and "(16 rows)" in result.stdout


#: The tables `evaluate` writes; a resumed reproduction must give them byte for byte.
TABLES = ("mi.csv", "summary.csv", "tests.csv", "effects.csv", "headline.csv", "classes.csv", "classes_summary.csv")


@pytest.mark.slow
def test_a_reproduction_killed_while_labelling_resumes_to_the_tables_of_an_uninterrupted_one(own_map, tmp_path):
    import os
    import re
    import signal
    import subprocess
    import sys
    import time

    config_path = grid_yaml(own_map, tmp_path)
    # runs enough for 3 blocks of labelling chains (16, 16 and 12: the 40 runs and restart 0's second
    # chains), and sweeps enough that a block lasts long enough for the kill to land after the first
    command = [sys.executable, "-m", "curiosity_cli", "reproduce", str(config_path), "--jobs", "1",
               "--cache-dir", str(tmp_path / "cache"), "--set", "explore.restarts=10", "--set", "label.sweeps=200",
               "--set", "label.warm_sweeps=50", "--no-reuse"]  # computed, not taken from the whole one's shared items
    whole = subprocess.run([*command, "--results-dir", str(tmp_path / "whole")], capture_output=True, text=True)
    assert whole.returncode == 0, whole.stderr
    # output to a pipe, as nohup or CI take it: a line per stage and its end, and the verdict last
    (sweeps,) = re.findall(r"labelling runs \(chain sweeps\): 0/(\d+)\n", whole.stderr)
    assert f"labelling runs (chain sweeps): {sweeps}/{sweeps} in " in whole.stderr
    assert whole.stdout.splitlines()[-1].startswith("  own: topic perplexity ")

    killed = tmp_path / "killed" / "grid"
    process = subprocess.Popen([*command, "--results-dir", str(tmp_path / "killed")],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and not list((killed / "labels").glob("*/*/restart-*.npz")):
        time.sleep(0.02)
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    labelled = len(list((killed / "labels").glob("*/*/restart-*.npz")))
    assert 1 <= labelled < 40, "the kill should land while labelling"
    assert not (killed / "mi.csv").exists()

    resumed = subprocess.run([*command, "--results-dir", str(tmp_path / "killed")], capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    for table in TABLES:
        assert (killed / table).read_bytes() == (tmp_path / "whole" / "grid" / table).read_bytes(), table
    assert not list(killed.rglob("*.tmp*")), "no half-written file is left"


def test_a_grid_narrowed_after_labelling_is_evaluated_on_its_own_runs(own_map, tmp_path):
    config, folder = small_experiment(own_map, tmp_path)
    label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1)
    narrowed = dataclasses.replace(
        config, explore=dataclasses.replace(config.explore, restarts=1, weight_functions=("random-walk", "topic-perplexity"))
    )
    run_grid(narrowed, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)
    evaluation = evaluate_experiment(folder)
    assert set(evaluation.mi["restart"]) == {0}
    assert set(evaluation.mi["weight_function"]) == {"random-walk", "topic-perplexity"}
    assert any(note.startswith("6 label files of runs outside the grid of") for note in evaluation.skipped)


@pytest.mark.slow
def test_a_failure_while_writing_the_tables_leaves_the_old_set_whole(own_map, tmp_path, monkeypatch):
    config, folder = small_experiment(own_map, tmp_path)
    label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1)
    evaluate_experiment(folder)
    tables = sorted(folder.glob("*.csv")) + [folder / "mi.parquet", folder / "skipped.json", folder / "tables.json"]
    before = {path: path.read_bytes() for path in tables}
    ExperimentFolder(folder).label_file("own", "random-walk", 1).unlink()  # the new tables would differ

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(pd.DataFrame, "to_parquet", full_disk)
    with pytest.raises(OSError):
        evaluate_experiment(folder, partial=True)
    assert {path: path.read_bytes() for path in tables} == before
    assert not [p for p in folder.iterdir() if ".tmp" in p.name]


@pytest.mark.slow
def test_an_unreadable_stage_seconds_file_is_named_and_what_was_lost_said(own_map, tmp_path):
    config, folder = small_experiment(own_map, tmp_path)
    label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1)
    evaluate_experiment(folder)
    path = folder / "stage_seconds.json"
    for garbage in ("{not json", '{"label": "12 s"}', ""):
        path.write_text(garbage)
        result = runner.invoke(app, ["plot", str(folder)])
        assert result.exit_code == 0, result.output
        report = (folder / "REPORT.md").read_text()
        assert "stage_seconds.json: " in report and "the time table lacks the stage times it held" in report
        assert "the stage times it held are lost: plot's is recorded alone" in result.stderr
        path.write_text(garbage)
        result = runner.invoke(app, ["evaluate", str(folder), "--cache-dir", str(tmp_path / "cache")])
        assert result.exit_code == 0, result.output
        assert "stage_seconds.json: " in result.stderr and "the stage times it held are lost: evaluate's is recorded alone" in result.stderr
        assert set(json.loads(path.read_text())) == {"evaluate"}


@pytest.mark.slow
def test_a_label_file_whose_tables_were_replaced_is_named_never_counted_and_labelled_again(own_map, tmp_path):
    # the hostile case of issue 44: the human tables rewritten with np.savez, the meta untouched
    config, folder = small_experiment(own_map, tmp_path)
    label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1)
    honest = evaluate_experiment(folder).mi
    path = ExperimentFolder(folder).label_file("own", "word-perplexity", 0)
    with np.load(path) as npz:
        arrays = {name: npz[name] for name in npz.files}
    arrays["human"] = arrays["human"] * 0 + np.eye(*arrays["human"].shape[1:], dtype=arrays["human"].dtype) * 1000
    with open(path, "wb") as handle:
        np.savez(handle, **arrays)
    evaluation = evaluate_experiment(folder, partial=True)
    assert len(evaluation.skipped) == 1
    assert "word-perplexity/restart-000.npz: corrupt or truncated (its tables are not those it was written with" in (
        evaluation.skipped[0]
    )
    with pytest.raises(EvaluationError, match="restart-000.npz: corrupt"):
        evaluate_experiment(folder)
    done = label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1)
    assert (done["labelled"], done["skipped"]) == (1, 7), "labelled again, not 'up to date'"
    pd.testing.assert_frame_equal(evaluate_experiment(folder).mi, honest)


@pytest.mark.slow
def test_an_edited_maps_table_is_named_and_explore_writes_it_again(own_map, tmp_path):
    # issue 44: maps.csv edited (its cells) went into the report unnoticed
    config, folder = small_experiment(own_map, tmp_path)
    label_experiment(config, folder, cache_dir=tmp_path / "cache", jobs=1)
    maps = folder / "maps.csv"
    written = maps.read_text()
    maps.write_text(written.replace(",48,", ",999,"))
    assert maps.read_text() != written
    with pytest.raises(EvaluationError, match=r"maps.csv: 144 bytes, but 143 were written \(explore wrote it\); explore writes it"):
        evaluate_experiment(folder)
    run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1)  # every run kept, the tables written
    assert maps.read_text() == written
    assert evaluate_experiment(folder).maps["cells"].tolist() == [48]
