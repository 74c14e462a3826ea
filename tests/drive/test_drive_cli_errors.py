"""`curiosity drive` and `curiosity simrobot` refuse a user's mistake in one line."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from curiosity_cli.cli import app

runner = CliRunner()


def usage_error(result) -> str:
    assert result.exit_code == 2, result.output
    return " ".join(result.stderr.replace("│", " ").split())


def one_line_error(result) -> str:
    """The error line (after any progress lines), checked to be the only one and untraced."""
    assert result.exit_code == 1, result.output
    errors = [line for line in result.stderr.splitlines() if line.startswith("Error: ")]
    assert len(errors) == 1 and result.stderr.strip().endswith(errors[0]) and "Traceback" not in result.stderr
    return errors[0]


def test_options_that_do_not_go_together_are_usage_errors(tmp_path):
    out = ["--out", str(tmp_path)]
    assert "--camera sim and --sim-map go together" in usage_error(runner.invoke(app, ["drive", "--dry-run", "--camera", "sim", *out]))
    assert "--camera sim and --sim-map go together" in usage_error(
        runner.invoke(app, ["drive", "--dry-run", "--sim-map", "reef-mosaic", *out])
    )
    assert "--dry-run sends nothing; leave out --serial" in usage_error(
        runner.invoke(app, ["drive", "--dry-run", "--serial", "/dev/null", *out])
    )
    assert "give the robot's port with --serial" in usage_error(runner.invoke(app, ["drive", *out]))
    assert "give the start to `curiosity simrobot`" in usage_error(
        runner.invoke(app, ["drive", "--serial", "/dev/null", "--camera", "sim", "--sim-map", "reef-mosaic", "--start", "1,1", *out])
    )
    assert "Invalid value for --heading-deg: only a dry run simulates the robot here" in usage_error(
        runner.invoke(app, ["drive", "--dry-run", "--camera", "0", "--heading-deg", "90", *out])
    )
    result = runner.invoke(app, ["drive", "--dry-run", "--camera", "sim", "--sim-map", "reef-mosaic", "--start", "9999,1", *out])
    assert "expected a point inside the map (2500 x 2500 px)" in usage_error(result)
    assert not any(tmp_path.iterdir())  # refused before anything was written


def test_contradicting_drive_keys_name_the_config_and_key():
    result = runner.invoke(app, ["drive", "--dry-run", "--set", "drive.surge_min=1.0"])
    # named where the key was set: here the --set, in a file the file
    assert "Error: --set: drive.surge_min: got 1.0, expected at most surge_max (0.5)" in one_line_error(result)
    result = runner.invoke(app, ["drive", "--dry-run", "--set", "drive.window_frames=300"])
    assert "Error: --set: drive.window_frames: got 300, but the key is retired: the live model no longer restarts" in (
        one_line_error(result)
    )
    result = runner.invoke(app, ["simrobot", "--map", "reef-mosaic", "--set", "drive.watchdog=0"])
    assert "--set: drive.watchdog: got 0 (int), expected a number > 0" in one_line_error(result)


def test_bad_noise_and_unknown_maps_are_one_line_errors():
    result = runner.invoke(app, ["simrobot", "--map", "reef-mosaic", "--noise", "static=0.5"])
    assert "--noise 'static=0.5': expected KIND=RATE" in one_line_error(result)
    result = runner.invoke(app, ["simrobot", "--map", "atlantis"])
    assert "no dataset 'atlantis'" in one_line_error(result)


def test_a_link_that_cannot_be_made_names_the_link_not_the_pty(tmp_path):
    result = runner.invoke(app, ["simrobot", "--map", "reef-mosaic", "--link", str(tmp_path / "none" / "robot")])
    line = one_line_error(result)
    assert "--link: " in line and "none is not a folder; expected the symlink's folder to exist" in line
    assert "/dev/" not in line
    (tmp_path / "robot").write_text("a file of the user's")
    result = runner.invoke(app, ["simrobot", "--map", "reef-mosaic", "--link", str(tmp_path / "robot")])
    assert "robot exists and is not a symlink; expected a new name" in one_line_error(result)
    assert (tmp_path / "robot").read_text() == "a file of the user's"


def test_a_camera_that_cannot_be_opened_is_a_one_line_error(tmp_path):
    result = runner.invoke(app, ["drive", "--dry-run", "--camera", str(tmp_path / "none.mp4"), "--out", str(tmp_path / "run")])
    assert "none.mp4': OpenCV cannot open it; expected a device index, a video file or a stream URL" in one_line_error(result)


@pytest.mark.parametrize("camera", ["", "  "])
def test_an_empty_camera_is_named_as_empty_not_read_as_the_working_folder(tmp_path, camera):
    """``--camera ''`` said ``.: not a bag folder`` (a caveat left at stop 70): an empty path is the working folder."""
    result = runner.invoke(app, ["drive", "--dry-run", "--camera", camera, "--out", str(tmp_path / "run")])
    assert one_line_error(result) == (
        f"Error: --camera: got {camera!r}; expected a device index, a video file, a stream URL, a bag, ros2:/TOPIC or 'sim'"
    )
    assert not (tmp_path / "run").exists()


def test_a_serial_port_that_does_not_exist_is_a_one_line_error(tmp_path):
    result = runner.invoke(
        app, ["drive", "--serial", str(tmp_path / "ttyUSB9"), "--camera", "sim", "--sim-map", "reef-mosaic", "--out", str(tmp_path / "run")]
    )
    line = one_line_error(result)
    assert f"serial port {tmp_path / 'ttyUSB9'}: cannot open it" in line
    # the run folder stays as the attempt's log, and the line says where
    assert line.endswith(f"; the session's log is kept in {tmp_path / 'run' / 'log.jsonl'}")
    assert '"error":"serial port' in (tmp_path / "run" / "log.jsonl").read_text()


@pytest.mark.parametrize(
    "given",
    [
        ["--out", "elsewhere"], ["--camera", "clip.avi"], ["--camera", "0"], ["--max-frames", "1"], ["--serial", "/dev/x"],
        ["--dry-run"], ["--force"], ["--strict"], ["--set", "drive.gamma=0.5"], ["--config", "quick"], ["--seed", "1"],
        ["--video-out", "v.avi"], ["--png-every", "1"], ["--topic", "/camera/image_raw"],
    ],
)
def test_a_timeline_refuses_every_driving_option_by_name(tmp_path, given):
    """Hostile-user F7: ``drive --timeline RUN --out elsewhere ...`` ignored them and exited 0."""
    result = runner.invoke(app, ["drive", "--timeline", str(tmp_path / "run"), *given])
    assert f"Invalid value for {given[0]}: goes with a drive, not --timeline" in usage_error(result)
    assert not any(tmp_path.iterdir())


def test_a_timeline_takes_its_clock():
    result = runner.invoke(app, ["drive", "--timeline", "no-such-run", "--clock", "header"])
    assert "no-such-run/log.jsonl: not found; give a run folder of `curiosity drive`" in one_line_error(result)


def _video(path):
    """A 5-frame Motion JPEG video of random 120 x 160 frames."""
    import cv2
    import numpy as np

    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 5, (160, 120))
    for i in range(5):
        writer.write(np.random.default_rng(i).integers(0, 256, (120, 160, 3), dtype=np.uint8))
    writer.release()
    return path


@pytest.mark.parametrize(
    "given, says",
    [
        (["--topic", "/camera/image_raw"], "--topic: got '/camera/image_raw', but camera '{camera}' is not a bag"),
        (["--clock", "header"], "--clock: got 'header', but camera '{camera}' is not a bag"),
        (["--strict"], "--strict: camera '{camera}' is not a bag; strict stops a replay at a bag's first damaged message"),
    ],
)
@pytest.mark.parametrize("camera", ["clip.avi", "sim"])
def test_a_replays_options_are_refused_for_a_camera_that_is_not_a_bag(tmp_path, monkeypatch, given, says, camera):
    """Hostile-user F8 and F12: ``--clock header`` and ``--strict`` with a video were taken in silence, and
    ``--topic`` was refused as ``topic:``, the API's argument."""
    monkeypatch.chdir(tmp_path)
    _video(tmp_path / "clip.avi")
    sim = ["--sim-map", "reef-mosaic"] if camera == "sim" else []
    # a frame at most: a dry run on the simulated camera that took them would run until stopped
    result = runner.invoke(app, ["drive", "--dry-run", "--camera", camera, *sim, "--out", "run", "--max-frames", "1", *given])
    assert f"Error: {says.format(camera=camera)}" in one_line_error(result)
    assert not (tmp_path / "run").exists()


def test_a_grid_finer_than_the_resized_frame_is_refused_by_its_key_before_any_work(tmp_path):
    """Hostile-user F15: ``--set drive.grid_rows=100000`` failed after the warm-up, blaming a 360 x 480 "frame"."""
    drive = ["drive", "--dry-run", "--camera", str(tmp_path / "clip.avi"), "--out", str(tmp_path / "run")]
    result = runner.invoke(app, [*drive, "--set", "drive.grid_rows=200"])
    line = one_line_error(result)
    assert line.startswith("Error: --set: drive.grid_rows: got 200, expected at most frame_width (192): a frame is")
    assert "loading" not in result.stderr and not any(tmp_path.iterdir())


def test_a_video_out_that_is_no_video_is_a_usage_error_before_anything_is_written(tmp_path):
    """Hostile-user F18: ``--video-out v.txt`` was found once the run folder was written (exit 1), and the
    corrected command was then refused for the earlier run in that folder."""
    video = _video(tmp_path / "clip.avi")
    drive = ["drive", "--dry-run", "--camera", str(video), "--out", str(tmp_path / "run"), "--max-frames", "1"]
    message = usage_error(runner.invoke(app, [*drive, "--video-out", str(tmp_path / "v.txt")]))
    assert f"Invalid value for --video-out: got {tmp_path / 'v.txt'}, expected a .mp4, .avi or .mkv file name" in message
    assert not (tmp_path / "run").exists() and not (tmp_path / "v.txt").exists()
    corrected = runner.invoke(app, [*drive, "--video-out", str(tmp_path / "v.avi")])
    assert corrected.exit_code == 0, corrected.output
    assert (tmp_path / "v.avi").is_file()


@pytest.mark.parametrize("folder", ["file", "sysfs"])
def test_a_video_out_whose_folder_takes_no_files_is_named_with_the_cause_before_the_run(tmp_path, folder):
    """Hostile-user audit (issue 64): OpenCV opened a writer in a read-only folder without a word, and the run
    ended on its missing temporary file ("No such file or directory")."""
    video = _video(tmp_path / "clip.avi")
    # a file where the folder goes, and a file system that takes no new files (sysfs: refused even to root)
    target, says = {
        "file": (video / "v.avi", f"{video}: is a file; expected a folder"), "sysfs": (Path("/sys/v.avi"), "/sys: "),
    }[folder]
    drive = ["drive", "--dry-run", "--camera", str(video), "--out", str(tmp_path / "run"), "--max-frames", "1"]
    result = runner.invoke(app, [*drive, "--video-out", str(target)])
    assert result.exit_code == 1, result.output
    assert one_line_error(result).startswith(f"Error: --video-out {target}: {says}")
    assert not (tmp_path / "run").exists() and not target.exists()
