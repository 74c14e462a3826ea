"""Issue 25: the experiment is one unit. Each stage checks, through the real CLI, what it reads
against the experiment as it is now: the maps' image and human labels, the saved config,
where each file sits and the bytes each writer recorded.

Every case breaks a copy of the small explored, labelled and evaluated experiment of
``conftest.py`` after it was made, runs the next stage, and checks that it refuses in one
``Error:`` line naming what changed, or redoes what was broken; never exit 0 with numbers
from files that are not the experiment's.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml
from cli_cases import EXPERIMENT, EXPLORE, LABEL, assert_clean_error, run_cli

#: Every case edits a copy of an experiment made through the command line (conftest.py's experiment).
pytestmark = pytest.mark.slow
RUNS = f"{EXPERIMENT}/runs/own/random-walk"
LABELS = f"{EXPERIMENT}/labels/own"


def _own_map_in(work: Path) -> Path:
    """Copy the map into ``work`` and point the experiment at the copy, then evaluate it
    again as it now stands: the case may edit the map without touching the shared one."""
    source = Path(yaml.safe_load((work / "grid.yaml").read_text())["datasets"][0])
    folder = work / "map"
    folder.mkdir()
    for name in ("own.yaml", "map.png", "labels.png", "legend.yaml"):
        shutil.copy(source.parent / name, folder)
    for config in (work / "grid.yaml", work / EXPERIMENT / "config.yaml"):
        data = yaml.safe_load(config.read_text())
        data["datasets"] = [str(folder / "own.yaml")]
        config.write_text(yaml.safe_dump(data, sort_keys=False))
    outcome = run_cli(["evaluate", EXPERIMENT], cwd=work)
    assert outcome.code == 0, outcome.output
    return folder


def _edit_png(path: Path, edit) -> None:
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    edit(image)
    cv2.imwrite(str(path), image)


def _relabel(labels: np.ndarray) -> None:
    labels[:40, :] = 1 - labels[:40, :]


def _flip_byte(path: Path, at: float = 0.5) -> None:
    data = bytearray(path.read_bytes())
    data[int(len(data) * at)] ^= 0xFF
    path.write_bytes(bytes(data))


def _tables(work: Path) -> dict[str, str]:
    return {name: (work / EXPERIMENT / name).read_text() for name in ("mi.csv", "summary.csv", "headline.csv")}


def test_human_labels_edited_after_labelling_are_refused_by_evaluate_until_relabelled(work: Path):
    folder = _own_map_in(work)
    _edit_png(folder / "labels.png", _relabel)
    line = assert_clean_error(run_cli(["evaluate", EXPERIMENT], cwd=work), "human labels changed", "`curiosity label`")
    assert "restart-000.npz" in line
    relabelled = run_cli(LABEL, cwd=work)
    assert relabelled.code == 0 and "labelled 8 runs" in relabelled.stdout, relabelled.output
    assert run_cli(["evaluate", EXPERIMENT], cwd=work).code == 0


def test_an_image_edited_after_exploring_is_refused_by_evaluate(work: Path):
    folder = _own_map_in(work)
    _edit_png(folder / "map.png", lambda image: image.__setitem__((slice(0, 8), slice(0, 8)), 0))
    assert_clean_error(run_cli(["evaluate", EXPERIMENT], cwd=work), "run.json: store was", "`curiosity label`")


def test_plot_refuses_tables_made_before_the_seed_was_edited(work: Path):
    config = work / EXPERIMENT / "config.yaml"
    data = yaml.safe_load(config.read_text())
    data["seed"] = 1
    config.write_text(yaml.safe_dump(data, sort_keys=False))
    line = assert_clean_error(run_cli(["plot", EXPERIMENT], cwd=work), "mi.csv", "config.yaml changed", "`curiosity evaluate`")
    assert "made from other files than the experiment holds now" in line


def test_plot_refuses_tables_made_before_the_human_labels_were_edited(work: Path):
    folder = _own_map_in(work)
    _edit_png(folder / "labels.png", _relabel)
    assert_clean_error(run_cli(["plot", EXPERIMENT], cwd=work), "map own's human labels changed", "`curiosity evaluate`")
    # and evaluate, asked, says the labels come first
    assert_clean_error(run_cli(["evaluate", EXPERIMENT], cwd=work), "human labels changed", "`curiosity label`")


def test_plot_refuses_a_table_that_is_not_of_the_set(work: Path):
    summary = work / EXPERIMENT / "summary.csv"
    summary.write_text(summary.read_text().replace("0.", "1.", 1))
    assert_clean_error(run_cli(["plot", EXPERIMENT], cwd=work), "summary.csv", "not the table evaluate wrote with the others")
    (work / EXPERIMENT / "tables.json").unlink()
    assert_clean_error(run_cli(["plot", EXPERIMENT], cwd=work), "tables.json: not found", "`curiosity evaluate`")
    assert run_cli(["evaluate", EXPERIMENT], cwd=work).code == 0
    assert run_cli(["plot", EXPERIMENT], cwd=work).code == 0


def test_an_example_map_copied_from_another_is_refused_by_evaluate_and_redone_by_label(work: Path):
    tables = _tables(work)
    examples = sorted((work / LABELS / "examples").glob("*.npz"))
    shutil.copy(examples[1], examples[0])
    # named by its size ("... were written") or, when the two maps happen to be as long, its digest ("... was written")
    assert_clean_error(run_cli(["evaluate", EXPERIMENT], cwd=work), examples[0].name, "written")
    relabelled = run_cli(LABEL, cwd=work)
    assert relabelled.code == 0 and "labelled 1 runs" in relabelled.stdout, relabelled.output
    assert run_cli(["evaluate", EXPERIMENT], cwd=work).code == 0
    assert _tables(work) == tables


def test_a_run_file_changed_after_exploring_is_named_by_label_and_redone_by_explore(work: Path):
    tables = _tables(work)
    _flip_byte(work / RUNS / "restart-000" / "candidates.csv")
    assert_clean_error(run_cli(LABEL, cwd=work), "restart-000/candidates.csv: its contents changed", "explore redoes the run")
    assert_clean_error(run_cli(["evaluate", EXPERIMENT], cwd=work), "candidates.csv: its contents changed", "--partial")
    redone = run_cli(EXPLORE, cwd=work)
    assert redone.code == 0 and "wrote 1 runs" in redone.stdout, redone.output
    assert "candidates.csv: its contents changed since it was written; redoing the run" in redone.stderr
    for args in (LABEL, ["evaluate", EXPERIMENT]):
        assert run_cli(args, cwd=work).code == 0
    assert _tables(work) == tables  # the same seed made the same run


def test_two_run_folders_swapped_are_refused_by_label_and_evaluate(work: Path):
    first, second = work / RUNS / "restart-000", work / RUNS / "restart-001"
    first.rename(work / "swap")
    second.rename(first)
    (work / "swap").rename(second)
    assert_clean_error(run_cli(LABEL, cwd=work), "restart-000/run.json: restart was 1, now 0", "`curiosity explore --force`")
    assert_clean_error(run_cli(["evaluate", EXPERIMENT], cwd=work), "restart was 1, now 0")
