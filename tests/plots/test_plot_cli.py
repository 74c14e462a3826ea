"""`curiosity plot` through the CLI: exit codes and what it prints."""

from __future__ import annotations

import shutil

import pytest
from synthetic_experiment import make_experiment, seal
from typer.testing import CliRunner

from curiosity_cli.cli import app

runner = CliRunner()


def plot(*args: str):
    return runner.invoke(app, ["plot", *args])


def one_line_error(result) -> str:
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("Error: ")
    return lines[0]


@pytest.mark.slow
def test_plot_writes_the_figures_and_lists_them(tmp_path, own_map):
    experiment = make_experiment(tmp_path, [str(own_map)], restarts=2, lengths=(10, 20, 40), n_topics=8, sweeps=10)
    shutil.rmtree(experiment / "batch")
    seal(experiment)
    result = plot(str(experiment))
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0].startswith("wrote ") and lines[0].endswith("figures/mi-vs-length-human.png")
    assert sum(line.endswith(".pdf") for line in lines) == sum(line.endswith(".png") for line in lines) == 5
    assert "skipped: " in result.stderr and "batch/own.npz: not found (label the experiment first)" in result.stderr


@pytest.mark.slow
def test_plot_defaults_to_the_quick_experiment(tmp_path, monkeypatch, own_map):
    make_experiment(tmp_path / "data", [str(own_map)], restarts=2, lengths=(10, 20), n_topics=6, sweeps=5)
    (tmp_path / "results").mkdir()
    (tmp_path / "data" / "synthetic").rename(tmp_path / "results" / "quick")
    monkeypatch.chdir(tmp_path)
    result = plot()
    assert result.exit_code == 0, result.output
    assert "wrote results/quick/figures/mi-vs-length-batch.png" in result.stdout


def test_plot_without_an_experiment_folder_says_what_to_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    line = one_line_error(plot())
    assert line == "Error: results/quick: no such experiment folder; `curiosity explore` makes it"


def test_plot_without_mi_table_says_to_evaluate_first(tmp_path):
    (tmp_path / "exp").mkdir()
    line = one_line_error(plot(str(tmp_path / "exp")))
    assert "exp/mi.csv: not found; `curiosity evaluate` makes it" in line
