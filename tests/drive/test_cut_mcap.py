"""An MCAP recording cut short replays up to its last whole message."""

from __future__ import annotations

import lz4.frame
import numpy as np
import pytest
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_typestore
from test_bags import START, PERIOD, _image, frame_records, replay

from curiosity_cli.drive.mcap_scan import _decompress
from curiosity_cli.maps.map_data import load_map

FRAMES = 40  # of 57.6 kB: about 18 in each 1 MiB chunk rosbags writes


@pytest.fixture(scope="module")
def views() -> list[np.ndarray]:
    image = load_map("aerial-mosaic").image
    return [np.ascontiguousarray(image[10 * i : 10 * i + 120, 12 * i : 12 * i + 160]) for i in range(FRAMES)]


def write_mcap(folder, views, zstd: bool, metadata: bool = False):
    """A ROS 2 bag folder of ``views`` as rgb8 Images, without its metadata.yaml unless said; returns its .mcap file."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    writer = Writer2(folder, version=9, storage_plugin=StoragePlugin.MCAP)
    if zstd:
        writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    with writer:
        connection = writer.add_connection("/camera/image_raw", "sensor_msgs/msg/Image", typestore=store)
        for i, view in enumerate(views):
            message = _image(store.types, view, "rgb8", START + i * PERIOD)
            writer.write(connection, START + i * PERIOD, store.serialize_cdr(message, "sensor_msgs/msg/Image"))
    if not metadata:
        (folder / "metadata.yaml").unlink()  # as a recorder killed before it could write it
    return next(folder.glob("*.mcap"))


@pytest.mark.slow
@pytest.mark.parametrize("cut", [0.3, 0.5, 0.71, 0.9])
def test_an_uncompressed_mcap_cut_anywhere_replays_every_whole_message(tmp_path, views, cut):
    mcap = write_mcap(tmp_path / "mission", views, zstd=False)
    data = mcap.read_bytes()
    keep = int(len(data) * cut)
    mcap.write_bytes(data[:keep])
    # a message is whole when its pixels, the last bytes of its record, are all before the cut
    whole = sum(data.find(view.tobytes()) + view.nbytes <= keep for view in views)
    assert 0 < whole < FRAMES
    result = replay(tmp_path / "mission", tmp_path / "run")
    assert result.exit_code == 0, result.output
    records = frame_records(tmp_path / "run")
    assert [r["bag_time"] for r in records] == [(START + i * PERIOD) / 1e9 for i in range(whole)]
    (said,) = [line for line in result.stderr.splitlines() if "ends before its summary" in line]
    assert f"(a recording cut short?): replaying its {whole} whole messages; its last " in said


@pytest.mark.slow
def test_a_chunk_left_open_by_a_killed_writer_replays_the_chunks_before_it(tmp_path, views):
    """Hostile round (issue 64): a chunk whose writer was killed still holds its length's placeholder, 2^64 - 1, and
    the replay ended in an OverflowError."""
    import struct

    mcap = write_mcap(tmp_path / "mission", views, zstd=False)
    data = bytearray(mcap.read_bytes())
    at, chunks = 8, []
    while data[at] not in (0x02, 0x0F):  # records up to the footer or the data end
        (length,) = struct.unpack_from("<Q", data, at + 1)
        chunks += [at] * (data[at] == 0x06)
        at += 9 + length
    last = chunks[-1]
    struct.pack_into("<Q", data, last + 1, 2**64 - 1)
    mcap.write_bytes(bytes(data[: last + 9 + 1000]))  # the chunk's first bytes written, then killed
    whole = sum(bytes(data).find(view.tobytes()) + view.nbytes <= last for view in views)
    assert 0 < whole < FRAMES
    result = replay(tmp_path / "mission", tmp_path / "run")
    assert result.exit_code == 0, result.output
    assert len(frame_records(tmp_path / "run")) == whole


@pytest.mark.slow
def test_a_bag_folder_whose_mcap_is_cut_replays_as_its_mcap_would(tmp_path, views):
    """Issue 64: a bag folder with its metadata.yaml and a cut .mcap failed on the metadata ("File end magic is
    invalid"), while the same file given alone replayed to its last whole message."""
    mcap = write_mcap(tmp_path / "mission", views, zstd=False, metadata=True)
    data = mcap.read_bytes()
    mcap.write_bytes(data[: len(data) // 2])
    whole = sum(data.find(view.tobytes()) + view.nbytes <= len(data) // 2 for view in views)
    folder = replay(tmp_path / "mission", tmp_path / "run")
    assert folder.exit_code == 0, folder.output
    assert len(frame_records(tmp_path / "run")) == whole > 0
    assert f"replaying its {whole} whole messages" in folder.stderr


@pytest.mark.slow
def test_a_zstd_mcap_cut_inside_a_chunk_replays_the_chunks_before_and_what_it_can_of_that_one(tmp_path, views):
    mcap = write_mcap(tmp_path / "mission", views, zstd=True)
    data = mcap.read_bytes()
    mcap.write_bytes(data[: len(data) * 3 // 5])
    result = replay(tmp_path / "mission", tmp_path / "run")
    assert result.exit_code == 0, result.output
    records = frame_records(tmp_path / "run")
    assert 18 <= len(records) < FRAMES  # at least the first chunk's
    assert [r["bag_time"] for r in records] == [(START + i * PERIOD) / 1e9 for i in range(len(records))]
    assert f"replaying its {len(records)} whole messages" in result.stderr


@pytest.mark.parametrize("compression", ["zstd", "lz4"])
def test_a_compressed_chunk_cut_short_gives_what_its_written_part_holds(compression):
    records = np.random.default_rng(0).integers(0, 16, 2**20, dtype=np.uint8).tobytes()  # 8 blocks of zstd's 128 KiB
    if compression == "zstd":
        try:
            from compression import zstd
        except ImportError:
            from backports import zstd
        packed = zstd.compress(records)
    else:
        packed = lz4.frame.compress(records)
    assert _decompress(compression, packed, whole=True) == records
    part = _decompress(compression, packed[: len(packed) * 2 // 3], whole=False)
    assert 0 < len(part) < len(records) and records.startswith(part)


def test_only_a_ros2_mcap_without_its_end_is_read_as_cut_short(tmp_path, views):
    from curiosity_cli.drive.mcap_scan import CutMcap, CutMcapError

    mcap = write_mcap(tmp_path / "mission", views[:3], zstd=False)
    with pytest.raises(CutMcapError, match="ends with its magic: not cut short"):
        CutMcap(mcap)
    data = mcap.read_bytes()
    mcap.write_bytes(data[:-100])
    assert CutMcap(mcap).message_count == 3
    mcap.write_bytes(b"not an mcap at all")
    with pytest.raises(CutMcapError, match="no MCAP magic at its start"):
        CutMcap(mcap)


@pytest.mark.slow
@pytest.mark.parametrize("encoding", ["protobuf", "json"])
def test_a_foxglove_mcap_cut_short_replays_its_whole_messages(tmp_path, encoding):
    """Issue 64: a Foxglove-profile MCAP cut short (as a killed drive leaves its own mission.mcap) was refused with
    "Profile is not ros2."; its whole messages replay, with their poses."""
    from test_mission import mission_frames, write_foxglove_mission

    mcap = write_foxglove_mission(tmp_path / "mission.mcap", mission_frames(6), encoding)
    data = mcap.read_bytes()
    mcap.write_bytes(data[:40])  # its header, and not one whole message
    result = replay(mcap, tmp_path / "none")
    assert result.exit_code == 1 and "before its first whole message: nothing to replay" in result.stderr, result.output
    mcap.write_bytes(data[: int(len(data) * 0.9)])
    result = replay(mcap, tmp_path / "run")
    assert result.exit_code == 0, result.output
    assert "ends before its summary (a recording cut short?)" in result.stderr
    records = frame_records(tmp_path / "run")
    assert 0 < len(records) < 6
    assert all(r["pose"] is not None and r["pose"]["frame_id"] == "map" for r in records)
