"""A recording's coordinate frames: the transforms of its ``/tf_static`` and ``/tf`` topics, at a frame's time.

ROS keeps the frames of a robot (``odom``, ``base_link``, a camera's optical frame) in
``tf2_msgs/msg/TFMessage`` messages: ``/tf_static`` for the fixed ones (a camera's mount),
``/tf`` for those that move. A replay reads both once, as it reads odometry, and a mission
file links its frames with them (:mod:`~curiosity_cli.drive.mission`). A transform outside
physical sense (a coordinate beyond :data:`~curiosity_cli.drive.odometry.MAX_COORDINATE`, a
value that is not finite, a quaternion of no length) is left out and counted. Frame ids are
taken as tf2 takes them, without a leading ``/`` (ROS 1 wrote one).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from curiosity_cli.drive.odometry import MAX_COORDINATE

#: The topics of a recording's transforms, fixed ones first, and their message types (ROS 2's, ROS 1's).
STATIC_TOPIC, DYNAMIC_TOPIC = "/tf_static", "/tf"
TF_TYPES = ("tf2_msgs/msg/TFMessage", "tf2_msgs/TFMessage")


@dataclass(frozen=True)
class Transform:
    """Where ``child`` is in ``parent``: ``translation`` (x, y, z) metres and ``rotation`` the quaternion (x, y, z, w)."""

    parent: str
    child: str
    translation: tuple[float, float, float]
    rotation: tuple[float, float, float, float]


@dataclass
class Transforms:
    """A recording's transforms: the fixed ones, and each moving link's in bag-time order.

    Attributes
    ----------
    static : list of Transform
        The newest of each (parent, child) link of ``/tf_static``.
    moving : dict of (str, str) to ((N,) int64 ndarray, (N, 7) float64 ndarray)
        Per ``/tf`` link, its bag times in nanoseconds and (x, y, z, qx, qy, qz, qw) at each.
    """

    static: list[Transform] = field(default_factory=list)
    moving: dict = field(default_factory=dict)

    def at(self, time_ns: int) -> list[Transform]:
        """The fixed transforms and, of each moving link, the newest at or before ``time_ns`` (none before its first)."""
        now = list(self.static)
        for (parent, child), (times, values) in self.moving.items():
            i = int(np.searchsorted(times, time_ns, side="right")) - 1
            if i >= 0:
                x, y, z, qx, qy, qz, qw = (float(v) for v in values[i])
                now.append(Transform(parent, child, (x, y, z), (qx, qy, qz, qw)))
        return now

    def children(self) -> set[str]:
        """Every frame that some transform places in another."""
        return {t.child for t in self.static} | {child for _, child in self.moving}


def read_transforms(reader, connections) -> tuple[Transforms, int, int]:
    """The transforms of ``connections`` (a rosbags reader's, on :data:`STATIC_TOPIC` or :data:`DYNAMIC_TOPIC`).

    Returns
    -------
    (Transforms, int, int)
        The transforms, the messages that could not be read (damaged), and the transforms left out as outside
        physical sense.
    """
    damaged = senseless = 0
    static: dict = {}
    moving: dict = {}
    for connection, stamp, data in reader.messages(connections=list(connections)):
        try:
            message = reader.deserialize(data, connection.msgtype)
            links = [(_frame(t.header.frame_id), _frame(t.child_frame_id), _values(t.transform)) for t in message.transforms]
        except Exception:  # noqa: BLE001 - rosbags' own errors, or a message without the fields of a TFMessage
            damaged += 1
            continue
        for parent, child, values in links:
            if not _sensible(values):
                senseless += 1
            elif connection.topic == STATIC_TOPIC:
                static[parent, child] = values
            else:
                moving.setdefault((parent, child), []).append((int(stamp), values))
    transforms = Transforms(
        [Transform(p, c, tuple(v[:3]), tuple(v[3:])) for (p, c), v in static.items()],
        {
            link: (np.array([t for t, _ in rows], np.int64), np.array([v for _, v in rows], np.float64))
            for link, rows in ((link, sorted(rows, key=lambda row: row[0])) for link, rows in moving.items())
        },
    )
    return transforms, damaged, senseless


def _frame(name: str) -> str:
    return str(name).lstrip("/")


def _values(transform) -> tuple[float, ...]:
    t, q = transform.translation, transform.rotation
    return tuple(float(v) for v in (t.x, t.y, t.z, q.x, q.y, q.z, q.w))


def _sensible(values: tuple[float, ...]) -> bool:
    array = np.asarray(values)
    return bool(np.isfinite(array).all() and np.abs(array[:3]).max() <= MAX_COORDINATE and np.linalg.norm(array[3:]) > 0)
