"""A drive's mission for the tools robotics people use: ``mission.mcap`` decoded with the mcap project's own
readers and Foxglove's schemas, ``frames.parquet`` and ``open_mission``, poses from a bag's odometry,
``trajectory.png``, MCAP files of Foxglove images replayed, and the live view over a real WebSocket."""

from __future__ import annotations

import base64
import json
import math
import re
import struct
import subprocess
import threading
import time
from collections import Counter
from pathlib import Path

import cv2
import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from curiosity_cli import api
from curiosity_cli.cli import app
from curiosity_cli.drive.frames_table import frame_summary
from curiosity_cli.maps.map_data import load_map

from drive_processes import CURIOSITY, START_SECONDS, read_log

pytest.importorskip("rosbags")
pytest.importorskip("foxglove")
from mcap.reader import make_reader  # noqa: E402
from mcap.records import Schema  # noqa: E402
from mcap_protobuf.decoder import DecoderFactory  # noqa: E402
from rosbags.rosbag2 import StoragePlugin, Writer  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

runner = CliRunner()
START = 1_700_000_000_000_000_000  # bag time of the first frame, ns since the epoch
PERIOD = 250_000_000  # 4 frames a second
ODOMETRY_OFFSET = 7_000_000  # odometry at twice the frame rate, 7 ms after each half period
GRID = ["--set", "drive.grid_rows=4", "--set", "drive.grid_cols=4"]


def mission_frames(count: int) -> list[np.ndarray]:
    """(120, 160, 3) RGB frames cut from the aerial mosaic along a diagonal."""
    image = load_map("aerial-mosaic").image
    return [np.ascontiguousarray(image[(5 * i) % 600 : (5 * i) % 600 + 120, (6 * i) % 600 : (6 * i) % 600 + 160])
            for i in range(count)]


def _png(frame: np.ndarray) -> bytes:
    ok, png = cv2.imencode(".png", frame[:, :, ::-1])
    assert ok
    return png.tobytes()


def write_ros2_mission(
    path: Path, frames: list[np.ndarray], odometry: tuple[str, ...] = ("/odom",), transforms: bool = False
) -> Path:
    """A ROS 2 MCAP bag: PNG frames on /camera/image and, on each of ``odometry``'s topics, a pose at twice
    the frame rate moving 0.1 m along x and 0.05 m along y each, turning 0.01 rad each. With ``transforms``,
    the images are in frame ``camera_optical``, /tf_static places it on ``base_link`` (0.2 m ahead, 0.5 m up,
    the optical axes: z forward, x right), and /tf moves ``base_link`` in ``odom`` 1 m along x each frame
    period, at each frame's time plus 1 ms, with one transform at infinity among them (left out)."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    t = store.types

    def header(stamp: int, frame_id: str):
        return t["std_msgs/msg/Header"](
            stamp=t["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id=frame_id
        )

    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        camera = writer.add_connection("/camera/image", "sensor_msgs/msg/CompressedImage", typestore=store)
        for topic in odometry:
            connection = writer.add_connection(topic, "nav_msgs/msg/Odometry", typestore=store)
            for i in range(2 * len(frames)):
                stamp = START + i * PERIOD // 2 + ODOMETRY_OFFSET
                yaw = 0.01 * i
                pose = t["geometry_msgs/msg/Pose"](
                    position=t["geometry_msgs/msg/Point"](x=0.1 * i, y=0.05 * i, z=0.0),
                    orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=np.sin(yaw / 2), w=np.cos(yaw / 2)),
                )
                zero = t["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
                message = t["nav_msgs/msg/Odometry"](
                    header=header(stamp, "odom"), child_frame_id="base_link",
                    pose=t["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
                    twist=t["geometry_msgs/msg/TwistWithCovariance"](
                        twist=t["geometry_msgs/msg/Twist"](linear=zero, angular=zero), covariance=np.zeros(36)
                    ),
                )
                writer.write(connection, stamp, store.serialize_cdr(message, "nav_msgs/msg/Odometry"))
        if transforms:
            def link(stamp: int, parent: str, child: str, xyz, quaternion):
                return t["geometry_msgs/msg/TransformStamped"](
                    header=header(stamp, parent), child_frame_id=child,
                    transform=t["geometry_msgs/msg/Transform"](
                        translation=t["geometry_msgs/msg/Vector3"](x=xyz[0], y=xyz[1], z=xyz[2]),
                        rotation=t["geometry_msgs/msg/Quaternion"](
                            x=quaternion[0], y=quaternion[1], z=quaternion[2], w=quaternion[3]
                        ),
                    ),
                )

            def tf(connection, stamp: int, links) -> None:
                message = t["tf2_msgs/msg/TFMessage"](transforms=links)
                writer.write(connection, stamp, store.serialize_cdr(message, "tf2_msgs/msg/TFMessage"))

            static = writer.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=store)
            tf(static, START, [link(START, "base_link", "camera_optical", (0.2, 0.0, 0.5), (-0.5, 0.5, -0.5, 0.5))])
            moving = writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=store)
            for i in range(len(frames)):
                stamp = START + i * PERIOD + 1_000_000
                tf(moving, stamp, [link(stamp, "odom", "base_link", (1.0 * i, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)),
                                   link(stamp, "odom", "far", (float("inf"), 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))])
        for i, frame in enumerate(frames):
            stamp = START + i * PERIOD
            message = t["sensor_msgs/msg/CompressedImage"](
                header=header(stamp, "camera_optical" if transforms else "camera"), format="png",
                data=np.frombuffer(_png(frame), np.uint8),
            )
            writer.write(camera, stamp, store.serialize_cdr(message, "sensor_msgs/msg/CompressedImage"))
    return path


def write_foxglove_mission(path: Path, frames: list[np.ndarray], encoding: str) -> Path:
    """An MCAP file as the Foxglove SDK records one: ``foxglove.CompressedImage`` (PNG) in protobuf, or
    ``foxglove.RawImage`` (rgb8) in JSON with its data in base64; and in the same encoding a
    ``foxglove.PoseInFrame`` on /pose 7 ms after each frame, 0.1 m further along x each time."""
    import foxglove
    from foxglove.channels import CompressedImageChannel, PoseInFrameChannel
    from foxglove.messages import CompressedImage, Pose, PoseInFrame, Quaternion, Timestamp, Vector3

    context = foxglove.Context()
    writer = foxglove.open_mcap(path, context=context)
    if encoding == "protobuf":
        channel, poses = CompressedImageChannel("/cam", context=context), PoseInFrameChannel("/pose", context=context)
    else:
        def json_channel(topic: str, name: str):
            schema = foxglove.Schema(name=name, encoding="jsonschema", data=b'{"type":"object"}')
            return foxglove.Channel(topic, schema=schema, message_encoding="json", context=context)

        channel, poses = json_channel("/cam", "foxglove.RawImage"), json_channel("/pose", "foxglove.PoseInFrame")
    for i, frame in enumerate(frames):
        stamp = START + i * PERIOD
        at = stamp + ODOMETRY_OFFSET
        if encoding == "protobuf":
            poses.log(PoseInFrame(
                timestamp=Timestamp(sec=at // 10**9, nsec=at % 10**9), frame_id="map",
                pose=Pose(position=Vector3(x=0.1 * i, y=0.0, z=0.0), orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)),
            ), log_time=at)
        else:
            poses.log(json.dumps({"timestamp": {"sec": at // 10**9, "nsec": at % 10**9}, "frame_id": "map",
                                  "pose": {"position": {"x": 0.1 * i}}}).encode(), log_time=at)
        if encoding == "protobuf":
            channel.log(
                CompressedImage(timestamp=Timestamp(sec=stamp // 10**9, nsec=stamp % 10**9), frame_id="camera",
                                data=_png(frame), format="png"),
                log_time=stamp,
            )
        else:
            rows, cols = frame.shape[:2]
            message = {
                "timestamp": {"sec": stamp // 10**9, "nsec": stamp % 10**9}, "frame_id": "camera", "width": cols,
                "height": rows, "encoding": "rgb8", "step": 3 * cols, "data": base64.b64encode(frame.tobytes()).decode(),
            }
            channel.log(json.dumps(message).encode(), log_time=stamp)
    writer.close()
    return path


def replay(camera: Path, out: Path, *extra: str):
    return runner.invoke(app, ["drive", "--dry-run", "--camera", str(camera), "--out", str(out), *GRID, *extra])


def frame_records(out: Path) -> list[dict]:
    return [r for r in read_log(out) if r["event"] == "frame"]


def decoded(mission: Path) -> dict[str, list]:
    """Every message of a mission file by topic: (schema name, log time, decoded message), each through the
    mcap project's protobuf decoder from the schema the file embeds (every channel is protobuf)."""
    by_topic: dict[str, list] = {}
    protobuf = DecoderFactory()
    with mission.open("rb") as file:
        for schema, channel, message in make_reader(file).iter_messages():
            assert channel.message_encoding == "protobuf" and schema.encoding == "protobuf", channel.topic
            body = protobuf.decoder_for(channel.message_encoding, schema)(message.data)
            by_topic.setdefault(channel.topic, []).append((schema.name, message.log_time, body))
    return by_topic


def contents(mission: Path) -> tuple[list, dict]:
    """A mission file's messages (topic, log time, bytes) in order, and its metadata but the moment and the command
    line of the run (``provenance``'s ``started`` and ``command``), which two runs of the same replay do not share."""
    with mission.open("rb") as file:
        reader = make_reader(file)
        messages = [(channel.topic, message.log_time, message.data) for _, channel, message in reader.iter_messages()]
        metadata = {record.name: dict(record.metadata) for record in reader.iter_metadata()}
    for moment in ("started", "command"):
        metadata["provenance"].pop(moment)
    return messages, metadata


def fields(message) -> dict:
    """A decoded protobuf message's fields by name, those at their default (zero) included."""
    return {field.name: getattr(message, field.name) for field in message.DESCRIPTOR.fields}


@pytest.fixture(scope="module")
def replayed(tmp_path_factory) -> Path:
    """A ROS 2 bag of 12 frames with odometry, replayed."""
    folder = tmp_path_factory.mktemp("replayed")
    bag = write_ros2_mission(folder / "bag", mission_frames(12))
    result = replay(bag, folder / "out")
    assert result.exit_code == 0, result.output
    assert "wrote timeline.png, mission.mcap, mission.layout.json, frames.parquet, trajectory.png in" in result.output
    assert "poses from /odom: 24 messages" in result.output
    return folder / "out"


@pytest.mark.slow
def test_the_mission_file_decodes_with_foxglove_schemas_and_agrees_with_the_log(replayed):
    records = frame_records(replayed)
    channels = decoded(replayed / "mission.mcap")
    assert {topic: (rows[0][0], len(rows)) for topic, rows in channels.items()} == {
        "/camera/image": ("foxglove.CompressedImage", 12),
        "/curiosity/surprise": ("curiosity.Surprise", 12),
        "/curiosity/perplexity": ("foxglove.RawImage", 12),
        "/curiosity/cells": ("foxglove.ImageAnnotations", 12),
        "/curiosity/command": ("curiosity.Command", 12),
        "/pose": ("foxglove.PoseInFrame", 12),
        "/tf": ("foxglove.FrameTransforms", 12),
    }
    times = [START + i * PERIOD for i in range(12)]
    for rows in channels.values():
        assert [log_time for _, log_time, _ in rows] == times
    for record, (_, _, image) in zip(records, channels["/camera/image"]):
        assert image.format == "jpeg" and image.timestamp.ToNanoseconds() == record["header_time_ns"]
        assert cv2.imdecode(np.frombuffer(image.data, np.uint8), cv2.IMREAD_COLOR).shape == (120, 160, 3)
    for record, (_, _, surprise) in zip(records, channels["/curiosity/surprise"]):
        assert fields(surprise) == {"frame": record["frame"], **frame_summary(record)}
    for record, (_, _, grid) in zip(records, channels["/curiosity/perplexity"]):
        assert (grid.width, grid.height, grid.encoding) == (4, 4, "32FC1")
        values = np.frombuffer(grid.data, "<f4").reshape(4, 4)
        np.testing.assert_array_equal(values, np.asarray(record["perplexity"], np.float32))
    for record, (_, _, command) in zip(records, channels["/curiosity/command"]):
        assert fields(command) == {"frame": record["frame"], "target_row": record["target"][0],
                                   "target_col": record["target"][1], **record["command"]}
    for record, (_, _, cells) in zip(records, channels["/curiosity/cells"]):
        corners = [(p.x, p.y) for p in cells.points[0].points]
        row, col = record["target"]
        assert corners[0] == (col * 40, row * 30) and corners[2] == ((col + 1) * 40, (row + 1) * 30)
    for record, (_, _, pose) in zip(records, channels["/pose"]):
        p = record["pose"]
        assert pose.frame_id == "odom"
        assert (pose.pose.position.x, pose.pose.position.y, pose.pose.orientation.z) == (p["x"], p["y"], p["qz"])
    # the transforms link the pose's frame to the robot (the pose itself) and the robot to the camera (the default)
    for record, (_, _, tf) in zip(records, channels["/tf"]):
        robot, camera = tf.transforms
        assert (robot.parent_frame_id, robot.child_frame_id, camera.parent_frame_id, camera.child_frame_id) == (
            "odom", "base_link", "base_link", "camera"
        )
        assert (robot.translation.x, robot.rotation.z) == (record["pose"]["x"], record["pose"]["qz"])
        assert (camera.translation.x, camera.rotation.w) == (0.0, 1.0)


@pytest.mark.slow
def test_the_mission_file_holds_the_runs_config_and_provenance_and_a_layout_beside_it(replayed):
    with (replayed / "mission.mcap").open("rb") as file:
        metadata = {record.name: record.metadata for record in make_reader(file).iter_metadata()}
    assert metadata["config"] == {"config.yaml": (replayed / "config.yaml").read_text()}
    assert metadata["provenance"]["seed"] == "0" and metadata["provenance"]["curiosity"]
    layout = json.loads((replayed / "mission.layout.json").read_text())
    panels = []

    def walk(content):
        if content["type"] == "split":
            for item in content["items"]:
                walk(item["content"])
        else:
            panels.append(content)

    walk(layout["content"])
    # each panel shows a channel the file holds
    held = set(decoded(replayed / "mission.mcap"))
    assert [panel["panelType"] for panel in panels] == ["Image", "Image", "Plot", "ThreeDee"]
    assert {panels[0]["config"]["imageMode"]["imageTopic"], panels[1]["config"]["imageMode"]["imageTopic"]} <= held
    assert set(panels[0]["config"]["imageMode"]["annotations"]) <= held
    assert {path["value"].split(".")[0] for path in panels[2]["config"]["paths"]} <= held
    assert panels[3]["config"]["followTf"] == "base_link" and set(panels[3]["config"]["topics"]) <= held


@pytest.mark.slow
def test_each_frame_gets_the_nearest_odometry_in_time_with_its_gap(replayed):
    for record in frame_records(replayed):
        i = record["frame"]
        # the odometry 7 ms after the frame is the nearest (the one before is 118 ms before)
        pose = record["pose"]
        assert pose["source"] == "odometry" and pose["frame_id"] == "odom"
        assert pose["x"] == pytest.approx(0.1 * 2 * i) and pose["y"] == pytest.approx(0.05 * 2 * i)
        assert pose["yaw"] == pytest.approx(0.01 * 2 * i)
        assert pose["gap_ms"] == 7.0
    assert (replayed / "trajectory.png").stat().st_size > 10_000
    assert read_log(replayed)[-1]["outcome"] == "end of bag"  # issue 62: it was logged as "end of video"


@pytest.mark.slow
def test_the_frames_table_has_integer_nanoseconds_and_opens_with_its_config(replayed):
    table = api.open_mission(replayed)
    records = frame_records(replayed)
    assert len(table) == 12 and table["frame"].tolist() == list(range(12))
    assert table["time_ns"].dtype == np.int64
    assert table["bag_time_ns"].tolist() == [START + i * PERIOD for i in range(12)]
    assert table["surprise"].tolist() == [frame_summary(r)["surprise"] for r in records]
    assert table["refined"].tolist() == [r["refined"] for r in records]
    assert table["pose_gap_ms"].eq(7.0).all() and table["pose_source"].eq("odometry").all()
    assert table.attrs["config"]["drive"]["grid_rows"] == 4 and table.attrs["provenance"]["seed"] == 0
    csv = pd.read_csv(replayed / "frames.csv")
    assert csv["time_ns"].tolist() == table["time_ns"].tolist()
    assert csv["surprise"].tolist() == table["surprise"].tolist()


@pytest.mark.slow
def test_open_mission_reads_the_log_of_a_drive_stopped_before_its_table(replayed, tmp_path):
    copy = tmp_path / "copy"
    copy.mkdir()
    for name in ("log.jsonl", "config.yaml", "provenance.yaml"):
        (copy / name).write_bytes((replayed / name).read_bytes())
    pd.testing.assert_frame_equal(api.open_mission(copy), api.open_mission(replayed), check_like=False)


@pytest.mark.slow
def test_a_frames_table_not_made_from_the_run_s_log_is_named_and_the_log_read(replayed, tmp_path, capsys):
    """Issue 63: open_mission returned an edited frames.parquet, another run's table, and 8 rows for a run whose
    log holds only its start record; the table records the log's SHA-256 and frames it was made from."""
    truth = api.open_mission(replayed)
    copy = tmp_path / "copy"
    copy.mkdir()
    for name in ("log.jsonl", "config.yaml", "provenance.yaml", "frames.parquet"):
        (copy / name).write_bytes((replayed / name).read_bytes())
    edited = truth.copy()
    edited["surprise"] = 99.0
    edited.to_parquet(copy / "frames.parquet", index=False)  # another tool's write: no record of its log
    capsys.readouterr()
    pd.testing.assert_frame_equal(api.open_mission(copy), truth)
    assert "frames.parquet: it does not say which log it was made from" in capsys.readouterr().err

    started = copy / "log.jsonl"
    started.write_text(started.read_text().splitlines()[0] + "\n")  # the start record alone
    (copy / "frames.parquet").write_bytes((replayed / "frames.parquet").read_bytes())  # another run's table
    table = api.open_mission(copy)
    assert len(table) == 0 and list(table.columns) == list(truth.columns)
    assert "frames.parquet: it was made from another log than this run's" in capsys.readouterr().err


def test_open_mission_of_a_folder_that_is_no_run_is_one_error(tmp_path):
    from curiosity_cli.errors import CuriosityError

    with pytest.raises(CuriosityError, match=r"log.jsonl: not found; give a run folder of `curiosity drive`"):
        api.open_mission(tmp_path)


@pytest.mark.slow
def test_a_drive_folder_given_as_an_experiment_points_to_open_mission_and_force_is_the_apis_word(replayed):
    """Issue 62, item 4: open_experiment on a drive folder said ``config.yaml: name: missing key``, and the API told
    a Python caller to use ``--force``."""
    from curiosity_cli.errors import CuriosityError

    says = f"{replayed}: a drive's run folder, not an experiment; its frames are read with curiosity_cli.api.open_mission"
    with pytest.raises(CuriosityError, match=re.escape(says)):
        api.open_experiment(replayed)
    for command in ("evaluate", "plot"):  # plot said `mi.csv: not found` (a caveat left at stop 70)
        given = runner.invoke(app, [command, str(replayed)])
        assert given.exit_code == 1 and f"Error: {says}" in given.stderr, (command, given.output)
    with pytest.raises(CuriosityError, match=r"holds an earlier run \(log.jsonl and \d+ more\); give a new folder, or `force` to "):
        api.drive(camera=str(replayed / "mission.mcap"), out=replayed, dry_run=True, max_frames=1)


@pytest.mark.slow
def test_a_drives_own_mission_file_replays_from_its_camera_without_a_topic(replayed, tmp_path):
    """A mission file has two image channels, the camera's and the perplexity grid the drive wrote: a replay of it
    asked for ``--topic`` (issue 64's caveat); the drive's own outputs are never taken as the camera unless named."""
    result = replay(replayed / "mission.mcap", tmp_path / "again")
    assert result.exit_code == 0, result.output
    assert "replaying /camera/image" in result.output
    first, again = frame_records(replayed), frame_records(tmp_path / "again")
    assert [r["header_time_ns"] for r in again] == [r["header_time_ns"] for r in first]
    assert [r["pose"]["frame_id"] for r in again] == [r["pose"]["frame_id"] for r in first]
    # named, the perplexity grid is taken, and its float pixels are refused as a camera's
    named = replay(replayed / "mission.mcap", tmp_path / "grid", "--topic", "/curiosity/perplexity")
    assert named.exit_code == 1 and "/curiosity/perplexity, message 0: encoding '32FC1': expected one of" in named.stderr


@pytest.mark.slow
def test_a_live_views_port_in_use_is_refused_before_the_model_loads(replayed, tmp_path):
    """A busy ``--foxglove`` port was found only after the model had loaded (a caveat left at stop 70)."""
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = replay(replayed / "mission.mcap", tmp_path / "run", "--foxglove", str(port))
    assert result.exit_code == 1, result.output
    assert result.stderr.strip().splitlines() == [f"Error: --foxglove: cannot serve a live view on port {port} (Address already in use)"]
    assert not (tmp_path / "run").exists()


@pytest.mark.slow
def test_a_bags_own_transforms_link_the_frames_in_place_of_the_stated_default(tmp_path):
    """Issue 62, item 2: the mission file's transforms come from the bag's /tf_static and /tf where it has them."""
    bag = write_ros2_mission(tmp_path / "bag", mission_frames(4), transforms=True)
    result = replay(bag, tmp_path / "out")
    assert result.exit_code == 0, result.output
    assert "frames linked by 2 transforms of /tf_static and /tf (4 transforms outside physical sense left out)" in (
        result.output
    )
    frames = decoded(tmp_path / "out" / "mission.mcap")["/tf"]
    assert len(frames) == 4
    for i, (_, _, message) in enumerate(frames):
        links = {(t.parent_frame_id, t.child_frame_id): t for t in message.transforms}
        # the bag's mount; the image's frame as the file's camera; the robot in odom as the bag's /tf had it at the
        # frame's time (its message 1 ms after the frame is the next frame's), and before its first, nowhere: the
        # odometry's pose does not place the robot again where the bag places it
        placed = {("odom", "base_link")} if i else set()
        assert set(links) == {("base_link", "camera_optical"), ("camera_optical", "camera")} | placed
        mount = links["base_link", "camera_optical"]
        assert (mount.translation.x, mount.translation.z, mount.rotation.x, mount.rotation.w) == (0.2, 0.5, -0.5, 0.5)
        assert links["camera_optical", "camera"].rotation.w == 1.0
        if i:
            assert links["odom", "base_link"].translation.x == i - 1.0


@pytest.mark.slow
def test_a_bag_without_odometry_has_frames_without_pose_and_no_trajectory(tmp_path):
    bag = write_ros2_mission(tmp_path / "bag", mission_frames(3), odometry=())
    result = replay(bag, tmp_path / "out")
    assert result.exit_code == 0, result.output
    assert "frames have no pose: " in result.output and "has no odometry topic" in result.output
    assert all(r["pose"] is None for r in frame_records(tmp_path / "out"))
    assert not (tmp_path / "out" / "trajectory.png").exists()
    assert "wrote timeline.png, mission.mcap, mission.layout.json, frames.parquet in" in result.output
    assert "/pose" not in decoded(tmp_path / "out" / "mission.mcap")


@pytest.mark.slow
def test_odometry_on_several_topics_needs_one_named(tmp_path):
    bag = write_ros2_mission(tmp_path / "bag", mission_frames(3), odometry=("/odom", "/odom_filtered"))
    result = replay(bag, tmp_path / "out")
    assert result.exit_code == 0 and "odometry on 2 topics (/odom, /odom_filtered): give one as odom_topic" in result.output
    result = replay(bag, tmp_path / "named", "--odom-topic", "/odom_filtered")
    assert result.exit_code == 0 and "poses from /odom_filtered: 6 messages" in result.output


@pytest.mark.parametrize("topic, says", [
    ("/camera/image", "--odom-topic: '/camera/image' holds sensor_msgs/msg/CompressedImage; the pose topics "
                      "(nav_msgs/msg/Odometry or foxglove.PoseInFrame) of"),
    ("/nowhere", "--odom-topic: '/nowhere' is not a topic there; the pose topics (nav_msgs/msg/Odometry or "
                 "foxglove.PoseInFrame) of"),
])
def test_an_odom_topic_that_is_no_odometry_is_one_error(tmp_path, topic, says):
    bag = write_ros2_mission(tmp_path / "bag", mission_frames(2))
    result = replay(bag, tmp_path / "out", "--odom-topic", topic)
    assert result.exit_code == 1 and says in result.output and "Traceback" not in result.output
    assert not (tmp_path / "out").exists()


def test_an_odom_topic_needs_a_bag(tmp_path):
    result = runner.invoke(app, ["drive", "--dry-run", "--camera", "0", "--odom-topic", "/odom"])
    assert result.exit_code != 0 and "--odom-topic: got '/odom', but camera '0' is not a bag" in result.output


@pytest.mark.slow
@pytest.mark.parametrize("encoding", ["protobuf", "json"])
def test_an_mcap_of_foxglove_images_replays_as_the_same_frames_in_a_ros_bag(tmp_path, replayed, encoding):
    mission = write_foxglove_mission(tmp_path / "foxglove.mcap", mission_frames(12), encoding)
    result = replay(mission, tmp_path / "out")
    assert result.exit_code == 0, result.output
    ours, ros = api.open_mission(tmp_path / "out"), api.open_mission(replayed)
    for column in ("time_ns", "header_time_ns", "surprise", "refined", "words", "target_row", "target_col"):
        assert ours[column].tolist() == ros[column].tolist(), column
    # its poses as a bag's odometry: the nearest in time (7 ms after), its frame, the identity where none is given
    assert "wrote timeline.png, mission.mcap, mission.layout.json, frames.parquet, trajectory.png in" in result.output
    assert ours["pose_frame"].eq("map").all() and ours["pose_gap_ms"].eq(7.0).all() and ours["yaw"].eq(0.0).all()
    assert ours["x"].tolist() == pytest.approx([0.1 * i for i in range(12)]) and ours["y"].eq(0.0).all()


def test_an_mcap_of_other_messages_names_what_is_read(tmp_path):
    import foxglove
    from foxglove.channels import LogChannel
    from foxglove.messages import Log, Timestamp

    context = foxglove.Context()
    writer = foxglove.open_mcap(tmp_path / "logs.mcap", context=context)
    LogChannel("/rosout", context=context).log(Log(timestamp=Timestamp(sec=1, nsec=0), message="hi"), log_time=10**9)
    writer.close()
    result = replay(tmp_path / "logs.mcap", tmp_path / "out")
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert re.search(
        r"logs\.mcap: not a readable bag: its channels hold foxglove\.Log \(protobuf\); expected ROS 2 images "
        r"\(profile ros2\) or Foxglove images \(foxglove\.CompressedImage or foxglove\.RawImage, encoded as "
        r"protobuf or json\)", " ".join(result.output.split()),
    ), result.output


def test_a_simulated_drive_writes_its_mission_with_the_robots_pose(tmp_path):
    result = runner.invoke(app, [
        "drive", "--dry-run", "--camera", "sim", "--sim-map", "aerial-mosaic", "--max-frames", "5",
        "--out", str(tmp_path / "out"), *GRID,
    ])
    assert result.exit_code == 0, result.output
    assert "wrote mission.mcap, mission.layout.json, frames.parquet, trajectory.png in" in result.output
    table = api.open_mission(tmp_path / "out")
    assert table["pose_source"].eq("robot").all() and table["x"].notna().all()
    live_times = table["time_ns"].tolist()
    assert live_times == sorted(live_times) and table["bag_time_ns"].isna().all()
    assert {topic: len(rows) for topic, rows in decoded(tmp_path / "out" / "mission.mcap").items()}["/pose"] == 5


@pytest.mark.slow
def test_the_live_view_serves_the_surprise_over_foxglove_websocket_and_changes_no_byte(tmp_path):
    """A real WebSocket client connects while a replay runs, subscribes to the surprise channel, receives
    frames whose values are the log's, and disconnects; the mission file is the one made without a viewer."""
    from websockets.sync.client import connect

    bag = write_ros2_mission(tmp_path / "bag", mission_frames(150))  # seconds of replay: time to subscribe
    command = [CURIOSITY, "drive", "--dry-run", "--camera", str(bag), *GRID]
    with subprocess.Popen([*command, "--out", str(tmp_path / "live"), "--foxglove", "0"],
                          stderr=subprocess.PIPE, text=True) as process:
        port = None
        for line in process.stderr:
            if found := re.search(r"live view: open ws://127\.0\.0\.1:(\d+) in Foxglove", line):
                port = int(found.group(1))
                break
        assert port is not None
        rest = threading.Thread(target=process.stderr.read)  # its progress must not fill the pipe and stall it
        rest.start()
        received = []
        try:
            with connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"],
                         open_timeout=START_SECONDS) as socket:
                while len(received) < 3:
                    message = socket.recv(timeout=START_SECONDS)
                    if isinstance(message, str):
                        control = json.loads(message)
                        if control["op"] == "advertise":
                            channels = {c["topic"]: c for c in control["channels"]}
                            assert {"/camera/image", "/curiosity/surprise", "/pose", "/tf"} <= set(channels)
                            surprise = channels["/curiosity/surprise"]
                            # decoded from the schema the server advertises, by the mcap project's decoder
                            schema = Schema(id=1, name=surprise["schemaName"], encoding=surprise["schemaEncoding"],
                                            data=base64.b64decode(surprise["schema"]))
                            decode = DecoderFactory().decoder_for(surprise["encoding"], schema)
                            socket.send(json.dumps({"op": "subscribe", "subscriptions": [
                                {"id": 7, "channelId": surprise["id"]}]}))
                    else:
                        assert message[0] == 1 and struct.unpack_from("<I", message, 1)[0] == 7  # message data, ours
                        received.append((struct.unpack_from("<Q", message, 5)[0], fields(decode(message[13:]))))
            process.wait(timeout=START_SECONDS * 3)
        finally:
            if process.poll() is None:
                process.kill()
            rest.join()
    assert process.returncode == 0
    records = {r["frame"]: r for r in frame_records(tmp_path / "live")}
    frames = [body["frame"] for _, body in received]
    assert frames == list(range(frames[0], frames[0] + 3))
    for log_time, body in received:
        record = records[body["frame"]]
        assert log_time == record["time_ns"] and body == {"frame": body["frame"], **frame_summary(record)}
    subprocess.run([*command, "--out", str(tmp_path / "alone")], check=True, capture_output=True)
    live, alone = (contents(tmp_path / name / "mission.mcap") for name in ("live", "alone"))
    assert live == alone and len(live[0]) == 7 * 150  # seven channels a frame
    assert Counter(r["event"] for r in read_log(tmp_path / "live"))["frame"] == 150


def test_a_mission_file_that_cannot_be_finished_is_one_error_naming_it(tmp_path):
    """Issue 64: a disk filling during a replay ended in a traceback (FoxgloveError: MCAP error)."""
    from curiosity_cli.drive.mission import MissionFile
    from curiosity_cli.errors import CuriosityError

    mission = MissionFile(tmp_path / "mission.mcap")
    real = mission._writer

    class Full:
        def close(self):
            real.close()
            raise RuntimeError("MCAP error: No space left on device (os error 28)")

    mission._writer = Full()
    with pytest.raises(CuriosityError, match=r"mission.mcap: cannot be finished \(MCAP error: No space left on device"):
        mission.close()
    mission.close()  # closed once: a second close is nothing


@pytest.mark.slow
def test_a_drive_killed_outright_leaves_a_mission_file_read_up_to_its_last_frame(tmp_path):
    """Hostile round (issue 64): a SIGKILLed drive's mission.mcap held only a chunk header with its length's
    placeholder (the SDK kept about a megabyte of frames in memory): no reader got a message, and a replay of it ended
    in an OverflowError."""
    from mcap.exceptions import EndOfFile
    from mcap.stream_reader import StreamReader

    bag = write_ros2_mission(tmp_path / "bag", mission_frames(400))  # seconds of replay: time to kill it
    out = tmp_path / "killed"
    with subprocess.Popen([CURIOSITY, "drive", "--dry-run", "--camera", str(bag), "--out", str(out), *GRID],
                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) as process:
        try:
            deadline = time.monotonic() + START_SECONDS * 2
            while len([r for r in read_log(out) if r["event"] == "frame"] if (out / "log.jsonl").is_file() else []) < 8:
                assert time.monotonic() < deadline and process.poll() is None
                time.sleep(0.05)
        finally:
            process.kill()
    logged = len(frame_records(out))
    messages = Counter()
    with (out / "mission.mcap").open("rb") as file, pytest.raises(EndOfFile):
        for record in StreamReader(file).records:  # the mcap project's own reader: every frame written, then the cut
            messages[type(record).__name__] += 1
    assert messages["Message"] >= 7 * (logged - 1) and messages["Metadata"] == 2
    again = replay(out / "mission.mcap", tmp_path / "again", "--topic", "/camera/image")
    assert again.exit_code == 0, again.output
    assert len(frame_records(tmp_path / "again")) >= logged - 1


def test_a_poses_quaternion_of_another_length_is_shown_as_the_unit_rotation_it_stands_for(tmp_path):
    """Hostile round (issue 64): odometry's quaternion of length 2 went into /pose and /tf as it was, which a viewer
    reads as a rotation that also scales."""
    from curiosity_cli.drive.mission import MissionFile, _rotation

    unit = {"qx": 0.1, "qy": 0.2, "qz": 0.3, "qw": math.sqrt(1 - 0.14)}
    assert _rotation(unit) == (0.1, 0.2, 0.3, unit["qw"])  # a unit one as recorded, value for value
    half = math.radians(30) / 2
    pose = {"frame_id": "odom", "x": 1.0, "y": 2.0, "z": 0.0, "qx": 0.0, "qy": 0.0, "qz": 2 * math.sin(half),
            "qw": 2 * math.cos(half)}
    mission = MissionFile(tmp_path / "mission.mcap")
    try:
        (_, _, _, rotation), _ = mission._links(0, pose)
    finally:
        mission.close()
    np.testing.assert_allclose(rotation, (0.0, 0.0, math.sin(half), math.cos(half)), rtol=0, atol=1e-15)


def test_a_pose_in_no_frame_or_in_the_robots_own_places_nothing(tmp_path):
    """Hostile round (issue 64): odometry whose frame_id was '' or base_link put a transform with no parent, or a
    loop base_link -> base_link, into /tf."""
    from curiosity_cli.drive.mission import MissionFile

    mission = MissionFile(tmp_path / "mission.mcap")
    pose = {"x": 1.0, "y": 2.0, "z": 0.0, "qx": 0.0, "qy": 0.0, "qz": 0.0, "qw": 1.0}
    try:
        for frame_id, placed in (("odom", True), ("", False), ("base_link", False)):
            links = [(parent, child) for parent, child, _, _ in mission._links(0, {**pose, "frame_id": frame_id})]
            assert links == [("odom", "base_link")] * placed + [("base_link", "camera")]
    finally:
        mission.close()


@pytest.mark.slow
def test_drive_timeline_of_a_live_ros_2_drive_draws_its_trajectory_alone(replayed, tmp_path):
    """Hostile round (issue 64): a live ROS 2 drive's log names its topic, and --timeline took it for a replay's ("holds
    no frame of the replay")."""
    import shutil

    live = Path(shutil.copytree(replayed, tmp_path / "live"))
    for name in ("timeline.png", "timeline.pdf", "trajectory.png"):
        (live / name).unlink(missing_ok=True)
    lines = (live / "log.jsonl").read_text().splitlines()
    start = json.loads(lines[0])
    start.pop("bag", None)
    (live / "log.jsonl").write_text("\n".join([json.dumps({**start, "camera": "ros2:/camera/image"}), *lines[1:]]) + "\n")
    result = runner.invoke(app, ["drive", "--timeline", str(live)])
    assert result.exit_code == 0, result.output
    assert f"wrote {live / 'trajectory.png'}" in result.stdout and not (live / "timeline.png").exists()
