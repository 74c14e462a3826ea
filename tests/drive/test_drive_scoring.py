"""Cell perplexity, the γ decay and the proportional controller, against their formulas."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import yaml

from curiosity_cli.config import CONFIG_DIR, load_config
from curiosity_cli.drive.controller import Command, steer, target_offset
from curiosity_cli.drive.curiosity import CuriosityScores, cell_perplexity
from curiosity_cli.errors import ConfigError, ParameterError
from curiosity_cli.files import display_path

DRIVE = load_config(CONFIG_DIR / "paper-grid.yaml").drive


def test_cell_perplexity_is_eq_12_on_the_cells_topics():
    alpha = 0.1
    totals = np.array([30, 10, 0, 60])
    counts = np.array([[2, 0, 0, 0], [0, 1, 1, 0], [0, 0, 0, 0], [1, 1, 0, 2]])
    p = (totals + alpha) / (totals.sum() + 4 * alpha)
    expected = [
        math.exp(-math.log(p[0])),
        math.exp(-(math.log(p[1]) + math.log(p[2])) / 2),
        1.0,
        math.exp(-(math.log(p[0]) + math.log(p[1]) + 2 * math.log(p[3])) / 4),
    ]
    assert np.allclose(cell_perplexity(counts, totals, alpha), expected, rtol=1e-12)


def test_cell_perplexity_checks_shapes():
    with pytest.raises(ParameterError, match="expected \\(n, K\\) and \\(K,\\)"):
        cell_perplexity(np.zeros((3, 4)), np.zeros(5), 0.1)


def test_scores_start_at_the_first_perplexity_then_decay_with_gamma():
    rng = np.random.default_rng(1)
    frames = rng.uniform(1, 50, size=(6, 2, 3))
    scores = CuriosityScores(0.7, (2, 3))
    expected = frames[0]
    assert np.array_equal(scores.update(frames[0]), expected)
    for frame in frames[1:]:
        expected = 0.7 * expected + 0.3 * frame
        assert np.allclose(scores.update(frame.ravel()), expected, rtol=1e-15)
    assert scores.target() == np.unravel_index(np.argmax(expected), (2, 3))


def test_gamma_zero_forgets_and_ties_go_to_the_first_cell():
    scores = CuriosityScores(0.0, (2, 2))
    scores.update([1.0, 5.0, 2.0, 3.0])
    assert np.array_equal(scores.update([4.0, 1.0, 4.0, 2.0]), [[4.0, 1.0], [4.0, 2.0]])
    assert scores.target() == (0, 0)
    with pytest.raises(ParameterError, match="gamma"):
        CuriosityScores(1.0, (2, 2))


def test_target_offsets_are_cell_centres_in_half_images():
    assert target_offset((0, 0), (6, 8)) == (-5 / 6, -7 / 8)
    assert target_offset((5, 7), (6, 8)) == (5 / 6, 7 / 8)
    assert target_offset((1, 1), (3, 3)) == (0.0, 0.0)


@pytest.mark.parametrize("target", [(0, 0), (0, 7), (2, 3), (3, 4), (5, 0), (5, 7)])
def test_steer_is_the_clipped_proportional_law(target):
    d = DRIVE
    e_row = (2 * target[0] + 1 - 6) / 6
    e_col = (2 * target[1] + 1 - 8) / 8
    expected = Command(
        surge=min(max(d.surge_cruise - d.surge_gain * e_row, d.surge_min), d.surge_max),
        yaw_rate=min(max(d.yaw_gain * e_col, -d.yaw_rate_max), d.yaw_rate_max),
        pitch_rate=min(max(-d.pitch_gain * e_row, -d.pitch_rate_max), d.pitch_rate_max),
    )
    assert steer(target, (6, 8), d) == expected


def test_steer_turns_towards_the_target_and_limits_apply():
    d = dataclasses.replace(DRIVE, surge_cruise=0.3, surge_gain=1.0, surge_min=0.1, surge_max=0.4, yaw_gain=2.0, yaw_rate_max=0.5)
    right, left = steer((3, 7), (6, 8), d), steer((3, 0), (6, 8), d)
    assert right.yaw_rate == 0.5 and left.yaw_rate == -0.5  # clipped at the limit
    assert steer((0, 4), (6, 8), d).surge == 0.4  # ahead: faster, up to surge_max
    assert steer((5, 4), (6, 8), d).surge == 0.1  # behind: slower, down to surge_min
    assert steer((0, 4), (6, 8), d).pitch_rate > 0 > steer((5, 4), (6, 8), d).pitch_rate


@pytest.mark.parametrize(
    "change, message",
    [
        (dict(surge_min=1.0), "drive.surge_min: got 1.0, expected at most surge_max (0.5)"),
        (dict(keepalive=0.15, watchdog=0.1), "drive.keepalive: got 0.15, expected shorter than the robot's watchdog (0.1 s)"),
        (dict(ack_timeout=2.0), "drive.ack_timeout: got 2.0, expected shorter than the robot's watchdog (1.0 s): a frame is "
         "resent before the robot stops for want of one"),
        (dict(frame_width=16, grid_cols=32), "drive.grid_cols: got 32, expected at most frame_width (16): a frame is "
         "resized to 16 px wide, a pixel at least to each column of cells"),
        # hostile-user F15: accepted, then refused after the warm-up for a "frame" of the simulated camera
        (dict(grid_rows=200), "drive.grid_rows: got 200, expected at most frame_width (192): a frame is resized "
         "to 192 px wide, and stretched no taller than that to give each row of cells a pixel"),
    ],
)
def test_drive_keys_that_contradict_each_other_are_refused_in_one_line(tmp_path, change, message):
    # refused by the config loader itself, so `config show` refuses what `drive` would
    config = tmp_path / "exp.yaml"
    config.write_text(yaml.safe_dump({"base": str(CONFIG_DIR / "paper-grid.yaml"), "drive": change}))
    with pytest.raises(ConfigError) as info:
        load_config(config)
    assert str(info.value) == f"{display_path(config)}: {message}"
    with pytest.raises(ConfigError, match=f"overrides: {message.split(':')[0]}"):
        load_config(CONFIG_DIR / "paper-grid.yaml", [f"drive.{key}={value}" for key, value in change.items()])


def test_the_retired_window_keys_load_at_their_old_defaults_and_are_refused_otherwise(tmp_path):
    # every config saved before the stream model stopped restarting holds all three at these values
    config = tmp_path / "saved.yaml"
    old = {"window_frames": 150, "carry_frames": 50, "carry_sweeps": 2}
    config.write_text(yaml.safe_dump({"base": str(CONFIG_DIR / "paper-grid.yaml"), "drive": old}))
    assert load_config(config).drive == load_config(CONFIG_DIR / "paper-grid.yaml").drive
    config.write_text(yaml.safe_dump({"base": str(CONFIG_DIR / "paper-grid.yaml"), "drive": {**old, "carry_frames": 20}}))
    with pytest.raises(ConfigError) as info:
        load_config(config)
    assert str(info.value) == (
        f"{display_path(config)}: drive.carry_frames: got 20, but the key is retired: the live model no longer "
        "restarts every window_frames frames; drive.memory_frames bounds what it remembers, forgetting one frame at a time"
    )
