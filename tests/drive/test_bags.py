"""Recorded missions as a camera: bags written here with rosbags' own writers (ROS 1, ROS 2 sqlite3,
ROS 2 MCAP), frames cut from an embedded map, replayed through ``curiosity drive --dry-run``."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from typer.testing import CliRunner

from curiosity_cli.cli import app
from curiosity_cli.maps.map_data import load_map
from curiosity_cli.drive.bags import BagCamera, decode
from curiosity_cli.drive.camera import CameraError

pytest.importorskip("rosbags")
from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import StoragePlugin  # noqa: E402
from rosbags.rosbag2 import Writer as Writer2  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

runner = CliRunner()
FRAMES = 4
START = 1_700_000_000_000_000_000  # bag time of the first frame, ns since the epoch
PERIOD = 250_000_000  # 4 frames a second


@pytest.fixture(scope="module")
def frames() -> list[np.ndarray]:
    """(120, 160, 3) RGB frames cut from the aerial mosaic along a diagonal."""
    image = load_map("aerial-mosaic").image
    return [np.ascontiguousarray(image[40 * i : 40 * i + 120, 50 * i : 50 * i + 160]) for i in range(FRAMES)]


@pytest.fixture(scope="module")
def standout() -> list[np.ndarray]:
    """(120, 160, 3) RGB frames: three of one place of the aerial mosaic, each with its own sensor noise, then one
    of the reef mosaic, which stands out (a perplexity 3 to 5 times theirs, far above the timeline's rule)."""
    view = load_map("aerial-mosaic").image[200:320, 300:460].astype(np.int16)
    rng = np.random.default_rng(0)
    same = [np.clip(view + rng.integers(-3, 4, view.shape), 0, 255).astype(np.uint8) for _ in range(FRAMES - 1)]
    return [*same, np.ascontiguousarray(load_map("reef-mosaic").image[1000:1120, 800:960])]


def _image(types, frame: np.ndarray, encoding: str, stamp: int):
    fields = {"stamp": types["builtin_interfaces/msg/Time"](sec=stamp // 10**9, nanosec=stamp % 10**9), "frame_id": "camera"}
    if "seq" in types["std_msgs/msg/Header"].__dataclass_fields__:  # ROS 1 headers count their messages
        fields["seq"] = 0
    header = types["std_msgs/msg/Header"](**fields)
    if encoding == "png":
        ok, png = cv2.imencode(".png", frame[:, :, ::-1])
        return types["sensor_msgs/msg/CompressedImage"](header=header, format="png", data=png.ravel())
    if encoding == "mono16":
        data = cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY).astype(np.uint16) * 257
    elif encoding == "mono8":
        data = cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY)
    elif encoding == "bgr8":
        data = frame[:, :, ::-1]
    else:
        data = frame
    data = np.ascontiguousarray(data)
    rows, cols = data.shape[:2]
    return types["sensor_msgs/msg/Image"](
        header=header, height=rows, width=cols, encoding=encoding, is_bigendian=0, step=data.strides[0],
        data=data.view(np.uint8).ravel(),
    )


def write_bag(path: Path, kind: str, topics: dict[str, str], frames: list[np.ndarray], damage=None) -> Path:
    """A bag of ``kind`` (``ros1``, ``sqlite3``, ``mcap``) with each topic's frames in its encoding; ``damage``
    maps a message's index to a function that makes it a damaged message."""
    store = get_typestore(Stores.ROS1_NOETIC if kind == "ros1" else Stores.ROS2_HUMBLE)
    writer = Writer1(path) if kind == "ros1" else Writer2(
        path, version=9, storage_plugin=StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
    )
    serialize = store.serialize_ros1 if kind == "ros1" else store.serialize_cdr
    with writer:
        for topic, encoding in topics.items():
            msgtype = "sensor_msgs/msg/CompressedImage" if encoding == "png" else "sensor_msgs/msg/Image"
            connection = writer.add_connection(topic, msgtype, typestore=store)
            for i, frame in enumerate(frames):
                stamp = START + i * PERIOD
                message = _image(store.types, frame, encoding, stamp)
                if damage and i in damage:
                    message = damage[i](message)
                writer.write(connection, stamp, serialize(message, msgtype))
    return path


def replay(bag: Path, out: Path, *extra: str):
    return runner.invoke(
        app, ["drive", "--dry-run", "--camera", str(bag), "--out", str(out), "--set", "drive.grid_rows=4",
              "--set", "drive.grid_cols=4", *extra],
    )


def frame_records(out: Path) -> list[dict]:
    return [r for r in map(json.loads, (out / "log.jsonl").read_text().splitlines()) if "frame" in r and "words" in r]


@pytest.mark.slow
@pytest.mark.parametrize("kind, name", [("ros1", "mission.bag"), ("sqlite3", "mission"), ("mcap", "mission")])
def test_a_bag_replays_one_record_per_message_with_its_bag_time(tmp_path, frames, kind, name):
    bag = write_bag(tmp_path / name, kind, {"/camera/image_raw": "rgb8"}, frames)
    result = replay(bag, tmp_path / "run")
    assert result.exit_code == 0, result.output
    records = frame_records(tmp_path / "run")
    assert [r["frame"] for r in records] == list(range(FRAMES))
    assert [r["bag_time"] for r in records] == pytest.approx([(START + i * PERIOD) / 1e9 for i in range(FRAMES)])
    assert f"drove {FRAMES} frames" in result.stdout


def test_a_bare_mcap_file_is_a_bag(tmp_path, frames):
    folder = write_bag(tmp_path / "mission", "mcap", {"/camera/image_raw": "rgb8"}, frames)
    (mcap,) = folder.glob("*.mcap")
    camera = BagCamera(str(mcap))
    assert camera.topic == "/camera/image_raw" and camera.messages == FRAMES
    np.testing.assert_array_equal(camera.read().image, frames[0])
    camera.close()


@pytest.mark.slow
def test_compressed_bgr_and_mono16_frames_decode_to_what_they_were_made_from(tmp_path, frames):
    encodings = {"/raw": "rgb8", "/png": "png", "/bgr": "bgr8", "/mono8": "mono8", "/mono16": "mono16"}
    bag = write_bag(tmp_path / "mission", "sqlite3", encodings, frames)
    decoded = {}
    for topic in encodings:
        camera = BagCamera(str(bag), topic)
        decoded[topic] = [camera.read().image for _ in range(FRAMES)]
        assert camera.read() is None
        camera.close()
    for topic in ("/png", "/bgr"):
        np.testing.assert_array_equal(np.stack(decoded[topic]), np.stack(decoded["/raw"]))
    np.testing.assert_array_equal(np.stack(decoded["/mono16"]), np.stack(decoded["/mono8"]))
    # and so the same words: the replays log the same word counts
    for topic in ("/raw", "/png", "/mono16", "/mono8"):
        assert replay(bag, tmp_path / topic.strip("/"), "--topic", topic).exit_code == 0
    words = {t: [r["words"] for r in frame_records(tmp_path / t.strip("/"))] for t in ("/raw", "/png", "/mono16", "/mono8")}
    assert words["/png"] == words["/raw"] and words["/mono16"] == words["/mono8"]


def test_a_bayer_frame_is_demosaiced_in_rosbag_naming():
    rgb = np.zeros((8, 8, 3), np.uint8)
    rgb[..., 0] = 200  # a red scene: in an RGGB mosaic the red sites are the top-left of each 2 x 2
    mosaic = np.zeros((8, 8), np.uint8)
    mosaic[0::2, 0::2] = 200

    class Message:
        encoding, height, width, step, is_bigendian, data = "bayer_rggb8", 8, 8, 8, 0, mosaic.ravel()

    image = decode(Message, "sensor_msgs/msg/Image", "test")
    assert image[2:-2, 2:-2, 0].min() > 150 and image[2:-2, 2:-2, 1:].max() < 50


@pytest.mark.parametrize(
    "case, says",
    [
        ("two-topics", "--topic: expected one of the image topics of "),
        ("unknown-topic", "--topic: got '/nope', which "),
        ("missing", "no such bag file or folder"),
        ("not-a-bag", "not a readable bag"),
        ("truncated", "mission.bag"),
        ("encoding", "encoding '32fc1': expected one of rgb8"),
    ],
)
def test_bad_bags_are_one_error_line(tmp_path, frames, case, says):
    extra = []
    if case == "two-topics":
        bag = write_bag(tmp_path / "mission.bag", "ros1", {"/a": "rgb8", "/b": "png"}, frames)
    elif case == "unknown-topic":
        bag, extra = write_bag(tmp_path / "mission.bag", "ros1", {"/a": "rgb8"}, frames), ["--topic", "/nope"]
    elif case == "missing":
        bag = tmp_path / "mission.bag"
    elif case == "not-a-bag":
        bag = tmp_path / "mission.bag"
        bag.write_text("not a bag\n")
    elif case == "truncated":
        bag = write_bag(tmp_path / "mission.bag", "ros1", {"/a": "rgb8"}, frames)
        bag.write_bytes(bag.read_bytes()[: bag.stat().st_size * 2 // 3])
    else:  # the frames' bytes, labelled with an encoding the camera does not decode
        bag = write_bag(tmp_path / "mission.bag", "ros1", {"/a": "32fc1"}, frames)
    result = replay(bag, tmp_path / "run", *extra)
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output
    errors = [line for line in result.stderr.splitlines() if line.startswith("Error: ")]
    assert len(errors) == 1 and says in errors[0], result.stderr
    if case == "two-topics":
        assert errors[0].endswith("mission.bag: /a (4 messages), /b (4 messages)")
    if case == "unknown-topic":
        assert errors[0].endswith("mission.bag does not have; its image topics: /a (4 messages)")


def test_a_topic_that_holds_no_images_is_named(tmp_path, frames):
    store = get_typestore(Stores.ROS1_NOETIC)
    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/a": "rgb8"}, frames)
    other = tmp_path / "imu.bag"
    with Writer1(other) as writer:
        connection = writer.add_connection("/imu/temp", "std_msgs/msg/Float64", typestore=store)
        writer.write(connection, START, store.serialize_ros1(store.types["std_msgs/msg/Float64"](data=1.0), "std_msgs/msg/Float64"))
    with pytest.raises(CameraError, match=r"^topic: '/imu/temp' holds std_msgs/msg/Float64, not images; the image topics of .*imu.bag: none$") as bad:
        BagCamera(str(other), "/imu/temp")
    assert bad.value.parameter == "topic"
    with pytest.raises(CameraError, match=r"imu.bag: no image topic to replay; its topics: /imu/temp \(std_msgs/msg/Float64\)$"):
        BagCamera(str(other))
    camera = BagCamera(str(bag))
    assert camera.topic == "/a"  # the one image topic, without naming it
    camera.close()


def test_a_topic_needs_a_bag():
    from curiosity_cli.drive.session import check_replay_options
    from curiosity_cli.errors import ParameterError

    with pytest.raises(ParameterError, match=r"topic: got '/a', but camera '0' is not a bag; a topic names a bag's images") as info:
        check_replay_options("0", topic="/a")
    assert info.value.parameter == "topic"  # hostile-user F12: the command line names it --topic


@pytest.mark.slow
def test_a_replay_shows_its_progress_and_the_same_seed_gives_the_same_log(tmp_path, frames):
    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/camera/image_raw": "rgb8"}, frames)
    first, second = replay(bag, tmp_path / "one"), replay(bag, tmp_path / "two")
    assert first.exit_code == second.exit_code == 0, first.output
    assert "replaying /camera/image_raw" in first.stderr  # the bar, with the bag's frame count

    def numbers(out: Path) -> list[dict]:  # what the model made, without the times this machine took
        return [{k: v for k, v in r.items() if k not in ("time", "latency_ms", "seconds")} for r in frame_records(out)]

    assert numbers(tmp_path / "one") == numbers(tmp_path / "two") and len(numbers(tmp_path / "one")) == FRAMES


@pytest.mark.slow
def test_a_replay_draws_its_surprise_timeline_with_the_frames_that_stand_out(tmp_path, frames, standout):
    from curiosity_cli.drive.timeline import surprise_series, timeline_figure

    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/camera/image_raw": "rgb8"}, standout)
    assert replay(bag, tmp_path / "run").exit_code == 0
    run = tmp_path / "run"
    image = cv2.imread(str(run / "timeline.png"))
    assert image is not None and image.shape[1] >= 1000 and image.std() > 10
    assert (run / "timeline.pdf").read_bytes().startswith(b"%PDF")
    surprising = sorted((run / "surprising").glob("frame-*.png"))
    assert [p.name for p in surprising] == ["frame-000003.png"]  # the reef's view, and none of the steady three
    np.testing.assert_array_equal(cv2.imread(str(surprising[0]))[:, :, ::-1], standout[3])  # the frame, whole
    series = surprise_series(run / "log.jsonl")
    assert series["time"].tolist() == pytest.approx([(START + i * PERIOD) / 1e9 for i in range(FRAMES)])
    assert series["clock"] == "bag" and not series["fell_back"]
    strip, surprise, score = timeline_figure(series, {0: frames[0]}, "mission").axes
    # two quantities on panels of their own, no legend over the data, the clock and the mission's start in UTC
    assert surprise.get_ylabel().startswith("topic perplexity") and score.get_ylabel().startswith("curiosity score")
    assert score.get_xlabel() == "bag time: seconds since the first frame, 2023-11-14 22:13:20.000 UTC"
    assert score.get_legend() is None and len(strip.artists) == 1
    (rule,) = surprise.get_legend().get_texts()  # the surprising frames' rule, above the panel
    assert rule.get_text().startswith("surprising above the median + 10 median absolute deviations")
    assert surprise.get_legend().get_bbox_to_anchor().y0 >= surprise.bbox.y1 - 1
    assert surprise.get_ylim()[0] == score.get_ylim()[0] == 1  # not zoomed into noise


def test_the_most_surprising_frames_are_peaks_apart():
    from curiosity_cli.drive.timeline import most_surprising

    perplexity = np.array([1, 9, 8.9, 2, 3, 7, 1, 1, 6, 1, 1, 1], float)
    # 12 frames, 2 wanted: at least 3 frames apart, so 8.9 (next to 9) gives way to 7
    assert most_surprising(perplexity, 2) == [1, 5]
    assert most_surprising(perplexity, 3) == [1, 5, 8]
    unrefined = np.arange(12) == 1  # its words kept their random topics: not a discovery
    assert most_surprising(perplexity, 2, ~unrefined) == [2, 5]


# no refinement at all; one sample a frame, the newest frame's share rounding to none (the first frame, alone, takes it)
@pytest.mark.slow
@pytest.mark.parametrize("budget", [0, 1])
def test_frames_no_refinement_picked_are_logged_marked_and_never_the_most_surprising(tmp_path, frames, budget):
    from curiosity_cli.drive.timeline import surprise_series

    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/camera/image_raw": "rgb8"}, frames)
    assert replay(bag, tmp_path / "run", "--set", f"drive.samples_per_frame={budget}").exit_code == 0
    records = frame_records(tmp_path / "run")
    refined = [r["refined"] for r in records]
    series = surprise_series(tmp_path / "run" / "log.jsonl")
    assert series["refined"].tolist() == [n > 0 for n in refined]
    shown = {int(p.stem.split("-")[1]) for p in (tmp_path / "run" / "surprising").glob("frame-*.png")}
    assert shown <= {i for i, n in enumerate(refined) if n > 0} if budget else not shown
    if budget:
        assert refined[0] == records[0]["words"]  # the first frame is the only time there is: always picked
        assert refined[1:] == [0] * (FRAMES - 1)


def test_without_rosbags_the_error_names_the_extra(tmp_path, frames, monkeypatch):
    import sys

    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/a": "rgb8"}, frames)
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)  # as if the extra were not installed
    with pytest.raises(CameraError, match=r"reading a bag needs rosbags: pip install 'curiosity-cli\[bags\]'"):
        BagCamera(str(bag))


@pytest.mark.slow
def test_a_replay_into_a_folder_in_use_is_refused_and_force_replaces_only_an_earlier_run(tmp_path, frames):
    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/camera/image_raw": "rgb8"}, frames)
    run = tmp_path / "run"
    assert replay(bag, run).exit_code == 0
    log = (run / "log.jsonl").read_bytes()
    again = replay(bag, run, "--max-frames", "2")
    assert again.exit_code == 1 and "Traceback" not in again.stderr
    assert again.stderr.strip().splitlines()[-1].startswith(f"Error: --out: {run} holds an earlier run (log.jsonl and ")
    assert (run / "log.jsonl").read_bytes() == log  # untouched

    (run / "my-notes.txt").write_text("the operator's notes")  # issue 44: --force deleted files the tool did not write
    replaced = replay(bag, run, "--max-frames", "2", "--force")
    assert replaced.exit_code == 0, replaced.output
    assert len(frame_records(run)) == 2  # the new run only, not mixed with the old one
    assert {int(p.stem.split("-")[1]) for p in (run / "surprising").glob("frame-*.png")} <= {0, 1}
    assert (run / "my-notes.txt").read_text() == "the operator's notes"

    # issue 44: two drives into one folder at once both exited 0 and one run was lost; the second is refused
    import subprocess
    import sys

    first = subprocess.Popen([sys.executable, "-c", (
        "import sys, time; from pathlib import Path; from curiosity_cli.drive.session import claimed_run_folder\n"
        f"with claimed_run_folder(Path({str(run)!r}), force=True) as out:\n"
        "    (out / 'log.jsonl').write_text('{}\\n'); print('running', flush=True); time.sleep(30)\n"
    )], stdout=subprocess.PIPE, text=True)
    try:
        assert first.stdout.readline().strip() == "running"
        busy = replay(bag, run, "--max-frames", "2", "--force")
    finally:
        first.kill()
        first.wait()
        first.stdout.close()
    assert busy.exit_code == 1 and "Traceback" not in busy.output
    assert f"{run}: another process works in this experiment (`curiosity drive`, process {first.pid}, since " in busy.stderr
    assert (run / "log.jsonl").read_text() == "{}\n", "the first drive's log is untouched"
    assert (run / "my-notes.txt").is_file()

    other = tmp_path / "notes"
    other.mkdir()
    (other / "mine.txt").write_text("not a run")
    for extra in ((), ("--force",)):
        refused = replay(bag, other, *extra)
        assert refused.exit_code == 1 and "is not empty (mine.txt) and holds no run" in refused.stderr
    assert (other / "mine.txt").read_text() == "not a run"


@pytest.fixture(scope="module")
def earlier_run(tmp_path_factory, frames) -> tuple[Path, Path]:
    """A bag, and a replay of it with an annotated PNG of every frame (``frames/``) beside its ``surprising/``."""
    folder = tmp_path_factory.mktemp("earlier")
    bag = write_bag(folder / "mission.bag", "ros1", {"/camera/image_raw": "rgb8"}, frames)
    result = replay(bag, folder / "run", "--png-every", "1")
    assert result.exit_code == 0, result.output
    return bag, folder / "run"


def _contents(folder: Path) -> dict[str, bytes | str]:
    """Every path below ``folder``: a file's bytes, a symlink's target."""
    return {
        str(p.relative_to(folder)): str(p.readlink()) if p.is_symlink() else p.read_bytes()
        for p in sorted(folder.rglob("*")) if p.is_symlink() or p.is_file()
    }


def _users_frame_in_frames(run: Path, tmp_path: Path) -> Path:
    (run / "frames" / "annotated-by-me.png").write_text("my own annotation")
    return run / "frames" / "annotated-by-me.png"


def _users_notes_in_surprising(run: Path, tmp_path: Path) -> Path:
    (run / "surprising" / "operator-notes.txt").write_text("operator's notes")
    return run / "surprising" / "operator-notes.txt"


def _frames_linked_to_the_users_photos(run: Path, tmp_path: Path) -> Path:
    (tmp_path / "photos").mkdir()
    (tmp_path / "photos" / "holiday.jpg").write_text("photo")
    for png in (run / "frames").iterdir():
        png.unlink()
    (run / "frames").rmdir()
    (run / "frames").symlink_to(tmp_path / "photos")
    return run / "frames"


def _a_folder_where_the_timeline_goes(run: Path, tmp_path: Path) -> Path:
    (run / "timeline.pdf").unlink()
    (run / "timeline.pdf").mkdir()
    (run / "timeline.pdf" / "mine.txt").write_text("not a timeline")
    return run / "timeline.pdf"


@pytest.mark.slow
@pytest.mark.parametrize(
    "users",
    [_users_frame_in_frames, _users_notes_in_surprising, _frames_linked_to_the_users_photos, _a_folder_where_the_timeline_goes],
)
def test_force_refuses_a_path_of_the_users_among_a_runs_files_and_deletes_nothing(tmp_path, earlier_run, users):
    """Hostile-user F1: ``--force`` deleted a user's files in ``frames/`` and ``surprising/``; with ``frames``
    a symlink it half-deleted the run, then said "Cannot call rmtree on a symbolic link", naming no path."""
    import shutil

    bag, earlier = earlier_run
    run = shutil.copytree(earlier, tmp_path / "run")
    theirs = users(run, tmp_path)
    before, photos = _contents(run), _contents(tmp_path / "photos") if (tmp_path / "photos").exists() else {}
    result = replay(bag, run, "--max-frames", "2", "--png-every", "1", "--force")
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert result.stderr.strip().splitlines() == [  # refused before the model loads, the path named
        f"Error: --out: {theirs} is a {'symlink' if theirs.is_symlink() else 'folder' if theirs.is_dir() else 'file'} "
        f"no run writes; --force replaces only a run's own files: move it out of {run}, or give a new folder"
    ]
    assert _contents(run) == before, "nothing deleted"
    assert not photos or _contents(tmp_path / "photos") == photos


@pytest.mark.slow
def test_force_replaces_the_frames_a_run_wrote_and_removes_their_folder_left_empty(tmp_path, earlier_run):
    import shutil

    bag, earlier = earlier_run
    run = shutil.copytree(earlier, tmp_path / "run")
    assert len(list((run / "frames").glob("frame-*.png"))) == FRAMES
    (run / "frames" / ".frame-000004.k3j9_x2a.tmp.png").write_bytes(b"half a PNG")  # what a killed run leaves
    (run / "my-notes.txt").write_text("the operator's notes")
    result = replay(bag, run, "--max-frames", "2", "--force")
    assert result.exit_code == 0, result.output
    assert not (run / "frames").exists()  # this run wrote no PNG: the earlier run's are gone, and their folder
    assert {p.name for p in (run / "surprising").iterdir()} <= {"frame-000000.png", "frame-000001.png"}
    assert len(frame_records(run)) == 2 and (run / "my-notes.txt").read_text() == "the operator's notes"


def test_runs_started_in_the_same_second_get_folders_of_their_own(tmp_path, monkeypatch):
    from datetime import datetime

    from curiosity_cli.drive import session

    class Frozen(datetime):
        @classmethod
        def now(cls, tz=None):
            return datetime(2026, 11, 26, 23, 0, 0)

    monkeypatch.setattr(session, "DEFAULT_RESULTS", tmp_path)
    monkeypatch.setattr(session, "datetime", Frozen)
    folders = []
    for _ in range(3):
        with session.claimed_run_folder(None) as folder:
            folders.append(folder)
    assert [f.name for f in folders] == ["20261126-230000", "20261126-230000-2", "20261126-230000-3"]
    assert all(f.is_dir() and [p.name for p in f.iterdir()] == [".lock"] for f in folders)


EMPTY = np.zeros(0, np.uint8)
DAMAGES = {
    "empty-jpeg": ("png", lambda m: dataclasses.replace(m, format="jpeg", data=EMPTY), "0 bytes that do not decode"),
    "corrupt-jpeg": ("png", lambda m: dataclasses.replace(m, format="jpeg", data=np.arange(64, dtype=np.uint8)),
                     "64 bytes that do not decode"),
    "zero-by-zero": ("rgb8", lambda m: dataclasses.replace(m, height=0, width=0, step=0, data=EMPTY), "a 0 x 0 image"),
    "cut-rows": ("rgb8", lambda m: dataclasses.replace(m, data=m.data[: len(m.data) // 2]), "rows of 480: expected at least"),
}


@pytest.mark.slow
@pytest.mark.parametrize("case", list(DAMAGES))
def test_a_damaged_message_is_skipped_logged_and_counted(tmp_path, standout, case):
    encoding, damage, says = DAMAGES[case]
    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/camera/image_raw": encoding}, standout, {1: damage})
    result = replay(bag, tmp_path / "run")
    assert result.exit_code == 0, result.output
    assert "drove 3 frames: end of the bag; 1 damaged messages skipped" in result.stdout
    records = [json.loads(line) for line in (tmp_path / "run" / "log.jsonl").read_text().splitlines()]
    (skipped,) = [r for r in records if r["event"] == "skipped"]
    assert skipped["message"] == 1 and skipped["bag_time"] == pytest.approx((START + PERIOD) / 1e9)
    assert says in skipped["reason"]
    assert [r["bag_time"] for r in frame_records(tmp_path / "run")] == pytest.approx(
        [(START + i * PERIOD) / 1e9 for i in (0, 2, 3)]
    )
    assert records[-1]["event"] == "end" and records[-1]["skipped"] == 1
    # frame n of the run is the n-th good message: the reef's view, message 3, is frame 2
    (thumbnail,) = (tmp_path / "run" / "surprising").glob("frame-*.png")
    assert thumbnail.name == "frame-000002.png"  # PNG and rgb8 frames are lossless
    np.testing.assert_array_equal(cv2.imread(str(thumbnail))[:, :, ::-1], standout[3])


@pytest.mark.slow
def test_strict_stops_at_a_damaged_message_and_still_draws_what_it_replayed(tmp_path, frames):
    encoding, damage, says = DAMAGES["zero-by-zero"]
    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/camera/image_raw": encoding}, frames, {2: damage})
    result = replay(bag, tmp_path / "run", "--strict")
    assert result.exit_code == 1 and "Traceback" not in result.output
    (line,) = [line for line in result.stderr.splitlines() if line.startswith("Error: ")]
    assert "/camera/image_raw, message 2: a 0 x 0 image" in line
    assert line.endswith(f"the session's log is kept in {tmp_path / 'run' / 'log.jsonl'}")
    assert len(frame_records(tmp_path / "run")) == 2 and (tmp_path / "run" / "timeline.png").is_file()


def test_a_bag_whose_every_message_is_damaged_is_an_error_not_an_empty_replay(tmp_path, frames):
    _, damage, _ = DAMAGES["empty-jpeg"]
    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/a": "png"}, frames, dict.fromkeys(range(FRAMES), damage))
    result = replay(bag, tmp_path / "run")
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert "every one of the 4 messages held no usable frame; the first: " in result.stderr


@pytest.mark.parametrize("encoding, order", [("yuv422", "uyvy"), ("uyvy", "uyvy"), ("yuv422_yuy2", "yuyv"), ("yuyv", "yuyv")])
def test_yuv_422_frames_decode(encoding, order):
    from types import SimpleNamespace

    rows, cols = 4, 6
    y, u, v = 120, 90, 200  # one colour everywhere
    pair = [u, y, v, y] if order == "uyvy" else [y, u, y, v]
    data = np.array(pair * (rows * cols // 2), np.uint8)
    message = SimpleNamespace(encoding=encoding, height=rows, width=cols, step=cols * 2, is_bigendian=0, data=data)
    image = decode(message, "sensor_msgs/msg/Image", "here")
    # ITU-R BT.601, video range (Y 16..235), as camera drivers send 4:2:2
    luma = 1.164 * (y - 16)
    expected = np.array([luma + 1.596 * (v - 128), luma - 0.813 * (v - 128) - 0.391 * (u - 128), luma + 2.018 * (u - 128)])
    assert image.shape == (rows, cols, 3) and image.dtype == np.uint8
    assert np.abs(image - expected).max() <= 2
    odd = SimpleNamespace(encoding=encoding, height=1, width=3, step=6, is_bigendian=0, data=np.zeros(6, np.uint8))
    with pytest.raises(CameraError, match="expected an even number"):
        decode(odd, "sensor_msgs/msg/Image", "here")


@pytest.mark.parametrize("encoding, channels", [("mono16", 1), ("16UC1", 1), ("rgb16", 3), ("bgr16", 3)])
@pytest.mark.parametrize("big_endian", [0, 1])
def test_16_bit_frames_decode_to_their_top_8_bits_in_either_byte_order(encoding, channels, big_endian):
    """Hostile round (issue 64): a valid mono16 frame flagged big-endian was refused as "got uint16"."""
    from types import SimpleNamespace

    rows, cols = 2, 3
    values = np.arange(rows * cols * channels, dtype=np.uint16).reshape(rows, cols, channels) * 4099
    data = np.frombuffer(values.astype(">u2" if big_endian else "<u2").tobytes(), np.uint8)
    message = SimpleNamespace(
        encoding=encoding, height=rows, width=cols, step=cols * channels * 2, is_bigendian=big_endian, data=data
    )
    image = decode(message, "sensor_msgs/msg/Image", "here")
    top = (values >> 8).astype(np.uint8)
    expected = np.repeat(top, 3, axis=2) if channels == 1 else top[:, :, ::-1] if encoding == "bgr16" else top
    assert image.dtype == np.uint8 and np.array_equal(image, expected)


@pytest.mark.slow
@pytest.mark.parametrize("kind, storage", [("mcap", ".mcap"), ("sqlite3", ".db3")])
def test_a_bag_folder_without_its_metadata_is_read_through_its_storage_file(tmp_path, frames, kind, storage):
    bag = write_bag(tmp_path / "mission", kind, {"/camera/image_raw": "rgb8"}, frames)
    (bag / "metadata.yaml").unlink()  # what a recorder killed before it wrote it leaves
    result = replay(bag, tmp_path / "run")
    assert result.exit_code == 0, result.output
    (said,) = [line for line in result.stderr.splitlines() if "has no metadata.yaml" in line]
    assert said.endswith(f"mission has no metadata.yaml (a recording cut short?): reading {next(bag.glob('*' + storage)).name}")
    assert len(frame_records(tmp_path / "run")) == FRAMES


def test_an_empty_folder_and_a_tiny_file_are_named_as_what_they_are(tmp_path):
    (tmp_path / "empty").mkdir()
    result = replay(tmp_path / "empty", tmp_path / "run")
    assert result.exit_code == 1 and "empty: not a bag folder (empty)" in result.stderr
    (tmp_path / "tiny.mcap").write_bytes(b"\x89MCAP0\r\n")
    result = replay(tmp_path / "tiny.mcap", tmp_path / "run2")
    assert result.exit_code == 1 and "Traceback" not in result.output
    (line,) = [line for line in result.stderr.splitlines() if line.startswith("Error: ")]
    assert "tiny.mcap: not a readable bag (" in line and "ord()" not in line and "expected a character" not in line


@pytest.mark.slow
def test_a_timeline_is_drawn_again_from_a_run_folder(tmp_path, frames):
    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/camera/image_raw": "rgb8"}, frames)
    assert replay(bag, tmp_path / "run").exit_code == 0
    (tmp_path / "run" / "timeline.png").unlink()
    result = runner.invoke(app, ["drive", "--timeline", str(tmp_path / "run")])
    assert result.exit_code == 0, result.output
    assert f"wrote {tmp_path / 'run' / 'timeline.png'}" in result.stdout and (tmp_path / "run" / "timeline.png").is_file()
    missing = runner.invoke(app, ["drive", "--timeline", str(tmp_path / "nothing")])
    assert missing.exit_code == 1 and "log.jsonl: not found; give a run folder of `curiosity drive`" in missing.stderr


@pytest.mark.slow
def test_a_timeline_is_refused_when_the_bag_was_replaced_by_another_recording(tmp_path, frames):
    """Issue 44: the frames were read from whatever file stood at the bag's path, exit 0."""
    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/camera/image_raw": "rgb8"}, frames)
    assert replay(bag, tmp_path / "run").exit_code == 0
    start = json.loads((tmp_path / "run" / "log.jsonl").read_text().splitlines()[0])
    assert start["bag"]["mission.bag"]["size"] == bag.stat().st_size
    (tmp_path / "run" / "timeline.png").unlink()
    bag.unlink()
    write_bag(bag, "ros1", {"/camera/image_raw": "rgb8"}, frames[::-1])  # another recording, the same size
    result = runner.invoke(app, ["drive", "--timeline", str(tmp_path / "run")])
    assert result.exit_code == 1 and "Traceback" not in result.output
    (line,) = [line for line in result.stderr.splitlines() if line.startswith("Error: ")]
    assert "mission.bag: not the bag" in line and "(mission.bag holds other records than the replay read)" in line
    assert not (tmp_path / "run" / "timeline.png").exists()
    bag.unlink()
    write_bag(bag, "ros1", {"/camera/image_raw": "rgb8"}, frames)  # the recording put back
    assert runner.invoke(app, ["drive", "--timeline", str(tmp_path / "run")]).exit_code == 0


@pytest.mark.slow
def test_header_stamps_are_logged_and_a_bag_of_equal_record_times_falls_back_to_them(tmp_path, frames):
    from curiosity_cli.drive.timeline import surprise_series

    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/camera/image_raw": "rgb8"}, frames)
    assert replay(bag, tmp_path / "run", "--clock", "header").exit_code == 0
    records = frame_records(tmp_path / "run")
    assert [r["header_time"] for r in records] == pytest.approx([(START + i * PERIOD) / 1e9 for i in range(FRAMES)])
    assert surprise_series(tmp_path / "run" / "log.jsonl", "header")["clock"] == "header"

    # a recorder that wrote every message at one record time: the timeline runs on the header stamps, and says so
    log = tmp_path / "run" / "log.jsonl"
    lines = [json.loads(line) for line in log.read_text().splitlines()]
    log.write_text("".join(json.dumps({**r, "bag_time": START / 1e9} if r["event"] == "frame" else r) + "\n" for r in lines))
    series = surprise_series(log)
    assert series["clock"] == "header" and series["fell_back"]
    assert series["time"].tolist() == pytest.approx([(START + i * PERIOD) / 1e9 for i in range(FRAMES)])
    result = runner.invoke(app, ["drive", "--timeline", str(tmp_path / "run")])
    assert result.exit_code == 0 and "every frame has the same bag time" in result.stderr


@pytest.mark.slow
def test_a_log_cut_short_or_damaged_is_named_not_a_traceback(tmp_path, frames):
    """Issue 44: a log.jsonl cut mid-line, holding a line that is not an object, or only its start record."""
    bag = write_bag(tmp_path / "mission.bag", "ros1", {"/camera/image_raw": "rgb8"}, frames)
    assert replay(bag, tmp_path / "run").exit_code == 0
    log = tmp_path / "run" / "log.jsonl"
    whole = log.read_text()
    lines = whole.splitlines()

    log.write_text(whole[: len(whole) - 20])  # killed while writing its last line
    result = runner.invoke(app, ["drive", "--timeline", str(tmp_path / "run")])
    assert result.exit_code == 0, result.output
    assert "log.jsonl: its last line is cut short (a run stopped while writing it?); it is left out" in result.stderr

    for bad, message in (("[1, 2]", "line 2: expected a JSON object, got list"), ("{oops", "line 2: not a JSON record")):
        log.write_text("\n".join([lines[0], bad, *lines[1:]]) + "\n")
        result = runner.invoke(app, ["drive", "--timeline", str(tmp_path / "run")])
        assert result.exit_code == 1 and "Traceback" not in result.output
        assert f"log.jsonl: {message}" in result.stderr

    log.write_text(lines[0] + "\n")
    result = runner.invoke(app, ["drive", "--timeline", str(tmp_path / "run")])
    assert result.exit_code == 1
    assert "log.jsonl: holds no frame of the replay (its start record alone); nothing to draw" in result.stderr
