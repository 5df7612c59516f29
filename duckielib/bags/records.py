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
index       0x04   how many messages of one connection a chunk holds, and where
chunk info  0x06   a chunk's position, time range and message counts by connection
=========== ====== ==========================================================================

Reading in file order needs no index, so this module reads what a killed recorder left
behind (:mod:`duckielib.bags.repair`), and it is the fast path for reading many small
messages: rosbags reads a message through the index in about 10 microseconds, this in
about 2. Bags are still opened, checked and written with rosbags
(:mod:`duckielib.bags.reader`, :mod:`duckielib.bags.writer`).

Damage. Every record header is checked as it is read: its fields parse, its kind is known
(inside a chunk only messages and connections belong), it has the fields its kind needs, and
it fits in its chunk and in the file. A record that fails is damage: the scan notes it as a
:class:`Damage` and searches forward for the next record that passes the same checks, so what
follows a damaged stretch is still read. A file that simply ends inside a record was cut short
(``ScanResult.cut``), which is not counted as damage. Damage inside a bz2 or lz4 chunk makes
the whole chunk unreadable. A byte changed inside a message's data cannot be noticed: ROS 1
bags carry no checksums, only the counts of their index (see :attr:`ScanResult.index_counts`).
"""

# Over 600 lines: one scanner reads a bag's records in file order, damage included; each record
# kind's checks sit beside the resynchronisation that relies on them, and the message path is its
# hot loop.

from __future__ import annotations

import bz2
import mmap
import stat
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Dict, List, Optional, Tuple, Union

from duckielib.errors import BagError

__all__ = [
    "MAGIC",
    "Connection",
    "Damage",
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
_PAIR = struct.Struct("<II")
_ENTRY = struct.Struct("<III")  # an index entry: record time (secs, nsecs), offset in the chunk
#: What records are read from: a chunk's bytes, or the whole bag mapped into memory.
_Buffer = Union[bytes, mmap.mmap]

_MESSAGE_OP = bytes([OP_MESSAGE])
#: A message record's header as rosbags, duckielib and ROS's rosbag write it: ``op``, then
#: ``conn`` (4 bytes), then ``time`` (8 bytes), each field after its length.
_USUAL_START = b"\x04\x00\x00\x00op=\x02\x09\x00\x00\x00conn="
_USUAL_TIME = b"\x0d\x00\x00\x00time="
_USUAL_LENGTH = len(_USUAL_START) + 4 + len(_USUAL_TIME) + 8
#: The kinds of record a chunk holds, and those found between chunks (messages there come
#: from a chunk whose own header was damaged).
_IN_CHUNK = frozenset([OP_MESSAGE, OP_CONNECTION])
_OUTSIDE_CHUNKS = frozenset([OP_CHUNK, OP_INDEX, OP_CONNECTION, OP_CHUNK_INFO, OP_MESSAGE])
_COMPRESSIONS = (b"none", b"bz2", b"lz4")
#: No record header is this long (their largest fields are a topic's name and a callerid).
_MAX_HEADER = 1 << 16
#: The ``op`` field as every record header holds it: its length, 4, then ``op=`` and a byte.
_OP_FIELD = b"\x04\x00\x00\x00op="
#: Records that lie only between chunks: one of them after a record that runs past the end of
#: the file shows that the record's length is damaged, not that the file was cut short.
_BETWEEN_CHUNKS = frozenset([OP_CHUNK, OP_INDEX, OP_CHUNK_INFO])
#: How far before its ``op`` field a record may start (the fields sorted before ``op``).
_RESYNC_BACK = 128
_HEAD = "the bag header (the file's first record, in its first 4 KB) cannot be read"


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


@dataclass(frozen=True)
class Damage:
    """A stretch of a bag that could not be read, and was skipped.

    Attributes:
        start: the byte offset in the file where the damage was found (inside a compressed
            chunk: where the chunk starts).
        skipped: how many bytes were skipped (inside a compressed chunk: of its decompressed
            data).
        what: what is wrong there, as a clause: ``"a record header cannot be read"``.
        chunk: the byte offset of the chunk the damage is in, or None outside chunks.
    """

    start: int
    skipped: int
    what: str
    chunk: Optional[int] = None

    def __str__(self) -> str:
        return f"at byte {self.start}, {self.what}; {self.skipped} bytes skipped"


@dataclass
class ScanResult:
    """What a scan of a bag found.

    Attributes:
        connections: every connection record, by id.
        messages: ``(connection id, record time in ns, serialized bytes)`` of each complete
            message of a wanted connection, in file order.
        counts: how many complete messages each connection has, wanted or not, by id.
        index_pos: where the bag's index starts, as its header says; 0 if the bag was never
            closed or its header is damaged.
        header_ok: whether the bag header (the first record) could be read.
        chunk_count: how many chunks the bag header says the index lists.
        chunks: how many chunks were found, completely or in part.
        chunk_spans: ``(start, end)`` byte offsets of each chunk record found.
        chunk_messages: how many messages the index records after each chunk list, by the
            chunk's offset.
        index_counts: how many messages each connection has, by id, as the chunk info records
            at the end of the bag list them (empty without an index).
        indexed_chunks: the chunk offsets the chunk info records list.
        damages: each damaged stretch that was skipped, in file order.
        cut: a sentence saying where the file ends inside a record (it was cut short), or None.
        damage: the first problem (damage or cut), as a sentence; None if there was none.
        orphans: messages skipped because their connection record was lost in damage.
        suspects: messages left out because damage starts right after them, so the first
            damaged bytes may be in their data (they are not in ``messages`` nor ``counts``).
        end: the offset up to which records were read.
        size: the file's size in bytes.
    """

    connections: Dict[int, Connection] = field(default_factory=dict)
    messages: List[Tuple[int, int, bytes]] = field(default_factory=list)
    counts: Dict[int, int] = field(default_factory=dict)
    index_pos: int = 0
    header_ok: bool = False
    chunk_count: int = 0
    chunks: int = 0
    chunk_spans: List[Tuple[int, int]] = field(default_factory=list)
    chunk_messages: Dict[int, int] = field(default_factory=dict)
    index_counts: Dict[int, int] = field(default_factory=dict)
    indexed_chunks: List[int] = field(default_factory=list)
    damages: List[Damage] = field(default_factory=list)
    cut: Optional[str] = None
    damage: Optional[str] = None
    orphans: int = 0
    suspects: int = 0
    end: int = 0
    size: int = 0

    @property
    def bytes_skipped(self) -> int:
        """How many bytes the damaged stretches held."""
        return sum(item.skipped for item in self.damages)

    @property
    def index_lists_chunks(self) -> bool:
        """Whether the bag was closed, and its header and index list exactly the chunks found."""
        return (
            self.header_ok
            and 0 < self.index_pos < self.size
            and self.chunk_count == len(self.indexed_chunks)
            and sorted(self.indexed_chunks) == sorted(start for start, _ in self.chunk_spans)
        )

    @property
    def index_matches(self) -> bool:
        """Whether the index lists exactly the chunks and the messages found.

        Meaningful after a scan that read inside the chunks.
        """
        found = {key: value for key, value in self.counts.items() if value}
        listed = {key: value for key, value in self.index_counts.items() if value}
        return self.index_lists_chunks and found == listed


def parse_fields(buffer: _Buffer, start: int, end: int) -> Dict[bytes, bytes]:
    """The ``name=value`` fields of a record header in ``buffer[start:end]``.

    Raises:
        ValueError: if the fields are malformed.
    """
    fields = {}
    pos = start
    while pos < end:
        if pos + 4 > end:
            raise ValueError("a header field's length runs past its header")
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


def _u32(fields: Dict[bytes, bytes], name: bytes) -> int:
    """A 4-byte field (KeyError if missing, struct.error if not 4 bytes)."""
    return int(_U32.unpack(fields[name])[0])


def _plausible(  # noqa: PLR0911 - one check per kind of record
    buffer: _Buffer, start: int, op_at: int, end: int, kinds: frozenset
) -> bool:
    """Whether a record of one of ``kinds`` that passes every check starts at ``start``."""
    if start + 8 > end:
        return False
    (header_length,) = _U32.unpack_from(buffer, start)
    header_end = start + 4 + header_length
    if header_length > _MAX_HEADER or header_end < op_at + 8 or header_end + 4 > end:
        return False
    try:
        fields = parse_fields(buffer, start + 4, header_end)
        op = fields[b"op"]
        kind = op[0]
        (data_length,) = _U32.unpack_from(buffer, header_end)
        data_end = header_end + 4 + data_length
        if len(op) != 1 or kind not in kinds:
            return False
        if kind == OP_CHUNK:  # the last chunk of a file cut short runs past its end
            compression = fields.get(b"compression", b"none")
            return compression in _COMPRESSIONS and _u32(fields, b"size") >= 0
        if data_end > end:
            return False
        if kind == OP_MESSAGE:
            return _u32(fields, b"conn") >= 0 and len(fields[b"time"]) == _TIME.size
        if kind == OP_CONNECTION:
            details = parse_fields(buffer, header_end + 4, data_end)
            return _u32(fields, b"conn") >= 0 and b"topic" in fields and b"type" in details
        if kind == OP_INDEX:
            return (
                _u32(fields, b"ver") == 1
                and _u32(fields, b"conn") >= 0
                and data_length == 12 * _u32(fields, b"count")
            )
        return (  # a chunk info record
            _u32(fields, b"ver") == 1
            and len(fields[b"chunk_pos"]) == _U64.size
            and data_length == 8 * _u32(fields, b"count")
        )
    except (ValueError, KeyError, IndexError, struct.error):
        return False


def _resync(buffer: _Buffer, start: int, end: int, kinds: frozenset) -> int:
    """Where the next record of one of ``kinds`` that passes every check starts, or ``end``."""
    search = start
    while True:
        found = buffer.find(_OP_FIELD, search, end)
        if found < 0 or found + len(_OP_FIELD) >= end:
            return end
        if buffer[found + len(_OP_FIELD)] not in kinds:
            search = found + 1
            continue
        for candidate in range(found - 4, max(start, found - 4 - _RESYNC_BACK) - 1, -1):
            if _plausible(buffer, candidate, found, end, kinds):
                return candidate
        search = found + 1


class _Damaged(Exception):
    """A record fails a check; the argument says how, as a clause."""


class _Cut(Exception):
    """The data ends inside a record."""


class _Stop(Exception):
    """The file ends inside its last chunk, whose complete records were read."""


class _Scanner:
    def __init__(
        self, wanted: Callable[[Connection], bool], read_chunks: bool, check_index: bool
    ) -> None:
        self.wanted = wanted
        self.read_chunks = read_chunks
        # With check_index: where each connection's messages are in the chunk being read,
        # as (secs, nsecs, offset in the chunk's data), to compare with its index records.
        self.where: Optional[Dict[int, List[Tuple[int, int, int]]]] = {} if check_index else None
        self.chunk_sound = False
        self.result = ScanResult()
        self.keep: Dict[int, bool] = {}
        self.unresolved = False  # a message came before its connection record
        self.last_chunk: Optional[int] = None

    def add_connection(self, connection: Connection) -> None:
        if connection.id not in self.result.connections:
            self.result.connections[connection.id] = connection
            self.keep[connection.id] = self.wanted(connection)

    def records(  # noqa: PLR0912, PLR0915 - the message path is kept in one loop for speed
        self,
        buffer: _Buffer,
        pos: int,
        end: int,
        chunk: Optional[int] = None,
        in_file: bool = True,
        cut_short: bool = False,
        base: int = 0,
    ) -> int:
        """Read the records of ``buffer[pos:end]``; return where reading ended.

        Args:
            buffer: the file, or a compressed chunk's decompressed data.
            pos: where to start reading.
            end: where to stop.
            chunk: the offset of the chunk whose records these are; None between chunks.
            in_file: whether offsets in ``buffer`` are offsets in the file.
            cut_short: whether the chunk's data ends early because the file does.
            base: where the chunk's data starts in ``buffer`` (offsets in an index count
                from there).

        Returns:
            ``end``, or the offset of the record the file ends inside of.
        """
        # Over 80 lines: the hot loop of every bag read, one pass per record with its lookups
        # bound to locals; a call per message would slow the reading of large bags.
        unpack_u32 = _U32.unpack_from
        unpack_time = _TIME.unpack
        unpack_time_from = _TIME.unpack_from
        messages = self.result.messages
        counts = self.result.counts
        keep = self.keep
        where = self.where
        # The last message read, while no other record came after it: damage found right
        # after a message may have begun inside that message's data.
        last_end, last_conn, last_kept = -1, 0, False
        while pos < end:
            try:
                if pos + 8 > end:
                    raise _Cut
                (header_length,) = unpack_u32(buffer, pos)
                header_end = pos + 4 + header_length
                if header_length > _MAX_HEADER:
                    raise _Damaged("a record header has an impossible length")
                if header_end + 4 > end:
                    raise _Cut
                (data_length,) = unpack_u32(buffer, header_end)
                data_end = header_end + 4 + data_length
                if (
                    header_length == _USUAL_LENGTH
                    and buffer[pos + 4 : pos + 21] == _USUAL_START
                    and buffer[pos + 25 : pos + 34] == _USUAL_TIME
                ):  # the header every writer we know writes, checked byte for byte
                    (conn,) = unpack_u32(buffer, pos + 21)
                    secs, nsecs = unpack_time_from(buffer, pos + 34)
                else:
                    fields = parse_fields(buffer, pos + 4, header_end)
                    if fields.get(b"op") != _MESSAGE_OP:
                        last_end = -1
                        self.other(fields, buffer, pos, header_end + 4, data_end, end, chunk)
                        pos = data_end
                        continue
                    (conn,) = _U32.unpack(fields[b"conn"])
                    secs, nsecs = unpack_time(fields[b"time"])
                if data_end > end:
                    raise _Cut
                counts[conn] = counts.get(conn, 0) + 1
                wanted = keep.get(conn)
                if wanted is None:
                    self.unresolved = True
                last_end, last_conn, last_kept = data_end, conn, wanted is not False
                if where is not None:
                    where.setdefault(conn, []).append((secs, nsecs, pos - base))
                if last_kept:
                    messages.append(
                        (conn, secs * 1_000_000_000 + nsecs, buffer[header_end + 4 : data_end])
                    )
                pos = data_end
                continue
            except _Cut:
                if cut_short or (chunk is None and not self.followed(buffer, pos, end)):
                    return pos
                what = "a record runs past the end of its chunk"
                if chunk is None:
                    what = "a record's length runs past the end of the file, yet records follow"
            except _Stop:
                return self.result.end
            except _Damaged as damaged:
                what = str(damaged)
            except (ValueError, KeyError, IndexError, struct.error):
                what = "a record header cannot be read"
            if pos == last_end:  # the message just before may hold the damage's first bytes
                counts[last_conn] -= 1
                self.result.suspects += 1
                if last_kept:
                    messages.pop()
            last_end = -1
            pos = self.skip(buffer, pos, end, what, chunk, in_file)
        return end

    @staticmethod
    def followed(buffer: _Buffer, pos: int, end: int, kinds: frozenset = _OUTSIDE_CHUNKS) -> bool:
        """Whether a sound record of one of ``kinds`` starts after ``pos``."""
        return _resync(buffer, pos + 1, end, kinds) < end

    def skip(
        self, buffer: _Buffer, pos: int, end: int, what: str, chunk: Optional[int], in_file: bool
    ) -> int:
        """Note the damage at ``pos``; return where the next sound record starts."""
        if chunk is None and pos == len(MAGIC):
            what = _HEAD
        kinds = _OUTSIDE_CHUNKS if chunk is None else _IN_CHUNK
        resume = _resync(buffer, pos + 1, end, kinds)
        if in_file:
            damage = Damage(pos, resume - pos, what, chunk)
        else:
            where = f"{what}, {pos} bytes into the chunk's decompressed data"
            damage = Damage(chunk or 0, resume - pos, where, chunk)
        self.result.damages.append(damage)
        return resume

    def other(  # noqa: PLR0912 - one branch per kind of record
        self,
        fields: Dict[bytes, bytes],
        buffer: _Buffer,
        pos: int,
        data_start: int,
        data_end: int,
        end: int,
        chunk: Optional[int],
    ) -> None:
        """Read a record that is not a message (raises _Damaged or _Cut)."""
        op = fields.get(b"op", b"")
        if len(op) != 1:
            raise _Damaged("a record header has no valid kind (op field)")
        kind = op[0]
        first = chunk is None and pos == len(MAGIC)
        if first and kind != OP_BAG_HEADER:
            raise _Damaged(_HEAD)
        if chunk is not None and kind not in _IN_CHUNK:
            raise _Damaged(
                f"a record of kind {kind:#04x} is inside a chunk, which holds only messages "
                "and connections"
            )
        if kind == OP_CHUNK:
            self.chunk(fields, buffer, pos, data_start, data_end, end)
            return
        if data_end > end:
            raise _Cut
        if kind == OP_CONNECTION:
            try:
                self.add_connection(_connection(fields, buffer[data_start:data_end]))
            except (ValueError, KeyError, struct.error):
                raise _Damaged("a connection record cannot be read") from None
        elif kind == OP_INDEX:
            count = _u32(fields, b"count")
            if _u32(fields, b"ver") != 1 or data_end - data_start != 12 * count:
                raise _Damaged("an index record cannot be read")
            if self.where is not None and self.chunk_sound:
                entries = [_ENTRY.unpack_from(buffer, data_start + 12 * i) for i in range(count)]
                if entries != self.where.get(_u32(fields, b"conn"), []):
                    raise _Damaged(
                        f"an index record of the chunk at byte {self.last_chunk} does not list "
                        "the messages that chunk holds"
                    )
            if self.last_chunk is not None:
                messages = self.result.chunk_messages
                messages[self.last_chunk] = messages.get(self.last_chunk, 0) + count
        elif kind == OP_CHUNK_INFO:
            count = _u32(fields, b"count")
            if _u32(fields, b"ver") != 1 or data_end - data_start != 8 * count:
                raise _Damaged("a chunk info record cannot be read")
            (chunk_pos,) = _U64.unpack(fields[b"chunk_pos"])
            self.result.indexed_chunks.append(chunk_pos)
            counts = self.result.index_counts
            for index in range(count):
                conn, number = _PAIR.unpack_from(buffer, data_start + 8 * index)
                counts[conn] = counts.get(conn, 0) + number
        elif kind == OP_BAG_HEADER:
            if not first:
                raise _Damaged("a second bag header is in the middle of the file")
            (index_pos,) = _U64.unpack(fields[b"index_pos"])
            chunk_count = _u32(fields, b"chunk_count")
            self.result.index_pos, self.result.chunk_count = index_pos, chunk_count
            self.result.header_ok = True
        elif kind != OP_MESSAGE:
            raise _Damaged(f"a record of unknown kind {kind:#04x} is there")

    def chunk(
        self,
        fields: Dict[bytes, bytes],
        buffer: _Buffer,
        pos: int,
        data_start: int,
        data_end: int,
        end: int,
    ) -> None:
        """Read a chunk's records; a chunk cut short gives its complete messages."""
        compression = fields.get(b"compression", b"none")
        try:
            size = _u32(fields, b"size")
        except (KeyError, struct.error):
            raise _Damaged("a chunk header cannot be read") from None
        if compression not in _COMPRESSIONS:
            raise _Damaged(f"a chunk header names the unknown compression {compression!r}")
        cut = data_end > end
        if cut and self.followed(buffer, pos, end, _BETWEEN_CHUNKS):
            raise _Damaged("a chunk's length runs past the end of the file, yet records follow")
        if compression == b"none" and size != data_end - data_start and not cut:
            raise _Damaged("a chunk header gives two different sizes for its data")
        self.result.chunk_spans.append((pos, data_end))
        self.result.chunks += 1
        self.last_chunk = pos
        stop = min(data_end, end)
        damages = len(self.result.damages)
        if self.where is not None:
            self.where = {}
        if self.read_chunks:
            if compression == b"none":
                stop = self.records(
                    buffer, data_start, stop, chunk=pos, cut_short=cut, base=data_start
                )
            else:
                self.compressed(compression.decode(), buffer[data_start:stop], size, pos, cut)
        self.chunk_sound = len(self.result.damages) == damages
        if cut:
            self.result.cut = (
                f"the file ends inside the chunk at byte {pos}: the last chunk was cut short; "
                "its complete messages were kept"
            )
            self.result.end = stop
            raise _Stop

    def compressed(self, compression: str, raw: bytes, size: int, pos: int, cut: bool) -> None:
        """Read the records of a bz2 or lz4 chunk, as far as it can be decompressed."""
        data, whole = _decompress(compression, raw)
        if not whole and not cut:
            if data:
                what = (
                    f"the {compression} chunk there can be decompressed only in part "
                    f"({len(data)} of {size} bytes), so its later messages are lost"
                )
            else:
                what = (
                    f"the {compression} chunk there cannot be decompressed, so its messages "
                    "are lost"
                )
            self.result.damages.append(Damage(pos, len(raw), what, pos))
        elif whole and len(data) != size:
            self.result.damages.append(
                Damage(
                    pos,
                    0,
                    f"the {compression} chunk there decompresses to {len(data)} bytes, not the "
                    f"{size} its header gives",
                    pos,
                )
            )
        self.records(data, 0, len(data), chunk=pos, in_file=False, cut_short=cut or not whole)


def _decompress(compression: str, raw: bytes) -> Tuple[bytes, bool]:
    """A chunk's data decompressed as far as it can be, and whether it was whole."""
    if compression == "bz2":
        decompressor = bz2.BZ2Decompressor()
        try:
            data = decompressor.decompress(raw)
        except (OSError, ValueError):
            return b"", False
        return data, decompressor.eof
    try:
        from lz4.frame import decompress
    except ImportError:  # pragma: no cover - lz4 comes with rosbags
        return b"", False
    try:
        return bytes(decompress(raw)), True
    except RuntimeError:
        return b"", False


def not_a_file(path: Path) -> Optional[str]:
    """Why ``path`` cannot be a bag file, in a sentence, without opening it; None if it can.

    A FIFO, a socket or a device is never opened: reading a FIFO blocks until someone
    writes to it, and a device may never end.
    """
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        return f"There is no file {path}."
    except OSError as error:
        return f"{path} cannot be read: {error.strerror}."
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return f"{path} is a directory, not a bag file."
    kind = (
        "a FIFO (a named pipe)"
        if stat.S_ISFIFO(mode)
        else "a socket"
        if stat.S_ISSOCK(mode)
        else "a device"
        if stat.S_ISCHR(mode) or stat.S_ISBLK(mode)
        else "not a regular file"
    )
    return f"{path} is {kind}, not a bag file: it was not opened. Give the bag's own file."


#: The first bytes of an MCAP file.
MCAP_MAGIC = b"\x89MCAP0\r\n"


def bag_format(path: Path) -> Optional[str]:
    """A bag's format from its contents: ``"ros1"``, ``"mcap"`` or ``"ros2"``; None if none.

    ``"ros2"`` is a ROS 2 bag folder (one with a ``metadata.yaml``).

    Raises:
        BagError: if it is missing, or not a regular file nor a ROS 2 bag folder (see
            :func:`not_a_file`).
    """
    if path.is_dir() and (path / "metadata.yaml").is_file():
        return "ros2"
    why = not_a_file(path)
    if why is not None:
        raise BagError(why)
    with path.open("rb") as file:
        start = file.read(max(len(MAGIC), len(MCAP_MAGIC)))
    if start.startswith(MAGIC):
        return "ros1"
    return "mcap" if start.startswith(MCAP_MAGIC) else None


def scan(
    path: Path,
    wanted: Optional[Callable[[Connection], bool]] = None,
    read_chunks: bool = True,
    check_index: bool = False,
) -> ScanResult:
    """Read every record of a bag in file order, skipping damage and stopping at a cut.

    Args:
        path: the bag file.
        wanted: which connections' messages to keep (default: all).
        read_chunks: whether to read the records inside the chunks; without, only what lies
            between them (the bag header, chunk headers, index and connection records) is
            read, which is quick: it is the bag's layout.
        check_index: also check that each index record lists exactly the messages of the
            chunk before it (their record times and offsets); one that does not is damage.

    Raises:
        BagError: if the file cannot be read or is not a ROS 1 bag.
    """
    why = not_a_file(Path(path))
    if why is not None:
        raise BagError(why)
    scanner = _Scanner(wanted or (lambda connection: True), read_chunks, check_index)
    result = scanner.result
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
                end = scanner.records(buffer, len(MAGIC), size)
    except OSError as error:
        raise BagError(f"Cannot read {path}: {error.strerror or error}.") from None
    if result.cut is None:
        result.end = end
        if end < size:
            result.cut = f"the file ends inside a record at byte {end}: it was cut short"
    result.size = size
    if scanner.unresolved:
        keep = scanner.keep
        result.orphans = sum(1 for conn, _, _ in result.messages if conn not in keep)
        result.messages = [item for item in result.messages if keep.get(item[0])]
    first = [str(result.damages[0])] if result.damages else []
    if result.cut is not None:
        first.append(result.cut)
    result.damage = first[0] if first else None
    return result
