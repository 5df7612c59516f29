"""The robot's side of the link: leads the clock, offers the robot, takes in what the nodes send.

See :mod:`duckielib.sim.link`.
"""

from __future__ import annotations

import json
import socket
import struct
import time
from typing import Any, Callable, Dict, List, Optional, Set, Tuple

from duckielib.errors import DuckielibError
from duckielib.ros import rospy
from duckielib.ros.context import node_context
from duckielib.ros.log import LogRecord
from duckielib.sim.link.wire import (
    TAKEN_LIMIT,
    TOPIC_LIMIT,
    VERSION,
    LinkError,
    NodesStopped,
    OutOfWallTime,
    _cut,
    _deliver,
    _Forward,
    _legal_global,
    _log_records,
    _split_name,
    receive,
    send,
)

__all__ = ["RobotLink"]

#: The fields of an answer that says nothing new when they are empty.
_QUIET = frozenset({"k", "next", "finished", "pubs", "subs", "msgs"})


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
        self._publishing = False  # while the link makes a publisher of its own
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
        header, body = self._await("idle")
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
        busy = body or header.get("pubs") or header.get("subs") or header.get("msgs")
        if not (busy or header.keys() - _QUIET):
            return False  # the most common answer: nothing new
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
                self._unexpected(header, wanted, body)

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
        self._publishing = True  # not a publisher of the robot's own: see _watch
        try:
            with node_context(node):
                publisher = rospy.Publisher(topic, data_class, queue_size=10)
        finally:
            self._publishing = False
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
        if publishes and user.name in self._wanted and not self._publishing:
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

    def _unexpected(self, header: Dict[str, Any], wanted: str, body: bytes = b"") -> None:
        if header["k"] == "bye":
            raise self._bye(header, body) or NodesStopped(
                "mission", "The nodes stopped before the mission's end."
            )
        raise LinkError(f"the nodes' side sent {header['k'][:20]!r} where {wanted!r} was due")


# -- the nodes' side --------------------------------------------------------------------------
