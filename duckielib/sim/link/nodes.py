"""The nodes' side of the link: a graph of their own that follows the robot's clock.

See :mod:`duckielib.sim.link`.
"""

from __future__ import annotations

import os
import socket
from typing import Any, Callable, Dict, List, Optional, Set, Tuple

from duckielib.ros import rospy
from duckielib.ros.context import node_context
from duckielib.sim.link.wire import (
    LOG_LIMIT,
    VERSION,
    LinkError,
    _cut,
    _deliver,
    _Forward,
    _split_name,
    receive,
    send,
)

__all__ = ["NodesLink"]


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
        self._seen: Tuple[int, int, int] = (-1, -1, -1)  # the graph's counts when last looked
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
            listed = header.get("msgs", [])
            if listed:  # what is due before the messages' arrival runs first
                graph.run_to(t)
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
        # Nodes come, end, or offer services rarely: look again only when their counts moved.
        seen = (len(graph.nodes), graph.nodes_shut_down, len(graph.services))
        if seen == self._seen:
            return {}
        self._seen = seen
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
