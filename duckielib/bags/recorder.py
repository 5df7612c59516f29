"""``rosbag record`` for the in-process graph: durable recording of topics to a bag.

Like ``rosbag record``, the recorder is a node that subscribes to the topics and writes each
message's bytes, undecoded, with the graph's time as record time. Its subscriptions count as
subscribers on the graph like any other; since they run no node code, each message is taken
the moment it is published rather than queued for a callback, and goes into the bag with the
next batch (a few hundred messages, or sooner: see below). While it records, the bag is
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
import collections
import contextlib
import itertools
import re
import threading
import time
from pathlib import Path
from typing import Any, Callable, Deque, Dict, Iterable, List, Optional, Tuple

from duckielib.bags.writer import BagWriter, PathLike, uninterrupted
from duckielib.errors import BagError
from duckielib.ros import names
from duckielib.ros.context import node_context
from duckielib.ros.graph import Graph, default_graph
from duckielib.ros.log import ERROR
from duckielib.ros.rospy import AnyMsg, Subscriber

__all__ = ["BagRecorder", "Tap", "record"]

#: How often, in simulated seconds, a recorder of all topics looks for new ones.
_DISCOVERY_PERIOD_NS = 100_000_000

#: How many messages a recorder keeps before it writes them into the bag's open chunk.
_BATCH = 256

_numbers = itertools.count(1)


class Tap(Subscriber):
    """A subscription that hands each message's bytes, as published, to ``deliver``.

    ``deliver(record, data)`` is called within ``publish()`` with the topic's record (its
    ``name`` and ``connection_header()``) and the message's serialized bytes, undecoded; also
    from ``__init__`` with the topic's latched messages. It runs no node code, so it must be
    quick: ``rosbag record`` (:class:`BagRecorder`) and the live view
    (:class:`duckielib.sim.live.LiveView`) use it.

    This class is the only tie to the internals of :class:`duckielib.ros.rospy.Subscriber`,
    which has no public way to take a message's bytes as it is published. It relies on two
    private names (``tests/bags/test_recorder_seam.py`` checks both):

    - ``Subscriber._enqueue(self, data: bytes) -> None``, overridden here: rospy calls it with
      each message's serialized bytes, within ``publish()``, and from ``Subscriber.__init__``
      with the topic's latched messages. The base method queues them for a callback; a tap
      has none, so it neither queues nor decodes.
    - ``Subscriber._record``: the topic's record (its ``name`` and ``connection_header()``),
      set before the latched messages arrive and None once unsubscribed.
    """

    def __init__(self, topic: str, deliver: Callable[[Any, bytes], None]) -> None:
        self._deliver = deliver  # first: a latched message arrives while subscribing
        super().__init__(topic, AnyMsg, queue_size=None)

    def _enqueue(self, data: bytes) -> None:  # overrides rospy's private method: see above
        record = self._record
        if record is not None:
            self._deliver(record, data)


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
        exclude: with ``topics`` None, a regular expression of topics not to record (whole
            names), as ``rosbag record -a -x``.

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
        exclude: Optional[str] = None,
    ) -> None:
        self.path = Path(path)
        self._exclude = None if exclude is None else re.compile(exclude)
        self.active_path = self.path.with_name(self.path.name + ".active")
        if self.path.exists():
            raise BagError(f"{self.path} exists already; choose another name or delete it first.")
        self.graph = default_graph() if graph is None else graph
        self.flush_interval = flush_interval
        self._counts: Dict[str, int] = {}
        # Messages taken but not yet written: (connection, record time, bytes), in order. The
        # graph's thread appends; whoever writes (that thread or the flusher) pops from the left.
        self._pending: Deque[Tuple[Any, int, bytes]] = collections.deque()
        self._batch = 1 if flush_interval <= 0 else _BATCH
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
        taken = sum(self._counts.values()) + len(self._pending)  # no writing to show it
        return f"<BagRecorder {self.path.name} ({state}): {taken} messages>"

    @property
    def counts(self) -> Dict[str, int]:
        """How many messages were recorded, by topic."""
        self._write_pending()
        return dict(self._counts)

    def add(self, topic: str) -> None:
        """Record ``topic`` (a global name) from now on, its next message included.

        A recorder of all topics finds a new topic within 0.1 simulated seconds, as
        ``rosbag record -a`` polls the master; a publisher that knows it starts a topic calls
        this to lose none of its first messages.
        """
        if not self.closed:
            self._subscribe(names.canonical(names.resolve(topic, "/")))

    def _subscribe(self, topic: str) -> None:
        if topic in self._subscribed:
            return
        self._counts.setdefault(topic, 0)
        with node_context(self._node):
            self._subscribed[topic] = Tap(topic, self._taker())

    def _taker(self) -> Callable[[Any, bytes], None]:
        """What a topic's tap calls with each message: keep it for the next batch."""
        graph, pending, batch = self.graph, self._pending, self._batch
        connection: List[Any] = []  # the bag's connection, made at the topic's first message

        def take(record: Any, data: bytes) -> None:
            if not connection:
                made = self._connect(record)
                if made is None:  # the recording has stopped
                    return
                connection.append(made)
            pending.append((connection[0], graph.now_ns, data))
            if len(pending) >= batch:
                self._write_pending()

        return take

    def _discover(self) -> None:
        if self.closed:
            return
        for topic, record in list(self.graph.topics.items()):
            if record.publishers and not (self._exclude and self._exclude.fullmatch(topic)):
                self._subscribe(topic)
        self.graph.schedule(self.graph.now_ns + _DISCOVERY_PERIOD_NS, self._discover)

    def _connect(self, record: Any) -> Any:
        """The bag's connection for a topic's first message, or None once recording stopped."""
        with self._lock:
            if self.closed or self.error is not None:
                return None
            header = record.connection_header()
            try:
                return self._writer.connection(
                    record.name,
                    header["type"],
                    header["md5sum"],
                    header["message_definition"],
                    callerid=header.get("callerid") or None,
                    latching=header.get("latching"),
                )
            except Exception as error:  # a full disk must not stop the node that published
                self._fail(error, f"the first message on {record.name}")
                return None

    def _write_pending(self) -> None:
        with uninterrupted(), self._lock:
            self._write_pending_locked()

    def _write_pending_locked(self) -> None:
        pending = self._pending
        if self.closed or self.error is not None:
            pending.clear()
            return
        batch = [pending.popleft() for _ in range(len(pending))]
        if not batch:
            return
        try:
            self._writer.write_many(batch)
            self._unflushed = True
            if time.monotonic() - self._last_flush >= self.flush_interval:
                self._flush_locked()
        except Exception as error:  # a full disk must not stop the node that published
            self._fail(error, f"a message on {batch[0][0].topic}")
            return
        counts = self._counts
        for connection, count in collections.Counter(item[0] for item in batch).items():
            counts[connection.topic] += count

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
            self._write_pending_locked()
            self._flush_locked()

    def _flush_locked(self) -> None:
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
            with uninterrupted():  # a bag finished whole, under its own name
                with self._lock:
                    self._write_pending_locked()
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
