"""An MCAP file cut short, read up to its last whole message.

A recorder killed mid-mission leaves an MCAP file without its summary and end magic,
which ``rosbags`` refuses. The records before the cut are whole and in order, so this
reads them one by one from the start (the MCAP format: an 8-byte magic, then records of
a 1-byte opcode, a little-endian uint64 length and that many bytes): schemas, channels
and messages, at the top level or inside chunks (uncompressed, ``zstd`` or ``lz4``, the
compressions ``rosbags`` reads too), and stops at the first record the file does not
hold whole. A chunk cut short gives the whole messages of the part that was written.
:class:`CutMcap` offers the part of ``rosbags``' ``AnyReader`` a :class:`BagCamera`
uses.
"""

from __future__ import annotations

import struct
from pathlib import Path

from curiosity_cli.drive.foxglove_mcap import ENCODINGS, Connection, decoder, foxglove_message

MAGIC = b"\x89MCAP0\r\n"
_HEADER, _FOOTER, _SCHEMA, _CHANNEL, _MESSAGE, _CHUNK, _DATA_END = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x0F


class CutMcapError(Exception):
    """Not an MCAP file, or one whose records are not what the format says."""


def _string(body: memoryview, at: int) -> tuple[str, int]:
    (size,) = struct.unpack_from("<I", body, at)
    return bytes(body[at + 4 : at + 4 + size]).decode(), at + 4 + size


def _records(data: memoryview):
    """(opcode, body) of each whole record of ``data``, up to the first it does not hold whole."""
    at = 0
    while at + 9 <= len(data):
        opcode = data[at]
        (size,) = struct.unpack_from("<Q", data, at + 1)
        if at + 9 + size > len(data):
            return
        yield opcode, data[at + 9 : at + 9 + size]
        at += 9 + size


def _decompress(compression: str, data: bytes, whole: bool) -> bytes:
    """A chunk's records; of a chunk cut short, what its written part decompresses to."""
    if compression == "":
        return data
    if compression == "zstd":
        try:
            from compression import zstd
        except ImportError:
            from backports import zstd
        return zstd.decompress(data) if whole else zstd.ZstdDecompressor().decompress(data)
    if compression == "lz4":
        import lz4.frame

        return lz4.frame.decompress(data) if whole else lz4.frame.LZ4FrameDecompressor().decompress(data)
    raise CutMcapError(f"a chunk compressed with {compression!r}; expected none, zstd or lz4")


class CutMcap:
    """The whole messages of an MCAP file without its end, in the order they were written.

    Parameters
    ----------
    path : Path
        The ``.mcap`` file.

    Attributes
    ----------
    connections : list of Connection
        The channels whose definition was written before the cut, with their whole messages' count.
    message_count : int
        Whole messages, all channels.
    unfinished : int
        Bytes at the end that are no whole record: the record being written when the
        file was cut (a chunk's whole messages are read all the same).

    Raises
    ------
    CutMcapError
        Not an MCAP file (its magic and header), one that ends as a whole file does, or a chunk the format
        does not allow. Its messages may be ROS 2's (CDR, as profile ``ros2`` says) or Foxglove's (protobuf or
        JSON, as the Foxglove SDK and the drive's own ``mission.mcap`` write them).
    """

    def __init__(self, path: Path):
        self.path = Path(path)
        with self.path.open("rb") as file:
            if file.read(8) != MAGIC:
                raise CutMcapError("no MCAP magic at its start")
            header = file.read(9)
            if len(header) < 9 or header[0] != _HEADER:
                raise CutMcapError("no header record after its magic")
            file.seek(-8, 2)
            if file.read(8) == MAGIC:
                raise CutMcapError("it ends with its magic: not cut short")
        self._schemas: dict[int, tuple[str, str, bytes]] = {}
        self._channels: dict[int, tuple[str, int, str]] = {}  # id -> (topic, schema id, message encoding)
        self.unfinished = 0
        counts: dict[int, int] = {}
        for channel, _, _ in self._scan():
            counts[channel] = counts.get(channel, 0) + 1
        self.connections = [
            Connection(key, topic, self._schemas.get(schema, ("", "", b""))[0], counts.get(key, 0))
            for key, (topic, schema, _) in sorted(self._channels.items())
        ]
        # a Foxglove schema's messages, by its name: their channel's encoding and the schema's data
        self._foxglove = {
            self._schemas[schema][0]: (encoding, self._schemas[schema][2])
            for topic, schema, encoding in self._channels.values() if encoding in ENCODINGS and schema in self._schemas
        }
        self.message_count = sum(counts.values())
        self._store = None

    def _scan(self):
        """(channel id, log time in ns, data) of every whole message, reading the file from its start."""
        size = self.path.stat().st_size
        with self.path.open("rb") as file:
            at = file.seek(8)
            while at + 9 <= size:
                opcode = file.read(1)[0]
                (length,) = struct.unpack("<Q", file.read(8))
                if opcode in (_FOOTER, _DATA_END):
                    return
                whole = at + 9 + length <= size
                # a chunk a killed writer left open still holds its length's placeholder, 2^64 - 1: read what is there
                body = memoryview(file.read(min(length, size - at - 9)))
                if opcode == _CHUNK:
                    yield from self._chunk(body, whole)
                elif whole:
                    yield from self._record(opcode, body)
                if not whole:
                    self.unfinished = size - at
                    return
                at += 9 + length
            self.unfinished = size - at

    def _chunk(self, body: memoryview, whole: bool):
        """The messages of a chunk record's body; of a chunk cut short, those of its written part."""
        if len(body) < 28 + 4:
            return
        compression, at = _string(body, 28)
        if len(body) < at + 8:
            return
        (size,) = struct.unpack_from("<Q", body, at)
        try:
            inner = _decompress(compression, bytes(body[at + 8 : at + 8 + size]), whole)
        except CutMcapError:
            raise
        except Exception:  # the codec's own error
            if whole:
                raise CutMcapError(f"a {compression} chunk that does not decompress") from None
            return  # too little of it was written to decompress anything
        for opcode, record in _records(memoryview(inner)):
            yield from self._record(opcode, record)

    def _record(self, opcode: int, body: memoryview):
        if opcode == _SCHEMA:
            (key,) = struct.unpack_from("<H", body, 0)
            name, at = _string(body, 2)
            encoding, at = _string(body, at)
            (size,) = struct.unpack_from("<I", body, at)
            self._schemas[key] = (name, encoding, bytes(body[at + 4 : at + 4 + size]))
        elif opcode == _CHANNEL:
            key, schema = struct.unpack_from("<HH", body, 0)
            topic, at = _string(body, 4)
            encoding, _ = _string(body, at)
            self._channels[key] = (topic, schema, encoding)
        elif opcode == _MESSAGE:
            channel, _, log_time, _ = struct.unpack_from("<HIQQ", body, 0)
            yield channel, log_time, body[22:]

    def messages(self, connections):
        """(connection, log time in ns, serialized data) of each whole message of ``connections``, in file order."""
        wanted = {c.id: c for c in connections}
        for channel, log_time, data in self._scan():
            if channel in wanted:
                yield wanted[channel], log_time, bytes(data)

    def deserialize(self, data: bytes, msgtype: str):
        """A message of ``msgtype``: from its CDR bytes, with the types its schema defines; or a Foxglove message
        from its protobuf or JSON bytes (:func:`~curiosity_cli.drive.foxglove_mcap.foxglove_message`)."""
        if msgtype in self._foxglove:
            encoding, schema = self._foxglove[msgtype]
            return foxglove_message(decoder(encoding)(data, msgtype, schema), msgtype)
        if self._store is None:
            from rosbags.typesys import Stores, get_types_from_msg, get_typestore

            self._store = get_typestore(Stores.ROS2_HUMBLE)
            for name, encoding, text in self._schemas.values():
                if encoding == "ros2msg" and name not in self._store.types:
                    try:
                        self._store.register(get_types_from_msg(text.decode(), name))
                    except Exception:  # a schema rosbags cannot parse: its messages will not decode
                        pass
        return self._store.deserialize_cdr(data, msgtype)

    def close(self) -> None:
        """Nothing to release: each pass opens the file and closes it at its end."""
