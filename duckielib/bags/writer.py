"""Writing ROS 1 bags with rosbags, whole even when the code writing them fails.

:class:`BagWriter` writes a bag uncompressed or BZ2 (rosbags' LZ4 chunks are rejected by ROS
1's own tools, so they are refused here), and always finishes the bag (chunks, index) when
closed, also when the code writing it fails. Its records go into rosbags' open chunk through
:class:`~duckielib.bags.seam.RosbagsSeam`. :func:`uninterrupted` holds Ctrl-C back while a
write is under way, so that a bag is never left with a chunk its index does not list.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, Iterator, List, Optional, Tuple, Union

from rosbags.rosbag1 import Writer, WriterError

from duckielib.bags.seam import RosbagsSeam, rosbags_type
from duckielib.errors import BagError

__all__ = ["COMPRESSIONS", "BagWriter", "PathLike", "uninterrupted"]

PathLike = Union[str, "os.PathLike[str]"]

#: Compressions a bag may be written with (ROS 1's tools read both).
COMPRESSIONS = ("none", "bz2")

#: The signals a command ends on: Ctrl-C, and SIGTERM where ``duckie`` takes it.
_ENDING_SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: How many :func:`uninterrupted` blocks the main thread is in (only the outermost swaps the
#: handlers).
_DEFERRING = [0]


@contextlib.contextmanager
def uninterrupted() -> Iterator[None]:
    """Let Ctrl-C (or SIGTERM) that comes while a bag is written wait until the write is whole.

    A ``KeyboardInterrupt`` raised between two statements of a write could leave a chunk in
    the file that the index never lists, or messages taken from a recorder's queue but never
    written. Inside this block, in the main thread, those signals are noted; the handler that
    was in place runs when the block ends (it raises ``KeyboardInterrupt`` then, as it would
    have). Other threads never run signal handlers, so there the block changes nothing.
    """
    if threading.current_thread() is not threading.main_thread() or _DEFERRING[0]:
        yield  # another thread, or inside an outer block that already holds the signals
        return
    handlers: Dict[int, Callable[[int, Any], Any]] = {}
    for ending in _ENDING_SIGNALS:
        handler = signal.getsignal(ending)
        if callable(handler):
            handlers[ending] = handler
    pending: List[Tuple[int, Any]] = []
    for taken in handlers:
        signal.signal(taken, lambda got, frame: pending.append((got, frame)))
    _DEFERRING[0] += 1
    try:
        yield
    finally:
        _DEFERRING[0] -= 1
        for taken, handler in handlers.items():
            signal.signal(taken, handler)
        for got, frame in pending[:1]:
            handlers[got](got, frame)


class BagWriter:
    """Write a ROS 1 bag (format 2.0) with rosbags.

    Use it as a context manager or call :meth:`close`: closing writes the last chunk and the
    index, also when the code in the ``with`` block raised, so nothing written is lost.

    Args:
        path: the new bag file; it must not exist.
        compression: ``"none"`` (default) or ``"bz2"``.

    Raises:
        BagError: if the file exists, cannot be created, or the compression is not allowed.
    """

    def __init__(self, path: PathLike, compression: str = "none") -> None:
        self.path = Path(path)
        if compression not in COMPRESSIONS:
            raise BagError(
                f"Bags are written uncompressed ('none') or with 'bz2', not {compression!r}: "
                "ROS 1's tools cannot read the lz4 chunks rosbags writes."
            )
        if self.path.exists():
            raise BagError(f"{self.path} exists already; choose another name or delete it first.")
        RosbagsSeam.check_writer(self.path)
        self.compression = compression
        self._writer = Writer(self.path)
        if compression == "bz2":
            self._writer.set_compression(Writer.CompressionFormat.BZ2)
        try:
            self._writer.open()
        except (OSError, WriterError) as error:
            raise BagError(f"Cannot create {self.path}: {error}.") from None
        self._seam = RosbagsSeam(self._writer, self.path.name)
        self._connections: Dict[Tuple[str, str], Any] = {}
        self.closed = False

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    @property
    def count(self) -> int:
        """How many messages were written."""
        return self._seam.written

    def write(self, topic: str, message: Any, time_ns: int) -> None:
        """Write a duckielib message on ``topic`` with record time ``time_ns`` (nanoseconds).

        Raises:
            BagError: if the bag is closed or the time is negative.
        """
        self.write_raw(
            topic,
            message._type,
            message._md5sum,
            message._full_text,
            time_ns,
            message.to_bytes(),
        )

    def write_raw(
        self,
        topic: str,
        message_type: str,
        md5sum: str,
        message_definition: str,
        time_ns: int,
        data: bytes,
        callerid: Optional[str] = None,
        latching: Optional[str] = None,
    ) -> None:
        """Write serialized message bytes, with the type's name, md5 sum and full definition.

        Raises:
            BagError: if the bag is closed or the time is negative.
        """
        connection = self.connection(
            topic, message_type, md5sum, message_definition, callerid, latching
        )
        self.write_connection(connection, time_ns, data)

    def connection(
        self,
        topic: str,
        message_type: str,
        md5sum: str,
        message_definition: str,
        callerid: Optional[str] = None,
        latching: Optional[str] = None,
    ) -> Any:
        """The bag's connection for a topic and type, added on first use.

        Writing many messages of one topic, get it once and pass it to
        :meth:`write_connection`.
        """
        key = (topic, md5sum)
        connection = self._connections.get(key)
        if connection is None:
            with uninterrupted():
                connection = self._add_connection(
                    key, topic, message_type, md5sum, message_definition, callerid, latching
                )
        return connection

    def _add_connection(
        self,
        key: Tuple[str, str],
        topic: str,
        message_type: str,
        md5sum: str,
        message_definition: str,
        callerid: Optional[str],
        latching: Optional[str],
    ) -> Any:
        connection = self._writer.add_connection(
            topic,
            rosbags_type(message_type),
            msgdef=message_definition,
            md5sum=md5sum,
            callerid=callerid,
            latching=None if latching is None else int(latching),
        )
        self._connections[key] = connection
        self._seam.register(connection)
        return connection

    def write_connection(self, connection: Any, time_ns: int, data: bytes) -> None:
        """Write serialized message bytes on a connection from :meth:`connection`.

        Raises:
            BagError: if the bag is closed, the time is negative, or the connection is not
                one of this bag's.
        """
        self.write_many(((connection, time_ns, data),))

    def write_many(self, items: Iterable[Tuple[Any, int, bytes]]) -> None:
        """Write ``(connection, time_ns, data)`` items, in order, as :meth:`write_connection`.

        The records go straight into rosbags' open chunk (see :class:`RosbagsSeam`), with the
        bytes its ``Writer.write`` would write, without rebuilding a record's header for each
        message: a recorder writes thousands a second. Items before a bad one are written.

        Raises:
            BagError: if the bag is closed, a time is negative, or a connection is not one of
                this bag's.
        """
        if self.closed:
            raise BagError(f"{self.path} is closed; open a new BagWriter to write more.")
        with uninterrupted():
            self._seam.write_messages(items)

    def flush(self) -> None:
        """Write the messages buffered so far to disk as a chunk.

        A bag whose writer is killed later keeps everything flushed (see ``duckie bag repair``).
        """
        if self.closed:
            return
        with uninterrupted():
            self._seam.write_open_chunk()
            file = self._seam.file
            if file is not None:
                file.flush()
                os.fsync(file.fileno())

    def abandon(self) -> None:
        """Close the file without finishing the bag, after a failed write.

        What was flushed before stays readable by ``duckie bag repair``.
        """
        self.closed = True
        file = self._seam.file
        if file is not None and not file.closed:
            # Its buffer may not be writable either: what was flushed before stays.
            with contextlib.suppress(OSError):
                file.close()

    def close(self) -> None:
        """Finish the bag: write the last chunk and the index. Closing twice does nothing."""
        if self.closed:
            return
        with uninterrupted():
            self.closed = True
            self._writer.close()
