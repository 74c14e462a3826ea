"""The ROS 2 messages a drive reads or sends, declared for Cyclone DDS (:mod:`~curiosity_cli.drive.ros2`).

ROS 2 puts a message type ``pkg/msg/Name`` on the wire as the DDS type
``pkg::msg::dds_::Name_``, final (XCDR1, the plain CDR of ROS 2 serialisation), its fields
in the order of the ``.msg`` file; a node of any ROS 2 distribution matches a reader or writer
whose type has that name and those fields. Importing this module needs ``cyclonedds`` (the
``ros2`` extra). ``tests/drive/test_ros2_cdr.py`` checks every type's bytes against rosbags'
serializer of ROS 2 messages.
"""

from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.annotations import final
from cyclonedds.idl.types import array, float32, float64, int32, sequence, uint8, uint32

# No `from __future__ import annotations` here: cyclonedds reads each field's type from the class's annotations, and
# cannot resolve them as strings (`str` is no name of this module).


@final
@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    """``builtin_interfaces/msg/Time``: seconds and nanoseconds since the epoch (or the robot's clock)."""

    sec: int32 = 0
    nanosec: uint32 = 0


@final
@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    """``std_msgs/msg/Header``."""

    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@final
@dataclass
class Image(IdlStruct, typename="sensor_msgs::msg::dds_::Image_"):
    """``sensor_msgs/msg/Image``: ``height`` rows of ``step`` bytes in ``data`` (``encoding``: ``rgb8``, ``mono16``, ...)."""

    header: Header = field(default_factory=Header)
    height: uint32 = 0
    width: uint32 = 0
    encoding: str = ""
    is_bigendian: uint8 = 0
    step: uint32 = 0
    data: sequence[uint8] = field(default_factory=list)


@final
@dataclass
class CompressedImage(IdlStruct, typename="sensor_msgs::msg::dds_::CompressedImage_"):
    """``sensor_msgs/msg/CompressedImage``: a JPEG or PNG file's bytes in ``data``."""

    header: Header = field(default_factory=Header)
    format: str = ""
    data: sequence[uint8] = field(default_factory=list)


@final
@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    """``geometry_msgs/msg/Point``, metres."""

    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@final
@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    """``geometry_msgs/msg/Quaternion`` (x, y, z, w; ROS's default is the identity)."""

    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@final
@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    """``geometry_msgs/msg/Vector3``."""

    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@final
@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    """``geometry_msgs/msg/Pose``."""

    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@final
@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    """``geometry_msgs/msg/PoseWithCovariance``: a (6, 6) row-major covariance as 36 values."""

    pose: Pose = field(default_factory=Pose)
    covariance: array[float64, 36] = field(default_factory=lambda: [0.0] * 36)


@final
@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    """``geometry_msgs/msg/Twist``: linear (m/s) and angular (rad/s) velocity in the body frame (REP 103: x forward,
    y left, z up)."""

    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@final
@dataclass
class TwistWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    """``geometry_msgs/msg/TwistWithCovariance``: a (6, 6) row-major covariance as 36 values."""

    twist: Twist = field(default_factory=Twist)
    covariance: array[float64, 36] = field(default_factory=lambda: [0.0] * 36)


@final
@dataclass
class Odometry(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    """``nav_msgs/msg/Odometry``: the pose in ``header.frame_id``, the twist in ``child_frame_id``."""

    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)
    twist: TwistWithCovariance = field(default_factory=TwistWithCovariance)


@final
@dataclass
class TwistStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TwistStamped_"):
    """``geometry_msgs/msg/TwistStamped``."""

    header: Header = field(default_factory=Header)
    twist: Twist = field(default_factory=Twist)


@final
@dataclass
class Float32(IdlStruct, typename="std_msgs::msg::dds_::Float32_"):
    """``std_msgs/msg/Float32``."""

    data: float32 = 0.0


@final
@dataclass
class PointStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PointStamped_"):
    """``geometry_msgs/msg/PointStamped``."""

    header: Header = field(default_factory=Header)
    point: Point = field(default_factory=Point)


#: Each type by its ROS 2 name (``pkg/msg/Name``), as rosbags and the bag replay name them.
BY_ROS_NAME = {
    f"{cls.__idl_typename__.split('::')[0]}/msg/{cls.__name__}": cls
    for cls in (Time, Header, Image, CompressedImage, Point, Quaternion, Vector3, Pose, PoseWithCovariance, Twist,
                TwistWithCovariance, Odometry, TwistStamped, Float32, PointStamped)
}
