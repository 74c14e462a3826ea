"""Field data at its edges (issue 64, item 1): images of no size or short rows, poses outside physical sense or far
from a frame's time, a topic with no message: each refused or flagged by name, never read as if it were sense."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from curiosity_cli.drive.bags import BadMessage, decode
from curiosity_cli.drive.odometry import MAX_POSE_GAP_NS, Odometry, read_odometry


def raw(width: int, height: int, step: int, data: bytes, encoding: str = "rgb8"):
    return SimpleNamespace(encoding=encoding, width=width, height=height, step=step, is_bigendian=0,
                           data=np.frombuffer(data, np.uint8))


@pytest.mark.parametrize(
    "message, says",
    [
        # a Foxglove RawImage of width -5 replayed as a 155-column image
        (raw(-5, 4, 15, bytes(60)), "a 4 x -5 image: expected a positive height and width"),
        (raw(4, 0, 12, b""), "a 0 x 4 image: expected a positive height and width"),
        # a step too short for its row blamed the byte count
        (raw(4, 2, 6, bytes(24)), "a row step of 6 bytes: expected at least 12, a row of 4 rgb8 pixels"),
        (raw(4, 2, 12, bytes(20)), "20 bytes for 2 x 4 rgb8 rows of 12: expected at least 24"),
    ],
)
def test_an_image_of_no_size_or_short_rows_is_a_damaged_message_naming_what(message, says):
    with pytest.raises(BadMessage, match=f"^where: {says}"):
        decode(message, "foxglove.RawImage", "where")


class _Reader:
    """A bag reader holding one topic's odometry messages, already decoded."""

    def __init__(self, poses):
        self.poses = poses

    def messages(self, connections):
        for stamp, pose in self.poses:
            yield SimpleNamespace(msgtype="nav_msgs/msg/Odometry"), stamp, pose

    @staticmethod
    def deserialize(pose, msgtype):
        position, orientation = pose
        return SimpleNamespace(
            header=SimpleNamespace(frame_id="odom"),
            pose=SimpleNamespace(pose=SimpleNamespace(
                position=SimpleNamespace(x=position[0], y=position[1], z=position[2]),
                orientation=SimpleNamespace(x=orientation[0], y=orientation[1], z=orientation[2], w=orientation[3]),
            )),
        )


def test_a_pose_outside_physical_sense_is_left_out_and_counted():
    upright = (0.0, 0.0, 0.0, 1.0)
    reader = _Reader([
        (0, ((1.0, 2.0, 0.0), upright)),
        (1, ((1e308, -1e308, 0.0), upright)),  # crashed the trajectory plot
        (2, ((1.0, 2.0, 0.0), (0.0, 0.0, 0.0, 0.0))),  # read as yaw 0 without a note
        (3, ((float("nan"), 0.0, 0.0), upright)),
    ])
    odometry, damaged, senseless = read_odometry(reader, [SimpleNamespace(msgcount=4)])
    assert (len(odometry), damaged, senseless) == (1, 1, 2)


def test_a_frame_far_from_every_pose_has_none_and_a_quaternion_need_not_be_a_unit_one():
    year = 365 * 24 * 3600 * 10**9
    # a single pose a year before the frames was given to every frame (pose_gap_ms -31,536,000,000)
    odometry = Odometry(np.array([0]), np.zeros((1, 3)), np.array([[0.0, 0.0, 0.0, 2.0]]), ["odom"])
    assert odometry.nearest(year) is None
    assert odometry.nearest(MAX_POSE_GAP_NS + 1) is None
    near = odometry.nearest(MAX_POSE_GAP_NS)
    assert near is not None and near.gap_ns == -MAX_POSE_GAP_NS and near.yaw == 0.0
    turned = Odometry(np.array([0]), np.zeros((1, 3)), np.array([[0.0, 0.0, 3.0, 3.0]]), ["odom"]).nearest(0)
    assert turned.yaw == pytest.approx(math.pi / 2), "a quaternion of length 3 sqrt(2), 90 degrees about z"


def test_a_bag_whose_image_topic_holds_no_message_is_refused_not_driven_for_zero_frames(tmp_path):
    from test_bags import replay, write_bag

    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/camera": "rgb8"}, [])
    result = replay(bag, tmp_path / "run")
    assert result.exit_code == 1 and "Traceback" not in result.output, result.output
    assert "/camera holds no message: no frame to replay" in result.stderr
    assert "drove 0 frames" not in result.output
