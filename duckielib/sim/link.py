"""The virtual Duckiebot and the nodes that drive it, in two processes joined by one socket.

On a real Duckiebot, a student's nodes reach the robot only through topics and services: they
cannot move the robot's body, read where it really is, or rewrite what the encoders count.
In one process they could (the simulator is an object away), so for grading, and with
``duckie mission --apart``, the two sides run apart, each on a graph of its own:

- the **robot's side** (:class:`RobotLink`): the simulator, the robot's driver nodes and the
  bag recorder, in the process that starts the other;
- the **nodes' side** (:class:`NodesLink`): the student's nodes, in a process of their own (in
  the grader's sandbox when grading).

The two graphs keep one simulated clock. The robot's side leads: it runs everything due on
its graph up to a time ``t``, hands the nodes' side the messages its nodes subscribed to and
the time ``t``, and waits while that side runs everything due there; the answer carries what
the nodes published, any new subscriptions, and when the nodes' side next has something to do.
The clock then moves to whichever side has the earlier next thing. Nothing runs on one side
while the other works, so the run unfolds as on one graph.

What crosses, and how it is checked on the robot's side:

- The robot's topics and services are offered to the nodes (the nodes' graph shows them as
  the robot's nodes' own), except the simulator's (``simulator_node/...``): no real robot has
  them. A topic's messages are sent over only once a node subscribes to it.
- What the nodes publish reaches the robot's graph as messages of the robot's known types,
  read by the types' own strict ROS 1 decoders, and is recorded from there. The robot's own
  outputs (encoder ticks, the executed wheel commands, the LED pattern it shows, the camera)
  are the robot's alone: the nodes' messages on those topics stay on the nodes' side.
- A node's service call to the robot is answered by the robot's service, at the same
  simulated time.
- Parameters: the nodes' side starts with a copy of the robot's.

Every frame is a length-prefixed JSON header followed by the messages' bytes; sizes are
bounded on both ends.
"""

from __future__ import annotations

import json
import os
import socket
import struct
import time
from typing import Any, Callable, Dict, List, Optional, Set, Tuple

from duckielib.errors import DuckielibError
from duckielib.ros import names, rospy
from duckielib.ros.context import node_context
from duckielib.ros.log import LEVEL_NAMES, LogRecord
from duckielib.ros.rospy.topics import AnyMsg, Subscriber

__all__ = [
    "HEADER_LIMIT",
    "LinkError",
    "MESSAGE_LIMIT",
    "NodesLink",
    "NodesStopped",
    "OutOfWallTime",
    "RobotLink",
]

#: The largest JSON header of a frame, in bytes.
HEADER_LIMIT = 1024 * 1024
#: The most bytes of messages one frame may carry (a camera image is about 20 kB).
MESSAGE_LIMIT = 16 * 1024 * 1024
#: The most bytes of messages the robot takes from the nodes in one run (the reference's
#: mission sends about 0.2 MB): a node that floods a topic cannot fill the grader's disk.
TAKEN_LIMIT = 100 * 1024 * 1024
#: The most topics the nodes may publish to, and the longest name they may use.
TOPIC_LIMIT = 200
NAME_LIMIT = 256
#: The most characters of the nodes' log lines handed over at the end.
LOG_LIMIT = 2 * 1024 * 1024
#: The first word of the exchange, so that each side knows it speaks to the other.
VERSION = "duckielib-link-1"

_SIZES = struct.Struct("!II")


class LinkError(DuckielibError):
    """The other side broke the exchange: it closed it, was too slow, or sent what is refused."""


class OutOfWallTime(LinkError):
    """The run's wall-clock time was over before the nodes' side answered."""


class NodesStopped(DuckielibError):
    """The nodes' side stopped before the run's end.

    Attributes:
        kind: ``"solution"`` when a part of the solution is unwritten, ``"mission"`` otherwise.
        why: the sentence that says what stopped it.
    """

    def __init__(self, kind: str, why: str) -> None:
        super().__init__(why)
        self.kind = kind
        self.why = why


# -- the wire ---------------------------------------------------------------------------------


def send(sock: socket.socket, header: Dict[str, Any], blobs: List[bytes] = ()) -> None:  # type: ignore[assignment]
    """Send one frame: the header as JSON, then the bytes of ``blobs``, one after the other."""
    head = json.dumps(header, separators=(",", ":")).encode("utf-8")
    body = b"".join(blobs)
    try:
        sock.sendall(_SIZES.pack(len(head), len(body)) + head + body)
    except OSError as error:
        raise LinkError(f"the other side closed the link ({error.strerror or error})") from None


def _exactly(sock: socket.socket, size: int) -> bytes:
    chunks = []
    while size:
        chunk = sock.recv(min(size, 1 << 20))
        if not chunk:
            raise LinkError("the other side closed the link")
        chunks.append(chunk)
        size -= len(chunk)
    return b"".join(chunks)


def receive(sock: socket.socket, timeout: Optional[float]) -> Tuple[Dict[str, Any], bytes]:
    """Receive one frame: its header (a JSON object) and its bytes.

    Raises:
        LinkError: if the other side closed the link, sent a frame over the limits, a header
            that is not a JSON object with a string ``k``, or sent nothing for ``timeout`` s.
    """
    sock.settimeout(timeout)
    try:
        head_size, body_size = _SIZES.unpack(_exactly(sock, _SIZES.size))
        if head_size > HEADER_LIMIT or body_size > MESSAGE_LIMIT:
            raise LinkError(f"a frame of {head_size + body_size} bytes is over the limit")
        head = _exactly(sock, head_size)
        body = _exactly(sock, body_size)
    except socket.timeout:
        raise LinkError(f"the other side sent nothing for {timeout:.0f} s") from None
    except OSError as error:
        raise LinkError(f"the link broke ({error.strerror or error})") from None
    try:
        header = json.loads(head.decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
        raise LinkError("a frame's header is not JSON") from None
    if not isinstance(header, dict) or not isinstance(header.get("k"), str):
        raise LinkError("a frame's header is not an object with a kind")
    return header, body


def _cut(body: bytes, sizes: List[int]) -> List[bytes]:
    """``body`` cut into pieces of ``sizes`` bytes, which must add up to all of it."""
    if any(type(size) is not int or size < 0 for size in sizes) or sum(sizes) != len(body):
        raise LinkError("a frame's message sizes do not match its bytes")
    pieces, start = [], 0
    for size in sizes:
        pieces.append(body[start : start + size])
        start += size
    return pieces


class _Forward(Subscriber):
    """A subscription of the link: takes each message's bytes as published, for the other side.

    Like the bag recorder's subscription, it relies on the private
    ``Subscriber._enqueue(data)``, which rospy calls with each message's serialized bytes.
    """

    def __init__(self, topic: str, outbox: List[Tuple[str, bytes]]) -> None:
        self._outbox = outbox
        self._topic = topic
        super().__init__(topic, AnyMsg, queue_size=None)

    def _enqueue(self, data: bytes) -> None:  # overrides rospy's private method: see above
        self._outbox.append((self._topic, data))


def _deliver(record: Any, data: bytes) -> None:
    """Hand ``data`` to the topic's subscribers as ``publish()`` does, except the link's own.

    A message from the other side is never sent back to it.
    """
    record.message_count += 1
    for subscriber in list(record.subscribers):
        if not isinstance(subscriber, _Forward):
            subscriber._enqueue(data)


def _log_records(given: Any, size: int = 0) -> List[LogRecord]:
    """The nodes' log lines as records, each given as ``[time, level, node, text]``.

    Anything else is dropped, and what comes past LOG_LIMIT characters (``size`` taken already).
    """
    if not isinstance(given, list):
        return []
    records = []
    for item in given:
        if not (isinstance(item, list) and len(item) == 4):
            continue
        when, level, node, text = item
        if not (
            type(when) in (int, float)
            and level in LEVEL_NAMES
            and isinstance(node, str)
            and isinstance(text, str)
        ):
            continue
        size += len(node) + len(text)
        if size > LOG_LIMIT:
            break
        records.append(LogRecord(float(when), level, node[:NAME_LIMIT], text[:LOG_LIMIT]))
    return records


def _split_name(full: str) -> Tuple[str, str]:
    """A node's global name as (base name, namespace)."""
    namespace, _, base = full.rpartition("/")
    return base, namespace + "/"


def _legal_global(name: Any) -> bool:
    return (
        isinstance(name, str)
        and 1 < len(name) <= NAME_LIMIT
        and name.startswith("/")
        and names.is_legal_name(name)
        and name == names.canonical(name)
    )


# -- the robot's side -------------------------------------------------------------------------


class RobotLink:
    """The robot's side: leads the clock, offers the robot, takes in what the nodes publish.

    Args:
        sock: the connected socket to the nodes' side.
        bot: the :class:`~duckielib.sim.VirtualDuckiebot` (its drivers on its graph).
        reply_timeout: wall-clock seconds the nodes' side may take to answer one exchange.
        deadline: the wall-clock time (``time.monotonic()``) by which the whole run must end.
    """

    def __init__(
        self,
        sock: socket.socket,
        bot: Any,
        reply_timeout: float = 60.0,
        deadline: Optional[float] = None,
    ) -> None:
        self.sock = sock
        self.bot = bot
        self.graph = bot.graph
        self.reply_timeout = reply_timeout
        self.deadline = deadline
        self.finished = False
        #: The nodes' log, as it came (at most LOG_LIMIT characters); each line is in the
        #: robot's graph's log too, as a master's ``/rosout`` gathers every node's.
        self.nodes_log: List[LogRecord] = []
        self._logged = 0  # characters of the nodes' log taken
        #: Topics whose messages the nodes published but the robot did not take, and why.
        self.refused: Dict[str, str] = {}
        self._outbox: List[Tuple[str, bytes]] = []
        self._forwarded: Set[str] = set()
        self._nodes_next: Optional[int] = self.graph.now_ns
        self._publishers: Dict[str, Any] = {}  # topic -> the robot graph's publisher for it
        self._node = self.graph.host_node("robot_link", bot.namespace)
        drivers = list(bot.driver_nodes.values())
        truth = bot.namespace + "simulator_node/"
        self._inputs = {sub.name for node in drivers for sub in node.subscribers}
        self._outputs = {pub.name for node in drivers for pub in node.publishers} - self._inputs
        self._offered = {
            pub.name: pub
            for node in drivers
            for pub in node.publishers
            if not pub.name.startswith(truth)
        }
        self._services = {
            record.name: record
            for node in drivers
            for record in node.services
            if not record.name.startswith(truth)
        }
        self._callers: Dict[str, Any] = {}
        #: The nodes' side's nodes, each stood for by a node of the robot's graph (by name).
        self._mirrors: Dict[str, Any] = {}
        self._accepted: Dict[str, Any] = {}  # topic -> the message class taken from the nodes
        self._wanted: Set[str] = set()  # topics the nodes subscribed to that nobody here offers
        self._stopped: Optional[NodesStopped] = None  # the nodes stopped during a call
        self.graph.topic_watchers.append(self._watch)
        self._exchanged_at = -1  # the last time the nodes' side was brought to
        self._taken = 0  # bytes of messages taken from the nodes

    # Start and end.

    def start(self) -> None:
        """Offer the robot to the nodes' side and wait until its nodes are launched.

        Raises:
            NodesStopped: if the nodes could not start (their solution failed to load).
            LinkError: if the nodes' side broke the exchange.
        """
        topics = [
            [pub.node.name, name, pub.type, bool(pub.latch)] for name, pub in self._offered.items()
        ]
        services = [
            [record.node.name, name, record.type] for name, record in self._services.items()
        ]
        try:
            params = json.loads(json.dumps(self.graph.get_param("/")))
        except (TypeError, ValueError):  # a value JSON cannot carry: the nodes go without
            params = {}
        send(
            self.sock,
            {
                "k": "hello",
                "version": VERSION,
                "namespace": self.bot.namespace,
                "t": self.graph.now_ns,
                "params": params,
                "topics": topics,
                "services": services,
            },
        )
        header, _ = self._receive()
        if header["k"] != "ready":
            self._unexpected(header, "ready")

    def advance(self, stop_ns: int, until_finished: bool = False) -> bool:
        """Run both sides up to ``stop_ns`` (or until the mission node has returned).

        Returns:
            Whether the nodes' side said its mission finished (only with ``until_finished``).

        Raises:
            NodesStopped: if a node stopped the nodes' side (a crash, a stalled node).
            LinkError: if the nodes' side broke the exchange.
        """
        graph = self.graph
        t = graph.now_ns
        while True:
            if self._stopped is not None:
                raise self._stopped
            graph.run_to(t)
            due = self._nodes_next is not None and self._nodes_next <= t
            if (self._outbox or due) and self._exchange(t):
                continue  # the nodes published, or subscribed: the robot answers at t
            if until_finished and self.finished:
                return True
            upcoming = [n for n in (graph.next_event_ns(), self._nodes_next) if n is not None]
            following = min(upcoming) if upcoming else stop_ns
            if following > stop_ns:
                graph.run_to(stop_ns)
                if graph.now_ns > self._exchanged_at:
                    self._exchange(stop_ns)  # the nodes' clock reads the same
                return False
            t = following

    def end(self, ended: bool) -> Optional[NodesStopped]:
        """Tell the nodes' side the run is over and take its last messages and its log.

        Returns:
            What stopped the nodes' side, when its code failed while shutting down or earlier.
        """
        send(self.sock, {"k": "end", "ended": bool(ended)})
        while True:
            header, body = self._receive()
            if header["k"] == "bye":
                return self._bye(header, body)
            self._unexpected(header, "bye")

    # The exchange.

    def _exchange(self, t: int) -> bool:
        """Hand the nodes' side the time ``t`` and what it subscribed to; take its answer.

        Returns:
            Whether the answer brought messages or subscriptions (the robot's graph then has
            more to do at ``t``).
        """
        outbox = self._outbox[:]  # the link's subscriptions hold this list: emptied in place
        self._outbox.clear()
        send(
            self.sock,
            {"k": "advance", "t": t, "msgs": [[topic, len(data)] for topic, data in outbox]},
            [data for _, data in outbox],
        )
        self._exchanged_at = t
        while True:
            header, body = self._receive()
            kind = header["k"]
            if kind == "call":
                self._answer_call(header, body)
            elif kind == "idle":
                break
            elif kind == "bye":
                raise self._bye(header, body) or NodesStopped(
                    "mission", "The nodes stopped before the mission's end."
                )
            else:
                self._unexpected(header, "idle")
        following = header.get("next")
        if following is not None and (type(following) is not int or following < t):
            raise LinkError("the nodes' side gave a time in the past for its next step")
        self._nodes_next = following
        self.finished = header.get("finished") is True
        return self._take_answer(header, body) or bool(self._outbox)

    def launch(self, part: str) -> None:
        """Launch the solution's node ``part`` (``"light_service_node"``) on the nodes' side.

        Raises:
            NodesStopped: if the nodes' side cannot (the part is missing or unfinished).
            LinkError: if the nodes' side broke the exchange.
        """
        send(self.sock, {"k": "launch", "part": part})
        header, body = self._await("idle")
        following = header.get("next")
        if following is not None and type(following) is not int:
            raise LinkError("the nodes' side gave no time for its next step")
        self._nodes_next = following
        self._take_answer(header, body)

    def _take_answer(self, header: Dict[str, Any], body: bytes) -> bool:
        """Take in what an answer of the nodes' side carries; whether it brought anything."""
        self._take_log(header.get("log"))
        self._take_registrations(header.get("nodes"), header.get("services"))
        busy = self._take_publishers(header.get("pubs", []))
        busy |= self._take_subscriptions(header.get("subs", []))
        return self._take_messages(header.get("msgs", []), body) or busy

    def _await(self, wanted: str) -> Tuple[Dict[str, Any], bytes]:
        """The next frame of kind ``wanted``, answering the nodes' service calls meanwhile."""
        while True:
            header, body = self._receive()
            if header["k"] == "call":
                self._answer_call(header, body)
            elif header["k"] == wanted:
                return header, body
            else:
                self._unexpected(header, wanted)

    def _bye(self, header: Dict[str, Any], body: bytes) -> Optional[NodesStopped]:
        self._take_publishers(header.get("pubs", []))
        self._take_messages(header.get("msgs", []), body)
        self.graph.run_to(self.graph.now_ns)  # the last commands reach the drivers
        self._take_log(header.get("log"))
        crash = header.get("crash")
        if (
            isinstance(crash, list)
            and len(crash) == 2
            and crash[0] in ("solution", "mission")
            and isinstance(crash[1], str)
        ):
            return NodesStopped(crash[0], crash[1][:2000])
        return None

    def _take_publishers(self, announced: Any) -> bool:
        """Make the robot's graph a publisher for each topic the nodes started publishing."""
        from duckielib.messages import get_message_class

        if not isinstance(announced, list):
            raise LinkError("the nodes' side announced its publishers wrongly")
        for item in announced:
            if not (isinstance(item, list) and len(item) == 3):
                raise LinkError("the nodes' side announced a publisher wrongly")
            node_name, topic, type_name = item
            if not (_legal_global(node_name) and _legal_global(topic)):
                raise LinkError("the nodes' side announced a name that is not a ROS name")
            if topic in self._publishers or topic in self.refused:
                continue
            if len(self._publishers) + len(self.refused) >= TOPIC_LIMIT:
                raise LinkError(f"the nodes publish to more than {TOPIC_LIMIT} topics")
            if topic in self._outputs or topic.startswith(self.bot.namespace + "simulator_node/"):
                self.refused[topic] = "the robot publishes it"
                continue
            try:
                data_class = get_message_class(str(type_name))
            except (DuckielibError, KeyError, ValueError):
                self.refused[topic] = f"its type {str(type_name)[:80]} is not one of the robot's"
                continue
            try:
                self._publish_for(self._host(node_name), topic, data_class)
            except (rospy.ROSException, DuckielibError, TypeError, ValueError) as error:
                self.refused[topic] = str(error)[:200]
        return False

    def _publish_for(self, node: Any, topic: str, data_class: Any) -> Any:
        """A publisher here, on ``node``, for what the nodes publish on ``topic``."""
        with node_context(node):
            publisher = rospy.Publisher(topic, data_class, queue_size=10)
        self._publishers[topic] = publisher
        self._accepted[topic] = data_class
        return publisher

    def _host(self, full_name: str) -> Any:
        """The robot graph's node standing for the nodes' node ``full_name`` (or the link's)."""
        return self._mirror(full_name) or self._node

    def _mirror(self, full_name: str) -> Any:
        """The node of the robot's graph that stands for the nodes' node ``full_name``.

        None when a node of the robot's own has that name.
        """
        mirror = self._mirrors.get(full_name)
        if mirror is not None and not mirror.is_shutdown:
            return mirror
        existing = self.graph.nodes.get(full_name)
        if existing is not None and not existing.is_shutdown:
            return None
        mirror = self._mirrors[full_name] = self.graph.host_node(*_split_name(full_name))
        return mirror

    def _take_log(self, given: Any) -> None:
        """Add the nodes' new log lines to the robot's graph's log (and print them if it does)."""
        records = _log_records(given, self._logged)
        self._logged += sum(len(record.node) + len(record.text) for record in records)
        self.nodes_log += records
        graph = self.graph
        for record in records:
            graph.log.append(record)
            if graph.echo_logs:
                graph.print_log(record)

    def _take_registrations(self, nodes: Any, services: Any) -> None:
        """Mirror the nodes' side's nodes and services in the robot's graph.

        As a master lists them: a node that ended there ends here, and its services with it.
        """
        from duckielib.messages import get_service_class

        if nodes is not None:
            if not (
                isinstance(nodes, list)
                and len(nodes) <= TOPIC_LIMIT
                and all(_legal_global(name) for name in nodes)
            ):
                raise LinkError("the nodes' side listed its nodes wrongly")
            for name in nodes:
                self._mirror(name)
            for name in [name for name in self._mirrors if name not in nodes]:
                self._mirrors.pop(name).shutdown("it ended on the nodes' side")
        if services is None:
            return
        if not (
            isinstance(services, list)
            and len(services) <= TOPIC_LIMIT
            and all(
                isinstance(item, list)
                and len(item) == 3
                and _legal_global(item[0])
                and _legal_global(item[1])
                and isinstance(item[2], str)
                for item in services
            )
        ):
            raise LinkError("the nodes' side listed its services wrongly")
        for node_name, name, type_name in services:
            mirror = self._mirrors.get(node_name)
            if mirror is None or mirror.is_shutdown or name in self.graph.services:
                continue
            try:
                service_class = get_service_class(type_name)
            except (DuckielibError, KeyError, ValueError):
                continue  # a type of the student's own: the robot's side cannot call it
            with node_context(mirror):
                rospy.Service(name, service_class, self._ask_nodes(name, service_class))

    def _ask_nodes(self, name: str, service_class: Any) -> Callable[[Any], Any]:
        """The handler of a mirrored service: the call goes to the nodes' side and back."""
        from duckielib.messages.message import MessageError

        def handle(request: Any) -> Any:
            send(self.sock, {"k": "call", "service": name}, [request.to_bytes()])
            while True:
                header, body = self._receive()
                if header["k"] == "call":
                    self._answer_call(header, body)
                    continue
                if header["k"] == "bye":
                    self._stopped = self._bye(header, body) or NodesStopped(
                        "mission", "The nodes stopped during a service call."
                    )
                    raise rospy.ServiceException("the node stopped")
                if header["k"] != "reply":
                    self._unexpected(header, "reply")
                break
            size = header.get("extra", 0)
            if type(size) is not int or not 0 <= size <= len(body):
                raise LinkError("the nodes' side sized its answer wrongly")
            self._take_answer(header, body[size:])
            if not header.get("ok"):
                raise rospy.ServiceException(str(header.get("error", ""))[:500])
            try:
                return service_class._response_class.from_bytes(body[:size])
            except (MessageError, ValueError, IndexError, struct.error, UnicodeDecodeError):
                raise LinkError(f"the nodes answered {name} with what is not a response") from None

        return handle

    def _watch(self, user: Any, publishes: bool) -> None:
        """A node of the robot's graph made a publisher: send its topic if the nodes want it."""
        if publishes and user.name in self._wanted and not isinstance(user, _Forward):
            self._forward(user.name)

    def _take_subscriptions(self, topics: Any) -> bool:
        """Send the nodes each robot topic they subscribed to (a latched message at once)."""
        if not isinstance(topics, list) or not all(isinstance(topic, str) for topic in topics):
            raise LinkError("the nodes' side announced its subscriptions wrongly")
        before = len(self._outbox)
        truth = self.bot.namespace + "simulator_node/"
        for topic in topics:
            if topic in self._forwarded or topic.startswith(truth) or not _legal_global(topic):
                continue
            self._wanted.add(topic)
            record = self.graph.topics.get(topic)
            mine = set(self._publishers.values())
            if record is not None and any(pub not in mine for pub in record.publishers):
                self._forward(topic)
        return len(self._outbox) > before

    def _forward(self, topic: str) -> None:
        """Send the nodes' side every message published here on ``topic`` from now on."""
        self._wanted.discard(topic)
        self._forwarded.add(topic)
        with node_context(self._node):
            _Forward(topic, self._outbox)

    def _take_messages(self, listed: Any, body: bytes) -> bool:
        """Publish on the robot's graph what the nodes published (each message decoded first)."""
        from duckielib.messages.message import MessageError

        if not isinstance(listed, list) or not all(
            isinstance(item, list) and len(item) == 2 and isinstance(item[0], str)
            for item in listed
        ):
            raise LinkError("the nodes' side listed its messages wrongly")
        pieces = _cut(body, [item[1] for item in listed])
        self._taken += len(body)
        if self._taken > TAKEN_LIMIT:
            raise LinkError(f"the nodes published more than {TAKEN_LIMIT // 1024**2} MB")
        for (topic, _), data in zip(listed, pieces):
            publisher = self._publishers.get(topic)
            if publisher is None:
                continue  # refused, or never announced: it stays on the nodes' side
            if publisher._record is None:  # the node that published it ended here
                publisher = self._publish_for(self._node, topic, self._accepted[topic])
            try:
                publisher.data_class.from_bytes(data)
            except (MessageError, ValueError, IndexError, struct.error, UnicodeDecodeError):
                raise LinkError(
                    f"the nodes sent a message on {topic} that is not a {publisher.type}"
                ) from None
            _deliver(publisher._record, data)
        return bool(listed)

    def _answer_call(self, header: Dict[str, Any], body: bytes) -> None:
        """Call the robot's service for a node of the nodes' side, and send back its answer."""
        from duckielib.messages.message import MessageError

        name = header.get("service")
        record = self._services.get(name) if isinstance(name, str) else None
        if record is None or not isinstance(name, str):
            raise LinkError("the nodes called a service the robot does not offer")
        try:
            request = record.service_class._request_class.from_bytes(body)
        except (MessageError, ValueError, IndexError, struct.error, UnicodeDecodeError):
            raise LinkError(f"the nodes sent {name} a request not of {record.type}") from None
        caller = self._callers.get(name)
        if caller is None:
            with node_context(self._node):
                caller = self._callers[name] = rospy.ServiceProxy(name, record.service_class)
        try:
            response = caller(request)
        except rospy.ServiceException as error:
            send(self.sock, {"k": "reply", "ok": False, "error": str(error)[:500]})
            return
        send(self.sock, {"k": "reply", "ok": True}, [response.to_bytes()])

    def _receive(self) -> Tuple[Dict[str, Any], bytes]:
        if self.deadline is None:
            return receive(self.sock, self.reply_timeout)
        left = self.deadline - time.monotonic()
        if left <= 0:
            raise OutOfWallTime("the run's wall-clock time is over")
        try:
            return receive(self.sock, min(self.reply_timeout, left))
        except LinkError:
            if self.deadline - time.monotonic() <= 0:
                raise OutOfWallTime("the run's wall-clock time is over") from None
            raise

    def _unexpected(self, header: Dict[str, Any], wanted: str) -> None:
        if header["k"] == "bye":
            raise self._bye(header, b"") or NodesStopped(
                "mission", "The nodes stopped before the mission's end."
            )
        raise LinkError(f"the nodes' side sent {header['k'][:20]!r} where {wanted!r} was due")


# -- the nodes' side --------------------------------------------------------------------------


class NodesLink:
    """The nodes' side: a graph of their own that follows the robot's clock.

    Args:
        sock: the connected socket to the robot's side.
        graph: the graph the nodes run on.

    Attributes:
        launcher: called with a solution part's name when the robot's side asks to launch it
            (``RobotLink.launch``); None refuses such requests.
    """

    def __init__(self, sock: socket.socket, graph: Any) -> None:
        self.sock = sock
        self.graph = graph
        self.launcher: Optional[Callable[[str], None]] = None
        self._outbox: List[Tuple[str, bytes]] = []
        self._announced: List[List[str]] = []
        self._subscribed: List[str] = []
        self._published: Set[str] = set()
        self._mine: Set[int] = set()  # the link's own publishers and subscriptions, by id
        self._offered: Dict[str, Any] = {}  # robot topic -> its publisher on this graph
        self._asked: Set[str] = set()
        self._listed: Tuple[Any, Any] = (None, None)  # the nodes and services last told
        self._sent_log = 0  # how many of the graph's log lines were sent
        self._log_size = 0
        header, _ = receive(sock, None)
        if header["k"] != "hello" or header.get("version") != VERSION:
            raise LinkError("the other side is not the virtual Duckiebot's link")
        self.namespace: str = header["namespace"]
        os.environ["VEHICLE_NAME"] = self.namespace.strip("/")
        graph.set_param("/", header.get("params") or {})
        graph.run_to(int(header["t"]))
        self._node = graph.host_node("nodes_link", self.namespace)
        self._robot_nodes: Set[str] = {self._node.name}

        def host(full: str) -> Any:
            if full not in self._robot_nodes:
                self._robot_nodes.add(full)
                graph.host_node(*_split_name(full))
            return graph.nodes[full]

        from duckielib.messages import get_message_class, get_service_class

        for node_name, topic, type_name, latch in header.get("topics", []):
            with node_context(host(node_name)):
                publisher = rospy.Publisher(
                    topic, get_message_class(type_name), latch=latch, queue_size=1
                )
            self._mine.add(id(publisher))
            self._offered[topic] = publisher
        for node_name, name, type_name in header.get("services", []):
            service_class = get_service_class(type_name)
            with node_context(host(node_name)):
                rospy.Service(name, service_class, self._remote(name, service_class))
        graph.topic_watchers.append(self._watch)

    def ready(self) -> None:
        """Say the nodes are launched: the run may start."""
        send(self.sock, {"k": "ready"})

    def _watch(self, user: Any, publishes: bool) -> None:
        """A node made a publisher or a subscriber: take what the other side needs of it."""
        if id(user) in self._mine or isinstance(user, _Forward):
            return
        topic = user.name
        if publishes:
            if topic not in self._published:
                self._published.add(topic)
                self._announced.append([user.node.name, topic, user.type])
                with node_context(self._node):
                    forward = _Forward(topic, self._outbox)
                self._mine.add(id(forward))
        elif topic not in self._asked:
            self._asked.add(topic)
            self._subscribed.append(topic)

    def _remote(self, name: str, service_class: Any) -> Callable[[Any], Any]:
        """The handler of a robot's service here: the call goes to the robot and back."""

        def call(request: Any) -> Any:
            send(self.sock, {"k": "call", "service": name}, [request.to_bytes()])
            while True:
                header, body = receive(self.sock, None)
                if header["k"] == "reply":
                    break
                if header["k"] != "call":
                    raise LinkError(f"the robot sent {header['k'][:20]!r} where a reply was due")
                self._answer(header, body)  # the robot's service calls one of ours
            if not header.get("ok"):
                raise rospy.ServiceException(str(header.get("error", "")))
            return service_class._response_class.from_bytes(body)

        return call

    def serve(self, finished: Callable[[], bool]) -> bool:
        """Follow the robot's clock, and answer its calls and launches, until it ends the run.

        Returns:
            Whether the robot's side said the mission ended.

        Raises:
            NodeCrashed: if a node's code failed or stalled (the run stops).
            LinkError: if the robot's side broke the exchange.
        """
        graph = self.graph
        while True:
            header, body = receive(self.sock, None)
            kind = header["k"]
            if kind == "end":
                return bool(header.get("ended"))
            if kind == "call":
                self._answer(header, body)
                continue
            if kind == "launch":
                if self.launcher is None:
                    raise LinkError("the robot asked to launch a node, which this side cannot")
                self.launcher(str(header.get("part")))
                self._send("idle", next=graph.next_event_ns(), finished=bool(finished()))
                continue
            if kind != "advance":
                raise LinkError(f"the robot sent {kind[:20]!r} where a step was due")
            t = int(header["t"])
            graph.run_to(t)
            listed = header.get("msgs", [])
            for (topic, _), data in zip(listed, _cut(body, [item[1] for item in listed])):
                publisher = self._offered.get(topic)
                if publisher is not None and publisher.latch:
                    publisher._record.latched[publisher] = data
                record = graph.topics.get(topic)
                if record is not None:
                    _deliver(record, data)
            graph.run_to(t)
            self._send("idle", next=graph.next_event_ns(), finished=bool(finished()))

    def _answer(self, header: Dict[str, Any], body: bytes) -> None:
        """Answer the robot's call of a service one of the nodes offers."""
        name = header.get("service")
        record = self.graph.services.get(name) if isinstance(name, str) else None
        if record is None or not isinstance(name, str) or record.node.name in self._robot_nodes:
            self._send("reply", ok=False, error=f"service [{name}] unavailable")
            return
        try:
            with node_context(self._node):
                caller = rospy.ServiceProxy(name, record.service_class)
            response = caller(record.service_class._request_class.from_bytes(body))
        except rospy.ServiceException as error:
            # As the handler said it: the caller's side says it cannot process the request.
            said, prefix = str(error), "service cannot process request: "
            said = said[len(prefix) :] if said.startswith(prefix) else said
            self._send("reply", ok=False, error=said)
            return
        self._send("reply", extra=response.to_bytes(), ok=True)

    def bye(self, crash: Optional[Tuple[str, str]]) -> None:
        """Hand over the last messages (a shutdown's zero command), log lines, and the crash.

        ``crash`` is what stopped the nodes, if something did.
        """
        self._send("bye", crash=list(crash) if crash else None)

    def _new_log(self) -> List[List[Any]]:
        """The graph's log lines not yet sent, as ``[time, level, node, text]``."""
        log = self.graph.log
        kept: List[List[Any]] = []
        while self._sent_log < len(log) and self._log_size <= LOG_LIMIT:
            record = log[self._sent_log]
            self._sent_log += 1
            self._log_size += len(record.text) + len(record.node)
            kept.append([record.time, record.level, record.node, record.text])
        return kept

    def _registrations(self) -> Dict[str, Any]:
        """The nodes and services of this side, when they changed since last told."""
        graph = self.graph
        nodes = sorted(
            name
            for name, node in graph.nodes.items()
            if not node.is_shutdown and name not in self._robot_nodes
        )
        services = sorted(
            [record.node.name, name, record.type]
            for name, record in graph.services.items()
            if record.node.name in nodes
        )
        if (nodes, services) == self._listed:
            return {}
        self._listed = (nodes, services)
        return {"nodes": nodes, "services": services}

    def _send(self, kind: str, extra: Optional[bytes] = None, **fields: Any) -> None:
        """Send an answer: ``fields``, then ``extra`` bytes and the messages published.

        It carries what the nodes published and subscribed to since the last answer, and their
        nodes and services when they changed.
        """
        outbox = self._outbox[:]  # the link's subscriptions hold this list: emptied in place
        self._outbox.clear()
        announced, self._announced = self._announced, []
        subscribed, self._subscribed = self._subscribed, []
        header = {
            "k": kind,
            "pubs": announced,
            "subs": subscribed,
            "msgs": [[topic, len(data)] for topic, data in outbox],
            **self._registrations(),
            **fields,
        }
        log = self._new_log()
        if log:
            header["log"] = log
        blobs = [data for _, data in outbox]
        if extra is not None:
            header["extra"] = len(extra)
            blobs.insert(0, extra)
        send(self.sock, header, blobs)
