"""Our ROS 2 message types put on the wire exactly the bytes ROS 2 does: each type, serialised by cyclonedds, is
byte for byte what rosbags' CDR serializer for ROS 2 (an independent implementation) makes of the same message, and
what rosbags serialises reads back as the same message. No DDS traffic: serialisation only."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pytest.importorskip("cyclonedds")
pytest.importorskip("rosbags")
from rosbags.typesys import Stores, get_typestore  # noqa: E402

from curiosity_cli.drive import ros2_types  # noqa: E402

TYPESTORE = get_typestore(Stores.ROS2_HUMBLE)
#: ROS 2's CDR encapsulation: plain CDR (XCDR1), little endian, no options.
CDR_LE = b"\x00\x01\x00\x00"
#: Odd and even lengths before 8-byte fields: every padding a string can leave (frame ids 0 to 8 characters long).
FRAME_IDS = ["", "a", "ab", "abc", "odom", "map_5", "camera", "optical", "base_lnk"]


def ros_name(cls) -> str:
    """``pkg/msg/Name`` of a type whose DDS name is ``pkg::msg::dds_::Name_``."""
    package, msg, _, name = cls.__idl_typename__.split("::")
    return f"{package}/{msg}/{name.removesuffix('_')}"


def to_rosbags(message):
    """The same message as rosbags' class of its ROS 2 type (arrays as the numpy arrays rosbags holds them in)."""
    fields = {}
    for field in dataclasses.fields(message):
        value = getattr(message, field.name)
        if dataclasses.is_dataclass(value):
            value = to_rosbags(value)
        elif isinstance(value, bytes):
            value = np.frombuffer(value, np.uint8)
        elif isinstance(value, list):
            value = np.array(value, np.float64 if field.name == "covariance" else np.uint8)
        fields[field.name] = value
    return TYPESTORE.types[ros_name(type(message))](**fields)


def header(frame_id: str, sec: int = 1_700_000_000, nanosec: int = 123_456_789) -> ros2_types.Header:
    return ros2_types.Header(stamp=ros2_types.Time(sec=sec, nanosec=nanosec), frame_id=frame_id)


def odometry(frame_id: str, child: str, rng: np.random.Generator) -> ros2_types.Odometry:
    t = ros2_types
    pose = t.Pose(position=t.Point(*rng.normal(size=3)), orientation=t.Quaternion(*rng.normal(size=4)))
    twist = t.Twist(linear=t.Vector3(*rng.normal(size=3)), angular=t.Vector3(*rng.normal(size=3)))
    return t.Odometry(
        header=header(frame_id), child_frame_id=child,
        pose=t.PoseWithCovariance(pose=pose, covariance=list(rng.normal(size=36))),
        twist=t.TwistWithCovariance(twist=twist, covariance=list(rng.normal(size=36))),
    )


def messages():
    """(what, message): every type the drive reads or sends, in the cases that exercise CDR's alignment."""
    t = ros2_types
    rng = np.random.default_rng(62)
    found = [("Time", t.Time(sec=-5, nanosec=999_999_999)), ("Float32", t.Float32(data=0.1)), ("Float32 zero", t.Float32())]
    for frame_id in FRAME_IDS:
        label = f"frame_id {len(frame_id)}"
        found += [
            (f"Header, {label}", header(frame_id)),
            (f"Odometry, {label}, child 3", odometry(frame_id, "abc", rng)),
            (f"Odometry, {label}, child 0", odometry(frame_id, "", rng)),
            (f"TwistStamped, {label}", t.TwistStamped(
                header=header(frame_id), twist=t.Twist(linear=t.Vector3(0.3, 0, 0), angular=t.Vector3(0, -0.1, -0.25)),
            )),
            (f"PointStamped, {label}", t.PointStamped(header=header(frame_id), point=t.Point(3.0, 2.0, 0.0))),
        ]
    found += [
        ("Twist", t.Twist(linear=t.Vector3(0.3, 0.0, 0.0), angular=t.Vector3(0.0, -0.1, -0.25))),
        ("Twist zero (STOP)", t.Twist()),
        ("Pose", t.Pose(position=t.Point(1.5, -2.5, 3.0), orientation=t.Quaternion(0.0, 0.0, 0.38268343, 0.92387953))),
        ("Point", t.Point(1.0, 2.0, -3.0)), ("Vector3", t.Vector3(0.5, 0.0, -0.5)), ("Quaternion", t.Quaternion()),
        ("PoseWithCovariance", odometry("odom", "base_link", rng).pose),
        ("TwistWithCovariance", odometry("odom", "base_link", rng).twist),
    ]
    for frame_id, data in [("", b""), ("c", b"\xff"), ("cam", bytes(range(7))), ("camera", rng.bytes(1 << 20))]:
        for image_format in ("jpeg", "png", "rgb8; jpeg compressed bgr8"):
            found.append((
                f"CompressedImage, frame_id {len(frame_id)}, format {len(image_format)}, {len(data)} bytes",
                t.CompressedImage(header=header(frame_id), format=image_format, data=data),
            ))
    for frame_id, encoding, (rows, cols, channels), bigendian in [
        ("", "rgb8", (0, 0, 3), 0), ("c", "mono8", (1, 3, 1), 0), ("cam", "bgr8", (3, 5, 3), 0),
        ("cam_1", "mono16", (4, 3, 2), 1), ("camera", "rgb8", (480, 640, 3), 0),
    ]:
        data = rng.bytes(rows * cols * channels)
        found.append((
            f"Image, frame_id {len(frame_id)}, {encoding}, {rows} x {cols}",
            t.Image(header=header(frame_id), height=rows, width=cols, encoding=encoding, is_bigendian=bigendian,
                    step=cols * channels, data=data),
        ))
    return found


MESSAGES = messages()


def test_every_type_is_declared_with_its_ros_2_name_final_and_checked_here():
    assert set(ros2_types.BY_ROS_NAME) == {ros_name(cls) for cls in ros2_types.BY_ROS_NAME.values()}
    assert all(name in TYPESTORE.types for name in ros2_types.BY_ROS_NAME)
    assert set(ros2_types.BY_ROS_NAME) == {ros_name(type(message)) for _, message in MESSAGES}
    for cls in ros2_types.BY_ROS_NAME.values():
        assert cls.__idl_annotations__["extensibility"] == "final"
        assert cls.__idl_typename__.split("::")[2] == "dds_" and cls.__idl_typename__.endswith("_")


@pytest.mark.parametrize("what, message", MESSAGES, ids=[what for what, _ in MESSAGES])
def test_the_bytes_are_ros_2_cdr_as_rosbags_writes_it(what, message):
    ours = message.serialize()
    theirs = bytes(TYPESTORE.serialize_cdr(to_rosbags(message), ros_name(type(message))))
    assert ours[:4] == CDR_LE
    assert ours == theirs
    # a DataWriter pads a sample to whole 4-byte words with zeros; a reader reads the message's own bytes
    written = ours.ljust((len(ours) + 3) & ~3, b"\0")
    assert written[len(theirs):] == bytes(len(written) - len(theirs))


@pytest.mark.parametrize("what, message", MESSAGES, ids=[what for what, _ in MESSAGES])
def test_rosbags_bytes_read_back_as_the_message(what, message):
    theirs = bytes(TYPESTORE.serialize_cdr(to_rosbags(message), ros_name(type(message))))
    read = type(message).deserialize(theirs)
    assert read.serialize() == theirs
    if hasattr(message, "data") and not isinstance(message, ros2_types.Float32):
        assert bytes(read.data) == bytes(message.data)
