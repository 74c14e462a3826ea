"""Camera sources: OpenCV captures (device, video file, stream URL) and the simulated camera;
recorded bags are in :mod:`curiosity_cli.drive.bags`.

A camera's :meth:`read` returns a :class:`Frame`, or None when the stream has ended.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import NamedTuple

import numpy as np

from curiosity_cli.drive.link import LinkError
from curiosity_cli.drive.protocol import State
from curiosity_cli.drive.sim import Body, Pose, render_view
from curiosity_cli.errors import CuriosityError


class CameraError(CuriosityError):
    """A camera that cannot be opened or stops delivering frames."""


class Frame(NamedTuple):
    """A camera frame.

    Attributes
    ----------
    image : (H, W, 3) uint8 ndarray
        RGB.
    captured : float
        The ``time.monotonic()`` at which it was captured (or read): the start of the
        frame-to-command latency.
    recorded_ns : int or None
        A recorded frame's time, nanoseconds since the epoch (a bag's record time); None for a live one.
    header_ns : int or None
        A recorded image message's own header stamp, nanoseconds since the epoch; None without one.
    pose : FramePose or None
        A recorded frame's pose (:mod:`~curiosity_cli.drive.odometry`); None without odometry.
    """

    image: np.ndarray
    captured: float
    recorded_ns: int | None = None
    header_ns: int | None = None
    pose: object = None


class OpenCVCamera:
    """Frames from ``cv2.VideoCapture``.

    Parameters
    ----------
    source : str
        A device index (``0``), a video file, or a stream URL (``rtsp://...``).

    Raises
    ------
    CameraError
        When OpenCV cannot open the source.
    """

    #: What ran out when the frames do: the run's outcome is ``end of video``.
    kind = "video"

    def __init__(self, source: str):
        import cv2

        self.source = source
        self._is_file = Path(source).is_file()
        target = int(source) if source.isdigit() else source
        self._capture = cv2.VideoCapture(target)
        if not self._capture.isOpened():
            raise CameraError(
                f"camera {source!r}: OpenCV cannot open it; expected a device index, a video file or a stream URL"
            )

    def read(self):
        """The next frame and its capture time; None at the end of a video file.

        Raises
        ------
        CameraError
            A device or stream that stops delivering frames (a file just ends).
        """
        import cv2

        ok, frame = self._capture.read()
        captured = time.monotonic()
        if not ok:
            if self._is_file:
                return None
            raise CameraError(f"camera {self.source!r}: no frame (disconnected, or the stream ended)")
        if frame.ndim == 2:
            return Frame(np.ascontiguousarray(cv2.cvtColor(frame, cv2.COLOR_GRAY2RGB)), captured)
        return Frame(np.ascontiguousarray(frame[:, :, 2::-1]), captured)  # OpenCV delivers BGR(A)

    def close(self) -> None:
        self._capture.release()


def pose_of(state: State) -> Pose:
    return Pose(state.x, state.y, state.heading)


class SimCamera:
    """The simulated robot's downward camera, rendered at the robot's reported pose.

    Parameters
    ----------
    image : (H, W, 3) uint8 ndarray
        The map, RGB.
    metres_per_pixel : float
    view_shape : (int, int)
        Rows and columns of a frame, in map pixels.
    robot
        Reports the pose: ``state()`` returns the newest :class:`State` (or None) and
        ``wait_state(newer_than, timeout)`` waits for one (a :class:`RobotLink`, or a
        :class:`LockstepRobot`).
    interval : float
        Seconds between frames (the camera's frame period); 0 for as fast as they are read.
    first_state_timeout : float
        How long to wait for the robot's first STATE.
    """

    def __init__(self, image, metres_per_pixel: float, view_shape, robot, interval: float, first_state_timeout: float):
        self._image = image
        self._mpp = metres_per_pixel
        self._view = view_shape
        self._robot = robot
        self._interval = interval
        self._timeout = first_state_timeout
        self._next = None

    def read(self):
        """A frame at the newest pose, at the camera's frame period.

        Raises
        ------
        CameraError
            No STATE from the robot within the timeout (the view needs its pose).
        LinkError
            The link was lost while waiting for the first STATE.
        """
        if self._interval > 0:
            now = time.monotonic()
            if self._next is not None and now < self._next:
                time.sleep(self._next - now)
                now = self._next
            # a loop slower than the frame period gets the next frame at once, without catching up
            self._next = now + self._interval
        state = self._robot.state() or self._robot.wait_state(None, self._timeout)
        if state is None and self._robot.error:
            raise LinkError(f"{self._robot.error}; STOP attempted")
        if state is None:
            raise CameraError(
                f"camera sim: no STATE from the robot within {self._timeout:g} s; the view is rendered at its pose",
                parameter="camera",
            )
        frame = render_view(self._image, pose_of(state), self._mpp, self._view)
        return Frame(frame, time.monotonic())

    def close(self) -> None:
        """Nothing to release."""


class LockstepRobot:
    """A simulated robot in this process, moved one frame period per command (dry runs).

    Stands in for the serial link with ``--dry-run --camera sim``: no wall clock is
    involved, so a run is a deterministic function of the seed and the start pose.

    Parameters
    ----------
    body : Body
    dt : float
        Simulated seconds per command (the camera's frame period), > 0.
    """

    # what the driver reads from a link: nothing can go wrong in-process
    error = None
    estop = None
    stats = None

    def __init__(self, body: Body, dt: float):
        self.body = body
        self.dt = dt
        self._time = 0.0

    def state(self) -> State:
        pose = self.body.pose
        return State(0, self._time, pose.x, pose.y, pose.heading, 0.0)

    def wait_state(self, newer_than, timeout: float) -> State:
        return self.state()

    def command(self, surge: float, yaw_rate: float, pitch_rate: float) -> None:
        """Move for one frame period (pitch is ignored: the map is flat)."""
        self.body.step(surge, yaw_rate, self.dt)
        self._time += self.dt

    def ack_latency(self, seq) -> None:
        return None

    def close(self) -> None:
        """Nothing to stop: the body moves only when commanded."""
