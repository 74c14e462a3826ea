"""A recorded mission's odometry, and the pose of each replayed frame: the nearest odometry in time.

A bag's ``nav_msgs/msg/Odometry`` messages (or a Foxglove recording's ``foxglove.PoseInFrame``)
are read once, before the first frame (they
are small: a pose and a twist each), and every frame is given the pose recorded nearest
its own bag time, with the gap between the two, so surprise can be put on a map of where
the robot went and a reader can see how far to trust the match.
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
            message = reader.deserialize(data, connection.msgtype)
            pose = message.pose.pose
            position = (pose.position.x, pose.position.y, pose.position.z)
            orientation = (pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w)
            frame_id = message.header.frame_id
        except Exception:  # rosbags' own errors for bytes that are no Odometry: that pose is missing, not the mission
            damaged += 1
            continue
        if not all(math.isfinite(v) for v in (*position, *orientation)):
            damaged += 1
            continue
        if max(abs(v) for v in position) > MAX_COORDINATE or sum(v * v for v in orientation) < 1e-12:
            senseless += 1
            continue
        times.append(stamp)
        positions.append(position)
        orientations.append(orientation)
        frame_ids.append(frame_id)
    if not times:
        return None, damaged, senseless
    odometry = Odometry(np.array(times, np.int64), np.array(positions), np.array(orientations), frame_ids)
    return odometry, damaged, senseless
