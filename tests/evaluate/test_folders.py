"""Every stage reads and writes the folder it was given, whatever the config inside calls it."""

from __future__ import annotations

import shutil

from small_maps import grid_yaml
from typer.testing import CliRunner

from curiosity_cli.cli import app

runner = CliRunner()


def test_label_and_evaluate_on_a_copied_experiment_write_only_into_the_copy(own_map, tmp_path):
    config = grid_yaml(own_map, tmp_path)
    common = ["--jobs", "1", "--cache-dir", str(tmp_path / "cache")]
    sets = ["--set", "label.sweeps=2", "--set", "label.batch_sweeps=5"]
    result = runner.invoke(app, ["explore", str(config), *common, "--results-dir", str(tmp_path / "results")])
    assert result.exit_code == 0, result.output
    original = tmp_path / "results" / "grid"
    copy = tmp_path / "elsewhere" / "grid-copy"
    shutil.copytree(original, copy)
    before = sorted(p.relative_to(original) for p in original.rglob("*"))

    result = runner.invoke(app, ["label", str(copy), *sets, *common])
    assert result.exit_code == 0, result.output
    assert "labelled 8 runs" in result.stdout
    assert sorted(p.relative_to(original) for p in original.rglob("*")) == before, "the original was written to"
    assert len(list((copy / "labels").glob("*/*/restart-*.npz"))) == 8
    result = runner.invoke(app, ["evaluate", str(copy)])
    assert result.exit_code == 0, result.output
    assert (copy / "mi.csv").is_file() and not (original / "mi.csv").exists()
