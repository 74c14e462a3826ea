"""Issue 16, item 1: a derived file is current only for the inputs it was made from, never for being there.

Each case edits a copy of one small explored, labelled and evaluated experiment the way a
researcher would (a hand-edited config, a ``--set`` at a later stage, a deleted config)
and runs ``curiosity`` on it in a subprocess: what no longer matches is refused by name
or made again with a note saying why, and every override is recorded in the experiment's
``config.yaml`` or refused.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml
from cli_cases import EXPERIMENT, EXPLORE, FAST_LABELS, assert_clean_error, run_cli

from curiosity_cli.experiment.layout import ExperimentFolder

#: Every case edits a copy of an experiment made through the command line (conftest.py's experiment).
pytestmark = pytest.mark.slow
CONFIG = f"{EXPERIMENT}/config.yaml"


def _edit_config(work: Path, section: str | None, key: str, value) -> None:
    path = work / CONFIG
    config = yaml.safe_load(path.read_text())
    (config if section is None else config[section])[key] = value
    path.write_text(yaml.safe_dump(config, sort_keys=False))


def _recipe(path: Path) -> dict:
    import numpy as np

    with np.load(path) as npz:
        return json.loads(str(npz["meta"]))["recipe"]


def test_an_edited_seed_is_refused_at_label_before_the_batch_reference_is_touched(work):
    batch = ExperimentFolder(work / EXPERIMENT).batch("own")
    before = batch.read_bytes()
    _edit_config(work, None, "seed", 5)
    error = assert_clean_error(
        run_cli(["label", EXPERIMENT, *FAST_LABELS], cwd=work), "runs were made otherwise", "run.json: seed was 0, now 5",
        "`curiosity explore --force`",
    )
    assert error.startswith("Error: 8 runs")  # every run of the grid, the first named
    assert batch.read_bytes() == before


def test_a_label_override_is_recorded_and_what_it_changes_is_made_again(work):
    folder = work / EXPERIMENT
    first = ExperimentFolder(folder).label_file("own", "random-walk", 0)
    old = _recipe(first)
    # a key given twice is refused (issue 63): FAST_LABELS's batch sweeps replaced, not overridden by a second --set
    relabel = [*FAST_LABELS[:-2], "--set", "label.batch_sweeps=3"]
    outcome = run_cli(["label", EXPERIMENT, *relabel], cwd=work)
    assert outcome.code == 0, outcome.output
    assert yaml.safe_load((work / CONFIG).read_text())["label"]["batch_sweeps"] == 3
    assert "recorded label.batch_sweeps=3" in outcome.stderr
    assert "batch/own.npz: sweeps was 5, now 3; computing it again" in outcome.stderr
    assert "labelling 8 runs again whose label files were made otherwise" in outcome.stderr
    assert "the batch reference changed" in outcome.stderr
    assert _recipe(ExperimentFolder(folder).batch("own"))["inputs"]["sweeps"] == 3
    assert _recipe(first)["inputs"]["batch"] != old["inputs"]["batch"]
    # the same command again finds everything current
    again = run_cli(["label", EXPERIMENT, *relabel], cwd=work)
    assert again.code == 0 and "8 were up to date" in again.stdout, again.output
    assert "recorded" not in again.stderr and "again" not in again.stderr, again.stderr


def test_an_override_of_how_the_runs_were_made_is_refused_at_label(work):
    before = (work / CONFIG).read_text()
    assert_clean_error(
        run_cli(["label", EXPERIMENT, "--set", "model.topics=4"], cwd=work),
        "model.topics: the experiment in", "was explored with 8, not 4", "only label settings can change",
    )
    assert (work / CONFIG).read_text() == before


def test_without_its_config_a_folder_does_not_adopt_runs_made_with_another_seed(work):
    folder = work / EXPERIMENT
    (folder / "config.yaml").unlink()
    runs_csv = (folder / "runs.csv").read_text()
    assert_clean_error(
        run_cli([*EXPLORE, "--set", "seed=5"], cwd=work),
        "8 finished runs were made otherwise than this config makes them", "run.json: seed was 0, now 5",
        "or run `curiosity explore --force` to redo them",
    )
    assert not (folder / "config.yaml").exists() and (folder / "runs.csv").read_text() == runs_csv


def test_force_redoes_runs_made_otherwise_and_labels_follow(work):
    folder = work / EXPERIMENT
    (folder / "config.yaml").unlink()
    outcome = run_cli([*EXPLORE, "--set", "seed=5", "--force"], cwd=work)
    assert outcome.code == 0, outcome.output
    assert json.loads((ExperimentFolder(folder).run("own", "random-walk", 0) / "run.json").read_text())["seed"][0] == 5
    assert yaml.safe_load((folder / "config.yaml").read_text())["seed"] == 5
    # the labels were made from the old runs: evaluate refuses them, label makes them again
    assert_clean_error(run_cli(["evaluate", EXPERIMENT], cwd=work), "label files or runs were made otherwise",
                       "batch/own.npz: seed was 0, now 5", "`curiosity label` makes the label files again")
    relabel = run_cli(["label", EXPERIMENT, *FAST_LABELS], cwd=work)
    assert relabel.code == 0 and "labelling 8 runs again" in relabel.stderr, relabel.output
    assert run_cli(["evaluate", EXPERIMENT], cwd=work).code == 0


def test_evaluate_refuses_labels_made_with_other_label_settings_than_the_config_says(work):
    _edit_config(work, "label", "sweeps", 3)
    assert_clean_error(
        run_cli(["evaluate", EXPERIMENT], cwd=work), "restart-000.npz: label.sweeps was 2, now 3", "`curiosity label` makes the label files again",
    )
