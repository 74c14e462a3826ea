"""The robot's commands as functions: ``drive`` (and its ``--timeline``) and ``simrobot``; a drive's frames read back
(``open_mission``)."""

from __future__ import annotations

import math
import numbers
import typing
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

from curiosity_cli.api.arguments import (
    boolean, callback, folder_argument, name_or_path, name_text, optional_count, optional_path,
)
from curiosity_cli.api.pipeline import Config, load
from curiosity_cli.errors import ParameterError, UsageError

if typing.TYPE_CHECKING:
    import pandas as pd

    from curiosity_cli.drive.driver import Outcome
    from curiosity_cli.maps.map_data import MapData

#: The config whose model, words and drive sections (and seed) the robot uses by default.
ROBOT_CONFIG = "paper-grid"


class RobotStart(NamedTuple):
    """Where :func:`simrobot`'s robot starts, and on what."""

    map_data: MapData
    row: float
    col: float
    heading_deg: float
    metres_per_pixel: float


def _finite(name: str, value: float | None) -> None:
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ParameterError(f"{name}: got {value!r} ({type(value).__name__}), expected a number")
    if not math.isfinite(value):
        raise UsageError(f"{name}: got {value}, expected a finite number", parameter=name)


def _clock(clock) -> str:
    """``clock``: a name of :data:`~curiosity_cli.drive.timeline.CLOCKS`."""
    from curiosity_cli.drive.timeline import CLOCKS

    if not isinstance(clock, str) or clock not in CLOCKS:
        raise ParameterError(f"clock: got {clock!r}, expected one of {', '.join(CLOCKS)}")
    return clock


def _start(start: tuple[float, float] | None, shape: tuple[int, int]) -> tuple[float, float]:
    """``start`` (row, col) in map pixels, the map's centre without it; refused unless inside the map."""
    if start is None:
        return shape[0] / 2, shape[1] / 2
    _check_start(start)
    row, col = start
    if not (0 <= row <= shape[0] and 0 <= col <= shape[1]):
        raise UsageError(
            f"start: got {row:g},{col:g}, expected a point inside the map ({shape[0]} x {shape[1]} px)", parameter="start"
        )
    return row, col


def _check_start(start) -> None:
    """``start`` is a (row, col) pair of finite numbers, or None."""
    if start is None:
        return
    if not isinstance(start, (tuple, list)) or len(start) != 2:
        raise ParameterError(f"start: got {start!r} ({type(start).__name__}), expected (row, col) in map pixels")
    for value in start:
        _finite("start", value)


def drive(
    *, serial: str | None = None, baud: int | None = None, dry_run: bool = False, camera: str = "0",
    cmd_vel: str | None = None, cmd_vel_stamped: bool = False, ros_domain_id: int | None = None,
    topic: str | None = None, odom_topic: str | None = None, foxglove: int | None = None, sim_map: str | None = None, start: tuple[float, float] | None = None,
    heading_deg: float | None = None, config: Config = ROBOT_CONFIG, overrides: typing.Iterable[str] = (),
    seed: int | None = None, out: Path | None = None, force: bool = False, clock: str = "bag", strict: bool = False,
    video_out: Path | None = None, png_every: int = 0, max_frames: int | None = None,
    on_status: Callable[[str], None] = lambda line: None, on_frame=lambda frame_number, decision: None,
    on_replay: Callable[[str, int], None] = lambda description, frames: None,
) -> tuple[Outcome, Path]:
    """``curiosity drive``: steer a robot towards what its camera finds most curious, until the camera ends,
    ``max_frames``, ESTOP, SIGINT or SIGTERM (paper section 5.2). Call it from the main thread.

    Parameters
    ----------
    serial : str, optional
        The robot's serial device or pyserial URL; default the config's ``drive.port``.
    dry_run : bool
        No serial port: commands are computed and logged, not sent (with
        ``camera="sim"`` the robot is simulated in this process).
    camera : str
        A device index, a video file, a stream URL, a recorded bag, a ROS 2 image topic ``ros2:/TOPIC``, or ``sim``.
    cmd_vel : str, optional
        A ROS 2 robot's velocity topic, the robot instead of ``serial`` (the config's ``drive.port`` is not used).
    ros_domain_id : int, optional
        With a ROS 2 camera or ``cmd_vel``: the ROS domain, 0..232; default ``ROS_DOMAIN_ID``, else 0.
    sim_map : str, optional
        With ``camera="sim"`` (and only then): the simulated robot's map.
    start, heading_deg : optional
        With ``dry_run`` and ``camera="sim"``: the start (row, col) in map pixels (default
        the map's centre) and heading, degrees clockwise from the map's +col axis.
    seed : int, optional
        Of the topic models; default the config's.

    The other arguments are :func:`~curiosity_cli.drive.session.drive_session`'s.

    Returns
    -------
    (Outcome, Path)
        How the drive ended, and its run folder.

    Raises
    ------
    UsageError
        Arguments that do not go together, naming them.
    """
    from curiosity_cli.checks import check_int
    from curiosity_cli.config import MAX_BAUD
    from curiosity_cli.drive.session import drive_session
    from curiosity_cli.maps.map_data import load_map

    _finite("heading_deg", heading_deg)
    _check_start(start)
    on_status, on_frame = callback(on_status, "on_status"), callback(on_frame, "on_frame")
    on_replay = callback(on_replay, "on_replay")
    serial = None if serial is None else name_text(serial, "serial")
    topic = None if topic is None else name_text(topic, "topic")
    sim_map = None if sim_map is None else name_or_path(sim_map, "sim_map")
    png_every = check_int("png_every", png_every, 0)
    dry_run, force, strict = boolean(dry_run, "dry_run"), boolean(force, "force"), boolean(strict, "strict")
    clock = _clock(clock)
    out, video_out = optional_path(out, "out"), optional_path(video_out, "video_out")
    seed, max_frames = optional_count(seed, "seed", 0), optional_count(max_frames, "max_frames")
    baud = None if baud is None else check_int("baud", baud, 1, MAX_BAUD)
    foxglove = optional_count(foxglove, "foxglove", 0)
    if foxglove is not None and foxglove > 65535:
        raise UsageError(f"foxglove: got {foxglove}, expected a port 0..65535 (0: any free one)", parameter="foxglove")
    if odom_topic is not None:
        odom_topic = name_or_path(odom_topic, "odom_topic")
    # a device index may come as the int it is
    camera = str(camera) if isinstance(camera, int) and not isinstance(camera, bool) else name_or_path(camera, "camera")
    if dry_run and serial is not None:
        raise UsageError("dry_run: `dry_run` sends nothing; leave out `serial`", parameter="dry_run")
    _check_ros(camera, cmd_vel, cmd_vel_stamped, ros_domain_id, serial=serial, dry_run=dry_run)
    if (camera == "sim") != (sim_map is not None):
        raise UsageError("sim_map: `camera` sim and `sim_map` go together", parameter="sim_map")
    if (start is not None or heading_deg is not None) and not (dry_run and camera == "sim"):
        parameter = "start" if start is not None else "heading_deg"
        raise UsageError(
            f"{parameter}: only a dry run simulates the robot here; give the start to `curiosity simrobot`",
            parameter=parameter,
        )
    resolved = load(config, overrides)
    port = None if cmd_vel is not None else serial or resolved.drive.port
    if not dry_run and port is None and cmd_vel is None:
        raise UsageError(
            "serial: give the robot's port with `serial` (or drive.port in the config), or `dry_run`", parameter="serial"
        )
    map_data, start_at = None, None
    if sim_map is not None:
        map_data = load_map(sim_map)
        if dry_run:
            if resolved.drive.sim_frame_interval <= 0:
                raise UsageError(
                    "overrides: a dry run with `camera` sim needs drive.sim_frame_interval > 0 (the simulated time per frame)",
                    parameter="overrides",
                )
            start_at = _start(start, map_data.image.shape[:2])
    return drive_session(
        resolved, seed=resolved.seed if seed is None else seed, camera=camera, topic=topic, odom_topic=odom_topic,
        foxglove=foxglove, cmd_vel=cmd_vel, cmd_vel_stamped=cmd_vel_stamped, ros_domain_id=ros_domain_id,
        port=None if dry_run else port, baud=baud, sim_map=map_data, start=start_at, heading_deg=heading_deg or 0.0,
        out=out, force=force, strict=strict, clock=clock, video_out=video_out, png_every=png_every, max_frames=max_frames,
        on_status=on_status, on_frame=on_frame, on_replay=on_replay,
    )


def _check_ros(camera: str, cmd_vel, cmd_vel_stamped, ros_domain_id, *, serial: str | None, dry_run: bool) -> None:
    """The ROS 2 arguments of :func:`drive`: each of the right type, and only with what it goes with."""
    from curiosity_cli.checks import check_int
    from curiosity_cli.drive.ros2 import MAX_DOMAIN_ID, PREFIX, is_ros2, ros_topic

    if is_ros2(camera):  # names checked before any work: a bad one found later leaves a run folder behind
        ros_topic(camera[len(PREFIX):], "camera", PREFIX)
    if cmd_vel is not None:
        ros_topic(name_text(cmd_vel, "cmd_vel"), "cmd_vel")
        if serial is not None:
            raise UsageError("cmd_vel: `cmd_vel` is the robot, a ROS 2 one; leave out `serial`", parameter="cmd_vel")
        if dry_run:
            raise UsageError("dry_run: `dry_run` sends nothing; leave out `cmd_vel`", parameter="dry_run")
        if camera == "sim":
            raise UsageError(
                "cmd_vel: `camera` sim views the simulated robot, not a ROS 2 one; give the robot's camera",
                parameter="cmd_vel",
            )
    if boolean(cmd_vel_stamped, "cmd_vel_stamped") and cmd_vel is None:
        raise UsageError("cmd_vel_stamped: goes with `cmd_vel`, the topic it stamps", parameter="cmd_vel_stamped")
    if ros_domain_id is not None:
        check_int("ros_domain_id", ros_domain_id, 0, MAX_DOMAIN_ID)
        if cmd_vel is None and not is_ros2(camera):
            raise UsageError(
                "ros_domain_id: goes with a ROS 2 `camera` (ros2:/TOPIC) or `cmd_vel`; neither is given",
                parameter="ros_domain_id",
            )


def redraw_timeline(folder: Path, clock: str = "bag") -> list[Path]:
    """``curiosity drive --timeline``: a run's figures drawn again from its run folder (a replay's surprise timeline,
    the trajectory where frames have a pose); the files written. As :func:`~curiosity_cli.drive.session.redraw_timeline`."""
    from curiosity_cli.drive.session import redraw_timeline as redraw

    return redraw(folder_argument(folder), _clock(clock))


def simrobot(
    map_name: str, *, start: tuple[float, float] | None = None, heading_deg: float = 0.0, noise: str = "",
    seed: int | None = None, estop_after: float | None = None, link: Path | None = None, log_file: Path | None = None,
    config: Config = ROBOT_CONFIG, overrides: typing.Iterable[str] = (),
    on_ready: Callable[[str, RobotStart], None] = lambda path, start: None,
) -> str:
    """``curiosity simrobot``: a simulated robot on a new pseudo-terminal, served until SIGINT or SIGTERM.

    Parameters
    ----------
    map_name : str
        The map the robot moves over (name or dataset YAML).
    start : (float, float), optional
        (row, col) in map pixels; default the map's centre.
    noise : str
        Line noise on what the robot sends: ``KIND=RATE,...`` of garbage, checksum,
        truncate and drop-ack, each a rate 0..1.
    seed : int, optional
        Of the noise; default the config's.
    on_ready : callable
        ``on_ready(path, start)`` once the pseudo-terminal at ``path`` is open.

    The other arguments are :func:`~curiosity_cli.drive.session.simrobot_session`'s.

    Returns
    -------
    str
        The signal that stopped it: ``SIGINT`` or ``SIGTERM``.
    """
    from curiosity_cli.drive.session import simrobot_session
    from curiosity_cli.drive.simrobot import Noise
    from curiosity_cli.maps.map_data import load_map

    _finite("heading_deg", heading_deg)
    _finite("estop_after", estop_after)
    on_ready = callback(on_ready, "on_ready")
    map_name, seed = name_or_path(map_name, "map_name"), optional_count(seed, "seed", 0)
    link, log_file = optional_path(link, "link"), optional_path(log_file, "log_file")
    if not isinstance(noise, str):
        raise ParameterError(f"noise: got {noise!r} ({type(noise).__name__}), expected KIND=RATE,... e.g. 'garbage=0.05'")
    resolved = load(config, overrides)
    rates = Noise.parse(noise)
    map_data = load_map(map_name)
    row, col = _start(start, map_data.image.shape[:2])
    robot = RobotStart(map_data, row, col, heading_deg, resolved.drive.sim_metres_per_pixel)
    return simrobot_session(
        resolved, map_data, start=(row, col), heading_deg=heading_deg, noise=rates,
        seed=resolved.seed if seed is None else seed, estop_after=estop_after, link=link, log_file=log_file,
        on_ready=lambda path: on_ready(path, robot),
    )


def open_mission(folder: Path | str) -> pd.DataFrame:
    """A drive's frames, one row per frame, from its run folder: ``frames.parquet``
    (:mod:`~curiosity_cli.drive.frames_table`) where it was made from the run's log as it is, else its
    ``log.jsonl``, with a note saying why (:func:`~curiosity_cli.drive.frames_table.read_frames_table`).

    The frame's times are integer nanoseconds (``time_ns``: the bag time of a replay, the
    host's clock live); ``surprise`` is the mean topic perplexity of its image cells, with
    its parts, the refinement it got, its command and its pose (``x``, ``y``, ``z``,
    ``yaw``; missing without one). ``attrs`` holds the run's ``config`` and ``provenance``
    (as read from their YAML files) and its ``folder``.

    Raises
    ------
    CuriosityError
        No ``log.jsonl`` in ``folder`` (not a drive's run folder), a table or log that
        cannot be read, naming the file.
    """
    import pandas as pd
    import yaml

    from curiosity_cli.drive.driver import RUN_LOG
    from curiosity_cli.drive.frames_table import read_frames_table
    from curiosity_cli.errors import CuriosityError
    from curiosity_cli.files import display_path

    folder = folder_argument(folder)
    if not (folder / RUN_LOG).is_file():
        raise CuriosityError(f"{display_path(folder / RUN_LOG)}: not found; give a run folder of `curiosity drive`")
    table = read_frames_table(folder)
    for name in ("config", "provenance"):
        path = folder / f"{name}.yaml"
        try:
            table.attrs[name] = yaml.safe_load(path.read_text()) if path.is_file() else None
        except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
            raise CuriosityError(f"{display_path(path)}: cannot be read ({' '.join(str(exc).split())})") from None
    table.attrs["folder"] = str(folder)
    return table
