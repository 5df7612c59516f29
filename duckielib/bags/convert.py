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

Laptop side; never deployed.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path
from typing import Any, Dict, Tuple

from duckielib.bags import records
from duckielib.bags.io import TO_ROS1, Bag, BagWriter, PathLike
from duckielib.errors import BagError

__all__ = ["bag_kind", "convert_bag", "to_ros1"]


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
    source: PathLike, target: PathLike, schema: str = "ros1", storage: str = "mcap"
) -> Path:
    """Write ``source`` (a ROS 1 bag, an MCAP file or a ROS 2 bag folder) as ``target``.

    Args:
        source: the bag to read.
        target: the bag to write; its name says its format (see the module's text). It must
            not exist.
        schema: for an MCAP target, ``"ros1"`` (ROS 1 bytes and definitions, nothing lost)
            or ``"ros2"`` (CDR, as rosbag2 writes).
        storage: for a ROS 2 bag folder, ``"mcap"`` or ``"sqlite3"``.

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
        written = folder / ("out" + target.suffix)
        if wanted == "ros1":
            if ros1 == source:
                shutil.copyfile(ros1, written)
            else:
                ros1.replace(written)
            Bag(written)  # opens only if whole: its index lists every chunk
        elif wanted == "mcap" and schema == "ros1":
            _ros1_to_mcap(Bag(ros1), written)
        elif wanted == "mcap":
            _rosbags_convert(ros1, folder / "ros2", "mcap")
            (mcap,) = (folder / "ros2").glob("*.mcap")
            mcap.replace(written)
        else:
            _rosbags_convert(ros1, written, storage)
        written.replace(target)
    return target


def to_ros1(source: Path, kind: str, out: Path) -> Path:
    """A ROS 1 bag of an MCAP file or a ROS 2 bag folder, written to ``out``."""
    if kind == "mcap" and _mcap_encodings(source) == {"ros1msg"}:
        _mcap_to_ros1(source, out)
    else:
        _rosbags_convert(source, out, "")
    return out


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
    """The schema encodings of an MCAP file (``ros1msg``, ``ros2msg``...)."""
    from mcap.reader import make_reader

    try:
        with path.open("rb") as file:
            summary = make_reader(file).get_summary()
    except Exception as error:
        raise BagError(f"{path} is a damaged MCAP file: {type(error).__name__}: {error}.") from None
    if summary is None:
        raise BagError(f"{path} is an MCAP file without its summary: it was not closed.")
    return {schema.encoding for schema in summary.schemas.values()}


def _ros1_to_mcap(bag: Bag, out: Path) -> None:
    """Every message of a ROS 1 bag into an MCAP file, with ROS 1 schemas and bytes."""
    from mcap.writer import Writer

    channels: Dict[int, int] = {}
    schemas: Dict[Tuple[str, str], int] = {}
    with out.open("wb") as file:
        writer = Writer(file)
        writer.start(profile="ros1", library="duckielib")
        for cid, time_ns, data in bag._raw(list(bag.topics)):
            if cid not in channels:
                info = bag._connections[cid]
                key = (info.type, info.md5sum)
                if key not in schemas:
                    schemas[key] = writer.register_schema(
                        name=info.type, encoding="ros1msg", data=info.message_definition.encode()
                    )
                channels[cid] = writer.register_channel(
                    topic=info.name,
                    message_encoding="ros1",
                    schema_id=schemas[key],
                    metadata={"md5sum": info.md5sum},
                )
            writer.add_message(channels[cid], log_time=time_ns, data=data, publish_time=time_ns)
        writer.finish()


def _mcap_to_ros1(source: Path, out: Path) -> None:
    """An MCAP file with ROS 1 schemas into a ROS 1 bag (the bytes as they are)."""
    from mcap.reader import make_reader

    md5sums: Dict[int, str] = {}
    try:
        with source.open("rb") as file, BagWriter(out) as writer:
            for schema, channel, message in make_reader(file).iter_messages(log_time_order=True):
                if schema is None:
                    raise BagError(f"{source}: the channel {channel.topic} has no schema.")
                md5 = md5sums.get(schema.id) or channel.metadata.get("md5sum") or _md5(schema)
                md5sums[schema.id] = md5
                writer.write_raw(
                    channel.topic,
                    schema.name,
                    md5,
                    schema.data.decode(),
                    message.log_time,
                    message.data,
                )
    except BagError:
        raise
    except Exception as error:  # the mcap reader checks records and CRCs as it reads
        raise BagError(
            f"{source} is a damaged MCAP file: {type(error).__name__}: {error}."
        ) from None


def _md5(schema: Any) -> str:
    """The ROS 1 md5 sum of a ``ros1msg`` schema, computed from its definition (rosbags)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(schema.data.decode(), schema.name))
    return str(store.generate_msgdef(schema.name.replace("/", "/msg/", 1))[1])


TO_ROS1.append(to_ros1)  # what Bag uses to read an MCAP file or a ROS 2 bag folder
