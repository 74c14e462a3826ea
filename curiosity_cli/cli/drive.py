"""``curiosity drive`` (steer a robot with live curiosity) and ``curiosity simrobot`` (a robot to steer)."""

from __future__ import annotations

import enum
from pathlib import Path

import typer

from curiosity_cli.cli.app import app, usage_errors

_CONFIG_HELP = "Experiment config whose model, words and drive sections (and seed) to use: a YAML file or a shipped config's name."
_START_HELP = "Start position ROW,COL in map pixels; default the map's centre."


def _parse_start(text: str | None) -> tuple[float, float] | None:
    """``--start ROW,COL`` as (row, col) in map pixels; None without it."""
    if text is None:
        return None
    try:
        row, col = (float(part) for part in text.split(","))
    except ValueError:
        raise typer.BadParameter(f"got {text!r}, expected ROW,COL in map pixels, e.g. 1250,1250", param_hint="--start") from None
    return row, col


#: The options `drive --timeline` takes: it draws from a run folder's log, and would ignore any other.
_TIMELINE_OPTIONS = ("timeline", "clock")


def _refuse_driving_options(ctx: typer.Context) -> None:
    """With ``--timeline``, refuse the first driving option given (on the command line or from the environment):
    ignored in silence, ``--out`` or ``--camera`` would seem to have been used."""
    for param in ctx.command.params:
        source = ctx.get_parameter_source(param.name)
        given = source is not None and source.name in ("COMMANDLINE", "ENVIRONMENT")
        if given and param.name not in _TIMELINE_OPTIONS:
            raise typer.BadParameter(
                "goes with a drive, not --timeline (which draws a run's timeline again, with --clock alone)",
                param_hint=param.opts[0],
            )


class Clock(str, enum.Enum):
    """The clock of a replay's timeline (``curiosity_cli.drive.timeline.CLOCKS``)."""

    bag = "bag"
    header = "header"


@app.command("drive")
@usage_errors
def drive(
    ctx: typer.Context,
    serial: str = typer.Option(None, "--serial", metavar="PORT", help="Serial device or pyserial URL of the robot; default the config's drive.port."),
    baud: int = typer.Option(None, "--baud", min=1, help="Serial speed; default the config's drive.baud (115200)."),
    dry_run: bool = typer.Option(False, "--dry-run", help="No serial port: commands are computed and logged, not sent (with --camera sim the robot is simulated in this process, one frame period per command)."),
    camera: str = typer.Option("0", "--camera", help="A device index, a video file, a stream URL, a recorded bag (ROS 1 .bag, ROS 2 bag folder, .mcap; needs the bags extra), a live ROS 2 image topic ros2:/TOPIC (CompressedImage if it ends in /compressed, else Image; needs the ros2 extra), or 'sim' for the simulated robot's camera."),
    cmd_vel: str = typer.Option(None, "--cmd-vel", metavar="TOPIC", help="Steer a ROS 2 robot instead of --serial: publish each command as geometry_msgs/msg/Twist on TOPIC (e.g. /cmd_vel), and each frame's surprise and target on /curiosity/surprise and /curiosity/target; needs the ros2 extra."),
    cmd_vel_stamped: bool = typer.Option(False, "--cmd-vel-stamped", help="With --cmd-vel: publish geometry_msgs/msg/TwistStamped instead."),
    ros_domain_id: int = typer.Option(None, "--ros-domain-id", min=0, max=232, help="With a ros2: camera or --cmd-vel: the ROS 2 domain; default ROS_DOMAIN_ID, else 0. The network is Cyclone DDS's: CYCLONEDDS_URI."),
    topic: str = typer.Option(None, "--topic", help="With a bag: its image topic; may be left out when it has one."),
    odom_topic: str = typer.Option(None, "--odom-topic", help="With a bag: its nav_msgs/msg/Odometry topic, whose nearest pose in time each frame gets (frames.parquet, mission.mcap, trajectory.png); default the bag's only one. With a ros2: camera: the robot's odometry topic, matched by header stamps."),
    foxglove: int = typer.Option(None, "--foxglove", min=0, max=65535, metavar="PORT", help="Serve the drive live to Foxglove over its WebSocket protocol on localhost at PORT (8765 is Foxglove's default; 0: any free one, printed)."),
    sim_map: str = typer.Option(None, "--sim-map", help="With --camera sim: the map the simulated robot is on (name or dataset YAML)."),
    start: str = typer.Option(None, "--start", metavar="ROW,COL", help="With --dry-run --camera sim: start position ROW,COL in map pixels; default the map's centre."),
    heading_deg: float = typer.Option(None, "--heading-deg", help="With --dry-run --camera sim: start heading, degrees clockwise from the map's +col axis (default 0)."),
    config: Path = typer.Option("paper-grid", "--config", help=_CONFIG_HELP),
    overrides: list[str] = typer.Option([], "--set", metavar="KEY=VALUE", help="Override a config key, e.g. --set drive.gamma=0.5."),
    seed: int = typer.Option(None, "--seed", min=0, help="Seed of the topic models; default the config's seed."),
    out: Path = typer.Option(None, "--out", help="Run folder (log.jsonl, config, provenance, frames/), new or empty; default a new results/drive/<date-time>."),
    force: bool = typer.Option(False, "--force", help="With --out: replace the earlier run in that folder."),
    timeline: Path = typer.Option(None, "--timeline", metavar="RUN_FOLDER", help="Instead of driving, draw a run's figures again from its run folder: a replay's surprise timeline (the bag must still be where it was) and the trajectory where frames have a pose (a drive stopped by Ctrl-C leaves them out)."),
    clock: Clock = typer.Option(Clock.bag, "--clock", help="A replay's timeline against the bag's record times (bag) or the messages' header stamps (header); both are logged."),
    strict: bool = typer.Option(False, "--strict", help="Stop a replay at its first message that holds no usable frame (damaged or empty), instead of skipping it with a `skipped` record in the log."),
    video_out: Path = typer.Option(None, "--video-out", help="Write the annotated video here (.mp4, .avi or .mkv)."),
    png_every: int = typer.Option(0, "--png-every", min=0, metavar="N", help="Write an annotated PNG every N frames into <out>/frames/."),
    max_frames: int = typer.Option(None, "--max-frames", min=1, help="Stop after this many frames."),
) -> None:
    """Steer a robot towards what its camera finds most curious (paper section 5.2).

    Image cells are scored by topic perplexity in a live topic model, with a decaying memory.

    Protocol: curiosity_cli/drive/PROTOCOL.md. Ctrl-C sends STOP, then exits with 130.
    """
    from curiosity_cli import api
    from curiosity_cli.files import display_path

    if timeline is not None:
        _refuse_driving_options(ctx)
        for path in api.redraw_timeline(timeline, clock.value):
            typer.echo(f"wrote {display_path(path)}")
        return
    bar = api.Progress()
    replaying = []  # a bag says how many frames it holds before the first (on_replay)

    def replay(description: str, frames: int) -> None:
        replaying.append(True)
        bar.stage(description, frames)

    def progress(number, decision):
        bar.advance()
        if number % 25 == 0 and not replaying:  # a bag's frames get a bar; a live camera's a line every 25 frames
            c = decision.command
            typer.echo(
                f"frame {number}: target (row {decision.target[0]}, col {decision.target[1]}), "
                f"surge {c.surge:+.2f} m/s, yaw {c.yaw_rate:+.2f} rad/s",
                err=True,
            )

    with bar:
        outcome, folder = api.drive(
            serial=serial, baud=baud, dry_run=dry_run, camera=camera, cmd_vel=cmd_vel, cmd_vel_stamped=cmd_vel_stamped,
            ros_domain_id=ros_domain_id, topic=topic, odom_topic=odom_topic,
            foxglove=foxglove, sim_map=sim_map,
            start=_parse_start(start), heading_deg=heading_deg, config=config, overrides=overrides, seed=seed, out=out,
            force=force, clock=clock.value, strict=strict, video_out=video_out, png_every=png_every, max_frames=max_frames,
            on_status=lambda line: typer.echo(line, err=True), on_frame=progress, on_replay=replay,
        )
    stopped = {True: "; STOP acknowledged", False: "; STOP sent, not acknowledged", None: ""}[outcome.stop_acked]
    skipped = f"; {outcome.skipped} damaged messages skipped (`skipped` in the log)" if outcome.skipped else ""
    typer.echo(f"drove {outcome.frames} frames: {outcome.detail}{stopped}{skipped}; log in {display_path(outcome.log)}")
    if outcome.products:
        typer.echo(f"wrote {', '.join(outcome.products)} in {display_path(folder)}")
    if video_out is not None:
        typer.echo(f"wrote {display_path(video_out)}")
    if outcome.reason in _SIGNAL_EXIT:
        raise typer.Exit(_SIGNAL_EXIT[outcome.reason])


#: The exit code of a command stopped by a signal, as a shell reports it: 128 + its number.
_SIGNAL_EXIT = {"SIGINT": 130, "SIGTERM": 143}


@app.command("simrobot")
@usage_errors
def simrobot(
    map_name: str = typer.Option(..., "--map", help="The map the robot moves over (name or dataset YAML)."),
    start: str = typer.Option(None, "--start", metavar="ROW,COL", help=_START_HELP),
    heading_deg: float = typer.Option(0.0, "--heading-deg", help="Start heading, degrees clockwise from the map's +col axis."),
    noise: str = typer.Option("", "--noise", metavar="KIND=RATE,...", help="Line noise on what the robot sends: garbage, checksum, truncate, drop-ack, each a rate 0..1."),
    seed: int = typer.Option(None, "--seed", min=0, help="Seed of the noise; default the config's seed."),
    estop_after: float = typer.Option(None, "--estop-after", min=0, metavar="SECONDS", help="Send ESTOP this long after the first VEL."),
    link: Path = typer.Option(None, "--link", help="Also make this symlink to the pseudo-terminal (a fixed name for scripts)."),
    log_file: Path = typer.Option(None, "--log", help="Write the robot's events (frames received, watchdog, noise) as JSON Lines."),
    config: Path = typer.Option("paper-grid", "--config", help=_CONFIG_HELP),
    overrides: list[str] = typer.Option([], "--set", metavar="KEY=VALUE", help="Override a config key, e.g. --set drive.watchdog=2."),
) -> None:
    """A simulated robot on a pseudo-terminal, for `curiosity drive --camera sim`.

    Prints the pseudo-terminal's path, then serves the robot side of the protocol until Ctrl-C.
    """
    from curiosity_cli import api
    from curiosity_cli.files import display_path

    def ready(path: str, robot) -> None:
        shape = robot.map_data.image.shape[:2]
        typer.echo(path)
        typer.echo(
            f"simrobot: {robot.map_data.config.name} ({shape[0]} x {shape[1]} px at {robot.metres_per_pixel:g} m/px), "
            f"start row {robot.row:.0f} col {robot.col:.0f}, heading {robot.heading_deg:g} deg; connect with\n"
            f"  curiosity drive --serial {display_path(link) if link else path} --camera sim --sim-map {map_name}",
            err=True,
        )

    stopped_by = api.simrobot(
        map_name, start=_parse_start(start), heading_deg=heading_deg, noise=noise, seed=seed, estop_after=estop_after,
        link=link, log_file=log_file, config=config, overrides=overrides, on_ready=ready,
    )
    typer.echo(f"simrobot: stopped by {stopped_by}", err=True)
    raise typer.Exit(_SIGNAL_EXIT[stopped_by])
