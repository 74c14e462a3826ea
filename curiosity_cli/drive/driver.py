"""The driver's loop: frame, decision, command, log row, overlay; and how a run ends.

Whatever ends a run (the end of a video, ``--max-frames``, ESTOP, SIGINT or SIGTERM, an
error anywhere) the robot is closed the same way: STOP, answered or resent like any
frame, then the port is closed. A lost link has attempted STOP itself before the error
reaches here.

The log (``log.jsonl`` in the run folder) holds one ``frame`` row per frame, written
when the next frame is done so that the row can carry its command's ACK latency, and
the link's events (``resend``, ``refused``, ``nak``, ``estop``, ``stop``,
``link-lost``) as they happen, then an ``end`` row with the outcome and counters. A
command replaced before it was sent (the link was busy) shares its row's ``seq`` and
``ack_ms`` with the command that replaced it.
"""

from __future__ import annotations

import contextlib
import math
import signal
import time
from dataclasses import dataclass
from pathlib import Path

from curiosity_cli.config import ExperimentConfig
from curiosity_cli.drive.jsonlines import JsonLines
from curiosity_cli.drive.link import LinkError
from curiosity_cli.drive.overlay import VideoSink, caption_for, draw_overlay, write_png
from curiosity_cli.drive.pipeline import CuriosityPipeline


class StopRequest:
    """Set by SIGINT or SIGTERM; the loop checks it between frames.

    A second SIGINT raises KeyboardInterrupt, for a loop stuck in a camera that hangs;
    the robot is still sent STOP on the way out.
    """

    def __init__(self):
        self.signal: str | None = None

    def __call__(self, signum, frame) -> None:
        if self.signal is not None and signum == signal.SIGINT:
            raise KeyboardInterrupt
        # a flag, not an exception: the first request ends the run between frames, in order
        self.signal = signal.Signals(signum).name


@contextlib.contextmanager
def stopping_on_signals(request: StopRequest):
    """Route SIGINT and SIGTERM to ``request`` for the duration of the block."""
    previous = {s: signal.signal(s, request) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield request
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


@dataclass(frozen=True)
class Outputs:
    """Where a run writes.

    Attributes
    ----------
    folder : Path
        ``log.jsonl``, ``config.yaml``, ``provenance.yaml`` and ``frames/`` go here.
    video : Path or None
        The annotated video.
    png_every : int
        An annotated PNG every this many frames (frame 0 first); 0 for none.
    """

    folder: Path
    video: Path | None
    png_every: int


#: A run folder's log, one JSON record per line: a folder holding one is a run's.
RUN_LOG = "log.jsonl"


def prepare_folder(folder: Path, config: ExperimentConfig, seed: int) -> None:
    """Write the settings the drive runs with (:func:`~curiosity_cli.config.drive_yaml`) and its provenance into ``folder``."""
    import yaml

    from curiosity_cli.config_yaml import drive_yaml
    from curiosity_cli.experiment.provenance import provenance
    from curiosity_cli.files import atomic_path

    folder.mkdir(parents=True, exist_ok=True)
    with atomic_path(folder / "config.yaml") as tmp:
        tmp.write_text(drive_yaml(config, seed))
    with atomic_path(folder / "provenance.yaml") as tmp:
        tmp.write_text(yaml.safe_dump(provenance(seed), sort_keys=False))


@dataclass(frozen=True)
class Outcome:
    """How a run ended: ``reason`` is ``end of video`` or ``end of bag`` (the camera's frames ran out), ``max frames``,
    ``estop``, ``SIGINT`` or ``SIGTERM``."""

    reason: str
    frames: int
    detail: str
    stop_acked: bool | None  # None without a robot (or a simulated one in this process)
    skipped: int = 0  # a replay's messages that held no usable frame (a ``skipped`` record each)
    products: tuple[str, ...] = ()  # what the run folder holds for a reader (``session.PRODUCTS``), by name
    log: Path | None = None  # the run's log, once its folder is known


def _rounded(array, places: int = 3) -> list:
    return [[round(float(v), places) for v in row] for row in array]


def run(
    pipeline: CuriosityPipeline,
    camera,
    robot,
    outputs: Outputs,
    log: JsonLines,
    *,
    max_frames: int | None,
    stop: StopRequest,
    strict: bool = False,
    mission=None,
    on_frame=lambda frame_number, decision: None,
) -> Outcome:
    """Drive until the camera ends, ``max_frames``, ESTOP or a stop request.

    Parameters
    ----------
    pipeline : CuriosityPipeline
    camera
        ``read()`` returns ``(frame, capture_time)`` or None; ``close()``.
    robot
        A :class:`~curiosity_cli.drive.link.RobotLink`, a
        :class:`~curiosity_cli.drive.ros2.Ros2Robot` (which also gets each frame's record: ``publish_frame``), a
        :class:`~curiosity_cli.drive.camera.LockstepRobot`, or None (dry run: commands are logged, not sent).
    outputs : Outputs
    log : JsonLines
    max_frames : int or None
    stop : StopRequest
    strict : bool
        Stop at a replay's first message that holds no usable frame
        (:class:`~curiosity_cli.drive.bags.BadMessage`) instead of skipping it with a
        ``skipped`` record (its message index, bag time and reason).
    mission : MissionFile, optional
        Gets each frame's record and image (:mod:`~curiosity_cli.drive.mission`).
    on_frame : callable
        Called after each frame with its number and :class:`Decision` (progress output).

    Raises
    ------
    LinkError
        The link was lost (STOP was attempted).
    CuriosityError
        A camera that fails, an output that cannot be written; a replay whose every
        message was skipped.
    """
    from curiosity_cli.drive.bags import BadMessage
    from curiosity_cli.drive.camera import CameraError

    video = VideoSink(outputs.video, pipeline.config.drive.video_fps) if outputs.video else None
    pending: dict | None = None
    frames = skipped = 0
    first_bad = None
    outcome = None
    error = None
    try:
        while outcome is None:
            if stop.signal is not None:
                outcome = Outcome(stop.signal, frames, f"stopped by {stop.signal}", None)
                break
            # ESTOP first: a robot that stopped itself and then went quiet ended the run cleanly
            if robot is not None and robot.estop:
                outcome = Outcome("estop", frames, f"the robot sent ESTOP ({robot.estop.reason})", None)
                break
            if robot is not None and robot.error:
                raise LinkError(f"{robot.error}; STOP attempted")
            try:
                got = camera.read()
            except BadMessage as bad:
                if strict:
                    raise
                log.write("skipped", message=bad.index, bag_time=bad.bag_time, reason=bad.reason)
                first_bad = first_bad or bad
                skipped += 1
                continue
            except CameraError:
                if stop.signal is None:
                    raise
                # a live camera's wait for its next frame, cut short by the signal: the stop, not a lost camera
                outcome = Outcome(stop.signal, frames, f"stopped by {stop.signal}", None)
                break
            if got is None:
                if frames == 0 and skipped:  # nothing replayed is no result, not a quiet one
                    raise CameraError(f"every one of the {skipped} messages held no usable frame; the first: {first_bad}")
                outcome = Outcome(f"end of {camera.kind}", frames, f"end of the {camera.kind}", None)
                break
            image, captured, recorded, header, pose = got
            state = robot.state() if robot is not None else None
            decision = pipeline.process(image)
            command = decision.command
            seq = robot.command(command.surge, command.yaw_rate, command.pitch_rate) if robot is not None else None
            latency = time.monotonic() - captured
            _flush(pending, robot, log)
            pending = {
                "frame": frames,
                # the frame's time on the mission's clock: its bag time in a replay, the host's clock live
                "time_ns": recorded if recorded is not None else time.time_ns(),
                **({} if recorded is None else {"bag_time": recorded / 1e9, "bag_time_ns": recorded}),
                **({} if header is None else {"header_time": header / 1e9, "header_time_ns": header}),
                "latency_ms": round(latency * 1000, 2),
                "seconds": {k: round(v, 5) for k, v in decision.seconds.items()},
                "words": decision.words,
                "refined": decision.refined,
                "state": None if state is None else {
                    "t": round(state.t, 3), "x": round(state.x, 4), "y": round(state.y, 4),
                    "heading": round(state.heading, 4), "depth": round(state.depth, 3),
                },
                "pose": _pose_record(pose, state),
                "perplexity": _rounded(decision.perplexity),
                "scores": _rounded(decision.scores),
                "target": list(decision.target),
                "command": {
                    "surge": round(command.surge, 4),
                    "yaw_rate": round(command.yaw_rate, 4),
                    "pitch_rate": round(command.pitch_rate, 4),
                },
                "seq": seq,
            }
            if mission is not None:
                mission.frame(pending, image)
            if hasattr(robot, "publish_frame"):  # a ROS 2 robot's network sees each frame's surprise and target too
                robot.publish_frame(pending)
            png_now = outputs.png_every and frames % outputs.png_every == 0
            if video is not None or png_now:
                annotated = draw_overlay(image, decision.scores, decision.target, caption_for(frames, command))
                if video is not None:
                    video.write(annotated)
                if png_now:
                    write_png(annotated, outputs.folder / "frames" / f"frame-{frames:06d}.png")
            on_frame(frames, decision)
            frames += 1
            if max_frames is not None and frames >= max_frames:
                outcome = Outcome("max frames", frames, "--max-frames reached", None)
    except BaseException as exc:
        if isinstance(exc, KeyboardInterrupt) and stop.signal is not None:
            # a second SIGINT (StopRequest) before the loop saw the first: the run was stopped by the first, at once
            outcome = Outcome(stop.signal, frames, f"stopped by {stop.signal}, then interrupted again", None)
        else:
            error = " ".join(str(exc).split()) or type(exc).__name__
        raise
    finally:
        _flush(pending, robot, log)
        if video is not None:
            video.close()
        camera.close()
        stop_acked = robot.close() if robot is not None else None
        stats = None if robot is None else robot.stats
        odometry = getattr(camera, "odometry_counts", None)  # a live topic's: what it left out, said nowhere else
        log.write(
            "end",
            outcome=None if outcome is None else outcome.reason,
            error=error,
            frames=frames,
            skipped=skipped,
            stop_acked=stop_acked,
            **({} if odometry is None else {"odometry": odometry}),
            **({} if stats is None else {
                "sent": stats.sent, "resent": stats.resent, "acked": stats.acked, "naks": stats.naks,
                "refused_lines": stats.refused_lines, "states": stats.states,
            }),
        )
    return Outcome(outcome.reason, outcome.frames, outcome.detail, stop_acked, skipped)


def _pose_record(pose, state) -> dict | None:
    """A frame's pose in its log record: a replay's odometry (:class:`~curiosity_cli.drive.odometry.FramePose`), else
    the robot's reported state (its x, y, heading; z is minus its depth), else None."""
    if pose is not None:
        (x, y, z), (qx, qy, qz, qw) = pose.position, pose.orientation
        return {
            "source": "odometry", "frame_id": pose.frame_id, "x": x, "y": y, "z": z, "qx": qx, "qy": qy, "qz": qz, "qw": qw,
            "yaw": round(pose.yaw, 6), "gap_ms": round(pose.gap_ns / 1e6, 3),
        }
    if state is None:
        return None
    half = state.heading / 2
    return {
        "source": "robot", "frame_id": "robot", "x": state.x, "y": state.y, "z": -state.depth,
        "qx": 0.0, "qy": 0.0, "qz": math.sin(half), "qw": math.cos(half), "yaw": state.heading, "gap_ms": 0.0,
    }


def _flush(row: dict | None, robot, log: JsonLines) -> None:
    """Write a frame row, with its command's ACK latency if the ACK came by now."""
    if row is None:
        return
    latency = robot.ack_latency(row["seq"]) if robot is not None and row["seq"] is not None else None
    row["ack_ms"] = None if latency is None else round(latency * 1000, 2)
    log.write("frame", **row)
