"""rosbag's Python API: write and read bags from a node's code, as on a Duckiebot.

Use it exactly as ROS's ``rosbag``::

    import rosbag

    with rosbag.Bag("run.bag", "w") as bag:
        bag.write("/duckiebot/notes", String(data="start"))      # record time: now
    with rosbag.Bag("run.bag") as bag:
        for topic, msg, t in bag.read_messages(topics=["/duckiebot/notes"]):
            print(t.to_sec(), msg.data)

Bags are ROS 1 bags (format 2.0), written and read with :mod:`duckielib.bags`, so ``rosbag
info``, ``rosbag play`` and the robot's own tools read them. Messages read back are the
course's classes (or, for a type the course does not know, one made from the definition in
the bag); record times are ``rospy.Time``.

Differences from the real one, on purpose: ``write`` without ``t`` records the node's ROS time
(``rospy.Time.now()``, the simulated clock) rather than the wall clock, which it uses only
outside a node; bags are opened by file name, not as open file objects; chunks are written
uncompressed or with bz2 (``lz4`` is refused: ROS 1's tools reject the lz4 chunks written
here); a bag opened with ``"a"`` is written to a new file that replaces the old one when it
is closed; ``raw=True`` messages carry no file position (None); a connection header holds the
topic's ``topic``, ``type``, ``md5sum`` and ``message_definition``.

Laptop side; never deployed (the robot has the real rosbag).
"""

# Over 600 lines: it stands in for ROS's rosbag Python API, one module robot code imports by that
# name, whose `Bag` reads, writes and appends.

from __future__ import annotations

import collections
import errno
import io
import os
import shutil
import statistics
import sys
import tempfile
import time as wallclock
import weakref
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional, Tuple, Union

from duckielib.bags import records
from duckielib.bags.reader import Bag as CourseBag
from duckielib.bags.reader import TopicInfo
from duckielib.bags.repair import copy_scanned
from duckielib.bags.writer import COMPRESSIONS, BagWriter
from duckielib.errors import BagError, UnknownTypeError
from duckielib.messages import get_message_class
from duckielib.ros import rospy
from duckielib.ros.exceptions import ROSInitException
from duckielib.ros.names import canonical

__all__ = [
    "Bag",
    "BagMessage",
    "BagMessageWithConnectionHeader",
    "Compression",
    "ROSBagException",
    "ROSBagFormatException",
    "ROSBagUnindexedException",
]


class ROSBagException(BagError):
    """A bag cannot be opened, read or written (the message says why)."""


class ROSBagFormatException(ROSBagException):
    """A bag's contents are damaged."""


class ROSBagUnindexedException(ROSBagException):
    """A bag has no index: its recording was interrupted."""


class Compression:
    """How a bag's chunks are compressed: ``Bag(..., compression=Compression.BZ2)``."""

    NONE = "none"
    BZ2 = "bz2"
    LZ4 = "lz4"


#: What ``read_messages`` yields: ``topic, msg, t = item`` or ``item.message``...
BagMessage = collections.namedtuple("BagMessage", "topic message timestamp")
BagMessageWithConnectionHeader = collections.namedtuple(
    "BagMessageWithConnectionHeader", "topic message timestamp connection_header"
)
TopicTuple = collections.namedtuple(
    "TopicTuple", ["msg_type", "message_count", "connections", "frequency"]
)
TypesAndTopicsTuple = collections.namedtuple("TypesAndTopicsTuple", ["msg_types", "topics"])

PathLike = Union[str, "os.PathLike[str]"]
_MODES = ("r", "w", "a")


def _topic_list(topics: Any) -> Optional[List[str]]:
    """Topic names as a list, canonical; None for "every topic" (None or an empty list)."""
    if not topics:
        return None
    if isinstance(topics, str):
        topics = [topics]
    return [canonical(name) for name in topics]


def _record_time(t: Any) -> int:
    """A write's record time in nanoseconds; None means now, as the node sees it."""
    if t is None:
        try:
            return rospy.Time.now().to_nsec()
        except ROSInitException:  # not in a node: the wall clock, as the real rosbag
            return wallclock.time_ns()
    to_nsec = getattr(t, "to_nsec", None)
    if not callable(to_nsec):
        raise TypeError(
            f"rosbag.Bag.write() takes the record time t as a rospy.Time "
            f"(for example rospy.Time.now() or msg.header.stamp), not {t!r}."
        )
    value = to_nsec()
    if value < 0:
        raise ValueError(f"A bag cannot record a time before 0, such as {t!r}.")
    return int(value)


def _serialize(msg: Any) -> bytes:
    to_bytes = getattr(msg, "to_bytes", None)
    if callable(to_bytes):
        return to_bytes()
    buffer = io.BytesIO()
    msg.serialize(buffer)
    return buffer.getvalue()


def _connection_header(info: TopicInfo) -> Dict[str, str]:
    return {
        "topic": info.name,
        "type": info.type,
        "md5sum": info.md5sum,
        "message_definition": info.message_definition,
    }


def _python_type(info: TopicInfo) -> Any:
    """The class of a topic's messages for ``raw=True``: the course's, or one naming the type."""
    try:
        cls = get_message_class(info.type)
    except UnknownTypeError:
        cls = None
    if cls is not None and cls._md5sum == info.md5sum:
        return cls
    name = info.type.rpartition("/")[2]
    attributes = {"_type": info.type, "_md5sum": info.md5sum, "_full_text": info.message_definition}
    return type(name, (), attributes)


def _on_topic(topic: str) -> Callable[[records.Connection], bool]:
    """Whether a connection is one of ``topic``'s."""
    return lambda connection: connection.topic == topic


def _is_indexed(path: Path) -> bool:
    """Whether a bag's header says where its index is (0 while it is being written)."""
    with path.open("rb") as file:
        if file.read(len(records.MAGIC)) != records.MAGIC:
            return True  # not a bag: opening it says so
        length = int.from_bytes(file.read(4), "little")
        header = file.read(min(length, 4096))
    try:
        position = records.parse_fields(header, 0, len(header)).get(b"index_pos", b"")
    except ValueError:
        return True
    return int.from_bytes(position, "little") != 0


class Bag:
    """A ROS 1 bag file, for reading (``"r"``), writing (``"w"``) or appending (``"a"``).

    Use it as a context manager or call :meth:`close`: closing a bag being written writes its
    index, which every reader needs.

    Args:
        f: the bag's file name.
        mode: ``"r"`` to read, ``"w"`` to write a new bag (an existing file is replaced),
            ``"a"`` to add messages to a bag (created if missing).
        compression: ``Compression.NONE`` (``"none"``) or ``Compression.BZ2`` (``"bz2"``).
        chunk_threshold: accepted as in rosbag; chunks here hold about 1 MB.
        allow_unindexed: read a bag whose recording was interrupted (no index) anyway.
        options: a dict that may give ``compression`` and ``chunk_threshold``.
        skip_index: accepted as in rosbag.

    Raises:
        ValueError: for an unknown mode or compression.
        FileNotFoundError: reading a file that does not exist.
        ROSBagException: if the file is not a bag or cannot be written;
            ROSBagUnindexedException if it has no index.
    """

    def __init__(
        self,
        f: PathLike,
        mode: str = "r",
        compression: str = Compression.NONE,
        chunk_threshold: int = 768 * 1024,
        allow_unindexed: bool = False,
        options: Optional[Dict[str, Any]] = None,
        skip_index: bool = False,
    ) -> None:
        if options is not None:
            if not isinstance(options, dict):
                raise ValueError("rosbag.Bag's options must be a dict.")
            compression = options.get("compression", compression)
            chunk_threshold = options.get("chunk_threshold", chunk_threshold)
        if not isinstance(f, (str, os.PathLike)) or not str(f):
            raise ValueError(
                f"rosbag.Bag opens a bag by its file name, such as 'run.bag', not {f!r}."
            )
        if mode not in _MODES:
            raise ValueError(
                f"rosbag.Bag's mode is 'r' (read), 'w' (write) or 'a' (append), not {mode!r}."
            )
        if compression not in COMPRESSIONS:
            why = (
                ": ROS 1's tools reject the lz4 chunks written here" if compression == "lz4" else ""
            )
            raise ValueError(
                f"rosbag.Bag compresses with 'none' or 'bz2', not {compression!r}{why}."
            )
        if chunk_threshold < 0:
            raise ValueError("rosbag.Bag's chunk_threshold cannot be negative.")
        self._filename = f
        self._path = Path(f)
        self._mode = mode
        self._compression = compression
        self._chunk_threshold = chunk_threshold
        self._closed = False
        self._bag: Optional[CourseBag] = None  # what reads see, once made
        self._writer: Optional[BagWriter] = None
        self._writing = self._path  # the file being written
        self._snapshots: Optional[Path] = None
        self._cleanup: Optional[weakref.finalize] = None
        self._snapshot_count = 0
        try:
            if mode == "r":
                self._open_read(allow_unindexed)
            else:
                self._open_write()
        except ROSBagException:
            raise
        except BagError as error:
            raise ROSBagException(str(error)) from None

    def _open_read(self, allow_unindexed: bool) -> None:
        if not self._path.exists():
            raise FileNotFoundError(errno.ENOENT, "There is no bag file", str(self._path))
        if self._path.is_file() and not _is_indexed(self._path):
            if not allow_unindexed:
                raise ROSBagUnindexedException(
                    f"{self._path} has no index: its recording was interrupted. Open it with "
                    f"allow_unindexed=True, or repair it: duckie bag repair {self._path} "
                    "FIXED.bag"
                )
            self._bag = self._snapshot(self._path)
            return
        self._bag = CourseBag(self._path)

    def _open_write(self) -> None:
        existing = self._mode == "a" and self._path.exists()
        if existing:
            if not _is_indexed(self._path):
                raise ROSBagUnindexedException(
                    f"{self._path} has no index, so messages cannot be added to it; repair it "
                    f"first: duckie bag repair {self._path} FIXED.bag"
                )
            CourseBag(self._path)  # it must be a readable bag
            self._writing = self._path.with_name(f".{self._path.name}.appending")
            self._writing.unlink(missing_ok=True)
        elif self._path.is_file():
            self._path.unlink()
        self._writer = BagWriter(self._writing, self._compression)
        if existing:
            copy_scanned(records.scan(self._path), self._writer)

    def _snapshot(self, path: Path) -> CourseBag:
        """A readable copy of a bag with no index (being written, or interrupted)."""
        if self._snapshots is None:
            self._snapshots = Path(tempfile.mkdtemp(prefix="rosbag-"))
            self._cleanup = weakref.finalize(self, shutil.rmtree, str(self._snapshots), True)
        self._snapshot_count += 1
        copy = self._snapshots / f"snapshot-{self._snapshot_count}.bag"
        with BagWriter(copy) as writer:
            copy_scanned(records.scan(path), writer)
        return CourseBag(copy)

    def _readable(self) -> CourseBag:
        """The bag as reads see it, with everything written so far."""
        if self._bag is None:
            try:
                if self._writer is None or self._writer.closed:
                    self._bag = CourseBag(self._path)
                else:
                    self._writer.flush()
                    self._bag = self._snapshot(self._writing)
            except BagError as error:
                raise ROSBagException(str(error)) from None
        return self._bag

    def _check_open(self, action: str) -> None:
        if self._closed:
            raise ValueError(
                f"I/O operation on closed bag: {self._path.name} is closed, so it cannot "
                f"{action}; open it again with rosbag.Bag()."
            )

    # The file.

    @property
    def filename(self) -> PathLike:
        """The bag's file name, as given."""
        return self._filename

    @property
    def mode(self) -> str:
        """``"r"``, ``"w"`` or ``"a"``."""
        return self._mode

    @property
    def compression(self) -> str:
        """The compression of the chunks written: ``"none"`` or ``"bz2"``."""
        return self._compression

    @property
    def chunk_threshold(self) -> int:
        """The chunk threshold given (chunks here hold about 1 MB)."""
        return self._chunk_threshold

    @property
    def version(self) -> int:
        """The bag format's version: 200 (2.0)."""
        return 200

    @property
    def size(self) -> int:
        """The file's size in bytes.

        Raises:
            ValueError: if the bag is closed.
        """
        self._check_open("tell its size")
        return self._writing.stat().st_size

    def __enter__(self) -> Bag:
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def __iter__(self) -> Iterator[Any]:
        return self.read_messages()

    def __str__(self) -> str:
        return self._readable().info()

    def __repr__(self) -> str:
        state = "closed" if self._closed else f"mode {self._mode!r}"
        return f"<rosbag.Bag {self._path.name}, {state}>"

    def flush(self) -> None:
        """Write the messages buffered so far to the file.

        Raises:
            ValueError: if the bag is closed.
        """
        self._check_open("be flushed")
        if self._writer is not None:
            self._writer.flush()

    def close(self) -> None:
        """Close the bag; a bag being written gets its index. Closing twice does nothing."""
        if self._closed:
            return
        self._closed = True
        if self._writer is not None:
            self._writer.close()
            if self._writing != self._path:
                self._writing.replace(self._path)
                self._writing = self._path
            self._bag = None  # reads now open the finished file
            if self._cleanup is not None:
                self._cleanup()

    # Writing.

    def write(
        self,
        topic: str,
        msg: Any,
        t: Any = None,
        raw: bool = False,
        connection_header: Optional[Dict[str, str]] = None,
    ) -> None:
        """Write a message on a topic.

        Args:
            topic: the topic's name, for example ``"/duckiebot/notes"``.
            msg: the message; with ``raw=True``, a tuple ``(type, serialized bytes, md5sum,
                python class)`` (or with the position before the class, as ``read_messages``
                gives it).
            t: the record time, a ``rospy.Time``; default: the node's current ROS time.
            raw: whether ``msg`` is serialized bytes.
            connection_header: the topic's connection header; its ``callerid`` and
                ``latching`` are kept.

        Raises:
            ValueError: if the bag is closed or not open for writing, or the topic is empty.
            TypeError: if ``msg`` is not a message or ``t`` not a time.
            ROSBagException: if a raw message's class cannot be found.
        """
        self._check_open("be written to")
        if self._writer is None:
            raise ValueError(
                f"{self._path.name} is open for reading; open it with rosbag.Bag(name, 'w') "
                "or 'a' to write."
            )
        if not topic or not isinstance(topic, str):
            raise ValueError(f"rosbag.Bag.write() needs a topic name, not {topic!r}.")
        if raw:
            message_type, data, md5sum, definition = self._unpack_raw(msg)
        else:
            if not all(hasattr(msg, name) for name in ("_type", "_md5sum", "_full_text")):
                raise TypeError(
                    f"rosbag.Bag.write() takes a ROS message (such as String(data='hi')), "
                    f"not {msg!r}."
                )
            message_type, md5sum, definition = msg._type, msg._md5sum, msg._full_text
            data = _serialize(msg)
        header = connection_header or {}
        time_ns = _record_time(t)
        try:
            self._writer.write_raw(
                topic,
                message_type,
                md5sum,
                definition,
                time_ns,
                data,
                header.get("callerid"),
                header.get("latching"),
            )
        except BagError as error:
            raise ROSBagException(str(error)) from None
        self._bag = None

    @staticmethod
    def _unpack_raw(msg: Any) -> Tuple[str, bytes, str, str]:
        if not isinstance(msg, tuple) or len(msg) not in (4, 5):
            raise ValueError(
                "With raw=True, rosbag.Bag.write() takes a tuple (type, bytes, md5sum, class) "
                "or (type, bytes, md5sum, position, class)."
            )
        message_type, data, md5sum, pytype = msg[0], msg[1], msg[2], msg[-1]
        if pytype is None:
            try:
                pytype = get_message_class(message_type)
            except UnknownTypeError:
                raise ROSBagException(
                    f"The class of {message_type} cannot be found, so its definition cannot be "
                    "written: pass the message class as the tuple's last item."
                ) from None
        return message_type, bytes(data), md5sum, pytype._full_text

    # Reading.

    def read_messages(
        self,
        topics: Any = None,
        start_time: Any = None,
        end_time: Any = None,
        connection_filter: Optional[Callable[..., bool]] = None,
        raw: bool = False,
        return_connection_header: bool = False,
    ) -> Iterator[Any]:
        """The bag's messages in record-time order, as ``(topic, msg, t)`` named tuples.

        Args:
            topics: a topic or a list of topics (default, or an empty list: every topic);
                topics the bag does not have are ignored.
            start_time: the first record time to give (a ``rospy.Time``; included).
            end_time: the last record time to give (included).
            connection_filter: ``f(topic, type, md5sum, message_definition, header)`` saying
                whether to read a topic.
            raw: give ``(type, serialized bytes, md5sum, None, class)`` instead of messages.
            return_connection_header: add the topic's connection header as a fourth item.

        Returns:
            A generator of ``BagMessage(topic, message, timestamp)`` (``timestamp`` a
            ``rospy.Time``), or of ``BagMessageWithConnectionHeader``.

        Raises:
            ValueError: if the bag is closed.
        """
        self._check_open("be read")
        bag = self._readable()
        wanted = _topic_list(topics)
        selected = []
        for name, info in bag.topics.items():
            if wanted is not None and name not in wanted:
                continue
            header = _connection_header(info)
            if connection_filter is not None and not connection_filter(
                name, info.type, info.md5sum, info.message_definition, header
            ):
                continue
            selected.append(name)
        first = start_time.to_nsec() if start_time else None
        last = end_time.to_nsec() if end_time else None
        return self._messages(bag, selected, first, last, raw, return_connection_header)

    @staticmethod
    def _messages(
        bag: CourseBag,
        topics: List[str],
        first: Optional[int],
        last: Optional[int],
        raw: bool,
        with_header: bool,
    ) -> Iterator[Any]:
        items: Iterator[Tuple[str, int, Any]]
        if raw:
            classes = {name: _python_type(bag.topics[name]) for name in topics}
            items = (
                (topic, time_ns, (cls._type, data, cls._md5sum, None, cls))
                for topic, time_ns, data in bag.raw_messages(topics)
                for cls in (classes[topic],)
            )
        else:
            items = ((item.topic, item.time_ns, item.message) for item in bag.messages(topics))
        for topic, time_ns, message in items:
            if first is not None and time_ns < first:
                continue
            if last is not None and time_ns > last:
                return
            stamp = rospy.Time(0, time_ns)
            if with_header:
                header = _connection_header(bag.topics[topic])
                yield BagMessageWithConnectionHeader(topic, message, stamp, header)
            else:
                yield BagMessage(topic, message, stamp)

    def get_message_count(self, topic_filters: Any = None) -> int:
        """How many messages the bag holds, on every topic or on a topic or list of topics."""
        bag = self._readable()
        wanted = _topic_list(topic_filters)
        if topic_filters is None:
            return bag.message_count
        return sum(bag.topics[name].count for name in set(wanted or ()) if name in bag.topics)

    def get_start_time(self) -> float:
        """The first record time, in seconds.

        Raises:
            ROSBagException: if the bag holds no messages.
        """
        return self._time("start") / 1e9

    def get_end_time(self) -> float:
        """The last record time, in seconds.

        Raises:
            ROSBagException: if the bag holds no messages.
        """
        return self._time("end") / 1e9

    def _time(self, which: str) -> int:
        bag = self._readable()
        if not bag.message_count:
            raise ROSBagException(
                f"{self._path.name} holds no messages, so it has no {which} time."
            )
        return bag.start_ns if which == "start" else bag.end_ns

    def get_type_and_topic_info(self, topic_filters: Any = None) -> Any:
        """The bag's types and topics, as ``rosbag info`` lists them.

        Args:
            topic_filters: a topic or a list of topics to describe (default: every topic).

        Returns:
            ``TypesAndTopicsTuple(msg_types, topics)``: ``msg_types`` maps each type of the bag
            to its md5 sum; ``topics`` maps each topic to ``TopicTuple(msg_type,
            message_count, connections, frequency)``, the frequency (Hz) from the median
            interval between record times, or None for fewer than two messages.
        """
        bag = self._readable()
        types = dict(sorted({(info.type, info.md5sum) for info in bag.topics.values()}))
        wanted = _topic_list(topic_filters) if topic_filters is not None else list(bag.topics)
        topics = {}
        for name in sorted(set(wanted or ())):
            info = bag.topics.get(name)
            if info is None:
                continue
            scan = records.scan(bag.path, _on_topic(name))
            connections = sum(1 for c in scan.connections.values() if c.topic == name)
            times = sorted(time_ns for _, time_ns, _ in scan.messages)
            frequency = None
            if len(times) > 1:
                period = statistics.median([b - a for a, b in zip(times, times[1:])])
                frequency = 1e9 / period if period > 0 else None
            topics[name] = TopicTuple(info.type, info.count, connections, frequency)
        return TypesAndTopicsTuple(msg_types=types, topics=topics)


#: ``rosbag.bag``: the real package's module for the same names.
bag = sys.modules[__name__]
