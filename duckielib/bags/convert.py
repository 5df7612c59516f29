"""Bags in today's formats: a ROS 1 bag to MCAP or a ROS 2 bag, and back.

PlotJuggler 4, Foxglove and Lichtblick open MCAP files; rosbag2 writes MCAP (or sqlite3)
folders. :func:`convert_bag` writes a bag in the format its target's name says:

- ``run.mcap``: one MCAP file. With ``schema="ros1"`` (the default) each message keeps its
  ROS 1 bytes and definition (``ros1msg`` schemas, ``ros1`` encoding): nothing is lost, a
  Header's ``seq`` included. With ``schema="ros2"`` the messages are in ROS 2's CDR, as
  rosbag2 writes them (``ros2msg`` schemas), and a Header's ``seq``, which ROS 2 does not
  have, is dropped.
- ``run.bag``: a ROS 1 bag.
- ``run`` (no suffix): a ROS 2 bag folder (``metadata.yaml`` and its storage, ``mcap`` or
  ``sqlite3``).

The sources are read with the libraries that keep these formats: rosbags for ROS 1 and ROS 2
bags, the ``mcap`` package for MCAP files with ROS 1 schemas. Every message keeps its record
time (MCAP's ``log_time``). The target appears only once it is complete.

With ``poses_3d=True``, each 2D pose (``duckietown_msgs/Pose2DStamped``) is also written as a
frame on ``/tf`` and a ``geometry_msgs/PoseStamped`` on ``TOPIC_3d``, at the pose's record
time (:mod:`duckielib.bags.viewers`): a 3D panel draws them without set-up.

Laptop side; never deployed.
"""

from __future__ import annotations

import contextlib
import io
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional, Set, Tuple

from duckielib.bags import records
from duckielib.bags.reader import TO_ROS1, Bag, PathLike
from duckielib.bags.viewers import ViewerPoses
from duckielib.bags.writer import BagWriter
from duckielib.errors import BagError
from duckielib.rostime import NS_PER_S

__all__ = ["McapScan", "bag_kind", "convert_bag", "scan_mcap", "to_ros1"]


def bag_kind(path: PathLike) -> str:
    """What a bag is, from its contents: ``"ros1"``, ``"mcap"`` or ``"ros2"`` (a folder).

    Raises:
        BagError: if it is none of them (said in a sentence), or is not a file or folder.
    """
    path = Path(path)
    if path.is_dir() and not (path / "metadata.yaml").is_file():
        raise BagError(
            f"{path} is a directory, not a bag file (a ROS 2 bag folder holds a metadata.yaml)."
        )
    found = records.bag_format(path)
    if found is None:
        with path.open("rb") as file:
            start = file.read(8)
        raise BagError(
            f"{path} is neither a ROS 1 bag, an MCAP file nor a ROS 2 bag folder: it starts "
            f"with {start!r}."
        )
    return found


def _target_kind(target: Path) -> str:
    if target.suffix == ".bag":
        return "ros1"
    if target.suffix == ".mcap":
        return "mcap"
    if target.suffix:
        raise BagError(
            f"{target}: name the target run.bag (ROS 1), run.mcap (MCAP) or run (a ROS 2 bag "
            f"folder); {target.suffix} is none of them."
        )
    return "ros2"


def convert_bag(
    source: PathLike,
    target: PathLike,
    schema: str = "ros1",
    storage: str = "mcap",
    poses_3d: bool = False,
) -> Path:
    """Write ``source`` (a ROS 1 bag, an MCAP file or a ROS 2 bag folder) as ``target``.

    Args:
        source: the bag to read.
        target: the bag to write; its name says its format (see the module's text). It must
            not exist.
        schema: for an MCAP target, ``"ros1"`` (ROS 1 bytes and definitions, nothing lost)
            or ``"ros2"`` (CDR, as rosbag2 writes).
        storage: for a ROS 2 bag folder, ``"mcap"`` or ``"sqlite3"``.
        poses_3d: also write each 2D pose as a TF frame and a PoseStamped (see above).

    Returns:
        The target's path.

    Raises:
        BagError: if the source cannot be read or is damaged, the target exists, or an
            option is not one of those.
    """
    source, target = Path(source), Path(target)
    if schema not in ("ros1", "ros2"):
        raise BagError(f"schema must be 'ros1' or 'ros2', not {schema!r}.")
    if storage not in ("mcap", "sqlite3"):
        raise BagError(f"storage must be 'mcap' or 'sqlite3', not {storage!r}.")
    kind, wanted = bag_kind(source), _target_kind(target)
    if target.exists():
        raise BagError(f"{target} exists already; choose another name or delete it first.")
    if not target.parent.is_dir():
        raise BagError(f"There is no folder {target.parent} to write {target.name} in.")
    with tempfile.TemporaryDirectory(prefix=".converting-", dir=target.parent) as work:
        folder = Path(work)
        ros1 = source if kind == "ros1" else to_ros1(source, kind, folder / "source.bag")
        # A ROS 2 bag folder's storage file is named after the folder, as rosbag2 names it.
        written = folder / (target.name if wanted == "ros2" else "out" + target.suffix)
        if poses_3d and not (wanted == "mcap" and schema == "ros1"):
            ros1 = _with_poses_3d(Bag(ros1), folder / "poses_3d.bag")
        if wanted == "ros1":
            if ros1 == source:
                shutil.copyfile(ros1, written)
            else:
                ros1.replace(written)
            Bag(written)  # opens only if whole: its index lists every chunk
        elif wanted == "mcap" and schema == "ros1":
            _ros1_to_mcap(Bag(ros1), written, poses_3d)
        elif wanted == "mcap":
            _rosbags_convert(ros1, folder / "ros2", "mcap")
            (mcap,) = (folder / "ros2").glob("*.mcap")
            mcap.replace(written)
        else:
            _rosbags_convert(ros1, written, storage)
        written.replace(target)
    return target


def to_ros1(source: Path, kind: str, out: Path) -> Path:
    """A ROS 1 bag of an MCAP file or a ROS 2 bag folder, written to ``out``.

    Raises:
        BagError: if the source is damaged (where, and what it costs, said).
    """
    if kind == "mcap" and _mcap_encodings(source) == {"ros1msg"}:
        _mcap_to_ros1(source, out)
        return out
    _check_storage(source)
    _rosbags_convert(source, out, "")
    return out


def _check_storage(source: Path) -> None:
    """Refuse, said in a sentence, a ROS 2 bag (or CDR MCAP file) whose storage is damaged.

    rosbags reads such files whole or not at all: MCAP files are checked chunk by chunk (each
    chunk's CRC) first, sqlite3 databases by SQLite's own integrity check.
    """
    import sqlite3

    files = sorted(source.iterdir()) if source.is_dir() else [source]
    for file in files:
        if file.suffix == ".mcap":
            scan = scan_mcap(file)
            if scan.damages:
                where = source if file == source else f"{source} (a ROS 2 bag folder): {file.name}"
                raise BagError(
                    scan.sentence(Path(str(where))).rstrip(".") + ". Only MCAP files with ROS 1 "
                    "schemas can be repaired here; the messages in the chunks that can be read "
                    "are whole."
                )
        elif file.suffix == ".db3":
            try:
                with contextlib.closing(sqlite3.connect(f"file:{file}?mode=ro", uri=True)) as db:
                    verdict = db.execute("PRAGMA integrity_check").fetchone()[0]
            except (sqlite3.DatabaseError, MemoryError) as error:  # SQLite's own verdict
                verdict = str(error) or "its pages cannot be read"
            if verdict != "ok":
                problems = [line for line in verdict.splitlines() if not line.startswith("***")]
                verdict = problems[0] if problems else verdict
                if len(problems) > 1:
                    verdict += f", and {len(problems) - 1} more problems"
                raise BagError(
                    f"{source} is a ROS 2 bag folder whose database {file.name} is damaged "
                    f"(SQLite says: {verdict}); its messages cannot be read."
                )


def _rosbags_convert(source: Path, out: Path, storage: str) -> None:
    """Convert with rosbags' converter (ROS 1 <=> ROS 2), its errors in a sentence."""
    from rosbags.convert.converter import convert

    try:
        convert(
            srcs=[source],
            dst=out,
            dst_storage=storage or "sqlite3",
            dst_version=8 if out.suffix != ".bag" else 0,
            compress=None,
            compress_mode="file",
            default_typestore=None,
            typestore=None,
            exclude_topics=[],
            include_topics=[],
            exclude_msgtypes=[],
            include_msgtypes=[],
        )
    except Exception as error:  # rosbags raises its own errors for unreadable input
        raise BagError(
            f"{source} could not be converted by rosbags: {type(error).__name__}: {error}."
        ) from None


def _mcap_encodings(path: Path) -> set:
    """The schema encodings of an MCAP file (``ros1msg``, ``ros2msg``...).

    From its summary; a file without one (cut short, never closed) is read up to its damage.

    Raises:
        BagError: if not one schema can be read.
    """
    from mcap.reader import make_reader

    with contextlib.suppress(Exception), path.open("rb") as file:
        summary = make_reader(file).get_summary()
        if summary is not None:
            return {schema.encoding for schema in summary.schemas.values()}
    scan = scan_mcap(path)
    if not scan.encodings:
        raise BagError(scan.sentence(path) if scan.damages else f"{path} holds no message.")
    return scan.encodings


def _ros1_to_mcap(bag: Bag, out: Path, poses_3d: bool = False) -> None:
    """Every message of a ROS 1 bag into an MCAP file, with ROS 1 schemas and bytes."""
    from mcap.writer import Writer

    channels: Dict[Any, int] = {}
    schemas: Dict[Tuple[str, str], int] = {}
    viewer = ViewerPoses() if poses_3d else None
    with out.open("wb") as file:
        writer = Writer(file)
        writer.start(profile="ros1", library="duckielib")

        def channel(key: Any, topic: str, type_name: str, md5sum: str, definition: str) -> int:
            if key not in channels:
                if (type_name, md5sum) not in schemas:
                    schemas[type_name, md5sum] = writer.register_schema(
                        name=type_name, encoding="ros1msg", data=definition.encode()
                    )
                channels[key] = writer.register_channel(
                    topic=topic,
                    message_encoding="ros1",
                    schema_id=schemas[type_name, md5sum],
                    metadata={"md5sum": md5sum},
                )
            return channels[key]

        for cid, time_ns, data in bag._raw(list(bag.topics)):
            info = bag._connections[cid]
            made = channel(cid, info.name, info.type, info.md5sum, info.message_definition)
            writer.add_message(made, log_time=time_ns, data=data, publish_time=time_ns)
            for extra in (
                [] if viewer is None else viewer.messages(info.name, info.type, data, time_ns)
            ):
                made = channel(extra.topic, *extra[:4])
                writer.add_message(made, log_time=time_ns, data=extra.data, publish_time=time_ns)
        writer.finish()


def _with_poses_3d(bag: Bag, out: Path) -> Path:
    """A copy of a ROS 1 bag with its 2D poses also as TF frames and PoseStamped messages."""
    viewer = ViewerPoses()
    with BagWriter(out) as writer:
        for cid, time_ns, data in bag._raw(list(bag.topics)):
            info = bag._connections[cid]
            writer.write_raw(
                info.name, info.type, info.md5sum, info.message_definition, time_ns, data
            )
            for extra in viewer.messages(info.name, info.type, data, time_ns):
                writer.write_raw(*extra[:4], time_ns, extra.data)
    return out


@dataclass
class McapScan:
    """What a record-by-record reading of an MCAP file found.

    Attributes:
        counts: how many messages could be read, by topic.
        encodings: the schema encodings of those messages (``ros1msg``, ``ros2msg``...).
        start_ns, end_ns: the first and last record time read (0 when none was).
        damages: where the file is damaged, a sentence each (empty for a sound file).
        lost: messages the damage cost, by topic, where the file's own index says.
        listed: how many messages the file's summary lists (0 without a summary).
        summarised: whether the file has its summary (it was closed properly).
    """

    counts: Dict[str, int] = field(default_factory=dict)
    encodings: Set[str] = field(default_factory=set)
    start_ns: int = 0
    end_ns: int = 0
    damages: List[str] = field(default_factory=list)
    lost: Dict[str, int] = field(default_factory=dict)
    listed: int = 0
    summarised: bool = False

    @property
    def count(self) -> int:
        """How many messages could be read."""
        return sum(self.counts.values())

    def took(self, schema: Any, channel: Any, log_time: int) -> None:
        """Count one message read."""
        self.counts[channel.topic] = self.counts.get(channel.topic, 0) + 1
        if schema is not None:
            self.encodings.add(schema.encoding)
        self.start_ns = log_time if self.count == 1 else min(self.start_ns, log_time)
        self.end_ns = max(self.end_ns, log_time)

    def sentence(self, path: Path) -> str:
        """The damage in a sentence: where, and how many messages of which topics it costs."""
        said = f"{path} is a damaged MCAP file: {self.damages[0]}"
        if len(self.damages) > 1:
            said += f" ({len(self.damages)} damaged chunks in all)"
        if self.lost:
            topics = ", ".join(f"{topic} {count}" for topic, count in sorted(self.lost.items()))
            said += f"; {sum(self.lost.values())} of its {self.listed} messages are lost ({topics})"
        return said + "."


#: What a scan hands each message it reads: ``take(schema, channel, log time in ns, bytes)``.
Take = Callable[[Any, Any, int, bytes], None]


def scan_mcap(path: Path, take: Optional[Take] = None) -> McapScan:
    """Read every message of an MCAP file that can be read, checking each chunk's CRC.

    With its summary (a file closed properly), each chunk is read on its own, so a damaged
    chunk costs only its own messages, which the file's message index counts. Without one
    (cut short, never closed), the file is read from its start up to the damage. Each message
    goes to ``take`` as it is read (a whole chunk at a time), in file order: nothing but one
    chunk is held in memory.
    """
    from mcap.reader import make_reader

    scan = McapScan()
    give: Take = take or (lambda schema, channel, log_time, data: None)
    with path.open("rb") as file:
        try:
            summary = make_reader(file, validate_crcs=True).get_summary()
        except Exception:  # a damaged end: read from the start instead
            summary = None
        if summary is None or not summary.chunk_indexes:
            _scan_stream(file, scan, summary, give)
        else:
            _scan_chunks(file, scan, summary, give)
    return scan


def _records(data: bytes) -> Iterator[Any]:
    """The records of a stretch of an MCAP file (no magic), each chunk's CRC checked.

    The stretch ends where its bytes do (the reader of a whole file expects a footer there).
    """
    from mcap.exceptions import EndOfFile
    from mcap.stream_reader import StreamReader

    stream = io.BytesIO(data)
    records = StreamReader(stream, skip_magic=True, validate_crcs=True).records
    while True:
        at = stream.tell()
        try:
            yield next(records)
        except StopIteration:
            return
        except EndOfFile:
            if at == len(data):
                return
            raise


def _scan_chunks(file: Any, scan: McapScan, summary: Any, take: Take) -> None:
    from mcap.records import Message, MessageIndex

    scan.summarised = True
    schemas, channels = summary.schemas, summary.channels
    stats = summary.statistics
    scan.listed = stats.message_count if stats is not None else 0
    for chunk in sorted(summary.chunk_indexes, key=lambda item: item.chunk_start_offset):
        file.seek(chunk.chunk_start_offset)
        data = file.read(chunk.chunk_length)
        try:
            found = [
                (schemas.get(channels[r.channel_id].schema_id), channels[r.channel_id], r)
                for r in _records(data)
                if isinstance(r, Message)
            ]
        except Exception as error:  # the mcap reader's errors, or a channel it never defined
            scan.damages.append(
                f"the chunk at byte {chunk.chunk_start_offset:,} (record times "
                f"{chunk.message_start_time / NS_PER_S:.3f} s to "
                f"{chunk.message_end_time / NS_PER_S:.3f} s) cannot be read ({_said(error)})"
            )
            file.seek(chunk.chunk_start_offset + chunk.chunk_length)
            with contextlib.suppress(Exception):  # the file's count of the chunk's messages
                for record in _records(file.read(chunk.message_index_length)):
                    if isinstance(record, MessageIndex) and record.channel_id in channels:
                        topic = channels[record.channel_id].topic
                        scan.lost[topic] = scan.lost.get(topic, 0) + len(record.records)
            continue
        for schema, channel, record in found:
            scan.took(schema, channel, record.log_time)
            take(schema, channel, record.log_time, record.data)


def _scan_stream(file: Any, scan: McapScan, summary: Any, take: Take) -> None:
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader

    schemas: Dict[int, Any] = {}
    channels: Dict[int, Any] = {}
    file.seek(0)
    last = None
    try:
        for record in StreamReader(file, validate_crcs=True).records:
            if isinstance(record, Schema):
                schemas[record.id] = record
            elif isinstance(record, Channel):
                channels[record.id] = record
            elif isinstance(record, Message) and record.channel_id in channels:
                channel = channels[record.channel_id]
                schema = schemas.get(channel.schema_id)
                scan.took(schema, channel, record.log_time)
                take(schema, channel, record.log_time, record.data)
                last = record.log_time
    except Exception as error:
        after = "" if last is None else f" (after the message recorded at {last / NS_PER_S:.3f} s)"
        scan.damages.append(
            f"it cannot be read past byte {file.tell():,}{after}, and its summary is lost: it "
            f"was cut short or never closed ({_said(error)})"
        )
        return
    if summary is None:
        scan.damages.append("it has no summary: it was cut short or never closed")


def _said(error: BaseException) -> str:
    """An error of the mcap reader, as a clause: its class, and its text if it has one."""
    text = str(error).strip()
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def _mcap_to_ros1(
    source: Path, out: Path, keep_going: bool = False, compression: str = "none"
) -> McapScan:
    """An MCAP file with ROS 1 schemas into a ROS 1 bag (the bytes as they are).

    Args:
        source: the MCAP file.
        out: the ROS 1 bag to write.
        keep_going: write what can be read of a damaged file (``duckie bag repair``) rather
            than refuse it.
        compression: the bag's compression, ``"none"`` or ``"bz2"``.

    Returns:
        What the scan found (the messages written, and the damage).

    Raises:
        BagError: if the file is damaged (and not ``keep_going``: what was written is then
            incomplete), a channel has no schema, or a schema is not ROS 1's.
    """
    md5sums: Dict[int, str] = {}
    with BagWriter(out, compression) as writer:

        def write(schema: Any, channel: Any, log_time: int, data: bytes) -> None:
            if schema is None:
                raise BagError(f"{source}: the channel {channel.topic} has no schema.")
            if schema.encoding != "ros1msg":
                raise BagError(
                    f"{source} holds messages with {schema.encoding} schemas; a ROS 1 bag is "
                    "written from MCAP files with ROS 1 (ros1msg) schemas only."
                )
            md5 = md5sums.get(schema.id) or channel.metadata.get("md5sum") or _md5(schema)
            md5sums[schema.id] = md5
            writer.write_raw(channel.topic, schema.name, md5, schema.data.decode(), log_time, data)

        scan = scan_mcap(source, write)
    if scan.damages and not keep_going:
        raise BagError(
            f"{scan.sentence(source)} `duckie bag repair {source} NEW.bag` recovers the "
            f"{scan.count} messages that can be read."
        )
    return scan


def _md5(schema: Any) -> str:
    """The ROS 1 md5 sum of a ``ros1msg`` schema, computed from its definition (rosbags)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(schema.data.decode(), schema.name))
    return str(store.generate_msgdef(schema.name.replace("/", "/msg/", 1))[1])


TO_ROS1.append(to_ros1)  # what Bag uses to read an MCAP file or a ROS 2 bag folder
