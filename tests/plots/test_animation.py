"""`curiosity plot --animate`: one run's path growing over its map beside Z_p, one frame per step."""

from __future__ import annotations

import re

import pytest
from PIL import Image
from small_maps import grid_config
from typer.testing import CliRunner

from curiosity_cli.cli import app
from curiosity_cli.label.stage import label_experiment
from curiosity_cli.experiment.saved_config import load_saved_config
from curiosity_cli.explore.grid import run_grid

runner = CliRunner()


@pytest.mark.slow
def test_a_run_animates_one_frame_per_step_with_its_checkpoints_labelled(own_map, tmp_path):
    config = grid_config(own_map, restarts=1)
    folder = run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1).folder
    label_experiment(load_saved_config(folder, ["label.sweeps=2", "label.batch_sweeps=5"]), folder, cache_dir=tmp_path / "cache", jobs=1)
    result = runner.invoke(
        app, ["plot", str(folder), "--animate", "own/topic-perplexity/0", "--cache-dir", str(tmp_path / "cache")]
    )
    assert result.exit_code == 0, result.output
    gif = folder / "figures" / "animation-own-topic-perplexity-000.gif"
    assert result.stdout.strip().endswith("figures/animation-own-topic-perplexity-000.gif")
    with Image.open(gif) as movie:
        assert movie.n_frames == config.explore.path_length
        first, last = movie.convert("RGB"), (movie.seek(movie.n_frames - 1), movie.convert("RGB"))[1]
    assert first.tobytes() != last.tobytes()  # the path grew and Z_p appeared


def test_animate_refuses_what_it_cannot_draw(own_map, tmp_path):
    config = grid_config(own_map, restarts=1)
    folder = run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1).folder
    bad = runner.invoke(app, ["plot", str(folder), "--animate", "own/topic-perplexity"])
    box = " ".join(re.sub("[│╭╮╰╯─]", " ", bad.stderr).split())  # click wraps its box to the terminal
    assert bad.exit_code == 2 and "expected MAP/WALKER/RESTART" in box
    other = runner.invoke(app, ["plot", str(folder), "--animate", "nowhere/topic-perplexity/0"])
    assert other.exit_code == 1 and "Error: --animate: map 'nowhere' is not in" in other.stderr
    avi = runner.invoke(app, ["plot", str(folder), "--animate", "own/topic-perplexity/0", "--out", str(tmp_path / "a.avi")])
    assert avi.exit_code == 1 and "--out: got" in avi.stderr and "expected a .gif or .mp4 file" in avi.stderr
    outside = runner.invoke(app, ["plot", str(folder), "--animate", "own/topic-perplexity/99"])
    assert outside.exit_code == 1 and "Error: --animate: restart 99 is not in the grid of" in outside.stderr
    assert "(restarts 0 to 0)" in outside.stderr and "not finished" not in outside.stderr
    walker = runner.invoke(app, ["plot", str(folder), "--animate", "own/lawnmower/0"])
    assert walker.exit_code == 1 and "Error: --animate: walker 'lawnmower' is not in" in walker.stderr
    (folder / "runs" / "own" / "topic-perplexity" / "restart-000" / "run.json").unlink()
    missing = runner.invoke(app, ["plot", str(folder), "--animate", "own/topic-perplexity/0"])
    assert missing.exit_code == 1 and "restart-000" in missing.stderr


def test_the_animated_labels_are_those_label_made(own_map, tmp_path):
    import numpy as np

    from curiosity_cli.maps.map_data import load_map
    from curiosity_cli.experiment.experiment import Experiment
    from curiosity_cli.explore.runs import read_run
    from curiosity_cli.plots.animation import checkpoint_labels
    from curiosity_cli.words.extract import extract_words

    config = grid_config(own_map, restarts=1)
    folder = run_grid(config, results_dir=tmp_path, cache_dir=tmp_path / "cache", jobs=1).folder
    label_experiment(load_saved_config(folder, ["label.sweeps=2", "label.batch_sweeps=5"]), folder, cache_dir=tmp_path / "cache", jobs=1)
    experiment = Experiment.open(folder)
    map_data = load_map(own_map)
    store = extract_words(map_data, experiment.config.words, cache_dir=tmp_path / "cache").store
    run = read_run(experiment.folder.run("own", "random-walk", 0))
    labels = checkpoint_labels(experiment, run, store, map_data.image.shape[:2])
    with np.load(experiment.folder.example("own", "random-walk", 0, 12)) as example:  # label keeps the last checkpoint's
        np.testing.assert_array_equal(labels[12], example["labels"])
