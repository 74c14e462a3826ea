"""``curiosity explore`` through the CLI: exit codes and what it prints."""

from __future__ import annotations

from small_maps import grid_yaml
from typer.testing import CliRunner

from curiosity_cli.cli import app
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.explore.runs import read_run

runner = CliRunner()


def explore(*args: str):
    return runner.invoke(app, ["explore", *args])


def usage_error(result) -> str:
    """A usage error's text without the box drawn around it."""
    assert result.exit_code == 2, result.output
    return " ".join(result.stderr.replace("│", " ").split())


def test_explore_runs_a_grid_and_resumes_it(own_map, tmp_path):
    config = str(grid_yaml(own_map, tmp_path))
    common = ["--jobs", "1", "--results-dir", str(tmp_path / "results"), "--cache-dir", str(tmp_path / "cache")]
    result = explore(config, "--weights", "random-walk,topic-perplexity", "--steps", "8", *common)
    assert result.exit_code == 0, result.output
    assert "grid: 4 runs to do, 0 already finished" in result.stderr
    assert "wrote 4 runs" in result.stdout
    run = read_run(ExperimentFolder(tmp_path / "results" / "grid").run("own", "topic-perplexity", 1))
    assert run.path.size == 8 and run.meta["checkpoints"] == [5, 8]

    again = explore(config, "--weights", "random-walk,topic-perplexity", "--steps", "8", *common)
    assert again.exit_code == 0 and "0 runs to do, 4 already finished" in again.stderr


def test_explore_with_an_unknown_weight_function_or_map_is_a_usage_error(own_map, tmp_path):
    config = str(grid_yaml(own_map, tmp_path))
    result = explore(config, "--weights", "random-walk,curious")
    assert "Invalid value for --weights: got 'curious', expected one of random-walk" in usage_error(result)
    result = explore(config, "--map", "atlantis")
    assert "Invalid value for --map: no dataset 'atlantis'" in usage_error(result)


def test_explore_with_a_bad_number_is_a_usage_error(tmp_path):
    for option in ("--steps", "--restarts", "--jobs"):
        result = explore("--results-dir", str(tmp_path), option, "0")
        assert f"Invalid value for '{option}': Input should be greater than or equal to 1" in usage_error(result)


def test_explore_of_a_map_smaller_than_the_path_is_a_one_line_error(own_map, tmp_path):
    config = str(grid_yaml(own_map, tmp_path))
    result = explore(config, "--steps", "60", "--results-dir", str(tmp_path), "--cache-dir", str(tmp_path / "cache"))
    assert result.exit_code == 1
    assert result.stderr.strip() == (
        "Error: explore.path_length: got 60 steps, but own has only 48 cells (6 x 8); "
        "use fewer steps or a smaller cell width"
    )
