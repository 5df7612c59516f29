r"""The records of a ROS 1 bag (format 2.0), read in file order, even from a damaged bag.

A bag is ``#ROSBAG V2.0\n`` followed by records. Each record is a header (``name=value``
fields, each prefixed by its length) and data, both prefixed by their length in bytes:

=========== ====== ==========================================================================
record      op     what it holds
=========== ====== ==========================================================================
bag header  0x03   where the index starts (``index_pos``, 0 while the bag is being written)
chunk       0x05   connection and message records, compressed (``none``, ``bz2`` or ``lz4``)
connection  0x07   a topic's id, name, type, md5 sum and full message definition
message     0x02   a connection id, the record time and the serialized message
index       0x04   where each message of a chunk is (skipped here)
chunk info  0x06   a chunk's time range and counts (skipped here)
=========== ====== ==========================================================================

Reading in file order needs no index, so this module reads what a killed recorder left
behind (:mod:`duckielib.bags.repair`), and it is the fast path for reading many small
messages: rosbags reads a message through the index in about 10 microseconds, this in
about 2. Bags are still opened, checked and written with rosbags (:mod:`duckielib.bags.io`).
"""

from __future__ import annotations

import bz2
import mmap
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Dict, List, Optional, Tuple, Union

from duckielib.errors import BagError

__all__ = [
    "MAGIC",
    "Connection",
    "ScanResult",
    "parse_fields",
    "scan",
]

MAGIC = b"#ROSBAG V2.0\n"

OP_MESSAGE = 0x02
OP_BAG_HEADER = 0x03
OP_INDEX = 0x04
OP_CHUNK = 0x05
OP_CHUNK_INFO = 0x06
OP_CONNECTION = 0x07

_U32 = struct.Struct("<I")
_U64 = struct.Struct("<Q")
_TIME = struct.Struct("<II")
#: What records are read from: a chunk's bytes, or the whole bag mapped into memory.
_Buffer = Union[bytes, mmap.mmap]


@dataclass
class Connection:
    """A connection record: one topic as one publisher's type describes it.

    Attributes:
        id: the connection's number in the bag.
        topic: the topic's name.
        type: the message type, ``package/Type``.
        md5sum: the type's md5 sum.
        message_definition: the type's full definition text, as genpy writes it.
        callerid: the node that published (when the recorder wrote it).
        latching: ``"1"`` for a latched topic (when the recorder wrote it).
    """

    id: int
    topic: str
    type: str
    md5sum: str
    message_definition: str
    callerid: Optional[str] = None
    latching: Optional[str] = None


@dataclass
class ScanResult:
    """What a scan of a bag found.

    Attributes:
        connections: every connection record, by id.
        messages: ``(connection id, record time in ns, serialized bytes)`` of each complete
            message of a wanted connection, in file order.
        index_pos: where the bag's index starts; 0 if the bag was never closed.
        chunks: how many chunks were read, completely or in part.
        damage: a sentence saying where reading stopped early, or None if the file ended
            cleanly.
        end: the offset up to which records were read.
        size: the file's size in bytes.
    """

    connections: Dict[int, Connection] = field(default_factory=dict)
    messages: List[Tuple[int, int, bytes]] = field(default_factory=list)
    index_pos: int = 0
    chunks: int = 0
    damage: Optional[str] = None
    end: int = 0
    size: int = 0


def parse_fields(buffer: _Buffer, start: int, end: int) -> Dict[bytes, bytes]:
    """The ``name=value`` fields of a record header in ``buffer[start:end]``.

    Raises:
        ValueError: if the fields are malformed.
    """
    fields = {}
    pos = start
    while pos < end:
        (length,) = _U32.unpack_from(buffer, pos)
        pos += 4
        stop = pos + length
        if stop > end:
            raise ValueError("a header field runs past its header")
        name, separator, value = buffer[pos:stop].partition(b"=")
        if not separator:
            raise ValueError("a header field has no '='")
        fields[name] = value
        pos = stop
    return fields


def _connection(fields: Dict[bytes, bytes], data: bytes) -> Connection:
    details = parse_fields(data, 0, len(data))

    def text(key: bytes) -> Optional[str]:
        value = details.get(key)
        return None if value is None else value.decode("utf-8", "replace")

    return Connection(
        id=_U32.unpack(fields[b"conn"])[0],
        topic=fields[b"topic"].decode("utf-8", "replace"),
        type=text(b"type") or "",
        md5sum=text(b"md5sum") or "",
        message_definition=text(b"message_definition") or "",
        callerid=text(b"callerid"),
        latching=text(b"latching"),
    )


class _Scanner:
    def __init__(self, wanted: Callable[[Connection], bool]) -> None:
        self.wanted = wanted
        self.result = ScanResult()
        self.keep: Dict[int, bool] = {}

    def add_connection(self, connection: Connection) -> None:
        if connection.id not in self.result.connections:
            self.result.connections[connection.id] = connection
            self.keep[connection.id] = self.wanted(connection)

    def records(  # noqa: PLR0911, PLR0912 - one branch per record kind and per damage
        self, buffer: _Buffer, pos: int, end: int
    ) -> Tuple[int, Optional[str]]:
        """Read the records of ``buffer[pos:end]``; return where reading stopped, and why."""
        unpack_u32 = _U32.unpack_from
        unpack_time = _TIME.unpack_from
        messages = self.result.messages
        keep = self.keep
        while pos < end:
            if pos + 4 > end:
                return pos, "the file ends inside a record"
            (header_length,) = unpack_u32(buffer, pos)
            header_start = pos + 4
            header_end = header_start + header_length
            if header_end + 4 > end:
                return pos, "the file ends inside a record"
            (data_length,) = unpack_u32(buffer, header_end)
            data_start = header_end + 4
            data_end = data_start + data_length
            try:
                fields = parse_fields(buffer, header_start, header_end)
                op = fields[b"op"][0]
            except (ValueError, KeyError, IndexError, struct.error):
                return pos, f"a record at byte {pos} is damaged"
            if op == OP_MESSAGE:
                if data_end > end:
                    return pos, "the file ends inside a message"
                try:
                    (conn,) = _U32.unpack(fields[b"conn"])
                    secs, nsecs = unpack_time(fields[b"time"])
                except (KeyError, struct.error):
                    return pos, f"the message record at byte {pos} is damaged"
                if keep.get(conn):
                    messages.append(
                        (conn, secs * 1_000_000_000 + nsecs, buffer[data_start:data_end])
                    )
            elif op == OP_CHUNK:
                self.result.chunks += 1
                problem = self.chunk(fields, buffer, data_start, min(data_end, end))
                if problem is not None:
                    return min(data_end, end), problem
            elif op == OP_CONNECTION:
                if data_end > end:
                    return pos, "the file ends inside a connection record"
                try:
                    self.add_connection(_connection(fields, buffer[data_start:data_end]))
                except (ValueError, KeyError, struct.error):
                    return pos, f"the connection record at byte {pos} is damaged"
            elif op == OP_BAG_HEADER:
                try:
                    (self.result.index_pos,) = _U64.unpack(fields[b"index_pos"])
                except (KeyError, struct.error):
                    return pos, "the bag header is damaged"
            if data_end > end:
                return pos, "the file ends inside a record"
            pos = data_end
        return pos, None

    def chunk(  # noqa: PLR0911 - one sentence per kind of damage
        self, fields: Dict[bytes, bytes], buffer: _Buffer, start: int, end: int
    ) -> Optional[str]:
        """Read a chunk's records (a cut one gives its complete messages); return any problem."""
        compression = fields.get(b"compression", b"none").decode("ascii", "replace")
        raw = buffer[start:end]
        try:
            (size,) = _U32.unpack(fields[b"size"])
        except (KeyError, struct.error):
            return "a chunk header is damaged"
        if compression == "none":
            data = raw
        elif compression == "bz2":
            decompressor = bz2.BZ2Decompressor()
            try:
                data = decompressor.decompress(raw)
            except (OSError, ValueError):
                return "a bz2 chunk is damaged"
        elif compression == "lz4":
            decompressed = _lz4(raw)
            if decompressed is None:
                return "an lz4 chunk is damaged or cut short"
            data = decompressed
        else:
            return f"a chunk uses the unknown compression {compression!r}"
        truncated = len(data) < size
        _, problem = self.records(data, 0, len(data))
        if truncated:
            return "the last chunk was cut short; its complete messages were kept"
        if problem is not None:
            return f"a chunk is damaged ({problem}); its complete messages were kept"
        return None


def _lz4(raw: bytes) -> Optional[bytes]:
    try:
        from lz4.frame import decompress
    except ImportError:  # pragma: no cover - lz4 comes with rosbags
        return None
    try:
        return decompress(raw)
    except RuntimeError:
        return None


def scan(path: Path, wanted: Optional[Callable[[Connection], bool]] = None) -> ScanResult:
    """Read every record of a bag in file order, stopping cleanly at damage.

    Args:
        path: the bag file.
        wanted: which connections' messages to keep (default: all).

    Raises:
        BagError: if the file cannot be read or is not a ROS 1 bag.
    """
    scanner = _Scanner(wanted or (lambda connection: True))
    try:
        with Path(path).open("rb") as file:
            size = file.seek(0, 2)
            if size < len(MAGIC):
                raise BagError(f"{path} is not a ROS 1 bag: it is too short ({size} bytes).")
            with mmap.mmap(file.fileno(), 0, access=mmap.ACCESS_READ) as buffer:
                if buffer[: len(MAGIC)] != MAGIC:
                    raise BagError(
                        f"{path} is not a ROS 1 bag: it does not start with '#ROSBAG V2.0'."
                    )
                end, damage = scanner.records(buffer, len(MAGIC), size)
    except OSError as error:
        raise BagError(f"Cannot read {path}: {error.strerror or error}.") from None
    result = scanner.result
    result.end, result.damage, result.size = end, damage, size
    return result
