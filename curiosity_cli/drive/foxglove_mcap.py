"""An MCAP file of Foxglove image messages, as a bag camera reads one.

The Foxglove SDK and Foxglove's recorders write images as ``foxglove.CompressedImage``
or ``foxglove.RawImage`` messages, encoded as protobuf (the schema a
``FileDescriptorSet``) or as JSON (a JSON schema; bytes in base64), under any profile
(the SDK leaves it empty): ``rosbags`` refuses such a file ("Profile is not ros2").
:class:`FoxgloveMcap` reads it with the ``mcap`` library and offers the part of
``rosbags``' ``AnyReader`` a :class:`~curiosity_cli.drive.bags.BagCamera` uses; each
message comes out with the fields of its ROS counterpart that
:func:`~curiosity_cli.drive.bags.decode` reads (``header.stamp``, ``data``, ``format``;
``encoding``, ``width``, ``height``, ``step``, ``is_bigendian``), and a
``foxglove.PoseInFrame`` with those of a ``nav_msgs/msg/Odometry`` that
:func:`~curiosity_cli.drive.odometry.read_odometry` reads (``header.frame_id``,
``pose.pose.position``, ``pose.pose.orientation``).
"""

from __future__ import annotations

import base64
import json
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace


#: The Foxglove image schemas a replay reads.
FOXGLOVE_COMPRESSED, FOXGLOVE_RAW = "foxglove.CompressedImage", "foxglove.RawImage"
#: The Foxglove pose schema whose messages give frames their pose (as a ROS bag's odometry does).
FOXGLOVE_POSE = "foxglove.PoseInFrame"
#: Message encodings it decodes.
ENCODINGS = ("protobuf", "json")


@dataclass(frozen=True)
class Connection:
    """A channel of an MCAP file, as ``rosbags`` names its parts (this reader's and
    :class:`~curiosity_cli.drive.mcap_scan.CutMcap`'s)."""

    id: int
    topic: str
    msgtype: str
    msgcount: int


class FoxgloveMcapError(Exception):
    """An MCAP file this reader cannot read (the reason in words)."""


class NoImagesError(FoxgloveMcapError):
    """A whole MCAP file that holds no Foxglove image channel this reader decodes."""


def is_foxglove_image(msgtype: str) -> bool:
    """Whether a channel's schema name is one of the Foxglove image schemas."""
    return msgtype in (FOXGLOVE_COMPRESSED, FOXGLOVE_RAW)


class FoxgloveMcap:
    """The channels and messages of an MCAP file with Foxglove image channels.

    Parameters
    ----------
    path : Path
        A whole ``.mcap`` file (with its summary).

    Attributes
    ----------
    connections : list of Connection
        Every channel (:class:`Connection`), its schema name as
        ``msgtype`` and its message count.

    Raises
    ------
    FoxgloveMcapError
        A file the ``mcap`` library cannot read, or one without its summary.
    NoImagesError
        A whole file with no Foxglove image channel in an encoding of :data:`ENCODINGS`
        (naming its schemas).
    """

    def __init__(self, path: Path):
        from mcap.reader import make_reader

        self.path = Path(path)
        self._file = self.path.open("rb")
        try:
            self._reader = make_reader(self._file)
            summary = self._reader.get_summary()
        except Exception as exc:  # the mcap library's own errors for bytes it cannot read
            self._file.close()
            raise FoxgloveMcapError(" ".join(str(exc).split()) or type(exc).__name__) from None
        if summary is None or summary.statistics is None:
            self._file.close()
            raise FoxgloveMcapError("no summary with message counts (a recording cut short?)")
        counts = summary.statistics.channel_message_counts
        channels = sorted(summary.channels.values(), key=lambda c: c.id)
        self.connections = [
            Connection(c.id, c.topic, summary.schemas[c.schema_id].name if c.schema_id else "", counts.get(c.id, 0))
            for c in channels
        ]
        self._encodings = {c.id: c.message_encoding for c in channels}
        if not any(is_foxglove_image(c.msgtype) and self._encodings[c.id] in ENCODINGS for c in self.connections):
            self._file.close()
            found = ", ".join(sorted({f"{c.msgtype or 'no schema'} ({self._encodings[c.id]})" for c in self.connections}))
            found = found or "no channels"
            raise NoImagesError(
                f"its channels hold {found}; expected ROS 2 images (profile ros2) or Foxglove images "
                f"({FOXGLOVE_COMPRESSED} or {FOXGLOVE_RAW}, encoded as {' or '.join(ENCODINGS)})"
            )
        self._decoders: dict[str, tuple] = {}  # schema name -> (its channel's decoder, its schema data)

    def messages(self, connections):
        """(connection, log time in ns, serialized data) of each message of ``connections``, in log-time order."""
        wanted = {c.id: c for c in connections}
        schemas = {s.name: s.data for s in self._reader.get_summary().schemas.values()}
        for c in wanted.values():
            self._decoders[c.msgtype] = (decoder(self._encodings[c.id]), schemas.get(c.msgtype, b""))
        topics = sorted({c.topic for c in wanted.values()})
        for _, channel, message in self._reader.iter_messages(topics=topics):
            if channel.id in wanted:
                yield wanted[channel.id], message.log_time, message.data

    def deserialize(self, data: bytes, msgtype: str):
        """The message, with the fields :func:`~curiosity_cli.drive.bags.decode` and a bag camera read
        (:func:`foxglove_message`)."""
        decode, schema = self._decoders[msgtype]
        return foxglove_message(decode(data, msgtype, schema), msgtype)

    def close(self) -> None:
        self._file.close()


def foxglove_message(message: dict, msgtype: str) -> SimpleNamespace:
    """A decoded Foxglove message (a :func:`decoder`'s fields) with the fields of its ROS counterpart a replay reads.

    Raises
    ------
    ValueError
        Bytes that did not decode as ``msgtype`` in its channel's encoding (raised by the decoder).
    """
    if msgtype == FOXGLOVE_POSE:
        pose = message["pose"]
        return SimpleNamespace(
            header=SimpleNamespace(frame_id=message["frame_id"]),
            pose=SimpleNamespace(pose=SimpleNamespace(
                position=SimpleNamespace(**pose["position"]), orientation=SimpleNamespace(**pose["orientation"]),
            )),
        )
    sec, nsec = message["timestamp"]
    fields = {
        "header": SimpleNamespace(stamp=SimpleNamespace(sec=int(sec), nanosec=int(nsec)), frame_id=message["frame_id"]),
        "data": message["data"],
    }
    if msgtype == FOXGLOVE_COMPRESSED:
        fields["format"] = message["format"]
    else:
        fields.update(
            encoding=message["encoding"], width=int(message["width"]), height=int(message["height"]),
            step=int(message["step"]), is_bigendian=False,
        )
    return SimpleNamespace(**fields)


#: The fields of the Foxglove image schemas a replay reads, besides ``timestamp`` and ``data``.
_FIELDS = {
    FOXGLOVE_COMPRESSED: ("frame_id", "format", "data"), FOXGLOVE_RAW: ("frame_id", "encoding", "width", "height", "step", "data"),
    FOXGLOVE_POSE: ("frame_id", "pose"),
}
#: A pose's parts and their components (a missing one is 0, as protobuf and Foxglove's JSON leave zeros out;
#: a missing orientation is the identity).
_POSE = {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}


def decoder(encoding: str):
    """A function of (data, schema name, schema data) to the fields a replay reads, as a dict:
    ``timestamp`` as (sec, nsec), ``data`` as bytes."""
    return _from_json if encoding == "json" else _from_protobuf


def _from_json(data: bytes, msgtype: str, schema: bytes) -> dict:
    message = json.loads(data)
    if not isinstance(message, dict):
        raise ValueError("not a JSON object")
    stamp = message.get("timestamp") or {}
    fields = {name: message.get(name, "" if name in ("frame_id", "format", "encoding") else 0) for name in _FIELDS[msgtype]}
    fields["timestamp"] = (stamp.get("sec", 0), stamp.get("nsec", 0))
    if "data" in fields:
        if not isinstance(fields["data"], str):
            raise ValueError("its data is not base64 text")
        fields["data"] = base64.b64decode(fields["data"], validate=True)
    if "pose" in fields:
        pose = fields["pose"] if isinstance(fields["pose"], dict) else {}
        fields["pose"] = {part: {k: float((pose.get(part) or {}).get(k, v)) for k, v in zero.items()} for part, zero in _POSE.items()}
    return fields


#: Protobuf message classes by schema data: each schema's descriptors are read once.
_PROTOBUF_CLASSES: dict[bytes, type] = {}


def _from_protobuf(data: bytes, msgtype: str, schema: bytes) -> dict:
    cls = _PROTOBUF_CLASSES.get(schema)
    if cls is None:
        cls = _PROTOBUF_CLASSES[schema] = _protobuf_class(msgtype, schema)
    message = cls.FromString(data)
    fields = {name: getattr(message, name) for name in _FIELDS[msgtype]}
    fields["timestamp"] = (message.timestamp.seconds, message.timestamp.nanos)
    if "data" in fields:
        fields["data"] = bytes(fields["data"])
    if "pose" in fields:
        pose = fields["pose"]
        fields["pose"] = {
            part: {k: float(getattr(getattr(pose, part), k)) for k in zero}
            # protobuf's default orientation is all zeros: no orientation recorded, the identity
            for part, zero in _POSE.items()
        }
        if not pose.HasField("orientation"):
            fields["pose"]["orientation"] = dict(_POSE["orientation"])
    return fields


def _protobuf_class(msgtype: str, schema: bytes) -> type:
    """The message class named ``msgtype`` in a schema's ``FileDescriptorSet``."""
    from google.protobuf.descriptor_pb2 import FileDescriptorSet
    from google.protobuf.descriptor_pool import DescriptorPool
    from google.protobuf.message_factory import GetMessageClass

    pending = {f.name: f for f in FileDescriptorSet.FromString(schema).file}
    pool = DescriptorPool()

    def add(proto) -> None:
        for dependency in proto.dependency:
            if dependency in pending:
                add(pending.pop(dependency))
        pool.Add(proto)

    while pending:
        add(pending.popitem()[1])
    return GetMessageClass(pool.FindMessageTypeByName(msgtype))
