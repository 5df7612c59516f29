"""``rosbag record`` for the in-process graph: durable recording of topics to a bag.

Like ``rosbag record``, the recorder is a node that subscribes to the topics and writes each
message's bytes, undecoded, with the graph's time as record time. Its subscriptions count as
subscribers on the graph like any other; since they run no node code, each message is written
the moment it is published rather than queued for a callback. While it records, the bag is
``NAME.bag.active``; it becomes ``NAME.bag`` when the recording is closed.

Nothing recorded is lost to an ordinary failure: the bag is closed (chunks and index written)
when the ``with`` block ends, also by an exception, when the graph shuts down, and when Python
exits. Against a killed process, the messages are written to disk at least once per second of
wall time (by a background thread, also while the graph is idle), and ``duckie bag repair``
recovers everything written before the kill. A write that fails (a full disk) stops the
recording, not the node that published: the failure is logged and kept in
:attr:`BagRecorder.error`, and the file keeps its ``.active`` name for ``duckie bag repair``.

Recording every topic also subscribes to the camera, which then renders its frames (about
15 ms each); list the topics to record when the images are not needed.
"""

from __future__ import annotations

import atexit
import contextlib
import itertools
import threading
import time
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, Optional

from duckielib.bags.io import BagWriter, PathLike
from duckielib.errors import BagError
from duckielib.ros import names
from duckielib.ros.graph import ERROR, Graph, default_graph, node_context
from duckielib.ros.rospy import AnyMsg, Subscriber

__all__ = ["BagRecorder", "record"]

#: How often, in simulated seconds, a recorder of all topics looks for new ones.
_DISCOVERY_PERIOD_NS = 100_000_000

_numbers = itertools.count(1)


class _Recording(Subscriber):
    """A subscription of ``rosbag record``: hands each message's bytes on as published."""

    def __init__(self, topic: str, write: Callable[[Any, bytes], None]) -> None:
        self._write = write  # first: a latched message arrives while subscribing
        super().__init__(topic, AnyMsg, queue_size=None)

    def _enqueue(self, data: bytes) -> None:
        if self._record is not None:
            self._write(self._record, data)


class BagRecorder:
    """Record topics of a graph to a ROS 1 bag, as ``rosbag record`` does.

    Args:
        path: the bag to write, for example ``"run.bag"``; it must not exist yet.
        topics: the topics to record (global names); None records every topic, including
            topics that appear later.
        graph: the graph (default: the current default graph).
        compression: ``"none"`` or ``"bz2"``.
        flush_interval: the longest wall-clock time, in seconds, recorded messages wait in
            memory before they are written to disk.

    Attributes:
        path: the finished bag's path.
        active_path: the file written while recording (``path`` + ``.active``).
        counts: how many messages were recorded, by topic.
        error: why recording stopped early (a full disk, for example), or None. The messages
            recorded before are kept; the error is also in the graph's log.

    Raises:
        BagError: if the bag (or its ``.active`` file) exists already or cannot be created.
    """

    def __init__(
        self,
        path: PathLike,
        topics: Optional[Iterable[str]] = None,
        graph: Optional[Graph] = None,
        compression: str = "none",
        flush_interval: float = 1.0,
    ) -> None:
        self.path = Path(path)
        self.active_path = self.path.with_name(self.path.name + ".active")
        if self.path.exists():
            raise BagError(f"{self.path} exists already; choose another name or delete it first.")
        self.graph = default_graph() if graph is None else graph
        self.flush_interval = flush_interval
        self.counts: Dict[str, int] = {}
        self.closed = False
        self.error: Optional[str] = None
        self._writer = BagWriter(self.active_path, compression)
        self._last_flush = time.monotonic()
        self._unflushed = False
        # The graph's thread writes, the flusher thread flushes: the lock keeps them apart.
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._node = self.graph.host_node(f"record_{next(_numbers)}")
        self._node.shutdown_hooks.append(self._close_quietly)
        self._subscribed: Dict[str, Any] = {}
        self._connections: Dict[str, Any] = {}  # the bag's connection of each topic
        self._all = topics is None
        for topic in [] if topics is None else topics:
            self._subscribe(names.canonical(names.resolve(topic, "/")))
        if self._all:
            self._discover()
        atexit.register(self._close_quietly)
        if flush_interval > 0:
            threading.Thread(
                target=self._flush_periodically, name=f"flush:{self.path.name}", daemon=True
            ).start()

    def __enter__(self) -> BagRecorder:
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self.closed else "recording"
        return f"<BagRecorder {self.path.name} ({state}): {sum(self.counts.values())} messages>"

    def _subscribe(self, topic: str) -> None:
        if topic in self._subscribed:
            return
        self.counts.setdefault(topic, 0)
        with node_context(self._node):
            self._subscribed[topic] = _Recording(topic, self._on_message)

    def _discover(self) -> None:
        if self.closed:
            return
        for topic, record in list(self.graph.topics.items()):
            if record.publishers:
                self._subscribe(topic)
        self.graph.schedule(self.graph.now_ns + _DISCOVERY_PERIOD_NS, self._discover)

    def _on_message(self, record: Any, data: bytes) -> None:
        if self.closed or self.error is not None:
            return
        topic = record.name
        try:
            with self._lock:
                connection = self._connections.get(topic)
                if connection is None:
                    header = record.connection_header()
                    connection = self._connections[topic] = self._writer.connection(
                        topic,
                        header["type"],
                        header["md5sum"],
                        header["message_definition"],
                        callerid=header.get("callerid") or None,
                        latching=header.get("latching"),
                    )
                self._writer.write_connection(connection, self.graph.now_ns, data)
                self._unflushed = True
            if time.monotonic() - self._last_flush >= self.flush_interval:
                self.flush()
            self.counts[topic] += 1
        except Exception as error:  # a full disk must not stop the node that published
            self._fail(error, f"a message on {topic}")

    def _fail(self, error: BaseException, where: str) -> None:
        """Stop recording after a failed write; what reached the disk stays in ``.active``."""
        if self.error is not None:
            return
        self.error = f"{type(error).__name__}: {error}"
        self._node.log(
            ERROR,
            f"Stopped recording {self.path.name} at {where} ({self.error}). What reached the "
            f"disk is in {self.active_path.name}; duckie bag repair recovers it.",
        )

    def _flush_periodically(self) -> None:
        while not self._stop.wait(self.flush_interval):
            try:
                self.flush()
            except Exception as error:  # reported by the recorder, not lost in a thread
                self._fail(error, "a periodic flush")
                return

    def flush(self) -> None:
        """Write every message recorded so far to disk."""
        with self._lock:
            if not self.closed and self._unflushed and self.error is None:
                self._writer.flush()
                self._unflushed = False
            self._last_flush = time.monotonic()

    def _close_quietly(self) -> None:
        """Close at shutdown or exit; a failure is in :attr:`error` and the graph's log."""
        with contextlib.suppress(BagError):
            self.close()

    def close(self) -> Path:
        """Finish the bag and give it its final name. Closing twice does nothing.

        After a failed write (see :attr:`error`) the bag cannot be finished: its file keeps the
        ``.active`` name, for ``duckie bag repair``, and that path is returned.

        Returns:
            The finished bag's path.

        Raises:
            BagError: if finishing the bag fails now (the ``.active`` file is kept).
        """
        if self.closed:
            return self.path if self.error is None else self.active_path
        self._stop.set()
        atexit.unregister(self._close_quietly)
        try:
            with self._lock:
                self.closed = True
                if self.error is not None:
                    self._writer.abandon()
                    return self.active_path
                try:
                    self._writer.close()
                except Exception as error:
                    self._fail(error, "the end")
                    self._writer.abandon()
                    raise BagError(
                        f"Could not finish {self.path}: {self.error}. What reached the "
                        f"disk is in {self.active_path}; duckie bag repair recovers it."
                    ) from None
            if self.active_path.exists():
                self.active_path.replace(self.path)
        finally:
            if not self._node.is_shutdown:
                self._node.shutdown("the recording was closed")
        return self.path if self.error is None else self.active_path


def record(path: PathLike, topics: Optional[Iterable[str]] = None, **options: Any) -> BagRecorder:
    """Start recording ``topics`` (default: all) of the default graph to ``path``.

    Use it in a ``with`` block, or call ``close()`` on what it returns, to finish the bag.
    """
    return BagRecorder(path, topics, **options)
