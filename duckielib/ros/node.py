"""A node on the in-process graph, and the topic and service records the graph keeps.

Node code never uses these classes directly: it calls rospy's functions
(:mod:`duckielib.ros.rospy`), which find the calling node (:mod:`duckielib.ros.context`) and
act on it. A node knows its graph only as a ``Host``: the few things it asks of it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, Dict, List, Optional, Set, Tuple, Type

from duckielib.ros import names
from duckielib.ros.context import node_context
from duckielib.ros.exceptions import ROSException
from duckielib.ros.log import ERROR, INFO, format_error

if TYPE_CHECKING:
    from typing import Protocol

    from duckielib.messages.message import Message, Service

    class Host(Protocol):
        """What a node, and rospy's handles of it, need of the graph they live on."""

        topics: Dict[str, TopicRecord]
        services: Dict[str, ServiceRecord]
        history: ConnectionHistory
        topic_watchers: List[Callable[[Any, bool], None]]

        @property
        def time(self) -> float: ...

        @property
        def now_ns(self) -> int: ...

        def schedule(self, t_ns: int, action: Callable[[], None]) -> Any: ...

        def call_soon(self, action: Callable[[], None]) -> Any: ...

        def run_callback(self, node: Node, topic: str, call: Callable[[], None]) -> bool: ...

        def block(
            self, deadline_ns: Optional[int], predicate: Callable[[], bool], polled: bool = True
        ) -> bool: ...

        def driving_here(self) -> bool: ...

        def log_message(self, level: int, node: str, text: str) -> None: ...

        def node_shut_down(self) -> None: ...

        def remove_node(self, node: Node) -> None: ...


__all__ = ["ConnectionHistory", "Node", "ServiceRecord", "TopicRecord"]


class TopicRecord:
    """What the master knows of a topic: its type, publishers, subscribers, latched messages."""

    def __init__(self, name: str, data_class: Type[Message]) -> None:
        self.name = name
        self.data_class = data_class
        self.publishers: List[Any] = []
        self.subscribers: List[Any] = []
        self.latched: Dict[Any, bytes] = {}
        self.message_count = 0
        self._header: Dict[str, str] = {}
        self._header_key: Tuple[Any, ...] = ()
        #: The publisher whose message is being handed to the subscribers (None: a message
        #: from outside the graph).
        self.sender: Any = None

    @property
    def type(self) -> str:
        """The topic's message type, ``package/Type``."""
        return self.data_class._type

    def connection_header(self) -> Dict[str, str]:
        """What a ROS 1 connection header says of this topic (a copy, to keep)."""
        return dict(self.shared_connection_header())

    def shared_connection_header(self) -> Dict[str, str]:
        """The connection header, one dict shared by the messages subscribers receive.

        rospy gives every message of a connection the same dict; it changes here only when
        the topic's publishers do.
        """
        key = (self.data_class, *self.publishers)
        if self._header_key != key:
            self._header, self._header_key = self._make_connection_header(), key
        return self._header

    def _make_connection_header(self) -> Dict[str, str]:
        callers = [publisher.node.name for publisher in self.publishers]
        return {
            "topic": self.name,
            "type": self.data_class._type,
            "md5sum": self.data_class._md5sum,
            "message_definition": self.data_class._full_text,
            "callerid": callers[0] if callers else "",
            "latching": "1" if any(publisher.latch for publisher in self.publishers) else "0",
        }

    def delivery_header(self) -> Dict[str, str]:
        """The connection header of the message being delivered now.

        As in rospy, each publisher's connection has its own header: its node as ``callerid``,
        its ``latching``, and the ``headers`` it was created with (which may override the
        others). A message from outside the graph gets the topic's shared header.
        """
        sender = self.sender
        if sender is None:
            return self.shared_connection_header()
        header: Optional[Dict[str, str]] = getattr(sender, "_connection_header", None)
        if header is None or header.get("topic") != self.name:
            header = {
                **self._make_connection_header(),
                "callerid": sender.node.name,
                "latching": "1" if sender.latch else "0",
                **sender.headers,
            }
            sender._connection_header = header
        return header

    def check_type(self, data_class: Type[Message], role: str, node: str) -> None:
        """Refuse a publisher or subscriber whose message type differs from the topic's.

        A subscriber with ``AnyMsg`` accepts any type; a topic known only to such subscribers
        takes the type of its first publisher or typed subscriber.

        Raises:
            ROSException: naming both types and who uses the topic.
        """
        if data_class._md5sum == "*":
            return
        if self.data_class._md5sum == "*":
            self.data_class = data_class
            return
        if data_class._md5sum == self.data_class._md5sum and data_class._type == self.type:
            return
        users = sorted({item.node.name for item in self.publishers + self.subscribers})
        raise ROSException(
            f"Topic {self.name} carries {self.type} (used by {', '.join(users)}), so "
            f"{node} cannot {role} it with {data_class._type}. Use the topic's type, "
            "or another topic name."
        )


class ServiceRecord:
    """What the master knows of a service: its type, handler and node."""

    def __init__(
        self,
        name: str,
        service_class: Type[Service],
        handler: Callable[[Any], Any],
        node: Node,
        error_handler: Optional[Callable[..., Any]],
    ) -> None:
        self.name = name
        self.service_class = service_class
        self.handler = handler
        self.node = node
        self.error_handler = error_handler
        self.call_count = 0

    @property
    def type(self) -> str:
        """The service's type, ``package/Type``."""
        return self.service_class._type


class ConnectionHistory:
    """Every connection the graph's nodes ever made, kept after the nodes shut down.

    The master's records (:class:`TopicRecord`, :class:`ServiceRecord`) say who is connected
    now; this says who ever was, so that a drawing of the graph can show what a node did
    before it finished. Each entry is added once, when a node registers a publisher, a
    subscriber or a service, or first calls a service: never per message.

    Attributes:
        nodes: every node registered, by name (the latest one of a name reused).
        topic_types: each topic's message type, ``package/Type``.
        service_types: each service's type.
        publishes: (node name, topic name) for every publisher ever registered.
        subscribes: (node name, topic name) for every subscriber.
        serves: (node name, service name) for every service offered.
        calls: (node name, service name) for every node that called a service.
    """

    def __init__(self) -> None:
        self.nodes: Dict[str, Node] = {}
        self.topic_types: Dict[str, str] = {}
        self.service_types: Dict[str, str] = {}
        self.publishes: Set[Tuple[str, str]] = set()
        self.subscribes: Set[Tuple[str, str]] = set()
        self.serves: Set[Tuple[str, str]] = set()
        self.calls: Set[Tuple[str, str]] = set()

    def add_node(self, node: Node) -> None:
        """Note a node that registered (it replaces an earlier node of the same name)."""
        self.nodes[node.name] = node

    def add_topic_user(self, node: Node, record: TopicRecord, publishes: bool) -> None:
        """Note that ``node`` publishes (or subscribes to) the topic of ``record``."""
        self.nodes.setdefault(node.name, node)
        if record.type != "*" or record.name not in self.topic_types:  # "*": AnyMsg's
            self.topic_types[record.name] = record.type
        (self.publishes if publishes else self.subscribes).add((node.name, record.name))

    def add_server(self, node: Node, record: ServiceRecord) -> None:
        """Note that ``node`` offers the service of ``record``."""
        self.nodes.setdefault(node.name, node)
        self.service_types[record.name] = record.type
        self.serves.add((node.name, record.name))

    def add_client(self, node: Node, record: ServiceRecord) -> None:
        """Note that ``node`` called the service of ``record``."""
        self.nodes.setdefault(node.name, node)
        self.service_types[record.name] = record.type
        self.calls.add((node.name, record.name))


class Node:
    """A node registered on a graph: its name, namespace, connections and shutdown hooks.

    Attributes:
        name: the node's global name, for example ``/duckiebot/odometry_node``.
        namespace: its namespace with slashes, for example ``/duckiebot/``.
    """

    def __init__(
        self,
        graph: Host,
        name: str,
        namespace: str,
        remappings: Optional[Dict[str, str]] = None,
        log_level: int = INFO,
        init_args: Optional[tuple] = None,
    ) -> None:
        self.graph = graph
        self.namespace = names.normalize_namespace(namespace)
        self.name = names.canonical(self.namespace + name)
        self.remappings = dict(remappings or {})
        self.log_level = log_level
        self.init_args = init_args
        self.publishers: List[Any] = []
        self.subscribers: List[Any] = []
        self.services: List[ServiceRecord] = []
        self.timers: List[Any] = []
        self.shutdown_hooks: List[Callable[[], Any]] = []
        #: What the node's code waits for now (``"service /name"``, ``"a message on /t"``) and
        #: since when (simulated seconds), or None.
        self.waiting_for: Optional[Tuple[str, float]] = None
        #: Whether the node's shutdown hooks are running now, and whether it has closed.
        self.in_shutdown_hooks = False
        self.closed = False
        self.is_shutdown = False
        self.shutdown_reason: Optional[str] = None
        self._log_marks: Dict[Any, float] = {}
        self._log_texts: Dict[Any, str] = {}
        #: Simulated time its main code owes for rospy calls made without waiting, in ns.
        self.compute_debt_ns = 0
        #: Whether it has main code of its own (False for a node that lives in callbacks,
        #: such as a driver): only main code is charged for never waiting.
        self.has_main_code = True

    def __repr__(self) -> str:
        return f"<Node {self.name}{' (shut down)' if self.is_shutdown else ''}>"

    def resolve(self, name: str) -> str:
        """Resolve a topic, service or parameter name as this node sees it."""
        return names.resolve(name, self.namespace, self.name, self.remappings)

    def resolve_param(self, name: str) -> str:
        """Resolve a parameter name (parameters are not remapped)."""
        return names.resolve(name, self.namespace, self.name)

    # -- logging ----------------------------------------------------------------------------
    def log(self, level: int, text: str) -> None:
        """Log a line at ``level`` if the node's level lets it through."""
        if level >= self.log_level:
            self.graph.log_message(level, self.name, text)

    def log_throttled(self, key: Any, period: float, level: int, text: str) -> None:
        """Log at most once per ``period`` simulated seconds for the same call site."""
        last = self._log_marks.get(key)
        if last is None or self.graph.time - last >= period:
            self._log_marks[key] = self.graph.time
            self.log(level, text)

    def log_throttled_identical(self, key: Any, period: float, level: int, text: str) -> None:
        """Log when the text differs from this call site's last, or ``period`` has passed."""
        last = self._log_marks.get(("time", key))
        elapsed = last is None or self.graph.time - last >= period
        if elapsed:
            self._log_marks[("time", key)] = self.graph.time
        changed = self._log_texts.get(key) != text
        self._log_texts[key] = text
        if changed or elapsed:
            self.log(level, text)

    def log_once(self, key: Any, level: int, text: str) -> None:
        """Log only the first time for the same call site."""
        if key not in self._log_marks:
            self._log_marks[key] = self.graph.time
            self.log(level, text)

    # -- connections ------------------------------------------------------------------------
    def topic(self, name: str, data_class: Type[Message], role: str) -> TopicRecord:
        """The record of topic ``name`` (created if new), after checking its type."""
        record = self.graph.topics.get(name)
        if record is None:
            record = self.graph.topics[name] = TopicRecord(name, data_class)
        else:
            record.check_type(data_class, role, self.name)
        return record

    def forget_topic_user(self, record: TopicRecord) -> None:
        """Drop the topic's record once nobody publishes or subscribes to it any more."""
        unused = not record.publishers and not record.subscribers
        if unused and self.graph.topics.get(record.name) is record:
            del self.graph.topics[record.name]

    # -- shutdown ---------------------------------------------------------------------------
    def shutdown(self, reason: str) -> None:
        """Shut the node down: run its hooks, then close its topics, services and timers."""
        self.run_shutdown_hooks(reason)
        self.close()

    def run_shutdown_hooks(self, reason: str) -> None:
        """Mark the node shut down and run its hooks (once); its connections stay open.

        A graph that shuts several nodes down runs every node's hooks before it closes any
        node's topics and services, so that a hook may still call another node's service or
        publish to its subscribers, as it may on a robot, where roslaunch signals every node
        and each ends in its own time.
        """
        if self.is_shutdown:
            return
        self.is_shutdown = True
        self.shutdown_reason = reason
        self.graph.node_shut_down()
        self.in_shutdown_hooks = True
        try:
            with node_context(self):
                for hook in list(self.shutdown_hooks):
                    try:
                        hook()
                    except Exception as error:  # a broken hook must not stop the others
                        self.log(ERROR, "shutdown hook failed:\n" + format_error(error))
        finally:
            self.in_shutdown_hooks = False

    def close(self) -> None:
        """Close the node's timers, topics and services, and leave the graph (once)."""
        if self.closed:
            return
        self.closed = True
        for timer in list(self.timers):
            timer.shutdown()
        for publisher in list(self.publishers):
            publisher.unregister()
        for subscriber in list(self.subscribers):
            subscriber.unregister()
        for service in list(self.services):
            if self.graph.services.get(service.name) is service:
                del self.graph.services[service.name]
        self.services.clear()
        self.graph.remove_node(self)
