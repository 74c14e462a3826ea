"""A ROS 2 robot for the loopback tests, written against cyclonedds alone: its message types are declared here from
the ROS 2 message definitions, not imported from curiosity_cli, so that a test of the drive against it is a test
against an independent implementation.

It publishes a camera at 10 Hz on ``/camera/image/compressed`` (``sensor_msgs/msg/CompressedImage``, JPEG) and
``/camera/image_raw`` (``sensor_msgs/msg/Image``, rgb8), and ``nav_msgs/msg/Odometry`` on ``/odom`` (x growing 0.1 m a
frame, stamped as the frames; every third frame also a pose whose x is NaN), and writes every ``geometry_msgs/msg/Twist`` its ``/cmd_vel`` subscriber receives as
a JSON line to TWISTS. It prints ``ready`` once its topics exist, and runs until SIGTERM or SIGINT.

Usage: ``python ros2_robot.py DOMAIN TWISTS``. Its DDS stays on loopback (:data:`LOOPBACK`), whatever the environment
says; a test imports :data:`LOOPBACK` for its own processes.
"""

import json
import os
import signal
import sys
import time
from dataclasses import dataclass, field

import cv2
import numpy as np
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, float64, int32, sequence, uint8, uint32
from cyclonedds.pub import DataWriter
from cyclonedds.qos import Policy, Qos
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

#: Cyclone DDS on the loopback interface alone: no multicast, one unicast peer (this machine).
LOOPBACK = (
    '<CycloneDDS><Domain id="any"><General><Interfaces><NetworkInterface name="lo"/></Interfaces>'
    "<AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex>"
    '<MaxAutoParticipantIndex>20</MaxAutoParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers></Discovery>'
    "</Domain></CycloneDDS>"
)


@dataclass
class Stamp(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Head(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Stamp
    frame_id: str


@dataclass
class Jpeg(IdlStruct, typename="sensor_msgs::msg::dds_::CompressedImage_"):
    header: Head
    format: str
    data: sequence[uint8]


@dataclass
class Raw(IdlStruct, typename="sensor_msgs::msg::dds_::Image_"):
    header: Head
    height: uint32
    width: uint32
    encoding: str
    is_bigendian: uint8
    step: uint32
    data: sequence[uint8]


@dataclass
class Xyz(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Place(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Turn(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64


@dataclass
class Where(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Place
    orientation: Turn


@dataclass
class WhereUncertain(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: Where
    covariance: array[float64, 36] = field(default_factory=lambda: [0.0] * 36)


@dataclass
class Velocity(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Xyz
    angular: Xyz


@dataclass
class VelocityUncertain(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    twist: Velocity
    covariance: array[float64, 36] = field(default_factory=lambda: [0.0] * 36)


@dataclass
class Odom(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    header: Head
    child_frame_id: str
    pose: WhereUncertain
    twist: VelocityUncertain


def main(domain: int, twists_path: str) -> None:
    os.environ["CYCLONEDDS_URI"] = LOOPBACK  # before the first participant: Cyclone DDS reads it then
    stopped = []
    for signum in (signal.SIGTERM, signal.SIGINT):
        signal.signal(signum, lambda number, frame: stopped.append(number))
    participant = DomainParticipant(domain)
    sensor = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(5))
    jpeg = DataWriter(participant, Topic(participant, "rt/camera/image/compressed", Jpeg), qos=sensor)
    raw = DataWriter(participant, Topic(participant, "rt/camera/image_raw", Raw), qos=sensor)
    odom = DataWriter(participant, Topic(participant, "rt/odom", Odom), qos=sensor)
    # a base's subscriber: reliable, as ROS's default; keeps all, so that no twist is lost to the record
    cmd_vel = DataReader(
        participant, Topic(participant, "rt/cmd_vel", Velocity),
        qos=Qos(Policy.Reliability.Reliable(max_blocking_time=100_000_000), Policy.History.KeepAll),
    )
    world = np.random.default_rng(7).integers(0, 256, (600, 800, 3), np.uint8)
    world = cv2.GaussianBlur(world, (0, 0), 3)  # texture the words can find
    print("ready", flush=True)
    frame, next_frame = 0, time.monotonic()
    with open(twists_path, "a") as twists:
        while not stopped:
            for twist in cmd_vel.take(100):
                if isinstance(twist, Velocity):
                    twists.write(json.dumps({"linear": [twist.linear.x, twist.linear.y, twist.linear.z],
                                             "angular": [twist.angular.x, twist.angular.y, twist.angular.z]}) + "\n")
                    twists.flush()
            if time.monotonic() < next_frame:
                time.sleep(0.01)
                continue
            next_frame += 0.1
            now = time.time_ns()
            head = Head(Stamp(now // 1_000_000_000, now % 1_000_000_000), "camera")
            view = np.ascontiguousarray(world[4 * frame % 360 : 4 * frame % 360 + 240, 3 * frame % 480 : 3 * frame % 480 + 320])
            jpeg.write(Jpeg(head, "jpeg", cv2.imencode(".jpg", view[:, :, ::-1])[1].tobytes()))
            raw.write(Raw(head, 240, 320, "rgb8", 0, 320 * 3, view.tobytes()))
            odom.write(Odom(
                Head(head.stamp, "odom"), "base_link",
                WhereUncertain(Where(Place(0.1 * frame, 0.0, 0.0), Turn(0.0, 0.0, 0.0, 1.0))),
                VelocityUncertain(Velocity(Xyz(1.0, 0.0, 0.0), Xyz(0.0, 0.0, 0.0))),
            ))
            if frame % 3 == 0:  # a pose that is no pose: a drive leaves it out, and counts it
                odom.write(Odom(
                    Head(head.stamp, "odom"), "base_link",
                    WhereUncertain(Where(Place(float("nan"), 0.0, 0.0), Turn(0.0, 0.0, 0.0, 1.0))),
                    VelocityUncertain(Velocity(Xyz(1.0, 0.0, 0.0), Xyz(0.0, 0.0, 0.0))),
                ))
            frame += 1


if __name__ == "__main__":
    main(int(sys.argv[1]), sys.argv[2])
