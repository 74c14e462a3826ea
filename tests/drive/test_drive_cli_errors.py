"""`curiosity drive` and `curiosity simrobot` refuse a user's mistake in one line."""

from __future__ import annotations

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


def test_a_serial_port_that_does_not_exist_is_a_one_line_error(tmp_path):
    result = runner.invoke(
        app, ["drive", "--serial", str(tmp_path / "ttyUSB9"), "--camera", "sim", "--sim-map", "reef-mosaic", "--out", str(tmp_path / "run")]
    )
    line = one_line_error(result)
    assert f"serial port {tmp_path / 'ttyUSB9'}: cannot open it" in line
    # the run folder stays as the attempt's log, and the line says where
    assert line.endswith(f"; the session's log is kept in {tmp_path / 'run' / 'log.jsonl'}")
    assert '"error":"serial port' in (tmp_path / "run" / "log.jsonl").read_text()
