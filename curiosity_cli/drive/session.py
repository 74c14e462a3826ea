"""Sessions of the two programs, ``curiosity drive`` and ``curiosity simrobot``: what they open, run and close.

:func:`drive_session` opens the camera (an OpenCV source, a bag, a ROS 2 topic or the simulated
camera), the robot (the serial link, a ROS 2 robot's ``cmd_vel``, an in-process simulated robot
for a dry run on a map, or none), the run folder and its log, runs
:func:`~curiosity_cli.drive.driver.run`, and closes what it opened whatever happens; a failure
before the loop starts is logged as the run's ``end`` row too, so every log ends with one.

:func:`simrobot_session` puts a :class:`~curiosity_cli.drive.simrobot.SimRobot` on a new
pseudo-terminal and serves it until it is told to stop, then closes the terminal and
removes its symlink.

Both route SIGINT and SIGTERM to a :class:`~curiosity_cli.drive.driver.StopRequest` while
they run, so a robot is stopped before the program ends: call them from the main thread.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import os
import re
from collections.abc import Callable
from datetime import datetime
from pathlib import Path

from curiosity_cli.config import ExperimentConfig
from curiosity_cli.maps.map_data import MapData
from curiosity_cli.drive import camera as cameras
from curiosity_cli.drive.driver import RUN_LOG, Outcome, Outputs, StopRequest, prepare_folder, run, stopping_on_signals
from curiosity_cli.drive.frames_table import FRAMES_CSV, FRAMES_PARQUET
from curiosity_cli.drive.jsonlines import JsonLines
from curiosity_cli.drive.link import LinkTiming, RobotLink
from curiosity_cli.drive.mission import LAYOUT_FILE, MISSION_FILE, PERPLEXITY, MissionFile, check_live_port, write_layout
from curiosity_cli.drive.overlay import check_video_out
from curiosity_cli.drive.pipeline import CuriosityPipeline, warm_up
from curiosity_cli.drive.sim import Body, Pose
from curiosity_cli.drive.simrobot import Noise, SimRobot, open_pty
from curiosity_cli.drive.trajectory import TRAJECTORY_FILE
from curiosity_cli.errors import CuriosityError, ParameterError
from curiosity_cli.experiment.layout import ExperimentFolder
from curiosity_cli.files import display_path
from curiosity_cli.paths import DEFAULT_RESULTS


def open_camera(
    camera: str, topic: str | None = None, odom_topic: str | None = None, ros_domain_id: int | None = None,
    stopped=lambda: False,
):
    """A ROS 2 image topic's frames (``ros2:/TOPIC``, :class:`~curiosity_cli.drive.ros2.Ros2Camera`), a bag's
    (:class:`~curiosity_cli.drive.bags.BagCamera`) or an OpenCV source's.

    Raises
    ------
    CameraError
        As the camera.
    """
    from curiosity_cli.drive.bags import BagCamera, is_bag
    from curiosity_cli.drive.ros2 import PREFIX, Ros2Camera, is_ros2

    if is_ros2(camera):
        return Ros2Camera(camera[len(PREFIX):], odom_topic, ros_domain_id, stopped)
    if is_bag(camera):
        return BagCamera(camera, topic, odom_topic, outputs=(PERPLEXITY,))
    return cameras.OpenCVCamera(camera)


def check_replay_options(
    camera: str, *, topic: str | None = None, odom_topic: str | None = None, strict: bool = False, clock: str = "bag"
) -> None:
    """Refuse a bag replay's options for a ``camera`` that is not a bag (a device, a video, a stream, ``sim``); a
    ROS 2 topic (``ros2:/TOPIC``) takes ``odom_topic`` alone.

    Each would be ignored there: a video has no topics, no damaged messages to skip and no
    header stamps, so a run would not do what the command says.

    Raises
    ------
    ParameterError
        Naming the first such option given.
    """
    from curiosity_cli.drive.bags import is_bag
    from curiosity_cli.drive.ros2 import is_ros2

    ros = is_ros2(camera)
    if camera != "sim" and not ros and is_bag(camera):
        return
    not_a_bag = f"camera {camera!r} is not a bag"
    if topic is not None:
        named = "; a ROS 2 camera's topic is the camera's own name" if ros else "; a topic names a bag's images"
        raise ParameterError(f"topic: got {topic!r}, but {not_a_bag}{named}", parameter="topic")
    if odom_topic is not None and not ros:
        raise ParameterError(
            f"odom_topic: got {odom_topic!r}, but {not_a_bag} or a ROS 2 topic; it names their odometry",
            parameter="odom_topic",
        )
    if clock != "bag":
        raise ParameterError(
            f"clock: got {clock!r}, but {not_a_bag}; a replay's timeline reads a bag's clocks", parameter="clock"
        )
    if strict:
        raise ParameterError(
            f"strict: {not_a_bag}; strict stops a replay at a bag's first damaged message", parameter="strict"
        )


def check_run_folder(out: Path | None, *, force: bool = False) -> None:
    """Refuse ``out`` as a run's folder when it holds anything: an earlier run's files would mix with the new ones.

    With ``force``, a folder that holds an earlier run (its :data:`RUN_LOG`) may be
    replaced, unless what that run wrote holds a path of the user's
    (:func:`earlier_run_files`); a folder of anything else never is. None (a new folder)
    is always fine.

    Raises
    ------
    ParameterError
        Naming ``out``, what it holds, and what to do.
    """
    if out is None or not Path(out).exists():
        return
    out = Path(out)
    if not out.is_dir():
        raise ParameterError(f"out: {display_path(out)} is a file; give a new or empty folder for the run", parameter="out")
    held = sorted(p.name for p in out.iterdir() if p != ExperimentFolder(out).lock)
    if not held:
        return
    if (out / RUN_LOG).is_file():
        if force:
            earlier_run_files(out)  # refused now, before the camera and the model, if it holds a file of the user's
            return
        raise ParameterError(
            f"out: {display_path(out)} holds an earlier run ({RUN_LOG} and {len(held) - 1} more); give a new folder, "
            "or `force` to replace that run", parameter="out",
        )
    raise ParameterError(
        f"out: {display_path(out)} is not empty ({', '.join(held[:3])}{', ...' if len(held) > 3 else ''}) and holds no "
        "run; give a new or empty folder for the run", parameter="out",
    )


#: The files a drive writes at the top of its run folder (besides the folder lock).
RUN_FILES = (
    RUN_LOG, "config.yaml", "provenance.yaml", "timeline.png", "timeline.pdf", MISSION_FILE, LAYOUT_FILE, FRAMES_PARQUET,
    FRAMES_CSV, TRAJECTORY_FILE,
)

#: What a drive leaves for a reader, named on its last line: a replay's timeline, the mission file Foxglove
#: opens and its layout, the frames table, and the trajectory where frames have a pose.
PRODUCTS = ("timeline.png", MISSION_FILE, LAYOUT_FILE, FRAMES_PARQUET, TRAJECTORY_FILE)

#: Its folders of frames: ``png_every``'s annotated ones, and a replay's most surprising.
FRAME_FOLDERS = ("frames", "surprising")

#: A frame a run writes into :data:`FRAME_FOLDERS` (``frame-NNNNNN.png``), or the temporary file
#: a run killed while writing one leaves (:func:`~curiosity_cli.files.atomic_path`).
FRAME_FILE = re.compile(r"frame-\d{6,}\.png|\.frame-\d{6,}\.\w+\.tmp\.png")


def earlier_run_files(out: Path) -> list[Path]:
    """The files of the run in ``out`` that ``force`` replaces: :data:`RUN_FILES`, and the frames in :data:`FRAME_FOLDERS`.

    Everything is checked before anything is deleted: a user may keep notes beside a
    run, or link a folder of their own where a run writes its frames, and a replay
    into the folder must not take those with it.

    Raises
    ------
    ParameterError
        Naming the first path there that a run does not write: a symlink, a folder where
        a run writes a file, a file in a folder of frames that is not a frame.
    """
    files = []
    for name in RUN_FILES:
        path = out / name
        if path.is_symlink() or (path.exists() and not path.is_file()):
            raise _not_written_by_a_run(out, path)
        if path.exists():
            files.append(path)
    for name in FRAME_FOLDERS:
        folder = out / name
        if folder.is_symlink() or (folder.exists() and not folder.is_dir()):
            raise _not_written_by_a_run(out, folder)
        if not folder.exists():
            continue
        for path in sorted(folder.iterdir()):
            if path.is_symlink() or not path.is_file() or not FRAME_FILE.fullmatch(path.name):
                raise _not_written_by_a_run(out, path)
            files.append(path)
    return files


def _not_written_by_a_run(out: Path, path: Path) -> ParameterError:
    what = "a symlink" if path.is_symlink() else "a folder" if path.is_dir() else "a file"
    shown = os.path.join(display_path(path.parent), path.name)  # a symlink by its own name, not its target's
    return ParameterError(
        f"out: {shown} is {what} no run writes; `force` replaces only a run's own files: "
        f"move it out of {display_path(out)}, or give a new folder", parameter="out",
    )


@contextlib.contextmanager
def claimed_run_folder(out: Path | None, *, force: bool = False):
    """Make the run's folder and hold its lock while the run writes there; yield the folder.

    ``out``, or a new ``results/drive/<date-time>``. Runs started in the same second without
    ``out`` each get their own folder (``<date-time>-2``, ``-3``, ...): a folder is made here,
    atomically, never taken when it exists. ``out`` is checked as :func:`check_run_folder`,
    again once its lock is held; with ``force``, the earlier run's files
    (:func:`earlier_run_files`) are removed then, and nothing else: a file of the user's
    stays, and a folder of frames goes only if that leaves it empty. A second drive into
    the same folder while one runs is refused, naming the first (its process id).

    Raises
    ------
    FolderInUseError
        Another drive writes in ``out``.
    ParameterError
        As :func:`check_run_folder`.
    """
    from curiosity_cli.experiment.lock import working_in

    if out is not None:
        check_run_folder(out, force=force)
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        with working_in(out, "drive"):
            check_run_folder(out, force=force)  # what another drive may have written before this one held the lock
            for path in earlier_run_files(out):  # all checked before the first is deleted
                path.unlink()
            for name in FRAME_FOLDERS:
                folder = out / name
                if folder.is_dir() and not any(folder.iterdir()):
                    folder.rmdir()
            yield out
        return
    base = DEFAULT_RESULTS / "drive" / datetime.now().strftime("%Y%m%d-%H%M%S")
    base.parent.mkdir(parents=True, exist_ok=True)
    for n in range(1, 10_000):
        folder = base if n == 1 else base.with_name(f"{base.name}-{n}")
        try:
            folder.mkdir()
        except FileExistsError:
            continue
        with working_in(folder, "drive"):
            yield folder
        return
    raise CuriosityError(f"{display_path(base)}: 10,000 runs started this second; give --out")


def redraw_timeline(folder: Path, clock: str = "bag") -> list[Path]:
    """Draw a run's figures again from its run folder (``curiosity drive --timeline``): a replay's surprise timeline
    from its log, and the trajectory where its frames have a pose (a live drive's alone).

    The bag and topic come from the log's ``start`` record; the bag must still be where it was.
    ``clock``: ``bag`` or ``header`` (:func:`~curiosity_cli.drive.timeline.surprise_series`).

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    CuriosityError
        No log in ``folder``, a log that is not a replay's, or a bag that cannot be read.
    """
    import json

    log = Path(folder) / RUN_LOG
    try:
        first = log.read_text().split("\n", 1)[0]
        start = json.loads(first)
    except FileNotFoundError:
        raise CuriosityError(f"{display_path(log)}: not found; give a run folder of `curiosity drive`") from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise CuriosityError(f"{display_path(log)}: its first line is not a JSON record ({exc})") from None
    if not isinstance(start, dict) or start.get("event") != "start":
        raise CuriosityError(f"{display_path(log)}: not the log of a drive (no start record)")
    from curiosity_cli.drive.bags import bag_fingerprint, fingerprint_change
    from curiosity_cli.drive.frames_table import read_frames_table
    from curiosity_cli.drive.timeline import surprise_series
    from curiosity_cli.drive.trajectory import write_trajectory

    from curiosity_cli.drive.ros2 import is_ros2

    if not start.get("topic") or is_ros2(str(start.get("camera", ""))):  # a live drive: its trajectory alone
        trajectory = write_trajectory(Path(folder), read_frames_table(Path(folder)))
        if trajectory is None:
            raise CuriosityError(
                f"{display_path(log)}: not the log of a replayed bag, and its frames have no pose: nothing to draw"
            )
        return [trajectory]

    frames = surprise_series(log)["frame"].size
    if frames == 0:
        raise CuriosityError(f"{display_path(log)}: holds no frame of the replay (its start record alone); nothing to draw")
    # the frames drawn are read from the bag again: it must be the recording the log's surprise came from
    if isinstance(start.get("bag"), dict) and (change := fingerprint_change(start["bag"], bag_fingerprint(start["camera"]))):
        raise CuriosityError(
            f"{display_path(Path(start['camera']))}: not the bag {display_path(log)} replayed ({change}); "
            "put that recording back, or replay this one with `curiosity drive`"
        )
    written = _draw_timeline(Path(folder), start["camera"], start["topic"], f"{frames} frames", clock)
    trajectory = write_trajectory(Path(folder), read_frames_table(Path(folder)))
    return written + [trajectory] * (trajectory is not None)


def _draw_timeline(out: Path, bag: str, topic: str, what: str, clock: str = "bag") -> list[Path]:
    """A replay's surprise timeline (:mod:`~curiosity_cli.drive.timeline`), its frames read from the bag again."""
    from curiosity_cli.drive.bags import BagCamera
    from curiosity_cli.drive.timeline import write_timeline

    again = BagCamera(bag, topic)
    try:
        return write_timeline(out, again, f"{Path(bag).name}: {topic}, {what}", clock=clock)
    finally:
        again.close()


def _body(sim_map: MapData, start: tuple[float, float], heading_deg: float, config: ExperimentConfig) -> Body:
    """A simulated robot on ``sim_map`` at ``start`` (row, col in pixels), heading degrees clockwise from +col."""
    metres_per_pixel = config.drive.sim_metres_per_pixel
    pose = Pose.at_pixel(*start, math.radians(heading_deg), metres_per_pixel)
    return Body(sim_map.image.shape[:2], metres_per_pixel, pose)


def drive_session(
    config: ExperimentConfig,
    *,
    seed: int,
    camera: str,
    port: str | None,
    cmd_vel: str | None = None,
    cmd_vel_stamped: bool = False,
    ros_domain_id: int | None = None,
    topic: str | None = None,
    odom_topic: str | None = None,
    foxglove: int | None = None,
    baud: int | None = None,
    sim_map: MapData | None = None,
    start: tuple[float, float] | None = None,
    heading_deg: float = 0.0,
    out: Path | None = None,
    force: bool = False,
    strict: bool = False,
    clock: str = "bag",
    video_out: Path | None = None,
    png_every: int = 0,
    max_frames: int | None = None,
    on_status: Callable[[str], None] = lambda line: None,
    on_frame=lambda frame_number, decision: None,
    on_replay: Callable[[str, int], None] = lambda description, frames: None,
) -> tuple[Outcome, Path]:
    """Drive until the camera ends, ``max_frames``, ESTOP, SIGINT or SIGTERM, then close everything.

    Parameters
    ----------
    config : ExperimentConfig
        Its ``model``, ``words`` and ``drive`` sections are used.
    seed : int
        Seeds the stream's topic models.
    camera : str
        A device index, a video file, a stream URL, a recorded bag
        (:mod:`~curiosity_cli.drive.bags`), a ROS 2 image topic ``ros2:/TOPIC``
        (:mod:`~curiosity_cli.drive.ros2`), or ``sim`` for the simulated camera over ``sim_map``.
    port : str or None
        Serial device or pyserial URL of the robot; None for a dry run (commands are
        logged, not sent) or a ROS 2 robot (``cmd_vel``).
    cmd_vel : str, optional
        Instead of ``port``: a ROS 2 robot's velocity topic (``/cmd_vel``), each command a
        ``geometry_msgs/msg/Twist`` (:class:`~curiosity_cli.drive.ros2.Ros2Robot`, which also publishes each frame's
        surprise and target).
    cmd_vel_stamped : bool
        With ``cmd_vel``: ``geometry_msgs/msg/TwistStamped`` instead.
    ros_domain_id : int, optional
        The ROS domain of a ROS 2 camera and robot, 0..232; default ``ROS_DOMAIN_ID``, else 0.
    topic : str, optional
        With a bag: its image topic, which may be left out when it has one.
    odom_topic : str, optional
        With a bag: its ``nav_msgs/msg/Odometry`` topic that gives each frame its pose
        (:mod:`~curiosity_cli.drive.odometry`); default its only one, if it has one. With a
        ROS 2 camera: the robot's odometry topic, none by default. A serial robot's frames
        take their pose from its reported state.
    foxglove : int, optional
        Serve the mission live over Foxglove's WebSocket protocol on this localhost port
        while it runs (:mod:`~curiosity_cli.drive.mission`; 0: any free port).
    baud : int, optional
        Serial speed; default ``config.drive.baud``.
    sim_map : MapData, optional
        With ``camera="sim"``: the map the simulated robot is on.
    start : (float, float), optional
        A dry run on ``sim_map`` simulates the robot in this process, moved one
        ``drive.sim_frame_interval`` per command: its start (row, col) in map pixels,
        required then.
    heading_deg : float
        That robot's start heading, degrees clockwise from the map's +col axis.
    out : Path, optional
        The run folder (``log.jsonl``, ``config.yaml``, ``provenance.yaml``, ``frames/``,
        and at the end ``mission.mcap``, ``frames.parquet`` and ``.csv``, and
        ``trajectory.png`` when frames have a pose), new or empty; default a new
        ``results/drive/<date-time>`` (:func:`claimed_run_folder`).
    force : bool
        Replace the earlier run in ``out`` (never a folder of anything else).
    strict : bool
        Stop a replay at its first message that holds no usable frame, instead of
        skipping it (:func:`~curiosity_cli.drive.driver.run`).
    clock : {"bag", "header"}
        A replay's timeline against the bag's record times or the messages' header
        stamps (both are logged).
    video_out : Path, optional
        The annotated video (``.mp4``, ``.avi`` or ``.mkv``).
    png_every : int
        An annotated PNG every this many frames into ``<out>/frames/``; 0 for none.
    max_frames : int, optional
        Stop after this many frames.
    on_status : callable
        Called with a line of text when the model starts loading and when the robot
        has answered.
    on_frame : callable
        Called after each frame with its number and its
        :class:`~curiosity_cli.drive.pipeline.Decision`.
    on_replay : callable
        With a recorded bag, called once before the first frame with a description and
        the number of frames it holds (a replay is not paced: it runs as fast as the
        model does, with the same per-frame sample budget). A replay's folder also gets
        its surprise timeline (:mod:`~curiosity_cli.drive.timeline`).

    Returns
    -------
    outcome : Outcome
        How the run ended.
    folder : Path
        The run folder.

    Raises
    ------
    ParameterError
        ``camera="sim"`` without ``sim_map`` or the other way round; a dry run on
        ``sim_map`` without ``start``; a replay's ``topic``, ``strict`` or ``clock`` with a
        camera that is not a bag (:func:`check_replay_options`); an ``out`` that is not new
        or empty (:func:`check_run_folder`); ``cmd_vel`` with ``port`` or the simulated camera.
    UsageError
        A ``video_out`` that is no video file name (:func:`~curiosity_cli.drive.overlay.check_video_out`).
    LinkError
        The robot cannot be reached, or the link was lost (STOP was attempted).
    CuriosityError
        A camera that cannot be opened or fails, an output that cannot be written, a
        ``foxglove`` port that cannot be served (found before the model loads).
    """
    if not camera.strip():  # Path('') is the working folder, which would be read as a bag folder
        raise ParameterError(
            f"camera: got {camera!r}; expected a device index, a video file, a stream URL, a bag, ros2:/TOPIC or 'sim'",
            parameter="camera",
        )
    if (camera == "sim") != (sim_map is not None):
        raise ParameterError(f"camera: got {camera!r}; camera 'sim' and a sim_map go together")
    if cmd_vel is not None and (port is not None or camera == "sim"):
        robot = f"port {port!r}" if port is not None else "the simulated robot (camera 'sim')"
        raise ParameterError(f"cmd_vel: got {cmd_vel!r}, but the robot is {robot}; steer one robot", parameter="cmd_vel")
    if cmd_vel is not None:  # before the camera and the model: the robot opens after both
        from curiosity_cli.drive.ros2 import require_dds

        require_dds("cmd_vel", cmd_vel)
    d = config.drive
    lockstep = port is None and sim_map is not None
    if lockstep and start is None:
        raise ParameterError("start: a dry run on a simulated map needs the robot's start (row, col)")
    if video_out is not None:  # a bad name found once the run is under way would leave its folder half-made
        check_video_out(video_out)
    check_replay_options(camera, topic=topic, odom_topic=odom_topic, strict=strict, clock=clock)
    check_run_folder(out, force=force)  # before the camera and the model: a folder in use is the only message
    check_live_port(foxglove)
    with stopping_on_signals(StopRequest()) as stop, contextlib.ExitStack() as held:

        def stopped() -> bool:  # a live camera's and robot's waits end on a signal
            return stop.signal is not None

        source = None if camera == "sim" else open_camera(camera, topic, odom_topic, ros_domain_id, stopped)
        if getattr(source, "note", ""):  # a bag read otherwise than named (a recording cut short)
            on_status(source.note)
        if getattr(source, "pose_note", ""):
            on_status(source.pose_note)
        on_status("loading the vocabularies and the topic model's kernels")
        pipeline = CuriosityPipeline(config, seed)
        warm_up(config)
        try:
            out = held.enter_context(claimed_run_folder(out, force=force))
        except BaseException:  # another drive holds the folder: the camera opened for nothing
            if source is not None:
                source.close()
            raise
        prepare_folder(out, config, seed)
        from curiosity_cli.drive.bags import BagCamera, bag_fingerprint

        log = JsonLines(out / RUN_LOG)
        map_name = None if sim_map is None else sim_map.config.name
        log.write(
            "start", seed=seed, camera=camera, topic=getattr(source, "topic", None), sim_map=map_name, serial=port,
            dry_run=port is None and cmd_vel is None,
            **({"bag": bag_fingerprint(camera)} if isinstance(source, BagCamera) else {}),
            **({"odom_topic": source.odom_topic, "poses": source.pose_note} if hasattr(source, "odom_topic") else {}),
            **({"cmd_vel": cmd_vel} if cmd_vel is not None else {}),
            **({"ros_domain_id": source.domain_id} if hasattr(source, "domain_id") else {}),
        )
        robot = mission = None
        try:
            mission = MissionFile(
                out / MISSION_FILE, live_port=foxglove, metadata=_run_metadata(out), recording=source
            )
            write_layout(out)
            if mission.port is not None:
                on_status(f"live view: open ws://127.0.0.1:{mission.port} in Foxglove")
            if port is not None:
                timing = LinkTiming(d.hello_timeout, d.ack_timeout, d.resends, d.keepalive)
                robot = RobotLink.open(port, baud or d.baud, timing, log=log.write)
                on_status(f"connected to {robot.robot_name or 'the robot'} on {port}")
                log.write("hello", robot=robot.robot_name)
            elif cmd_vel is not None:
                from curiosity_cli.drive.ros2 import Ros2Robot

                robot = Ros2Robot(
                    cmd_vel, cmd_vel_stamped, ros_domain_id, keepalive=d.keepalive, log=log.write, stopped=stopped
                )
                on_status(
                    f"publishing {robot.message_type} on {robot.topic} (ROS domain {robot.domain_id}) to "
                    f"{robot.subscribers} subscriber{'s' * (robot.subscribers != 1)}"
                )
                log.write(
                    "ros2", cmd_vel=robot.topic, message_type=robot.message_type, ros_domain_id=robot.domain_id,
                    subscribers=robot.subscribers,
                )
            elif lockstep:
                robot = cameras.LockstepRobot(_body(sim_map, start, heading_deg, config), d.sim_frame_interval)
            if camera == "sim":
                # a lockstep robot moves only when the loop commands it: no wall-clock frame period
                interval = 0.0 if port is None else d.sim_frame_interval
                source = cameras.SimCamera(
                    sim_map.image, d.sim_metres_per_pixel, (d.sim_view_rows, d.sim_view_cols), robot, interval, d.hello_timeout
                )
            if hasattr(source, "messages"):  # a bag knows how many frames it holds
                frames = source.messages if max_frames is None else min(max_frames, source.messages)
                on_replay(f"replaying {source.topic}", frames)
            outputs = Outputs(out, video_out, png_every)
            outcome = run(
                pipeline, source, robot, outputs, log, max_frames=max_frames, stop=stop, strict=strict,
                mission=mission, on_frame=on_frame,
            )
            mission.close()
            left_out = getattr(source, "odometry_counts", None) or {}
            if left_out.get("damaged") or left_out.get("senseless"):
                on_status(
                    f"{source.odom_topic}: {left_out['damaged'] + left_out['senseless']} odometry messages left out "
                    f"({left_out['damaged']} damaged: not decoded or a value not finite; {left_out['senseless']} "
                    f"outside physical sense), {left_out['kept']} kept (`odometry` in the log's end)"
                )
            # a drive stopped by a signal exits at once: its data is written, its figures left for --timeline
            drawn = outcome.reason not in _SIGNALS
            _write_tables(out, figures=drawn)
            if drawn and hasattr(source, "messages"):
                _draw_timeline(out, camera, source.topic, f"{outcome.frames} frames", clock)
            if not drawn:
                on_status(
                    f"stopped by {outcome.reason}: its figures are left out, to exit at once; "
                    f"curiosity drive --timeline {display_path(out)} draws them"
                )
        except BaseException as exc:
            if not log.ended:
                # run() closes both and logs its end itself; this covers a failure before its loop
                if source is not None:
                    source.close()
                if robot is not None:
                    robot.close()
                log.write("end", outcome=None, error=" ".join(str(exc).split()) or type(exc).__name__, frames=0)
            elif isinstance(exc, CuriosityError):
                # a drive that stopped: the tables and timeline of what it did; the error it stopped on is the message
                with contextlib.suppress(CuriosityError, OSError):
                    if mission is not None:
                        mission.close()
                    _write_tables(out)
                    if hasattr(source, "messages"):
                        _draw_timeline(out, camera, source.topic, "stopped early", clock)
            if isinstance(exc, KeyboardInterrupt) and log.ended:  # a second Ctrl-C (StopRequest): no line came
                on_status(
                    f"interrupted again: stopped at once, its tables and figures left out; curiosity drive --timeline "
                    f"{display_path(out)} draws them; the session's log is kept in {display_path(out / RUN_LOG)}"
                )
            if isinstance(exc, CuriosityError):  # the folder stays, as a log of the attempt: say where
                kept = f"{exc.args[0]}; the session's log is kept in {display_path(out / RUN_LOG)}"
                raise type(exc)(kept, parameter=exc.parameter, rerun=exc.rerun) from None
            raise
        finally:
            if mission is not None:
                mission.close()
            log.close()
    products = tuple(name for name in PRODUCTS if (out / name).is_file())
    return dataclasses.replace(outcome, products=products, log=out / RUN_LOG), out


def _run_metadata(out: Path) -> dict[str, dict[str, str]]:
    """The run's config and provenance (as :func:`~curiosity_cli.drive.driver.prepare_folder` wrote them) as a
    mission file's metadata records: ``config`` holds the YAML, ``provenance`` each of its lines' value."""
    import yaml

    provenance = yaml.safe_load((out / "provenance.yaml").read_text())
    return {
        "config": {"config.yaml": (out / "config.yaml").read_text()},
        "provenance": {str(key): str(value) for key, value in provenance.items()},
    }


def _write_tables(out: Path, figures: bool = True) -> None:
    """The run's frames table and, with ``figures`` and where its frames have a pose, its trajectory figure."""
    from curiosity_cli.drive.frames_table import write_frames_table
    from curiosity_cli.drive.trajectory import write_trajectory

    table = write_frames_table(out)
    if figures:
        write_trajectory(out, table)


#: The outcomes of a drive stopped by a signal (:class:`~curiosity_cli.drive.driver.StopRequest`).
_SIGNALS = ("SIGINT", "SIGTERM")


def _check_log_file(log_file: Path) -> None:
    """Refuse a ``log_file`` that exists: the robot's events would be written over it."""
    if log_file.exists() or log_file.is_symlink():
        raise ParameterError(
            f"log_file: {display_path(log_file)} exists; expected a new file name for the robot's events",
            parameter="log_file",
        )


def _check_link(link: Path) -> None:
    """Refuse a ``link`` that cannot become a symlink: in a missing folder, or where a file is."""
    if not link.parent.is_dir():
        raise ParameterError(
            f"link: {display_path(link.parent)} is not a folder; expected the symlink's folder to exist",
            parameter="link",
        )
    if link.exists() and not link.is_symlink():
        raise ParameterError(
            f"link: {display_path(link)} exists and is not a symlink; expected a new name (or a symlink to replace)",
            parameter="link",
        )


def simrobot_session(
    config: ExperimentConfig,
    sim_map: MapData,
    *,
    start: tuple[float, float],
    heading_deg: float,
    noise: Noise,
    seed: int,
    estop_after: float | None = None,
    link: Path | None = None,
    log_file: Path | None = None,
    on_ready: Callable[[str], None] = lambda path: None,
) -> str:
    """Serve a simulated robot on a new pseudo-terminal until SIGINT or SIGTERM.

    Parameters
    ----------
    config : ExperimentConfig
        Its ``drive`` section: the map's scale, STATE rate and watchdog.
    sim_map : MapData
        The map the robot moves over.
    start : (float, float)
        Where it starts, (row, col) in map pixels.
    heading_deg : float
        Its start heading, degrees clockwise from the map's +col axis.
    noise : Noise
        Line noise on what the robot sends.
    seed : int
        Seeds the noise.
    estop_after : float, optional
        Send ESTOP this many seconds after the first VEL.
    link : Path, optional
        Also a symlink to the pseudo-terminal here (replacing a symlink already there),
        removed when the session ends.
    log_file : Path, optional
        The robot's events (frames received, watchdog, noise) as JSON Lines: a new file,
        never one that exists.
    on_ready : callable
        Called with the pseudo-terminal's path once a host can open it.

    Returns
    -------
    str
        The signal that stopped it, ``SIGINT`` or ``SIGTERM``.
    """
    d = config.drive
    if link is not None:
        _check_link(link)
    if log_file is not None:
        _check_log_file(log_file)
    body = _body(sim_map, start, heading_deg, config)
    events = JsonLines(log_file) if log_file is not None else None
    master, slave, path = open_pty()
    try:
        if link is not None:
            if link.is_symlink():
                link.unlink()
            link.symlink_to(path)
        on_ready(path)
        robot = SimRobot(
            body, state_rate=d.state_rate, watchdog=d.watchdog, noise=noise, seed=seed, estop_after=estop_after,
            log=events.write if events else (lambda event, **fields: None),
        )
        with stopping_on_signals(StopRequest()) as stop:
            robot.serve(master, lambda: stop.signal is not None)
        return stop.signal
    finally:
        os.close(master)
        os.close(slave)
        if link is not None and link.is_symlink():
            link.unlink()
        if events is not None:
            events.close()
