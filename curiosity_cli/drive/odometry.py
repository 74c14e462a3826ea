"""A recorded mission's odometry, and the pose of each replayed frame: the nearest odometry in time.

A bag's ``nav_msgs/msg/Odometry`` messages (or a Foxglove recording's ``foxglove.PoseInFrame``)
are read once, before the first frame (they
are small: a pose and a twist each), and every frame is given the pose recorded nearest
its own bag time, with the gap between the two, so surprise can be put on a map of where
the robot went and a reader can see how far to trust the match. A live ROS 2 topic's odometry
(:class:`RecentPoses`) is matched the same way, on the messages' header stamps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

ODOMETRY = "nav_msgs/msg/Odometry"
#: The message types a frame's pose is read from: a ROS bag's odometry, a Foxglove recording's poses.
POSE_TYPES = (ODOMETRY, "foxglove.PoseInFrame")
#: Odometry messages a replay reads at most: 10 hours at 100 Hz, about 1 GB of arrays beyond that
#: would be read before the first frame.
MAX_ODOMETRY = 3_600_000
#: A pose outside physical sense is left out: a coordinate beyond this many metres (a UTM northing reaches 10^7),
#: or a quaternion of no length (no orientation at all).
MAX_COORDINATE = 1e8
#: A frame is given the nearest pose only within this of its bag time; farther, the robot's pose then is not known.
MAX_POSE_GAP_NS = 2_000_000_000


@dataclass(frozen=True)
class FramePose:
    """A frame's pose: the odometry recorded nearest its time.

    Attributes
    ----------
    frame_id : str
        The odometry's frame of reference (its header's ``frame_id``, e.g. ``odom``).
    position : (float, float, float)
        x, y, z in metres.
    orientation : (float, float, float, float)
        The quaternion x, y, z, w.
    gap_ns : int
        The odometry's bag time minus the frame's, nanoseconds.
    """

    frame_id: str
    position: tuple[float, float, float]
    orientation: tuple[float, float, float, float]
    gap_ns: int

    @property
    def yaw(self) -> float:
        """Heading about z, radians (from the quaternion, normalised: a recorder's quaternion need not be a unit one)."""
        x, y, z, w = np.asarray(self.orientation) / np.linalg.norm(self.orientation)
        return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


class Odometry:
    """A topic's odometry in bag-time order.

    Parameters
    ----------
    times : (N,) int64 ndarray
        Bag times in nanoseconds, N >= 1.
    positions : (N, 3) float64 ndarray
    orientations : (N, 4) float64 ndarray
        Quaternions x, y, z, w.
    frame_ids : list of str
    """

    def __init__(self, times: np.ndarray, positions: np.ndarray, orientations: np.ndarray, frame_ids: list[str]):
        order = np.argsort(times, kind="stable")
        self.times = np.asarray(times, np.int64)[order]
        self.positions = np.asarray(positions, np.float64)[order]
        self.orientations = np.asarray(orientations, np.float64)[order]
        self.frame_ids = [frame_ids[i] for i in order]

    def __len__(self) -> int:
        return self.times.size

    def nearest(self, time_ns: int) -> FramePose | None:
        """The pose recorded nearest ``time_ns`` (the earlier one of two as near); None when it is more than
        :data:`MAX_POSE_GAP_NS` away (a single pose a year before the frames was given to every frame)."""
        at = int(np.searchsorted(self.times, time_ns))
        if at == self.times.size or (at > 0 and time_ns - self.times[at - 1] <= self.times[at] - time_ns):
            at -= 1
        if abs(int(self.times[at]) - int(time_ns)) > MAX_POSE_GAP_NS:
            return None
        return FramePose(
            self.frame_ids[at], tuple(float(v) for v in self.positions[at]),
            tuple(float(v) for v in self.orientations[at]), int(self.times[at]) - int(time_ns),
        )


def message_pose(message) -> tuple[tuple[float, float, float], tuple[float, float, float, float], str]:
    """(position x, y, z; orientation x, y, z, w; frame id) of a ``nav_msgs/msg/Odometry`` (or ``foxglove.PoseInFrame``)
    message, as any reader gives it: its ``pose.pose`` and its ``header.frame_id``.

    Raises
    ------
    AttributeError
        A message without those fields.
    """
    pose = message.pose.pose
    position = (float(pose.position.x), float(pose.position.y), float(pose.position.z))
    orientation = tuple(float(v) for v in (pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w))
    return position, orientation, message.header.frame_id


def pose_problem(position, orientation) -> str | None:
    """What keeps a pose out: ``damaged`` (a value that is not finite), ``senseless`` (a coordinate beyond
    :data:`MAX_COORDINATE`, a quaternion of no length), or None for a pose in physical sense."""
    if not all(math.isfinite(v) for v in (*position, *orientation)):
        return "damaged"
    if max(abs(v) for v in position) > MAX_COORDINATE or sum(v * v for v in orientation) < 1e-12:
        return "senseless"
    return None


def read_odometry(reader, connections) -> tuple[Odometry | None, int, int]:
    """The odometry of ``connections`` of a bag ``reader`` (rosbags' ``AnyReader`` or one like it), how many of
    its messages did not decode and how many held a pose outside physical sense (a coordinate beyond
    :data:`MAX_COORDINATE`, a quaternion of no length), both left out. None when no message is left.

    Raises
    ------
    ValueError
        More than :data:`MAX_ODOMETRY` messages.
    """
    total = sum(c.msgcount for c in connections)
    if total > MAX_ODOMETRY:
        raise ValueError(f"{total:,} odometry messages; at most {MAX_ODOMETRY:,} are read")
    times, positions, orientations, frame_ids = [], [], [], []
    damaged = senseless = 0
    for connection, stamp, data in reader.messages(connections=connections):
        try:
            position, orientation, frame_id = message_pose(reader.deserialize(data, connection.msgtype))
        except Exception:  # rosbags' own errors for bytes that are no Odometry: that pose is missing, not the mission
            damaged += 1
            continue
        problem = pose_problem(position, orientation)
        damaged += problem == "damaged"
        senseless += problem == "senseless"
        if problem is not None:
            continue
        times.append(stamp)
        positions.append(position)
        orientations.append(orientation)
        frame_ids.append(frame_id)
    if not times:
        return None, damaged, senseless
    odometry = Odometry(np.array(times, np.int64), np.array(positions), np.array(orientations), frame_ids)
    return odometry, damaged, senseless


#: Odometry messages a live topic's frames are matched against: the newest ones (50 s at 20 Hz).
MAX_LIVE_POSES = 1000


class RecentPoses:
    """A live topic's newest odometry, each at its header stamp, and a frame's pose: the nearest to its own stamp.

    A live camera's frames and the robot's odometry carry stamps of the robot's clock; matched on
    them as a replay matches bag times (:meth:`Odometry.nearest`), within :data:`MAX_POSE_GAP_NS`.

    Attributes
    ----------
    kept, damaged, senseless : int
        Messages kept, and left out as :func:`pose_problem` says.
    """

    def __init__(self):
        from collections import deque

        self._poses = deque(maxlen=MAX_LIVE_POSES)
        self._odometry: Odometry | None = None
        self.kept = self.damaged = self.senseless = 0

    def add(self, message) -> None:
        """Keep an odometry message (any object with its fields) at its header stamp, unless :func:`pose_problem`
        leaves it out."""
        try:
            position, orientation, frame_id = message_pose(message)
            stamp = message.header.stamp
            time_ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
        except (AttributeError, TypeError, ValueError):
            self.damaged += 1
            return
        problem = pose_problem(position, orientation)
        self.damaged += problem == "damaged"
        self.senseless += problem == "senseless"
        if problem is None:
            self._poses.append((time_ns, position, orientation, frame_id))
            self._odometry = None
            self.kept += 1

    def nearest(self, time_ns: int) -> FramePose | None:
        """The kept pose nearest ``time_ns`` (:meth:`Odometry.nearest`); None without one within :data:`MAX_POSE_GAP_NS`."""
        if not self._poses:
            return None
        if self._odometry is None:  # made again only once new poses came: a frame asks once, odometry comes often
            times, positions, orientations, frame_ids = zip(*self._poses)
            self._odometry = Odometry(np.array(times, np.int64), np.array(positions), np.array(orientations), list(frame_ids))
        return self._odometry.nearest(time_ns)
