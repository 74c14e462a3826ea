"""Recorded missions as a camera: ROS 1 bags, ROS 2 bag folders (sqlite3 or MCAP storage) and
bare ``.mcap`` or ``.db3`` files, read with ``rosbags`` (pure Python; no ROS installation),
and MCAP files of Foxglove images (:mod:`~curiosity_cli.drive.foxglove_mcap`).

:class:`BagCamera` yields a topic's frames in recorded order, each with its bag time
(nanoseconds since the epoch) and, where the bag has odometry, its pose
(:mod:`~curiosity_cli.drive.odometry`). Images are ``sensor_msgs/Image`` in the encodings of
:data:`ENCODINGS` or ``sensor_msgs/CompressedImage`` (JPEG, PNG), or their Foxglove
counterparts ``foxglove.RawImage`` and ``foxglove.CompressedImage``; every frame becomes an
RGB ``(H, W, 3)`` uint8 array as the live cameras deliver it (16-bit values keep their
top 8 bits, so a ``mono16`` frame of ``v * 257`` is the ``mono8`` frame of ``v``).

A message that is damaged (empty or cut data, a JPEG that does not decode, a 0 x 0 image)
is a :class:`BadMessage`: the replay may skip it and go on. An encoding the camera does
not decode is not: every message of the topic has it.
"""

from __future__ import annotations

import struct
import time
from pathlib import Path

import numpy as np

from curiosity_cli.drive.camera import CameraError, Frame
from curiosity_cli.drive.foxglove_mcap import FOXGLOVE_COMPRESSED, FOXGLOVE_RAW
from curiosity_cli.drive.odometry import POSE_TYPES
from curiosity_cli.files import display_path

IMAGE = "sensor_msgs/msg/Image"
COMPRESSED = "sensor_msgs/msg/CompressedImage"
#: The message types a replay reads frames from: raw and compressed, ROS's and Foxglove's.
IMAGE_TYPES = (IMAGE, COMPRESSED, FOXGLOVE_RAW, FOXGLOVE_COMPRESSED)
#: What a bag's storage is told by: its suffix, or a ROS 2 bag folder's metadata file.
BAG_SUFFIXES = (".bag", ".mcap", ".db3")
#: YUV 4:2:2 encodings, two bytes a pixel: ROS's ``yuv422`` is UYVY order, ``yuv422_yuy2`` (usb_cam's) YUYV.
_YUV422 = {"yuv422": "COLOR_YUV2RGB_UYVY", "uyvy": "COLOR_YUV2RGB_UYVY", "yuv422_yuy2": "COLOR_YUV2RGB_YUYV",
           "yuyv": "COLOR_YUV2RGB_YUYV"}
_BAYER = {  # ROS names the pattern from the top-left pixel; OpenCV from the second row's second and third
    "bayer_rggb8": "COLOR_BayerBG2RGB", "bayer_bggr8": "COLOR_BayerRG2RGB",
    "bayer_gbrg8": "COLOR_BayerGR2RGB", "bayer_grbg8": "COLOR_BayerGB2RGB",
}
#: The ``sensor_msgs/Image`` encodings a frame may have: (channels, bytes per value).
ENCODINGS = {
    "rgb8": (3, 1), "bgr8": (3, 1), "rgba8": (4, 1), "bgra8": (4, 1), "mono8": (1, 1), "8uc1": (1, 1),
    "mono16": (1, 2), "16uc1": (1, 2), "rgb16": (3, 2), "bgr16": (3, 2), **{name: (1, 1) for name in _BAYER},
    **{name: (2, 1) for name in _YUV422},
}


class BadMessage(CameraError):
    """A message of the topic that holds no usable frame (damaged, empty, 0 x 0): a replay may skip it.

    Attributes
    ----------
    reason : str
        What is wrong with it.
    index : int or None
        The message's place among the topic's messages, from 0 (set by :meth:`BagCamera.read`).
    bag_time : float or None
        Its bag time, seconds since the epoch (set likewise).
    """

    def __init__(self, message: str, *, reason: str | None = None, **kwargs):
        super().__init__(message, **kwargs)
        self.reason = message if reason is None else reason
        self.index = self.bag_time = None


def is_bag(source: str) -> bool:
    """Whether a camera source names a recorded bag rather than a device, video file or stream: a bag
    file, or any folder (a ROS 2 bag folder, or one a killed recorder left without its ``metadata.yaml``)."""
    path = Path(source)
    return path.suffix.lower() in BAG_SUFFIXES or path.is_dir()


def bag_paths(source: str) -> tuple[list[Path], str]:
    """What to read of a bag source, and a note on how it was read (empty when as named).

    A ROS 2 bag folder is read through its ``metadata.yaml``; a folder without one, as a
    recorder killed before writing it leaves, through the ``.mcap`` or ``.db3`` storage
    files in it.

    Raises
    ------
    CameraError
        No such file or folder, or a folder with neither ``metadata.yaml`` nor storage files.
    """
    path = Path(source)
    where = display_path(path)
    if not path.exists():
        raise CameraError(f"{where}: no such bag file or folder")
    if not path.is_dir() or (path / "metadata.yaml").is_file():
        return [path], ""
    storage = sorted(p for p in path.iterdir() if p.suffix.lower() in (".mcap", ".db3"))
    if not storage:
        held = "empty" if not any(path.iterdir()) else "neither metadata.yaml nor a .mcap or .db3 file in it"
        raise CameraError(f"{where}: not a bag folder ({held})")
    return storage, f"{where} has no metadata.yaml (a recording cut short?): reading {', '.join(p.name for p in storage)}"


#: Bytes read from each end of a bag's storage file for its fingerprint: a recording is gigabytes,
#: and another recording differs in its size or its first and last records.
_FINGERPRINT_BYTES = 1 << 20


def bag_fingerprint(source: str) -> dict:
    """What identifies a bag without reading all of it: per storage file (:func:`bag_paths`), its size
    and the SHA-256 of its first and last :data:`_FINGERPRINT_BYTES` bytes, by name.

    Raises
    ------
    CameraError
        As :func:`bag_paths`.
    """
    import hashlib

    fingerprint = {}
    for path in bag_paths(source)[0]:
        if path.is_dir():  # a ROS 2 bag folder: its storage files and its metadata.yaml
            files = sorted(p for p in path.iterdir() if p.suffix.lower() in (".mcap", ".db3", ".yaml"))
        else:
            files = [path]
        for file in files:
            size = file.stat().st_size
            digest = hashlib.sha256()
            with open(file, "rb") as handle:
                digest.update(handle.read(_FINGERPRINT_BYTES))
                handle.seek(max(0, size - _FINGERPRINT_BYTES))
                digest.update(handle.read(_FINGERPRINT_BYTES))
            fingerprint[file.name] = {"size": size, "sha256_ends": digest.hexdigest()}
    return fingerprint


def fingerprint_change(recorded: dict, now: dict) -> str | None:
    """How a bag's :func:`bag_fingerprint` now differs from the one recorded, in words; None when it does not."""
    if set(recorded) != set(now):
        return f"its files are {', '.join(sorted(now))}, the replay read {', '.join(sorted(recorded))}"
    for name, was in sorted(recorded.items()):
        if now[name]["size"] != was.get("size"):
            return f"{name} is {now[name]['size']:,} bytes, the replay read {was.get('size'):,}"
        if now[name]["sha256_ends"] != was.get("sha256_ends"):
            return f"{name} holds other records than the replay read"
    return None


class BagCamera:
    """The frames of one image topic of a bag, in recorded order, as fast as they are read.

    Parameters
    ----------
    source : str
        A ROS 1 ``.bag``, a ROS 2 bag folder, or a ``.mcap`` / ``.db3`` file.
    topic : str, optional
        The image topic; may be left out when the bag has exactly one other than ``outputs``.
    odom_topic : str, optional
        A ``nav_msgs/msg/Odometry`` topic (or ``foxglove.PoseInFrame``, in a Foxglove
        recording) whose nearest pose in time each frame gets; default the bag's only one,
        if it has one.
    outputs : tuple of str, optional
        Image topics a drive writes (its mission file's), never taken as the camera unless
        ``topic`` names one: a drive's own ``mission.mcap`` replays from its camera.

    Attributes
    ----------
    odometry : Odometry or None
        The poses frames are given; None: frames have none, and :attr:`pose_note` says why.
    transforms : Transforms or None
        The bag's ``/tf_static`` and ``/tf`` (:mod:`~curiosity_cli.drive.transforms`), for the mission file; None
        without either.
    image_frame_id : str or None
        The image messages' frame, once a frame with one is read.

    Raises
    ------
    CameraError
        rosbags not installed (naming the ``bags`` extra); a missing, truncated or
        non-bag file; no image topic, several without ``topic``, an unknown topic or one
        that is not an image, each naming the bag's image topics and their message counts
        (``parameter="topic"``, but for a bag without image topics); an ``odom_topic``
        the bag does not have as odometry (``parameter="odom_topic"``).
    """

    #: What ran out when the frames do: the run's outcome is ``end of bag``.
    kind = "bag"

    def __init__(
        self, source: str, topic: str | None = None, odom_topic: str | None = None, outputs: tuple[str, ...] = ()
    ):
        try:
            from rosbags.highlevel import AnyReader
        except ImportError:
            raise CameraError(
                f"camera {source!r}: reading a bag needs rosbags: pip install 'curiosity-cli[bags]'"
            ) from None
        self.source = source
        where = display_path(Path(source))
        paths, self.note = bag_paths(source)
        try:
            self._reader = AnyReader(paths)
            self._reader.open()
        except Exception as exc:  # rosbags raises its own errors, and Python's own for torn or foreign bytes
            # a bag folder whose .mcap is cut short fails on its metadata.yaml: its storage file is read as given alone
            stored = _storage_files(paths)
            self._reader = _foxglove_mcap(stored, where) or _cut_mcap(stored)
            if self._reader is None:
                raise CameraError(f"{where}: not a readable bag ({_why_unreadable(exc, paths)})") from None
            if getattr(self._reader, "message_count", None) == 0:
                self._reader.close()
                raise CameraError(
                    f"{where}: ends before its summary (a recording cut short?) and before its first whole message: "
                    "nothing to replay"
                ) from None
            if hasattr(self._reader, "unfinished"):
                cut = (
                    f"{display_path(paths[0])} ends before its summary (a recording cut short?): replaying its "
                    f"{self._reader.message_count} whole messages; its last {self._reader.unfinished:,} bytes are an unfinished record"
                )
                self.note = f"{self.note}; {cut}" if self.note else cut
        counts = {}
        for connection in self._reader.connections:
            counts.setdefault(connection.topic, [connection.msgtype, 0])[1] += connection.msgcount
        images = {name: n for name, (kind, n) in counts.items() if kind in IMAGE_TYPES}
        listed = ", ".join(f"{name} ({n} messages)" for name, n in sorted(images.items())) or "none"
        if topic is None and not images:
            self.close()
            topics = ", ".join(f"{name} ({kind})" for name, (kind, _) in sorted(counts.items())) or "none"
            raise CameraError(f"{where}: no image topic to replay; its topics: {topics}")
        cameras = [name for name in images if name not in outputs]
        if topic is None and len(cameras) != 1:
            self.close()
            raise CameraError(f"topic: expected one of the image topics of {where}: {listed}", parameter="topic")
        topic = topic if topic is not None else cameras[0]
        if topic not in counts:
            self.close()
            raise CameraError(
                f"topic: got {topic!r}, which {where} does not have; its image topics: {listed}", parameter="topic"
            )
        if topic not in images:
            self.close()
            raise CameraError(
                f"topic: {topic!r} holds {counts[topic][0]}, not images; the image topics of {where}: {listed}",
                parameter="topic",
            )
        if not images[topic]:
            self.close()
            raise CameraError(f"{where}: {topic} holds no message: no frame to replay")
        self.topic = topic
        self.messages = images[topic]
        try:
            self.odom_topic, self.odometry, self.pose_note = self._read_odometry(odom_topic, counts, where)
            self.transforms, frames_note = self._read_transforms(counts)
        except BaseException:
            self.close()
            raise
        if frames_note:
            self.pose_note = f"{self.pose_note}; {frames_note}"
        self.image_frame_id = None  # the image messages' header frame id, once a frame is read
        connections = [c for c in self._reader.connections if c.topic == topic]
        self._messages = self._reader.messages(connections=connections)
        self._index = 0

    def _read_odometry(self, odom_topic: str | None, counts: dict, where: str):
        """(the odometry topic or None, its :class:`~curiosity_cli.drive.odometry.Odometry` or None, why frames have
        no pose or what to know of it)."""
        from curiosity_cli.drive.odometry import MAX_COORDINATE, MAX_POSE_GAP_NS, read_odometry

        odometry = sorted(name for name, (kind, _) in counts.items() if kind in POSE_TYPES)
        if odom_topic is None and len(odometry) != 1:
            why = "no odometry topic" if not odometry else f"odometry on {len(odometry)} topics ({', '.join(odometry)}): give one as odom_topic"
            return None, None, f"frames have no pose: {where} has {why}"
        if odom_topic is not None and odom_topic not in odometry:
            listed = ", ".join(odometry) or "none"
            held = f"holds {counts[odom_topic][0]}" if odom_topic in counts else "is not a topic there"
            raise CameraError(
                f"odom_topic: {odom_topic!r} {held}; the pose topics ({' or '.join(POSE_TYPES)}) of {where}: {listed}",
                parameter="odom_topic",
            )
        name = odom_topic or odometry[0]
        try:
            poses, damaged, senseless = read_odometry(self._reader, [c for c in self._reader.connections if c.topic == name])
        except ValueError as exc:
            raise CameraError(f"odom_topic: {name} of {where}: {exc}", parameter="odom_topic") from None
        parts = [f"{damaged} damaged"] * bool(damaged) + [
            f"{senseless} outside physical sense (a coordinate beyond {MAX_COORDINATE:.0e} m, or a quaternion of no length)"
        ] * bool(senseless)
        left_out = f" ({' and '.join(parts)} left out)" if parts else ""
        if poses is None:
            return name, None, f"frames have no pose: no message of {name} is left{left_out}"
        return name, poses, (
            f"poses from {name}: {len(poses)} messages{left_out}, each frame given the nearest in time within "
            f"{MAX_POSE_GAP_NS / 1e9:g} s (none beyond)"
        )

    def _read_transforms(self, counts: dict):
        """(the bag's :class:`~curiosity_cli.drive.transforms.Transforms` or None, what to know of them or '')."""
        from curiosity_cli.drive.transforms import DYNAMIC_TOPIC, STATIC_TOPIC, TF_TYPES, read_transforms

        topics = [name for name in (STATIC_TOPIC, DYNAMIC_TOPIC) if counts.get(name, ("", 0))[0] in TF_TYPES]
        if not topics:
            return None, ""
        connections = [c for c in self._reader.connections if c.topic in topics]
        transforms, damaged, senseless = read_transforms(self._reader, connections)
        parts = [f"{damaged} damaged messages"] * bool(damaged) + [f"{senseless} transforms outside physical sense"] * bool(senseless)
        left_out = f" ({' and '.join(parts)} left out)" if parts else ""
        links = len(transforms.static) + len(transforms.moving)
        return transforms, f"frames linked by {links} transforms of {' and '.join(topics)}{left_out}"

    def read(self) -> Frame | None:
        """The next frame, with its bag time and pose; None after the last.

        Raises
        ------
        BadMessage
            A message that holds no usable frame (damaged or empty data), naming it; the
            next call reads the message after it.
        CameraError
            A bag that cannot be read on (a torn file) or an encoding the camera does not
            decode, naming the frame, the topic and the bag.
        """
        index = self._index
        where = f"{display_path(Path(self.source))}: {self.topic}, message {index}"
        try:
            connection, stamp, data = next(self._messages)
        except StopIteration:
            return None
        except Exception as exc:
            raise CameraError(f"{where}: cannot be read ({' '.join(str(exc).split()) or type(exc).__name__})") from None
        self._index += 1
        try:
            try:
                message = self._reader.deserialize(data, connection.msgtype)
            except Exception as exc:  # rosbags' own errors for a message it cannot parse
                reason = f"not a {connection.msgtype} ({' '.join(str(exc).split()) or type(exc).__name__})"
                raise BadMessage(f"{where}: {reason}", reason=reason) from None
            image = decode(message, connection.msgtype, where)
        except BadMessage as exc:
            exc.index, exc.bag_time = index, stamp / 1e9
            raise
        if self.image_frame_id is None and getattr(getattr(message, "header", None), "frame_id", ""):
            self.image_frame_id = str(message.header.frame_id).lstrip("/")
        header = getattr(getattr(message, "header", None), "stamp", None)
        header = None if header is None else int(header.sec) * 1_000_000_000 + int(header.nanosec)
        pose = None if self.odometry is None else self.odometry.nearest(stamp)
        return Frame(image, time.monotonic(), int(stamp), header, pose)

    def close(self) -> None:
        if hasattr(self, "_messages"):
            self._messages.close()
        self._reader.close()


def _storage_files(paths: list[Path]) -> list[Path]:
    """``paths``, or, for a ROS 2 bag folder, the storage files in it (what a folder without ``metadata.yaml`` is
    read through, :func:`bag_paths`)."""
    if len(paths) == 1 and paths[0].is_dir():
        return sorted(p for p in paths[0].iterdir() if p.suffix.lower() in (".mcap", ".db3"))
    return paths


def _foxglove_mcap(paths: list[Path], where: str):
    """A :class:`~curiosity_cli.drive.foxglove_mcap.FoxgloveMcap` of a lone, whole MCAP file rosbags could not open;
    None for anything else (a file cut short, not an MCAP).

    Raises
    ------
    CameraError
        A whole MCAP file of neither ROS 2 nor Foxglove images, naming what it holds and what is read.
    """
    if len(paths) != 1 or paths[0].suffix.lower() != ".mcap" or not paths[0].is_file():
        return None
    from curiosity_cli.drive.foxglove_mcap import FoxgloveMcap, FoxgloveMcapError, NoImagesError

    try:
        return FoxgloveMcap(paths[0])
    except NoImagesError as exc:
        raise CameraError(f"{where}: not a readable bag: {exc}") from None
    except (FoxgloveMcapError, ImportError, OSError):  # mcap missing: rosbags' own reason is given
        return None


def _cut_mcap(paths: list[Path]):
    """A :class:`~curiosity_cli.drive.mcap_scan.CutMcap` of a lone MCAP file rosbags could not open (a file cut
    short); None otherwise."""
    from curiosity_cli.drive.mcap_scan import CutMcap, CutMcapError

    if len(paths) != 1 or paths[0].suffix.lower() != ".mcap" or not paths[0].is_file():
        return None
    try:
        scan = CutMcap(paths[0])
    except (CutMcapError, OSError, struct.error, UnicodeDecodeError):
        return None
    return scan


def _why_unreadable(exc: Exception, paths: list[Path]) -> str:
    """Why rosbags could not open a bag, in words: its own message, or what the bytes are when Python's
    errors speak (``ord() expected a character`` for an 8-byte file says nothing to a user)."""
    if type(exc).__module__.startswith("rosbags"):
        return " ".join(str(exc).split()) or type(exc).__name__
    size = sum(p.stat().st_size for p in paths if p.is_file())
    return f"{size:,} bytes that are not a ROS 1 bag, a ROS 2 bag or an MCAP or SQLite storage file"


def decode(message, msgtype: str, where: str) -> np.ndarray:
    """(H, W, 3) uint8 RGB: an image message as the live cameras deliver frames.

    Raises
    ------
    BadMessage
        Damaged data: a compressed image that does not decode, an image of 0 x 0 pixels,
        data that does not fit the message's size; naming ``where``.
    CameraError
        An encoding the camera does not decode, naming ``where``.
    """
    import cv2

    if msgtype in (COMPRESSED, FOXGLOVE_COMPRESSED):
        data = np.frombuffer(bytes(message.data), np.uint8)
        image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
        if image is None or image.size == 0:
            _damaged(where, f"format {message.format!r}: {data.size} bytes that do not decode as a JPEG or PNG image")
        channels = 1 if image.ndim == 2 else image.shape[2]
        return _to_rgb8(image, "mono" if channels == 1 else "bgr")
    encoding = message.encoding.lower()
    if encoding not in ENCODINGS:
        raise CameraError(f"{where}: encoding {message.encoding!r}: expected one of {', '.join(ENCODINGS)}")
    channels, size = ENCODINGS[encoding]
    dtype = np.dtype(np.uint8 if size == 1 else (">u2" if message.is_bigendian else "<u2"))
    rows, cols, step = message.height, message.width, message.step
    data = np.frombuffer(bytes(message.data), np.uint8)
    if rows <= 0 or cols <= 0:
        _damaged(where, f"a {rows} x {cols} image: expected a positive height and width")
    if encoding in _YUV422 and cols % 2:
        _damaged(where, f"{encoding} of {cols} columns: expected an even number (two pixels share their colour)")
    if step < cols * channels * size:
        _damaged(where, f"a row step of {step} bytes: expected at least {cols * channels * size}, a row of {cols} {encoding} pixels")
    if data.size < rows * step:
        _damaged(where, f"{data.size} bytes for {rows} x {cols} {encoding} rows of {step}: expected at least {rows * step}")
    image = data[: rows * step].reshape(rows, step)[:, : cols * channels * size].copy().view(dtype)
    image = image.reshape(rows, cols, channels).squeeze(axis=2) if channels == 1 else image.reshape(rows, cols, channels)
    if encoding in _BAYER:
        return np.ascontiguousarray(cv2.cvtColor(image, getattr(cv2, _BAYER[encoding])))
    if encoding in _YUV422:
        return np.ascontiguousarray(cv2.cvtColor(image, getattr(cv2, _YUV422[encoding])))
    order = "bgr" if encoding.startswith("bgr") else "rgb" if channels > 1 else "mono"
    return _to_rgb8(image, order)


def _damaged(where: str, reason: str):
    """Raise the :class:`BadMessage` of a message at ``where`` whose data is damaged."""
    raise BadMessage(f"{where}: {reason}", reason=reason)


def _to_rgb8(image: np.ndarray, order: str) -> np.ndarray:
    """RGB uint8 from a mono, RGB(A) or BGR(A) image of 8 or 16 bits (16 bits: the top 8)."""
    import cv2

    if image.dtype.itemsize == 2:  # big-endian data too: its dtype is '>u2', not the native uint16
        image = (image.astype(np.uint16) >> 8).astype(np.uint8)
    if order == "mono":
        return np.ascontiguousarray(cv2.cvtColor(image, cv2.COLOR_GRAY2RGB))
    image = image[:, :, :3]
    return np.ascontiguousarray(image[:, :, ::-1] if order == "bgr" else image)
