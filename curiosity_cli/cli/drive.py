"""``curiosity drive`` (steer a robot with live curiosity) and ``curiosity simrobot`` (a robot to steer)."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli import app
from curiosity_cli.config import CONFIG_DIR
from curiosity_cli.layout import DEFAULT_RESULTS

_CONFIG_HELP = "Experiment config whose model, words and drive sections (and seed) to use."
_START_HELP = "Start position ROW,COL in map pixels; default the map's centre."


def _finite(value: float | None) -> float | None:
    """A float option's value, refused unless finite: ``nan`` and ``inf`` parse as floats but steer nowhere."""
    import math

    if value is not None and not math.isfinite(value):
        raise typer.BadParameter(f"got {value}, expected a finite number")
    return value


def _parse_start(text: str | None, map_shape: tuple[int, int]) -> tuple[float, float]:
    if text is None:
        return map_shape[0] / 2, map_shape[1] / 2
    try:
        row, col = (float(part) for part in text.split(","))
    except ValueError:
        raise typer.BadParameter(f"got {text!r}, expected ROW,COL in map pixels, e.g. 1250,1250", param_hint="--start") from None
    if not (0 <= row <= map_shape[0] and 0 <= col <= map_shape[1]):
        raise typer.BadParameter(
            f"got {text!r}, expected a point inside the map ({map_shape[0]} x {map_shape[1]} px)", param_hint="--start"
        )
    return row, col




def _default_out() -> Path:
    from datetime import datetime

    return DEFAULT_RESULTS / "drive" / datetime.now().strftime("%Y%m%d-%H%M%S")


@app.command("drive")
def drive(
    serial: str = typer.Option(None, "--serial", metavar="PORT", help="Serial device or pyserial URL of the robot; default the config's drive.port."),
    baud: int = typer.Option(None, "--baud", min=1, help="Serial speed; default the config's drive.baud (115200)."),
    dry_run: bool = typer.Option(False, "--dry-run", help="No serial port: commands are computed and logged, not sent (with --camera sim the robot is simulated in this process, one frame period per command)."),
    camera: str = typer.Option("0", "--camera", help="A device index, a video file, a stream URL, or 'sim' for the simulated robot's camera."),
    sim_map: str = typer.Option(None, "--sim-map", help="With --camera sim: the map the simulated robot is on (name or dataset YAML)."),
    start: str = typer.Option(None, "--start", metavar="ROW,COL", help="With --dry-run --camera sim: start position ROW,COL in map pixels; default the map's centre."),
    heading_deg: float = typer.Option(None, "--heading-deg", callback=_finite, help="With --dry-run --camera sim: start heading, degrees clockwise from the map's +col axis (default 0)."),
    config: Path = typer.Option(CONFIG_DIR / "paper-grid.yaml", "--config", help=_CONFIG_HELP),
    overrides: list[str] = typer.Option([], "--set", metavar="KEY=VALUE", help="Override a config key, e.g. --set drive.gamma=0.5."),
    seed: int = typer.Option(None, "--seed", min=0, help="Seed of the topic models; default the config's seed."),
    out: Path = typer.Option(None, "--out", help="Run folder (log.jsonl, config, provenance, frames/); default results/drive/<date-time>."),
    video_out: Path = typer.Option(None, "--video-out", help="Write the annotated video here (.mp4, .avi or .mkv)."),
    png_every: int = typer.Option(0, "--png-every", min=0, metavar="N", help="Write an annotated PNG every N frames into <out>/frames/."),
    max_frames: int = typer.Option(None, "--max-frames", min=1, help="Stop after this many frames."),
) -> None:
    """Steer a robot towards what its camera finds most curious (paper section 5.2).

    Image cells are scored by topic perplexity in a live topic model, with a decaying memory.

    Protocol: curiosity_cli/drive/PROTOCOL.md. Ctrl-C sends STOP, then exits with 130.
    """
    from curiosity_cli.config import load_config
    from curiosity_cli.drive.driver import StopRequest, stopping_on_signals

    if dry_run and serial is not None:
        raise typer.BadParameter("--dry-run sends nothing; leave out --serial", param_hint="--dry-run")
    if (camera == "sim") != (sim_map is not None):
        raise typer.BadParameter("--camera sim and --sim-map go together", param_hint="--sim-map")
    if (start is not None or heading_deg is not None) and not (dry_run and camera == "sim"):
        raise typer.BadParameter(
            "only a dry run simulates the robot here; give the start to `curiosity simrobot`",
            param_hint="--start" if start is not None else "--heading-deg",
        )
    resolved = load_config(config, overrides)
    port = serial or resolved.drive.port
    if not dry_run and port is None:
        raise typer.BadParameter("give the robot's port with --serial (or drive.port in the config), or --dry-run", param_hint="--serial")
    map_data, start_pose = None, None
    if sim_map is not None:
        import math

        from curiosity_cli.data import load_map
        from curiosity_cli.drive.sim import Pose

        map_data = load_map(sim_map)
        if dry_run:
            if resolved.drive.sim_frame_interval <= 0:
                raise typer.BadParameter(
                    "a dry run with --camera sim needs drive.sim_frame_interval > 0 (the simulated time per frame)",
                    param_hint="--set",
                )
            row, col = _parse_start(start, map_data.image.shape[:2])
            mpp = resolved.drive.sim_metres_per_pixel
            start_pose = Pose(col * mpp, row * mpp, math.radians(heading_deg or 0.0))

    with stopping_on_signals(StopRequest()) as stop:
        outcome, folder = _drive(
            resolved, port=None if dry_run else port, baud=baud, camera=camera, map_data=map_data,
            start_pose=start_pose, seed=resolved.seed if seed is None else seed, out=out or _default_out(),
            video_out=video_out, png_every=png_every, max_frames=max_frames, stop=stop,
        )
    from curiosity_cli.files import display_path

    stopped = {True: "; STOP acknowledged", False: "; STOP sent, not acknowledged", None: ""}[outcome.stop_acked]
    typer.echo(f"drove {outcome.frames} frames: {outcome.detail}{stopped}; log in {display_path(folder / 'log.jsonl')}")
    if video_out is not None:
        typer.echo(f"wrote {display_path(video_out)}")
    if outcome.reason in ("SIGINT", "SIGTERM"):
        raise typer.Exit(128 + {"SIGINT": 2, "SIGTERM": 15}[outcome.reason])


def _drive(resolved, *, port, baud, camera, map_data, start_pose, seed, out, video_out, png_every, max_frames, stop):
    from curiosity_cli.drive import camera as cameras
    from curiosity_cli.drive.driver import Outputs, prepare_folder, run
    from curiosity_cli.drive.jsonlines import JsonLines
    from curiosity_cli.drive.link import LinkTiming, RobotLink
    from curiosity_cli.drive.pipeline import CuriosityPipeline, warm_up
    from curiosity_cli.drive.sim import Body

    d = resolved.drive
    source = None if camera == "sim" else cameras.OpenCVCamera(camera)
    typer.echo("loading the vocabularies and the topic model's kernels", err=True)
    pipeline = CuriosityPipeline(resolved, seed)
    warm_up(resolved)
    prepare_folder(out, resolved, seed)
    log = JsonLines(out / "log.jsonl")
    sim_map = None if map_data is None else map_data.config.name
    log.write("start", seed=seed, camera=camera, sim_map=sim_map, serial=port, dry_run=port is None)
    robot = None
    try:
        if port is not None:
            timing = LinkTiming(d.hello_timeout, d.ack_timeout, d.resends, d.keepalive)
            robot = RobotLink.open(port, baud or d.baud, timing, log=log.write)
            typer.echo(f"connected to {robot.robot_name or 'the robot'} on {port}", err=True)
            log.write("hello", robot=robot.robot_name)
        elif start_pose is not None:
            robot = cameras.LockstepRobot(Body(map_data.image.shape[:2], d.sim_metres_per_pixel, start_pose), d.sim_frame_interval)
        if camera == "sim":
            # a lockstep robot moves only when the loop commands it: no wall-clock frame period
            interval = 0.0 if port is None else d.sim_frame_interval
            source = cameras.SimCamera(
                map_data.image, d.sim_metres_per_pixel, (d.sim_view_rows, d.sim_view_cols), robot, interval, d.hello_timeout
            )

        def progress(number, decision):
            if number % 25 == 0:
                c = decision.command
                typer.echo(
                    f"frame {number}: target (row {decision.target[0]}, col {decision.target[1]}), "
                    f"surge {c.surge:+.2f} m/s, yaw {c.yaw_rate:+.2f} rad/s",
                    err=True,
                )

        outputs = Outputs(out, video_out, png_every)
        outcome = run(pipeline, source, robot, outputs, log, max_frames=max_frames, stop=stop, on_frame=progress)
    except BaseException as exc:
        if not log.ended:
            # run() closes both and logs its end itself; this covers a failure before its loop
            if source is not None:
                source.close()
            if robot is not None:
                robot.close()
            log.write("end", outcome=None, error=" ".join(str(exc).split()) or type(exc).__name__, frames=0)
        raise
    finally:
        log.close()
    return outcome, out


@app.command("simrobot")
def simrobot(
    map_name: str = typer.Option(..., "--map", help="The map the robot moves over (name or dataset YAML)."),
    start: str = typer.Option(None, "--start", metavar="ROW,COL", help=_START_HELP),
    heading_deg: float = typer.Option(0.0, "--heading-deg", callback=_finite, help="Start heading, degrees clockwise from the map's +col axis."),
    noise: str = typer.Option("", "--noise", metavar="KIND=RATE,...", help="Line noise on what the robot sends: garbage, checksum, truncate, drop-ack, each a rate 0..1."),
    seed: int = typer.Option(None, "--seed", min=0, help="Seed of the noise; default the config's seed."),
    estop_after: float = typer.Option(None, "--estop-after", min=0, metavar="SECONDS", callback=_finite, help="Send ESTOP this long after the first VEL."),
    link: Path = typer.Option(None, "--link", help="Also make this symlink to the pseudo-terminal (a fixed name for scripts)."),
    log_file: Path = typer.Option(None, "--log", help="Write the robot's events (frames received, watchdog, noise) as JSON Lines."),
    config: Path = typer.Option(CONFIG_DIR / "paper-grid.yaml", "--config", help=_CONFIG_HELP),
    overrides: list[str] = typer.Option([], "--set", metavar="KEY=VALUE", help="Override a config key, e.g. --set drive.watchdog=2."),
) -> None:
    """A simulated robot on a pseudo-terminal, for `curiosity drive --camera sim`.

    Prints the pseudo-terminal's path, then serves the robot side of the protocol until Ctrl-C.
    """
    import math
    import os

    from curiosity_cli.config import load_config
    from curiosity_cli.data import load_map
    from curiosity_cli.drive.driver import StopRequest, stopping_on_signals
    from curiosity_cli.drive.jsonlines import JsonLines
    from curiosity_cli.drive.sim import Body, Pose
    from curiosity_cli.drive.simrobot import Noise, SimRobot, open_pty
    from curiosity_cli.files import display_path

    resolved = load_config(config, overrides)
    rates = Noise.parse(noise)
    map_data = load_map(map_name)
    shape = map_data.image.shape[:2]
    row, col = _parse_start(start, shape)
    d = resolved.drive
    mpp = d.sim_metres_per_pixel
    body = Body(shape, mpp, Pose(col * mpp, row * mpp, math.radians(heading_deg)))
    events = JsonLines(log_file) if log_file is not None else None
    master, slave, path = open_pty()
    try:
        if link is not None:
            if link.is_symlink():
                link.unlink()
            link.symlink_to(path)
        typer.echo(path)
        typer.echo(
            f"simrobot: {map_data.config.name} ({shape[0]} x {shape[1]} px at {mpp:g} m/px), start row {row:.0f} "
            f"col {col:.0f}, heading {heading_deg:g} deg; connect with\n"
            f"  curiosity drive --serial {display_path(link) if link else path} --camera sim --sim-map {map_name}",
            err=True,
        )
        robot = SimRobot(
            body, state_rate=d.state_rate, watchdog=d.watchdog, noise=rates,
            seed=resolved.seed if seed is None else seed, estop_after=estop_after,
            log=events.write if events else (lambda event, **fields: None),
        )
        with stopping_on_signals(StopRequest()) as stop:
            robot.serve(master, lambda: stop.signal is not None)
        typer.echo(f"simrobot: stopped by {stop.signal}", err=True)
    finally:
        os.close(master)
        os.close(slave)
        if link is not None and link.is_symlink():
            link.unlink()
        if events is not None:
            events.close()
