"""The parts of a drive from a ROS 2 robot: its options and their one-line refusals, the ``ros2`` extra missing, ROS
names and domains, a live topic's poses; and, over real DDS on loopback in this process (each test on a ROS domain of
its own), the camera and the robot classes: the newest frame, a damaged one, a camera lost, twists in ROS's body
frame, the keepalive, each frame's surprise and target, STOP, a robot no one listens to."""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from types import SimpleNamespace

import cv2
import numpy as np
import pytest
from test_drive_cli_errors import one_line_error, usage_error
from typer.testing import CliRunner

from curiosity_cli.cli import app
from curiosity_cli.drive import ros2
from curiosity_cli.drive.bags import BadMessage
from curiosity_cli.drive.camera import CameraError
from curiosity_cli.drive.link import LinkError
from curiosity_cli.drive.odometry import RecentPoses
from curiosity_cli.errors import CuriosityError, ParameterError

runner = CliRunner()


def test_options_that_do_not_go_together_are_refused_before_anything_runs(tmp_path):
    out = ["--out", str(tmp_path / "run")]
    ros = ["--camera", "ros2:/camera/image/compressed"]
    assert "--cmd-vel is the robot, a ROS 2 one; leave out --serial" in usage_error(
        runner.invoke(app, ["drive", *ros, "--cmd-vel", "/cmd_vel", "--serial", "/dev/null", *out])
    )
    assert "--dry-run sends nothing; leave out --cmd-vel" in usage_error(
        runner.invoke(app, ["drive", *ros, "--cmd-vel", "/cmd_vel", "--dry-run", *out])
    )
    assert "--camera sim views the simulated robot, not a ROS 2 one" in usage_error(
        runner.invoke(app, ["drive", "--camera", "sim", "--sim-map", "reef-mosaic", "--cmd-vel", "/cmd_vel", *out])
    )
    assert "--cmd-vel-stamped: goes with --cmd-vel" in usage_error(
        runner.invoke(app, ["drive", *ros, "--dry-run", "--cmd-vel-stamped", *out])
    )
    assert "--ros-domain-id: goes with a ROS 2 --camera (ros2:/TOPIC) or --cmd-vel" in usage_error(
        runner.invoke(app, ["drive", "--camera", "0", "--dry-run", "--ros-domain-id", "3", *out])
    )
    assert "Invalid value for '--ros-domain-id'" in usage_error(
        runner.invoke(app, ["drive", *ros, "--dry-run", "--ros-domain-id", "233", *out])
    )
    # a bag replay's options mean nothing to a live topic; its odometry topic does (it gets through to the camera)
    assert "Error: --topic: got '/x', but camera 'ros2:/camera/image/compressed' is not a bag; a ROS 2 camera's topic" in (
        one_line_error(runner.invoke(app, ["drive", *ros, "--dry-run", "--topic", "/x", *out]))
    )
    assert "Error: --strict: camera 'ros2:/camera/image/compressed' is not a bag" in one_line_error(
        runner.invoke(app, ["drive", *ros, "--dry-run", "--strict", *out])
    )
    assert "Error: --odom-topic: got '/odom', but camera '0' is not a bag or a ROS 2 topic" in one_line_error(
        runner.invoke(app, ["drive", "--camera", "0", "--dry-run", "--odom-topic", "/odom", *out])
    )
    assert "Error: --camera: got 'ros2:/1st/image', expected a ROS topic name" in one_line_error(
        runner.invoke(app, ["drive", "--camera", "ros2:/1st/image", "--dry-run", *out])
    )
    assert not (tmp_path / "run").exists()


def test_without_cyclonedds_a_ros_2_camera_or_robot_names_the_extra(tmp_path, monkeypatch):
    for module in ("cyclonedds.core", "cyclonedds.domain"):
        monkeypatch.setitem(sys.modules, module, None)  # an import of it fails as if it were not installed
    extra = "ROS 2 is spoken through Cyclone DDS's Python binding: pip install 'curiosity-cli[ros2]'"
    result = runner.invoke(app, ["drive", "--dry-run", "--camera", "ros2:/camera/image", "--out", str(tmp_path / "a")])
    assert one_line_error(result) == f"Error: --camera ros2:/camera/image: {extra}"
    # refused before the camera opens (camera 7, no such device, would be the error otherwise) and the model loads
    result = runner.invoke(app, ["drive", "--camera", "7", "--cmd-vel", "cmd_vel", "--out", str(tmp_path / "b")])
    assert one_line_error(result) == f"Error: --cmd-vel cmd_vel: {extra}"
    assert not any(tmp_path.iterdir())


def test_ros_names_and_domains(monkeypatch):
    assert ros2.ros_topic("camera/image", "camera") == "/camera/image"
    assert ros2.ros_topic("/a_1/B/_c", "cmd_vel") == "/a_1/B/_c"
    for bad in ("", "/", "//a", "/a/", "/a//b", "/1a", "a b", "/a-b", "~/a", "/" + "a" * 253):
        with pytest.raises(ParameterError, match="^cmd_vel: got .* expected a ROS topic name") as info:
            ros2.ros_topic(bad, "cmd_vel")
        assert info.value.parameter == "cmd_vel"
    monkeypatch.delenv("ROS_DOMAIN_ID", raising=False)
    assert ros2.ros_domain_id(None) == 0 and ros2.ros_domain_id(232) == 232
    monkeypatch.setenv("ROS_DOMAIN_ID", " 42 ")
    assert ros2.ros_domain_id(None) == 42 and ros2.ros_domain_id(7) == 7  # given, it wins over the environment
    for text in ("x", "-1", "233", "4.5", "\u00b2", "\u0663"):  # superscript two and Arabic-Indic three: digits to isdigit
        monkeypatch.setenv("ROS_DOMAIN_ID", text)
        with pytest.raises(ParameterError, match=rf"^ros_domain_id: not given, and ROS_DOMAIN_ID is '{text}'"):
            ros2.ros_domain_id(None)
    for value in (-1, 233, True, 1.0):
        with pytest.raises(ParameterError, match=r"^ros_domain_id: got .*, expected a whole number 0\.\.232$"):
            ros2.ros_domain_id(value)


def odometry(sec: int, nanosec: int, x: float, frame_id: str = "odom"):
    """An odometry message as any reader gives one: its header and its pose's fields."""
    orientation = SimpleNamespace(x=0.0, y=0.0, z=0.0, w=1.0)
    return SimpleNamespace(
        header=SimpleNamespace(stamp=SimpleNamespace(sec=sec, nanosec=nanosec), frame_id=frame_id),
        pose=SimpleNamespace(pose=SimpleNamespace(position=SimpleNamespace(x=x, y=0.0, z=0.0), orientation=orientation)),
    )


def test_a_live_topics_poses_are_matched_to_a_frame_by_header_stamps():
    poses = RecentPoses()
    assert poses.nearest(10**9) is None
    for second, x in ((10, 1.0), (11, 2.0), (12, float("nan")), (13, 1e9)):
        poses.add(odometry(second, 0, x))
    poses.add(SimpleNamespace(header=None))
    assert (poses.kept, poses.damaged, poses.senseless) == (2, 2, 1)
    pose = poses.nearest(11_300_000_000)
    assert pose.position == (2.0, 0.0, 0.0) and pose.gap_ns == -300_000_000 and pose.frame_id == "odom"
    assert poses.nearest(10_500_000_000).position == (1.0, 0.0, 0.0)  # the earlier of two as near, as a replay's
    assert poses.nearest(14_000_000_000) is None  # 3 s from the newest kept: beyond MAX_POSE_GAP_NS
    poses.add(odometry(14, 0, 3.0))
    assert poses.nearest(14_000_000_000).position == (3.0, 0.0, 0.0)  # made again once new poses came


# ------------------------------------------------------------------ over DDS, in this process


@pytest.fixture
def dds(monkeypatch):
    """DDS on loopback (before this test's first participant), and short timeouts; our types, and a participant."""
    pytest.importorskip("cyclonedds")
    from ros2_robot import LOOPBACK

    monkeypatch.setenv("CYCLONEDDS_URI", LOOPBACK)
    monkeypatch.delenv("ROS_DOMAIN_ID", raising=False)
    for name, seconds in (("FRAME_TIMEOUT", 1.0), ("MATCH_TIMEOUT", 1.0)):
        monkeypatch.setattr(ros2, name, seconds)
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from curiosity_cli.drive import ros2_types

    def writer(participant, topic: str, kind):
        return DataWriter(participant, Topic(participant, f"rt{topic}", kind))

    def reader(participant, topic: str, kind):
        keep_all = Qos(Policy.Reliability.Reliable(max_blocking_time=10**8), Policy.History.KeepAll)
        return DataReader(participant, Topic(participant, f"rt{topic}", kind), qos=keep_all)

    return SimpleNamespace(types=ros2_types, participant=DomainParticipant, writer=writer, reader=reader)


def wait_for(condition, seconds: float = 5.0):
    deadline = time.monotonic() + seconds
    while not (got := condition()) and time.monotonic() < deadline:
        time.sleep(0.02)
    return got


def png_frame(dds, value: int, sec: int):
    """A compressed frame of one grey ``value`` (PNG: lossless), stamped ``sec`` s and 5 ns."""
    image = np.full((48, 64, 3), value, np.uint8)
    header = dds.types.Header(stamp=dds.types.Time(sec=sec, nanosec=5), frame_id="camera")
    return dds.types.CompressedImage(header=header, format="png", data=cv2.imencode(".png", image)[1].tobytes())


def opened(dds, frames, topic: str, domain: int):
    """A Ros2Camera on ``topic``, opened while ``frames`` publishes grey frames of 10 (the first is what it opens on;
    a frame written before the camera's reader matched would be lost)."""
    publishing = True

    def publish():
        while publishing:
            frames.write(png_frame(dds, 10, 1))
            time.sleep(0.02)

    thread = threading.Thread(target=publish)
    thread.start()
    try:
        return ros2.Ros2Camera(topic, domain_id=domain)
    finally:
        publishing = False
        thread.join()


@pytest.mark.slow  # two waits of a timeout each, 1 s here
def test_the_camera_reads_the_newest_frame_skips_a_damaged_one_and_ends_when_frames_stop(dds):
    participant = dds.participant(74)
    frames = dds.writer(participant, "/camera/image/compressed", dds.types.CompressedImage)
    frames.write(png_frame(dds, 10, 1))
    with pytest.raises(CameraError, match=r"^camera ros2:/other/compressed: no frame within 1 s on ROS domain 74"):
        ros2.Ros2Camera("/other/compressed", domain_id=74)
    camera = opened(dds, frames, "camera/image/compressed", 74)
    assert (camera.topic, camera.odom_topic, camera.domain_id) == ("/camera/image/compressed", None, 74)
    for value, sec in ((20, 2), (30, 3)):
        frames.write(png_frame(dds, value, sec))
    time.sleep(0.3)
    frame = camera.read()  # the newest of those waiting: the ones before it are stale
    assert frame.image.shape == (48, 64, 3) and (frame.image == 30).all()
    assert frame.header_ns == 3_000_000_005 and frame.recorded_ns is None and frame.pose is None
    damaged = dds.types.CompressedImage(header=png_frame(dds, 0, 4).header, format="jpeg", data=b"\xff\xd8 not a jpeg")
    frames.write(damaged)
    with pytest.raises(BadMessage, match="ros2:/camera/image/compressed, message .*: format 'jpeg': 13 bytes") as bad:
        camera.read()
    assert bad.value.index >= 3 and bad.value.bag_time is None
    with pytest.raises(CameraError, match=r"^camera ros2:/camera/image/compressed: no frame for 1 s on ROS domain 74 "
                                          r"\(the camera stopped publishing, or the network lost it\)$"):
        camera.read()
    camera.close()


def test_the_robot_publishes_twists_in_ros_axes_again_while_no_new_one_comes_and_stops(dds):
    participant = dds.participant(75)
    twists = dds.reader(participant, "/cmd_vel", dds.types.TwistStamped)
    surprise = dds.reader(participant, "/curiosity/surprise", dds.types.Float32)
    target = dds.reader(participant, "/curiosity/target", dds.types.PointStamped)
    stops = []
    robot = ros2.Ros2Robot("/cmd_vel", stamped=True, domain_id=75, keepalive=0.05, log=lambda e, **f: stops.append(f))
    assert (robot.subscribers, robot.message_type, robot.error, robot.state()) == (1, "geometry_msgs/msg/TwistStamped", None, None)
    before = time.time_ns()
    assert robot.command(0.3, 0.25, -0.1) == 0 and robot.ack_latency(0) is None
    time.sleep(0.4)  # the keepalive publishes the same command again every 0.05 s
    robot.publish_frame({"frame": 0, "time_ns": 5, "header_time_ns": 7_000_000_011, "perplexity": [[1.0, 2.0], [3.0, 6.0]],
                         "scores": [[1.0]], "words": 4, "target": [1, 0]})
    assert robot.close() is True and robot.close() is True and robot.command(0.3, 0.0, 0.0) is None
    received = wait_for(lambda: twists.take(100))
    moving = [t for t in received if t.twist.linear.x]
    assert len(moving) >= 3 and all(t.header.frame_id == "base_link" and t.header.stamp.sec >= before // 10**9 for t in moving)
    # REP 103: y left and z up; the wire protocol's yaw is positive to the right and its pitch positive nose up
    assert {(t.twist.linear.x, t.twist.angular.y, t.twist.angular.z) for t in moving} == {(0.3, 0.1, -0.25)}
    stop = received[len(moving):]
    assert len(stop) == 3 and all(t.twist == dds.types.Twist() for t in stop)
    assert str(stop[0].twist.angular.z) == "0.0"  # +0.0, not -0.0
    assert stops == [{"topic": "/cmd_vel", "sent": 3, "subscribers": 1, "acknowledged": True}]
    (value,) = wait_for(lambda: surprise.take(10))
    assert value.data == 3.0  # the frames table's surprise: the mean over the frame's image cells
    (point,) = wait_for(lambda: target.take(10))
    assert (point.point.x, point.point.y, point.header.frame_id) == (0.0, 1.0, "curiosity_image_cells")
    assert (point.header.stamp.sec, point.header.stamp.nanosec) == (7, 11)  # the frame's header stamp


@pytest.mark.slow  # two waits of a timeout each, 1 s here
def test_a_robot_no_one_listens_to_is_refused_and_one_that_leaves_is_an_error(dds):
    with pytest.raises(LinkError, match=r"^cmd_vel: no subscriber of /nobody \(geometry_msgs/msg/Twist\) within 1 s on "
                                        r"ROS domain 76 \(is the robot's driver running") as info:
        ros2.Ros2Robot("nobody", domain_id=76)
    assert info.value.parameter == "cmd_vel"
    participant = dds.participant(76)
    listener = dds.reader(participant, "/cmd_vel", dds.types.Twist)
    robot = ros2.Ros2Robot("/cmd_vel", domain_id=76)
    assert robot.command(0.1, 0.0, 0.0) == 0
    del listener, participant  # the robot's driver leaves
    assert wait_for(lambda: robot.command(0.1, 0.0, 0.0) is None and robot.error)
    assert robot.error == "/cmd_vel has no subscriber any more (the robot's driver left, or the network lost it)"
    assert robot.close() is False  # STOP sent to no one after waiting MATCH_TIMEOUT for one: not acknowledged


def test_a_domain_cyclone_dds_cannot_join_is_one_line(dds, monkeypatch):
    monkeypatch.setenv("CYCLONEDDS_URI", "<CycloneDDS><Domain id='any'><NoSuchSection/></Domain></CycloneDDS>")
    with pytest.raises(CuriosityError, match=r"^cmd_vel /cmd_vel: Cyclone DDS cannot join ROS domain 80 \(.*\); is "
                                             r"CYCLONEDDS_URI right\?$"):
        ros2.Ros2Robot("/cmd_vel", domain_id=80)


def test_a_camera_sending_only_damaged_frames_ends_and_a_stop_ends_every_wait(dds):
    """Hostile round (issue 64): a camera whose frames were all damaged was skipped for ever; a signal during a wait
    for a frame or a subscriber waited it out."""
    participant = dds.participant(82)
    frames = dds.writer(participant, "/camera/image/compressed", dds.types.CompressedImage)
    camera = opened(dds, frames, "/camera/image/compressed", 82)
    assert (camera.read().image == 10).all()
    damaged = dds.types.CompressedImage(header=png_frame(dds, 0, 2).header, format="jpeg", data=b"\xff\xd8 not a jpeg")
    deadline = time.monotonic() + 5
    with pytest.raises(CameraError, match=r"^camera ros2:/camera/image/compressed: no usable frame for 1 s on ROS domain "
                                          r"82, only damaged ones \(the last: format 'jpeg': 13 bytes"):
        while time.monotonic() < deadline:  # a drive skips each, and reads on
            frames.write(damaged)
            with contextlib.suppress(BadMessage):
                camera.read()
    camera.close()
    started = time.monotonic()
    silent = ros2.Ros2Camera("/camera/silent/compressed", domain_id=82, stopped=lambda: True)  # no frame, no error
    with pytest.raises(CameraError):  # the driver takes this for the stop, as its signal is set
        silent.read()
    nobody = ros2.Ros2Robot("/cmd_vel_nobody", domain_id=82, stopped=lambda: True)
    assert nobody.subscribers == 0 and nobody.close() is False
    assert time.monotonic() - started < 0.9, "a stop ends the waits at once (each is 1 s here)"


def test_the_robot_is_halted_once_the_drive_stops_commanding(dds, monkeypatch):
    """Hostile round (issue 64): while the camera stalled, the keepalive published the last moving twist for 5 s."""
    monkeypatch.setattr(ros2, "STALE_AFTER", 0.3)
    participant = dds.participant(83)
    twists = dds.reader(participant, "/cmd_vel", dds.types.Twist)
    robot = ros2.Ros2Robot("/cmd_vel", domain_id=83, keepalive=0.05)
    robot.command(0.3, 0.0, 0.0)
    time.sleep(1.0)  # no new command: the drive's camera stalled
    received = wait_for(lambda: twists.take(200))
    moving = [t for t in received if t.linear.x]
    assert 2 <= len(moving) <= 12, "the command, and again every 0.05 s for 0.3 s"
    assert received[len(moving):] == [dds.types.Twist()], "then one zero twist, and nothing more"
    robot.close()
