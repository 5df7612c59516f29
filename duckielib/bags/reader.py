"""Opening and reading ROS 1 bags (and MCAP files and ROS 2 bags, made into one).

:class:`Bag` opens a bag for reading. rosbags checks it and reads its index (topics, types,
counts, times). Messages are decoded with duckielib's classes when the bag's type has the same
md5 sum, and otherwise with a rosbags type built from the definition embedded in the bag, so a
bag recorded on any Duckiebot reads without registering anything. Messages are read in file
order (:mod:`duckielib.bags.records`), every record checked and the count of each topic
compared with the index: a damaged bag raises a sentence saying where, never gives part of
its messages as if they were all.

Times at this edge are integer nanoseconds (``time_ns``); a bag's record time is when the
recorder received the message, which is not the message's header stamp.
"""

from __future__ import annotations

import os
import struct
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, Iterator, List, Optional, Tuple, Union

from rosbags.rosbag1 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from duckielib import messages as course_messages
from duckielib.bags import records
from duckielib.bags.seam import RosbagsSeam, ros1_type, rosbags_type
from duckielib.errors import BagError, UnknownTypeError
from duckielib.rostime import NS_PER_S

__all__ = ["Bag", "BagMessage", "PathLike", "TopicInfo", "ros1_copy"]

PathLike = Union[str, "os.PathLike[str]"]


@dataclass(frozen=True)
class TopicInfo:
    """One topic of a bag.

    Attributes:
        name: the topic's name.
        type: its message type, ``package/Type``.
        count: how many messages the bag holds on it.
        md5sum: the type's md5 sum.
        message_definition: the type's full definition, as recorded.
    """

    name: str
    type: str
    count: int
    md5sum: str
    message_definition: str


@dataclass(frozen=True)
class BagMessage:
    """A message read from a bag.

    Attributes:
        topic: the topic it was recorded on.
        time_ns: its record time, in integer nanoseconds.
        message: the message: a duckielib message, or a rosbags one for other types.
    """

    topic: str
    time_ns: int
    message: Any

    @property
    def time(self) -> float:
        """The record time, in seconds."""
        return self.time_ns / NS_PER_S


def _repair_advice(path: Path) -> str:
    return f"Recover its messages into a new bag with: duckie bag repair {path} FIXED.bag"


def _unindexed_advice(path: Path) -> str:
    return (
        f"{path} was not closed properly (its recording was interrupted), so it has no index; "
        f"recover its messages with: duckie bag repair {path} FIXED.bag"
    )


def _unreadable(path: Path, layout: records.ScanResult, error: Exception) -> str:
    """Why rosbags cannot open a bag, from what a quick look at its layout found."""
    if not layout.header_ok:
        return (
            f"{path} cannot be read: its bag header (the first record, in the file's first "
            f"4 KB) is damaged, so where its index is cannot be known. {_repair_advice(path)}."
        )
    if layout.index_pos == 0:
        return _unindexed_advice(path)
    if layout.damages:
        return (
            f"{path} cannot be read through its index: the file is damaged "
            f"({layout.damages[0]}). {_repair_advice(path)}."
        )
    if layout.cut is not None or layout.index_pos >= layout.size:
        return (
            f"{path} cannot be read: the file was cut short, so its index is missing or "
            f"incomplete. {_repair_advice(path)}."
        )
    reason = str(error).rstrip(".") or type(error).__name__
    return (
        f"{path} cannot be read as a ROS 1 bag: {reason}. If the file was damaged, recover "
        f"its messages into a new bag with: duckie bag repair {path} FIXED.bag"
    )


@dataclass(frozen=True)
class _Chunk:
    """Where a chunk is in the file, and how many messages the index says it holds."""

    number: int
    start: int
    end: int
    messages: int


_FORMATS = {"mcap": "an MCAP file", "ros2": "a ROS 2 bag folder"}
#: How an MCAP file or a ROS 2 bag becomes a ROS 1 bag: ``to_ros1(source, kind, out)``, set
#: by :mod:`duckielib.bags.convert` (which imports this module) when the package is imported.
TO_ROS1: List[Callable[[Path, str, Path], Any]] = []


#: The version of how ROS 1 copies are made; a change here makes every copy anew.
_COPY_VERSION = 2


def ros1_copy(path: Path, kind: str) -> Path:
    """A ROS 1 bag of an MCAP file or a ROS 2 bag folder, made once and kept while unchanged.

    The copy lives in the system's temporary folder, named after the source's path, size and
    time of change; a source that changes is copied anew.

    Raises:
        BagError: if the source cannot be read or is damaged.
    """
    import hashlib
    import tempfile

    files = sorted(path.rglob("*")) if path.is_dir() else [path]
    stats = [(each.resolve(), each.stat()) for each in files if each.is_file()]
    stamp = "|".join(f"{name}:{found.st_size}:{found.st_mtime_ns}" for name, found in stats)
    stamp += f"|copy {_COPY_VERSION}"  # a copy made by an older reading is not trusted
    folder = Path(tempfile.gettempdir()) / "duckielib-bags"
    folder.mkdir(exist_ok=True)
    copy = folder / f"{path.stem}-{hashlib.sha256(stamp.encode()).hexdigest()[:16]}.bag"
    if not copy.is_file():
        partial = copy.with_name(f"{copy.stem}.{os.getpid()}.partial.bag")
        try:
            TO_ROS1[0](path, kind, partial)
            partial.replace(copy)
        finally:
            partial.unlink(missing_ok=True)
    return copy


class Bag:
    """A ROS 1 bag, opened for reading.

    Opening reads the bag's index (with rosbags) and checks, quickly, that the index lists every
    chunk of the file. Reading messages checks every record it reads, and that as many messages
    were read as the index lists: a bag damaged in the middle raises a :class:`BagError` saying
    where, rather than giving part of its messages (``duckie bag repair`` recovers what can be
    read). :meth:`check` reads the whole bag this way; :meth:`info` reports what it finds.

    Args:
        path: the bag file.

    Attributes:
        path: the bag file.
        topics: every topic, by name (sorted), as :class:`TopicInfo`.
        start_ns, end_ns: the first and last record times, in nanoseconds (0 for an empty bag).
        message_count: how many messages the bag holds, as its index lists them.
        chunk_count: how many chunks the index lists.

    Raises:
        BagError: if the file is missing or is not a ROS 1 bag, if it was never closed (no
            index), if its header or index is damaged, or if its index leaves out chunks of
            the file. The message says what to do (usually ``duckie bag repair``).
    """

    def __init__(self, path: PathLike) -> None:
        self.path = Path(path)
        self._checked: Optional[Tuple[str]] = None  # what check() found, once it has run
        #: The format it was in: "ros1", "mcap" (an MCAP file) or "ros2" (a ROS 2 bag folder).
        found = records.bag_format(self.path)
        if found is None:
            raise BagError(
                f"{self.path} is not a ROS 1 bag: it does not start with '#ROSBAG V2.0' "
                "(nor is it an MCAP file or a ROS 2 bag folder)."
            )
        self.format: str = found
        #: The ROS 1 bag that is read: the file itself, or the MCAP file or ROS 2 bag made
        #: into one once (see :func:`ros1_copy`).
        self.file = self.path if self.format == "ros1" else ros1_copy(self.path, self.format)
        layout = records.scan(self.file, read_chunks=False)
        try:
            reader = Reader(self.file)
            reader.open()
        except Exception as error:  # rosbags raises more than ReaderError on damaged bytes
            raise BagError(_unreadable(self.path, layout, error)) from None
        try:
            self._chunk_positions = RosbagsSeam.chunk_positions(reader)
            self._check_layout(layout)
            topics = {}
            self._connections: Dict[int, TopicInfo] = {}
            self._topic_connections: Dict[str, List[int]] = {}
            for name in sorted(reader.topics):
                info = reader.topics[name]
                connection = info.connections[0]
                topics[name] = TopicInfo(
                    name=name,
                    type=ros1_type(info.msgtype or connection.msgtype),
                    count=info.msgcount,
                    md5sum=connection.digest,
                    message_definition=connection.msgdef.data,
                )
                self._topic_connections[name] = [item.id for item in info.connections]
                for item in info.connections:
                    self._connections[item.id] = TopicInfo(
                        name=name,
                        type=ros1_type(item.msgtype),
                        count=layout.index_counts.get(item.id, 0),
                        md5sum=item.digest,
                        message_definition=item.msgdef.data,
                    )
            self.topics: Dict[str, TopicInfo] = topics
            self.message_count: int = reader.message_count
            self.start_ns: int = reader.start_time if self.message_count else 0
            # rosbags gives the end as the last record time + 1 ns.
            self.end_ns: int = reader.end_time - 1 if self.message_count else 0
            self.chunk_count = len(self._chunk_positions)
        finally:
            reader.close()
        self._chunks = [
            _Chunk(number, start, end, layout.chunk_messages.get(start, 0))
            for number, (start, end) in enumerate(layout.chunk_spans, start=1)
        ]
        self._layout_damage = layout.damages[0] if layout.damages else None
        self._decoders: Dict[Tuple[str, str], Any] = {}

    def _check_layout(self, layout: records.ScanResult) -> None:
        """Raise if the index leaves out chunks that the file holds."""
        listed = set(self._chunk_positions)
        unlisted = [start for start, _ in layout.chunk_spans if start not in listed]
        if unlisted:
            raise BagError(
                f"{self.path} cannot be read through its index: the index lists "
                f"{len(listed)} chunks, but the file holds {len(layout.chunk_spans)} (the first "
                f"one left out starts at byte {unlisted[0]}), so the bag was not closed "
                f"properly or its index is damaged. {_repair_advice(self.path)}."
            )

    def __repr__(self) -> str:
        return f"<Bag {self.path.name}: {self.message_count} messages on {len(self.topics)} topics>"

    @property
    def compression(self) -> str:
        """``none``, ``bz2`` or ``lz4``: how the chunks are compressed, read from their headers."""
        kinds = set()
        with self.file.open("rb") as file:
            for position in self._chunk_positions:
                file.seek(position)
                length = int.from_bytes(file.read(4), "little")
                try:
                    fields = records.parse_fields(file.read(length), 0, length)
                except (ValueError, struct.error):
                    kinds.add("(damaged)")
                    continue
                kinds.add(fields.get(b"compression", b"none").decode("ascii", "replace"))
        return "/".join(sorted(kinds)) if kinds else "none"

    def check(self) -> Optional[str]:
        """Read every record of the bag to check it: what is wrong, or None if nothing is.

        This reads the whole file (about as long as reading every message, without decoding
        them). It finds records that cannot be read, counts that differ from the index, and
        index records that do not list where the messages are; a byte changed inside a
        message's data cannot be found (bags carry no checksums).

        Returns:
            None for a sound bag, else sentences saying where the damage is, how many
            messages it affects, and how to recover them.
        """
        if self._checked is None:
            scan = records.scan(self.file, lambda connection: False, check_index=True)
            counted = self._counted(scan, list(self.topics))
            if not scan.damages and not any(read != listed for _, read, listed in counted):
                self._checked = ("",)
            else:
                sentence = f"{self._damaged_sentence(scan, counted)} {_repair_advice(self.path)}."
                self._checked = (sentence,)
        return self._checked[0] or None

    def info(self, check: bool = True) -> str:
        """A summary like ``rosbag info``: path, duration, times, size, types and topics.

        Args:
            check: also read every record (see :meth:`check`) and say what is damaged.
        """
        files = sorted(self.path.rglob("*")) if self.path.is_dir() else [self.path]
        size = sum(each.stat().st_size for each in files if each.is_file())
        problem = self.check() if check else None
        lines = [
            f"path:        {self.path}",
            "version:     2.0"
            if self.format == "ros1"
            else f"format:      {_FORMATS[self.format]}, read as a ROS 1 bag",
            f"duration:    {self.duration:.1f}s",
            f"start:       {self.start_ns / NS_PER_S:.2f} s",
            f"end:         {self.end_ns / NS_PER_S:.2f} s",
            f"size:        {_human_size(size)}",
            f"messages:    {self.message_count}",
            f"compression: {self.compression} [{self.chunk_count} chunks]",
        ]
        types = sorted({(info.type, info.md5sum) for info in self.topics.values()})
        for index, (kind, md5sum) in enumerate(types):
            lines.append(f"{'types:' if index == 0 else '':<13}{kind} [{md5sum}]")
        if not types:
            lines.append("types:       (none)")
        width = max((len(name) for name in self.topics), default=0)
        for index, info in enumerate(self.topics.values()):
            label = "topics:" if index == 0 else ""
            lines.append(f"{label:<13}{info.name:<{width}}  {info.count:>7} msgs    : {info.type}")
        if not self.topics:
            empty = "(none: the bag is empty)" if problem is None else "(none in its index)"
            lines.append(f"topics:      {empty}")
        if problem is not None:
            wrapped = textwrap.wrap(problem, 87)
            lines += [
                f"{'damage:' if index == 0 else '':<13}{line}" for index, line in enumerate(wrapped)
            ]
        return "\n".join(lines)

    @property
    def duration(self) -> float:
        """Seconds from the first to the last message."""
        return (self.end_ns - self.start_ns) / NS_PER_S

    def topic(self, name: str) -> TopicInfo:
        """The topic ``name``.

        Raises:
            BagError: if the bag has no such topic (the message lists those it has).
        """
        info = self.topics.get(name)
        if info is None:
            known = ", ".join(self.topics) or "none, the bag is empty"
            raise BagError(f"{self.path.name} has no topic {name}; its topics are: {known}.")
        return info

    def connections_of(self, name: str) -> List[TopicInfo]:
        """The topic ``name`` as each of its connections (publishers) recorded it.

        A topic recorded from two publishers has two connections, which may even carry two
        definitions of its type; ``count`` is then each connection's share of the messages.

        Raises:
            BagError: if the bag has no such topic.
        """
        self.topic(name)
        return [self._connections[cid] for cid in self._topic_connections[name]]

    def topics_of_type(self, message_type: str) -> List[str]:
        """The names of the topics carrying ``message_type`` (``package/Type``)."""
        return [name for name, info in self.topics.items() if info.type == message_type]

    def raw_messages(self, topics: Iterable[str]) -> List[Tuple[str, int, bytes]]:
        """``(topic, record time in ns, serialized bytes)`` of the topics' messages, by time.

        Raises:
            BagError: if a topic is not in the bag, or if the bag is damaged: a record
                cannot be read, or fewer (or more) of the topics' messages were found than
                the index lists. The message says where, how many messages are affected, and
                how to recover them; no message is returned.
        """
        return [(self._connections[cid].name, t, data) for cid, t, data in self._raw(topics)]

    def _raw(self, topics: Iterable[str]) -> List[Tuple[int, int, bytes]]:
        """``(connection id, record time in ns, bytes)`` of the topics' messages, by time."""
        names = [self.topic(name).name for name in topics]
        wanted = {cid for name in names for cid in self._topic_connections[name]}
        scan = records.scan(self.file, lambda connection: connection.id in wanted)
        counted = self._counted(scan, names)
        if scan.damages or any(read != listed for _, read, listed in counted):
            raise BagError(
                f"{self._damaged_sentence(scan, counted)} Nothing is returned rather than a "
                f"part. {_repair_advice(self.path)}, and read FIXED.bag instead."
            )
        found = scan.messages
        found.sort(key=lambda item: item[1])
        return found

    def _counted(self, scan: records.ScanResult, names: List[str]) -> List[Tuple[str, int, int]]:
        """``(topic, messages read, messages the index lists)`` of each topic."""
        counted = []
        for name in names:
            ids = self._topic_connections[name]
            read = sum(scan.counts.get(cid, 0) for cid in ids)
            listed = sum(self._connections[cid].count for cid in ids)
            counted.append((name, read, listed))
        return counted

    def _damaged_sentence(
        self, scan: records.ScanResult, counted: List[Tuple[str, int, int]]
    ) -> str:
        """Where a bag is damaged, and how many messages of which topics it costs."""
        damage = scan.damages[0] if scan.damages else self._layout_damage
        if damage is not None:
            where = f"is damaged {self._where(damage)}"
            if len(scan.damages) > 1:
                where += f" ({len(scan.damages)} damaged stretches in all)"
        elif scan.cut is not None:
            where = f"was cut short ({scan.cut})"
        else:
            where = "has an index that does not match its records"
        short = [item for item in counted if item[1] != item[2]] or counted
        read = sum(item[1] for item in short)
        listed = sum(item[2] for item in short)
        if len(short) == 1:
            topics = short[0][0]
        elif read == listed:
            topics = f"its {len(short)} topics"
        else:
            topics = ", ".join(f"{name}: {got} of {count}" for name, got, count in short)
            topics = f"its topics ({topics})"
        if read < listed:
            counts = (
                f"only {read} of the {listed} messages its index lists on {topics} could be "
                f"read; {listed - read} {'is' if listed - read == 1 else 'are'} lost or may be "
                "damaged"
            )
        elif read > listed:
            counts = (
                f"{read} messages were found on {topics}, more than the {listed} its index lists"
            )
        elif damage is not None and self._chunk_of(damage) is None:
            counts = (
                f"the {listed} messages its index lists on {topics} were all found, but "
                "readers that go by the index (ROS's rosbag, rosbags) cannot read them"
            )
        else:
            counts = (
                f"the {listed} messages its index lists on {topics} were found, but a message "
                "next to damage may be damaged too"
            )
        return f"{self.path.name} {where}: {counts}."

    def _chunk_of(self, damage: records.Damage) -> Optional[_Chunk]:
        """The chunk a damage is in, or None if it lies between chunks or after them."""
        for item in self._chunks:
            if item.start == damage.chunk or item.start <= damage.start < item.end:
                return item
        return None

    def _where(self, damage: records.Damage) -> str:
        """Where a damage is: its byte offset, its chunk, and what is wrong there."""
        chunk = self._chunk_of(damage)
        if chunk is not None:
            place = (
                f"in chunk {chunk.number} of {len(self._chunks)} (bytes {chunk.start} to "
                f"{chunk.end}, which holds {chunk.messages} messages)"
            )
        elif not self._chunks or damage.start >= self._chunks[-1].end:
            place = "after its chunks, among its index records"
        elif damage.start < self._chunks[0].start:
            place = "before its first chunk"
        else:
            place = "between two of its chunks, among index records"
        return f"{place}: {damage}"

    def messages(self, topics: Optional[Iterable[str]] = None) -> Iterator[BagMessage]:
        """The messages of ``topics`` (default: all), decoded, in record-time order.

        Each message is decoded as its own connection recorded it.

        Raises:
            BagError: if a topic is not in the bag, the bag is damaged (see
                :meth:`raw_messages`), or a message cannot be decoded.
        """
        names = list(self.topics) if topics is None else list(topics)
        for cid, time_ns, data in self._raw(names):
            info = self._connections[cid]
            yield BagMessage(info.name, time_ns, self._decode(info, data))

    def read(self, topic: str) -> List[BagMessage]:
        """Every message of one topic, decoded, in record-time order.

        Raises:
            BagError: as :meth:`messages` does.
        """
        return list(self.messages([topic]))

    def _decode(self, info: TopicInfo, data: bytes) -> Any:
        key = (info.type, info.md5sum)
        decoder = self._decoders.get(key)
        if decoder is None:
            decoder = self._decoders[key] = _decoder(info)
        try:
            return decoder(data)
        except Exception as error:
            raise BagError(
                f"A message on {info.name} ({info.type}) in {self.path.name} cannot be decoded: "
                f"{error}."
            ) from None


def _human_size(size: int) -> str:
    value = float(size)
    for unit in ("B", "KB", "MB", "GB"):
        if value < 1024 or unit == "GB":
            return f"{value:.1f} {unit}" if unit != "B" else f"{size} B"
        value /= 1024
    return f"{size} B"  # pragma: no cover


def _decoder(info: TopicInfo) -> Any:
    """A function decoding a topic's bytes: duckielib's class if it is the same type."""
    try:
        cls = course_messages.get_message_class(info.type)
    except UnknownTypeError:
        cls = None
    if cls is not None and cls._md5sum == info.md5sum:
        return cls.from_bytes
    store = get_typestore(Stores.EMPTY)
    msgtype = rosbags_type(info.type)
    try:
        store.register(get_types_from_msg(info.message_definition, msgtype))
    except Exception as error:
        raise BagError(
            f"The definition of {info.type} recorded for {info.name} cannot be read: {error}."
        ) from None
    return lambda data: store.deserialize_ros1(data, msgtype)
