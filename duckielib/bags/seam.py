"""The seam with rosbags: the only code that relies on rosbags' undocumented internals.

- :class:`RosbagsSeam` writes messages straight into a rosbags writer's open chunk (the bytes
  ``Writer.write`` would write, without rebuilding each record's header) and finds a bag's
  chunks through its reader. What it relies on is listed in its docstring and checked
  against the installed rosbags at first use; :data:`ROSBAGS_CHECKED` names the versions it
  was read against, as a test does.
- Names of types between ROS 1 (``package/Type``) and rosbags (``package/msg/Type``), and
  :func:`course_typestore`, a rosbags typestore with the course's types, registered from the
  same ``.msg`` text as :mod:`duckielib.messages`.

:mod:`duckielib.bags.reader` and :mod:`duckielib.bags.writer` use rosbags through its
documented API and through this module only. A record time of 0 is written as 1 ns, ROS 1's
smallest valid time, so ``rosbag play`` loads the message.
"""

from __future__ import annotations

import io
import struct
from importlib import metadata
from pathlib import Path
from typing import Any, BinaryIO, Dict, Iterable, List, Optional, Tuple

from rosbags.rosbag1 import Reader, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from duckielib import messages as course_messages
from duckielib.bags import records
from duckielib.errors import BagError
from duckielib.rostime import NS_PER_S

__all__ = [
    "ROSBAGS_CHECKED",
    "RosbagsSeam",
    "course_typestore",
    "ros1_type",
    "rosbags_type",
    "rosbags_version",
]

#: The rosbags versions :class:`RosbagsSeam` was checked with.
ROSBAGS_CHECKED = ("0.11.9",)

_UINT32 = struct.Struct("<L")
_MESSAGE_TAIL = struct.Struct("<LLL")  # record time (secs, nsecs), then the data's length


#: ROS 1's smallest valid time (``ros::TIME_MIN``), in ns. Debian's rosbag_storage drops a
#: message whose record time is below it ("contains invalid time"), so a message recorded at
#: time 0 (the simulation's first instant) is written 1 ns later: then every bag written here
#: replays whole in ``rosbag play``.
_TIME_MIN_NS = 1


def rosbags_version() -> str:
    """The installed rosbags' version."""
    try:
        return metadata.version("rosbags")
    except metadata.PackageNotFoundError:  # pragma: no cover - rosbags run from a checkout
        return "(unknown version)"


class RosbagsSeam:
    """The only code that uses rosbags beyond its documented API.

    rosbags' ``Writer.write`` builds each record's header anew, and a recorder writes thousands
    of messages a second, so :meth:`write_messages` puts the same bytes straight into the
    writer's open chunk. It relies on these undocumented parts of ``rosbags.rosbag1``:

    - ``Writer.chunks``: the writer's chunks (``WriteChunk``), the last one open.
    - ``Writer.chunk_threshold``: the size in bytes past which the open chunk is written.
    - ``Writer.write_chunk(chunk)``: writes a chunk and its index, then opens the next chunk.
    - ``Writer.bio``: the bag's file, None once the writer is closed.
    - ``WriteChunk.data``: a ``BytesIO`` holding the chunk's records.
    - ``WriteChunk.connections``: a ``defaultdict(list)`` from connection id to
      ``(record time ns, offset in data)`` pairs.
    - ``WriteChunk.start``, ``WriteChunk.end``: the chunk's first and last record time.
    - The message data record ``Writer.write`` writes: header fields ``op``, ``conn`` and
      ``time`` in that order (:meth:`record_start`), the data's length, the data.
    - ``Reader.chunk_infos`` and their ``pos``: where each chunk starts in the file.

    Checked with the rosbags versions in :data:`ROSBAGS_CHECKED`. :meth:`check_writer` tests
    the writer's part once, before the first bag is written: a probe writes the same messages
    with ``Writer.write`` and with :meth:`write_messages`, in memory, and the bytes must match.
    :meth:`chunk_positions` tests the reader's part when the first bag is opened. Both raise a
    :class:`~duckielib.errors.BagError` naming what the installed rosbags lacks.

    Args:
        writer: an open ``rosbags.rosbag1.Writer``.
        name: the bag's file name, for messages.

    Attributes:
        written: how many messages :meth:`write_messages` wrote.
    """

    #: Whether :meth:`check_writer` passed in this process.
    writer_checked = False
    #: Whether :meth:`chunk_positions` checked the reader's part in this process.
    reader_checked = False

    def __init__(self, writer: Writer, name: str) -> None:
        self.writer = writer
        self.name = name
        self.written = 0
        self._starts: Dict[int, Tuple[Any, bytes]] = {}

    @staticmethod
    def record_start(connection_id: int) -> bytes:
        """A message data record's bytes up to its time, in the field order rosbags writes.

        Format 2.0: the header's length, then ``op=0x02``, ``conn=<uint32>`` and ``time=`` with
        the time's 8 bytes to follow; each field is preceded by its own length.
        """
        fields = [b"op=\x02", b"conn=" + _UINT32.pack(connection_id), b"time="]
        sizes = [len(fields[0]), len(fields[1]), len(fields[2]) + 8]
        header = b"".join(_UINT32.pack(size) + value for size, value in zip(sizes, fields))
        return _UINT32.pack(len(header) + 8) + header

    def register(self, connection: Any) -> None:
        """Accept messages on ``connection``, which the writer's ``add_connection`` returned."""
        self._starts[connection.id] = (connection, self.record_start(connection.id))

    def write_messages(self, items: Iterable[Tuple[Any, int, bytes]]) -> None:
        """Write ``(connection, time_ns, data)`` items into the open chunk, in order.

        The bytes are those ``Writer.write`` writes; a full chunk is written to the file as
        ``Writer.write`` does. Items before a bad one are written.

        Raises:
            BagError: if a time is negative or a connection was not registered.
        """
        writer = self.writer
        threshold = writer.chunk_threshold
        starts = self._starts
        pack = _MESSAGE_TAIL.pack
        chunk = writer.chunks[-1]
        out = chunk.data
        index = chunk.connections
        first, last = chunk.start, chunk.end
        written = 0
        try:
            for connection, record_ns, data in items:
                time_ns = record_ns
                if time_ns.__class__ is not int or time_ns < _TIME_MIN_NS:
                    if time_ns.__class__ is not int or time_ns < 0:
                        raise BagError(
                            "A record time must be a whole number of nanoseconds >= 0, "
                            f"not {time_ns!r}."
                        )
                    time_ns = _TIME_MIN_NS  # see _TIME_MIN_NS
                known, start = starts.get(connection.id, (None, b""))
                if known is not connection:
                    raise BagError(f"{connection.topic} is not a connection of {self.name}.")
                index[connection.id].append((time_ns, out.tell()))
                first = min(first, time_ns)
                last = max(last, time_ns)
                secs, nsecs = divmod(time_ns, NS_PER_S)
                out.write(start + pack(secs, nsecs, len(data)))
                out.write(data)
                written += 1
                if out.tell() > threshold:
                    chunk.start, chunk.end = first, last
                    writer.write_chunk(chunk)
                    chunk = writer.chunks[-1]
                    out = chunk.data
                    index = chunk.connections
                    first, last = chunk.start, chunk.end
        finally:
            chunk.start, chunk.end = first, last
            self.written += written

    def write_open_chunk(self) -> None:
        """Write the open chunk to the file, if it holds anything."""
        chunk = self.writer.chunks[-1]
        if chunk.data.tell() > 0:
            self.writer.write_chunk(chunk)

    @property
    def file(self) -> Optional[BinaryIO]:
        """The bag's file, or None once the writer is closed."""
        return self.writer.bio

    @classmethod
    def check_writer(cls, path: Path) -> None:
        """Check once that the installed rosbags' writer has and does what the seam relies on.

        Args:
            path: a file that does not exist; nothing is written to it.

        Raises:
            BagError: if it does not, naming what is missing or different.
        """
        if cls.writer_checked:
            return
        try:
            missing = _missing_from_writer(path)
            same = not missing and _probe(path, seam=False) == _probe(path, seam=True)
        except Exception as error:
            raise _unusable(
                "writing test messages into its Writer's open chunk failed "
                f"({type(error).__name__}: {error})"
            ) from None
        if missing:
            raise _unusable(
                f"it lacks {' and '.join(missing)}, which duckielib.bags.seam relies on"
            )
        if not same:
            raise _unusable("its Writer.write writes other bytes than duckielib.bags.seam does")
        cls.writer_checked = True

    @classmethod
    def chunk_positions(cls, reader: Reader) -> List[int]:
        """Where each chunk of an open reader's bag starts in the file.

        Checks once that the positions point at chunk records.

        Raises:
            BagError: if the installed rosbags' reader has no ``chunk_infos`` with ``pos``.
        """
        infos = getattr(reader, "chunk_infos", None)
        if infos is None:
            raise _unusable(
                "it lacks Reader.chunk_infos, which duckielib.bags.seam relies on", "read"
            )
        try:
            positions = [info.pos for info in infos]
        except AttributeError:
            raise _unusable(
                "it lacks ChunkInfo.pos, which duckielib.bags.seam relies on", "read"
            ) from None
        if positions and not cls.reader_checked:
            with reader.path.open("rb") as file:
                file.seek(positions[0])
                length = int.from_bytes(file.read(4), "little")
                header = file.read(min(length, 4096))
            try:
                op = records.parse_fields(header, 0, len(header)).get(b"op")
            except (ValueError, struct.error):
                op = None
            if op != bytes([records.OP_CHUNK]):
                raise _unusable("its ChunkInfo.pos no longer points at a chunk", "read")
            cls.reader_checked = True
        return positions


def _unusable(why: str, action: str = "write") -> BagError:
    """The error for an installed rosbags the seam was not made for."""
    return BagError(
        f"duckielib cannot {action} bags with rosbags {rosbags_version()}: {why}; install "
        f"rosbags=={ROSBAGS_CHECKED[-1]} (duckielib was checked with rosbags "
        f"{', '.join(ROSBAGS_CHECKED)})."
    )


def _missing_from_writer(path: Path) -> List[str]:
    """The parts of rosbags' writer the seam relies on that the installed rosbags lacks."""
    writer = Writer(path)
    missing = [
        f"Writer.{name}"
        for name in ("chunks", "chunk_threshold", "bio")
        if not hasattr(writer, name)
    ]
    if not callable(getattr(Writer, "write_chunk", None)):
        missing.append("Writer.write_chunk")
    chunks = getattr(writer, "chunks", None)
    if chunks:
        missing += [
            f"WriteChunk.{name}"
            for name in ("data", "connections", "start", "end")
            if not hasattr(chunks[-1], name)
        ]
    return missing


def _probe(path: Path, seam: bool) -> Tuple[Any, ...]:
    """What an in-memory writer holds after three messages: its file, and its chunks' state."""
    writer = Writer(path)
    writer.bio = io.BytesIO()
    connection = writer.add_connection(
        "/probe",
        "std_msgs/msg/String",
        msgdef="string data\n",
        md5sum="992ce8a1687cec8c8bd883ec73ca41d1",
    )
    writer.chunk_threshold = writer.chunks[-1].data.tell() + 60  # the second message ends it
    items = [
        (connection, 2_000_000_001, b"\x01\x00\x00\x00a"),
        (connection, 7, b"\x00\x00\x00\x00"),
        (connection, 5, b"\x01\x00\x00\x00b"),
    ]
    if seam:
        chunks = RosbagsSeam(writer, path.name)
        chunks.register(connection)
        chunks.write_messages(items)
    else:
        for item in items:
            writer.write(*item)
    state = [(chunk.start, chunk.end, dict(chunk.connections)) for chunk in writer.chunks]
    return writer.bio.getvalue(), writer.chunks[-1].data.getvalue(), state


def rosbags_type(ros1: str) -> str:
    """``package/Type`` as rosbags names it: ``package/msg/Type``."""
    package, _, name = ros1.partition("/")
    return f"{package}/msg/{name}"


def ros1_type(msgtype: str) -> str:
    """The ROS 1 name ``package/Type`` of rosbags' ``package/msg/Type``."""
    return msgtype.replace("/msg/", "/")


def course_typestore() -> Any:
    """A rosbags typestore holding every message type of the course, from its ``.msg`` text."""
    store = get_typestore(Stores.EMPTY)
    for name in course_messages.message_types():
        cls = course_messages.get_message_class(name)
        store.register(get_types_from_msg(cls._full_text, rosbags_type(name)))
    return store
