"""Recorded missions as a camera: ROS 1 bags, ROS 2 bag folders (sqlite3 or MCAP storage) and
bare ``.mcap`` or ``.db3`` files, read with ``rosbags`` (pure Python; no ROS installation).

:class:`BagCamera` yields a topic's frames in recorded order, each with its bag time
(seconds since the epoch). Images are ``sensor_msgs/Image`` in the encodings of
:data:`ENCODINGS` or ``sensor_msgs/CompressedImage`` (JPEG, PNG); every frame becomes an
RGB ``(H, W, 3)`` uint8 array as the live cameras deliver it (16-bit values keep their
top 8 bits, so a ``mono16`` frame of ``v * 257`` is the ``mono8`` frame of ``v``).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from curiosity_cli.drive.camera import CameraError, Frame
from curiosity_cli.files import display_path

IMAGE = "sensor_msgs/msg/Image"
COMPRESSED = "sensor_msgs/msg/CompressedImage"
#: What a bag's storage is told by: its suffix, or a ROS 2 bag folder's metadata file.
BAG_SUFFIXES = (".bag", ".mcap", ".db3")
_BAYER = {  # ROS names the pattern from the top-left pixel; OpenCV from the second row's second and third
    "bayer_rggb8": "COLOR_BayerBG2RGB", "bayer_bggr8": "COLOR_BayerRG2RGB",
    "bayer_gbrg8": "COLOR_BayerGR2RGB", "bayer_grbg8": "COLOR_BayerGB2RGB",
}
#: The ``sensor_msgs/Image`` encodings a frame may have: (channels, bytes per value).
ENCODINGS = {
    "rgb8": (3, 1), "bgr8": (3, 1), "rgba8": (4, 1), "bgra8": (4, 1), "mono8": (1, 1), "8uc1": (1, 1),
    "mono16": (1, 2), "16uc1": (1, 2), "rgb16": (3, 2), "bgr16": (3, 2), **{name: (1, 1) for name in _BAYER},
}


def is_bag(source: str) -> bool:
    """Whether a camera source names a recorded bag rather than a device, video file or stream."""
    path = Path(source)
    return path.suffix.lower() in BAG_SUFFIXES or (path / "metadata.yaml").is_file()


class BagCamera:
    """The frames of one image topic of a bag, in recorded order, as fast as they are read.

    Parameters
    ----------
    source : str
        A ROS 1 ``.bag``, a ROS 2 bag folder, or a ``.mcap`` / ``.db3`` file.
    topic : str, optional
        The image topic; may be left out when the bag has exactly one.

    Raises
    ------
    CameraError
        rosbags not installed (naming the ``bags`` extra); a missing, truncated or
        non-bag file; no image topic, several without ``topic``, an unknown topic or one
        that is not an image, each naming the bag's image topics and their message counts.
    """

    def __init__(self, source: str, topic: str | None = None):
        try:
            from rosbags.highlevel import AnyReader
        except ImportError:
            raise CameraError(
                f"camera {source!r}: reading a bag needs rosbags: pip install 'curiosity[bags]'"
            ) from None
        self.source = source
        where = display_path(Path(source))
        if not Path(source).exists():
            raise CameraError(f"{where}: no such bag file or folder")
        try:
            self._reader = AnyReader([Path(source)])
            self._reader.open()
        except Exception as exc:  # rosbags raises its own errors, and struct/zip errors for torn files
            raise CameraError(f"{where}: not a readable bag ({' '.join(str(exc).split()) or type(exc).__name__})") from None
        counts = {}
        for connection in self._reader.connections:
            counts.setdefault(connection.topic, [connection.msgtype, 0])[1] += connection.msgcount
        images = {name: n for name, (kind, n) in counts.items() if kind in (IMAGE, COMPRESSED)}
        listed = ", ".join(f"{name} ({n} messages)" for name, n in sorted(images.items())) or "none"
        if topic is None and len(images) != 1:
            self.close()
            raise CameraError(f"{where}: topic: expected one of the bag's image topics: {listed}")
        topic = topic if topic is not None else next(iter(images))
        if topic not in counts:
            self.close()
            raise CameraError(f"{where}: topic: got {topic!r}, which the bag does not have; its image topics: {listed}")
        if topic not in images:
            self.close()
            raise CameraError(
                f"{where}: topic: {topic!r} holds {counts[topic][0]}, not images; the bag's image topics: {listed}"
            )
        self.topic = topic
        self.messages = images[topic]
        connections = [c for c in self._reader.connections if c.topic == topic]
        self._messages = self._reader.messages(connections=connections)
        self._index = 0

    def read(self) -> Frame | None:
        """The next frame, with its bag time; None after the last.

        Raises
        ------
        CameraError
            A message that cannot be read or decoded (a truncated bag, an unsupported
            encoding), naming the frame, the topic and the bag.
        """
        where = f"{display_path(Path(self.source))}: {self.topic}, message {self._index}"
        try:
            connection, stamp, data = next(self._messages)
        except StopIteration:
            return None
        except Exception as exc:
            raise CameraError(f"{where}: cannot be read ({' '.join(str(exc).split()) or type(exc).__name__})") from None
        try:
            message = self._reader.deserialize(data, connection.msgtype)
        except Exception as exc:
            raise CameraError(f"{where}: not a {connection.msgtype} ({exc})") from None
        image = decode(message, connection.msgtype, where)
        self._index += 1
        return Frame(image, time.monotonic(), stamp / 1e9)

    def close(self) -> None:
        self._reader.close()


def decode(message, msgtype: str, where: str) -> np.ndarray:
    """(H, W, 3) uint8 RGB: an image message as the live cameras deliver frames.

    Raises
    ------
    CameraError
        An unsupported encoding or compression, or data that does not fit the message's
        size, naming ``where``.
    """
    import cv2

    if msgtype == COMPRESSED:
        image = cv2.imdecode(np.frombuffer(bytes(message.data), np.uint8), cv2.IMREAD_UNCHANGED)
        if image is None:
            raise CameraError(f"{where}: format {message.format!r}: expected a JPEG or PNG image")
        channels = 1 if image.ndim == 2 else image.shape[2]
        return _to_rgb8(image, "mono" if channels == 1 else "bgr")
    encoding = message.encoding.lower()
    if encoding not in ENCODINGS:
        raise CameraError(f"{where}: encoding {message.encoding!r}: expected one of {', '.join(ENCODINGS)}")
    channels, size = ENCODINGS[encoding]
    dtype = np.dtype(np.uint8 if size == 1 else (">u2" if message.is_bigendian else "<u2"))
    rows, cols, step = message.height, message.width, message.step
    data = np.frombuffer(bytes(message.data), np.uint8)
    if step < cols * channels * size or data.size < rows * step:
        raise CameraError(
            f"{where}: {data.size} bytes for {rows} x {cols} {encoding} rows of {step}: expected at least {rows * step}"
        )
    image = data[: rows * step].reshape(rows, step)[:, : cols * channels * size].copy().view(dtype)
    image = image.reshape(rows, cols, channels).squeeze(axis=2) if channels == 1 else image.reshape(rows, cols, channels)
    if encoding in _BAYER:
        return np.ascontiguousarray(cv2.cvtColor(image, getattr(cv2, _BAYER[encoding])))
    order = "bgr" if encoding.startswith("bgr") else "rgb" if channels > 1 else "mono"
    return _to_rgb8(image, order)


def _to_rgb8(image: np.ndarray, order: str) -> np.ndarray:
    """RGB uint8 from a mono, RGB(A) or BGR(A) image of 8 or 16 bits (16 bits: the top 8)."""
    import cv2

    if image.dtype == np.uint16:
        image = (image >> 8).astype(np.uint8)
    if order == "mono":
        return np.ascontiguousarray(cv2.cvtColor(image, cv2.COLOR_GRAY2RGB))
    image = image[:, :, :3]
    return np.ascontiguousarray(image[:, :, ::-1] if order == "bgr" else image)
