"""The ROS command-line tools, as functions that read the live in-process graph.

Each mirrors the command a ROS user types in a terminal, and prints like it when shown in a
notebook::

    from duckielib.ros import rostopic, rosnode, rosservice, rosmsg, rossrv, rosparam

    rostopic.list()                          # $ rostopic list
    rostopic.info("/duckiebot/left_wheel_encoder_node/tick")
    rostopic.echo("/chatter", count=2)       # runs the graph until two messages arrive
    rostopic.hz("/duckiebot/left_wheel_encoder_node/tick", duration=2.0)
    rosservice.call("/duckiebot/led_emitter_node/set_pattern", pattern_name=String("RED"))
    rosmsg.show("duckietown_msgs/WheelEncoderStamped")

Results are ordinary Python values (lists and strings) that display as the terminal would.
"""

from __future__ import annotations

import math
from typing import Any, Callable, Dict, List, Optional, Type

from duckielib import messages
from duckielib.errors import UnknownTypeError
from duckielib.messages.message import Message
from duckielib.ros import names
from duckielib.ros.context import node_context
from duckielib.ros.exceptions import ROSException
from duckielib.ros.graph import Graph, current_graph
from duckielib.ros.node import Node

__all__ = ["Printout", "Names", "rosmsg", "rosnode", "rosparam", "rosservice", "rossrv", "rostopic"]


class Printout(str):
    """Text that a notebook shows as a terminal would (no quotes, real line breaks)."""

    def __repr__(self) -> str:
        return str(self)

    def _repr_pretty_(self, printer: Any, cycle: bool) -> None:
        printer.text(str(self))


class Names(list):
    """A list of names that a notebook shows one per line, as ``rostopic list`` does."""

    def __repr__(self) -> str:
        return "\n".join(self)

    def _repr_pretty_(self, printer: Any, cycle: bool) -> None:
        printer.text(repr(self))


def _graph(graph: Optional[Graph]) -> Graph:
    return graph if graph is not None else current_graph()


def _bullets(items: List[str]) -> str:
    return "\n".join(f" * {item}" for item in items) if items else " None"


def tool_node(graph: Graph, tool: str) -> Node:
    """An anonymous node for a tool (``rostopic``, a notebook's image view), as ROS's tools make.

    The graph drawing hides the course's tools' nodes (see :data:`duckielib.ros.rosgraph.HIDDEN`).
    """
    node = Node(graph, tool + graph.anonymous_suffix(), "/")
    graph.nodes[node.name] = node
    graph.history.add_node(node)
    return node


def topic_record(graph: Graph, name: str) -> Any:
    """What the master knows of topic ``name``.

    Raises:
        ROSException: if no node publishes or subscribes to it (naming those there are).
    """
    record = graph.topics.get(names.canonical(name))
    if record is None:
        known = ", ".join(sorted(graph.topics)) or "none yet"
        raise ROSException(
            f"Unknown topic {name}: no node publishes or subscribes to it. Topics: {known}."
        )
    return record


def _listen(
    graph: Graph, topic: str, callback: Callable[[Message], Any], run: Callable[[], Any]
) -> Any:
    """Subscribe a ``rostopic`` tool node to ``topic``, call ``run()``, then remove the node.

    Returns:
        The topic's record.
    """
    from duckielib.ros.rospy import Subscriber

    record = topic_record(graph, topic)
    node = tool_node(graph, "rostopic")
    with node_context(node):
        Subscriber(record.name, record.data_class, callback)
    try:
        run()
    finally:
        node.shutdown("rostopic finished")
    return record


def _nested_messages(message_class: Type[Message], fields: Dict[str, Any]) -> Dict[str, Any]:
    """``fields`` with dicts given for message-typed fields turned into those messages.

    ``rosservice call`` takes YAML such as ``pattern_name: {data: RED}``; here the same is
    ``pattern_name={"data": "RED"}``.
    """
    types = dict(zip(message_class.__slots__, message_class._slot_types))
    converted = dict(fields)
    for key, value in fields.items():
        slot_type = types.get(key, "")
        if isinstance(value, dict) and "/" in slot_type and not slot_type.endswith("]"):
            nested = messages.get_message_class(slot_type)
            converted[key] = nested(**_nested_messages(nested, value))
    return converted


def _expand(full_name: str, indent: str = "") -> List[str]:
    """A message's fields, nested types expanded, as ``rosmsg show`` prints them."""
    spec = messages.REGISTRY.message(full_name)
    lines = [f"{indent}{c.type} {c.name}={c.value_text}" for c in spec.constants]
    for field in spec.fields:
        lines.append(f"{indent}{field.type} {field.name}")
        if not field.is_primitive:
            lines += _expand(field.base_type, indent + "  ")
    return lines


class rostopic:  # noqa: N801 - named after the command
    """``rostopic``: topics, their types, publishers, subscribers, messages and rates."""

    @staticmethod
    def list(graph: Optional[Graph] = None) -> Names:
        """Every topic someone publishes or subscribes to, sorted (``rostopic list``)."""
        return Names(sorted(_graph(graph).topics))

    @staticmethod
    def type(topic: str, graph: Optional[Graph] = None) -> Printout:
        """The message type of a topic (``rostopic type``)."""
        return Printout(topic_record(_graph(graph), topic).type)

    @staticmethod
    def info(topic: str, graph: Optional[Graph] = None) -> Printout:
        """Type, publishers and subscribers of a topic (``rostopic info``)."""
        record = topic_record(_graph(graph), topic)
        publishers = sorted({item.node.name for item in record.publishers})
        subscribers = sorted({item.node.name for item in record.subscribers})
        return Printout(
            f"Type: {record.type}\n\nPublishers:\n{_bullets(publishers)}\n\n"
            f"Subscribers:\n{_bullets(subscribers)}"
        )

    @staticmethod
    def echo(
        topic: str, count: int = 1, timeout: float = 10.0, graph: Optional[Graph] = None
    ) -> Printout:
        """Run the graph until ``count`` messages arrive on a topic and show them.

        Args:
            topic: the topic's name.
            count: how many messages to wait for.
            timeout: the longest wait, in simulated seconds.
            graph: the graph (default: the current one).

        Raises:
            ROSException: if fewer messages arrive before the timeout.
        """
        graph = _graph(graph)
        received: List[Message] = []
        record = _listen(
            graph,
            topic,
            received.append,
            lambda: graph.run_until(lambda: len(received) >= count, timeout),
        )
        if len(received) < count:
            raise ROSException(
                f"Only {len(received)} of {count} messages arrived on {record.name} within "
                f"{timeout} s of simulated time; is a node publishing it?"
            )
        return Printout("\n".join(f"{message}\n---" for message in received[:count]))

    @staticmethod
    def hz(topic: str, duration: float = 2.0, graph: Optional[Graph] = None) -> Printout:
        """Measure how often messages arrive on a topic, over ``duration`` simulated seconds."""
        graph = _graph(graph)
        arrivals: List[float] = []
        record = _listen(
            graph, topic, lambda _: arrivals.append(graph.time), lambda: graph.run(duration)
        )
        if len(arrivals) < 2:
            return Printout(f"no new messages on {record.name} in {duration} s")
        gaps = [later - earlier for earlier, later in zip(arrivals, arrivals[1:])]
        mean = sum(gaps) / len(gaps)
        spread = math.sqrt(sum((gap - mean) ** 2 for gap in gaps) / len(gaps))
        return Printout(
            f"average rate: {1.0 / mean:.3f}\n\tmin: {min(gaps):.3f}s max: {max(gaps):.3f}s "
            f"std dev: {spread:.5f}s window: {len(arrivals)}"
        )


class rosnode:  # noqa: N801
    """``rosnode``: the nodes and what each publishes, subscribes to and offers."""

    @staticmethod
    def list(graph: Optional[Graph] = None) -> Names:
        """Every running node, sorted (``rosnode list``)."""
        return Names(sorted(_graph(graph).nodes))

    @staticmethod
    def info(node_name: str, graph: Optional[Graph] = None) -> Printout:
        """A node's publications, subscriptions and services (``rosnode info``)."""
        graph = _graph(graph)
        node = graph.nodes.get(names.canonical(node_name))
        if node is None:
            known = ", ".join(sorted(graph.nodes)) or "none"
            raise ROSException(f"Unknown node {node_name}. Running nodes: {known}.")
        publications = sorted({f"{p.name} [{p.type}]" for p in node.publishers})
        subscriptions = sorted({f"{s.name} [{s.type}]" for s in node.subscribers})
        services = sorted(service.name for service in node.services)
        return Printout(
            "-" * 80 + f"\nNode [{node.name}]\nPublications:\n{_bullets(publications)}\n\n"
            f"Subscriptions:\n{_bullets(subscriptions)}\n\nServices:\n{_bullets(services)}"
        )


class rosservice:  # noqa: N801
    """``rosservice``: the services, their types, and calling them."""

    @staticmethod
    def list(graph: Optional[Graph] = None) -> Names:
        """Every offered service, sorted (``rosservice list``)."""
        return Names(sorted(_graph(graph).services))

    @staticmethod
    def type(service: str, graph: Optional[Graph] = None) -> Printout:
        """A service's type (``rosservice type``)."""
        return Printout(rosservice._record(_graph(graph), service).type)

    @staticmethod
    def info(service: str, graph: Optional[Graph] = None) -> Printout:
        """Who offers a service, its type and its request fields (``rosservice info``)."""
        record = rosservice._record(_graph(graph), service)
        request = record.service_class._request_class
        return Printout(
            f"Node: {record.node.name}\nType: {record.type}\nArgs: {' '.join(request.__slots__)}"
        )

    @staticmethod
    def call(service: str, *args: Any, graph: Optional[Graph] = None, **fields: Any) -> Printout:
        """Call a service with a request built from ``args`` or ``fields`` and show the reply."""
        from duckielib.ros.rospy import ServiceProxy

        graph = _graph(graph)
        record = rosservice._record(graph, service)
        node = tool_node(graph, "rosservice")
        try:
            with node_context(node):
                request = record.service_class._request_class
                fields = _nested_messages(request, fields)
                response = ServiceProxy(record.name, record.service_class)(*args, **fields)
        finally:
            node.shutdown("rosservice call finished")
        return Printout(str(response))

    @staticmethod
    def _record(graph: Graph, service: str) -> Any:
        record = graph.services.get(names.canonical(service))
        if record is None:
            known = ", ".join(sorted(graph.services)) or "none"
            raise ROSException(f"Unknown service {service}. Services: {known}.")
        return record


class rosmsg:  # noqa: N801
    """``rosmsg``: the fields of a message type."""

    @staticmethod
    def show(message_type: str) -> Printout:
        """The fields of a message type, nested types expanded (``rosmsg show``).

        Raises:
            UnknownTypeError: if the course has no such type.
        """
        return Printout("\n".join(_expand(message_type)))

    info = show

    @staticmethod
    def list() -> Names:
        """Every message type the course knows (``rosmsg list``)."""
        return Names(messages.message_types())


class rossrv:  # noqa: N801
    """``rossrv``: the request and response fields of a service type."""

    @staticmethod
    def show(service_type: str) -> Printout:
        """Request fields, ``---``, response fields (``rossrv show``).

        Raises:
            UnknownTypeError: if the course has no such type.
        """
        if service_type not in messages.REGISTRY.services:
            raise UnknownTypeError(
                f"There is no service type {service_type!r}; known types are: "
                f"{', '.join(messages.service_types())}."
            )
        spec = messages.REGISTRY.services[service_type]
        lines = [*_expand(spec.request.full_name), "---", *_expand(spec.response.full_name)]
        return Printout("\n".join(lines))

    info = show

    @staticmethod
    def list() -> Names:
        """Every service type the course knows (``rossrv list``)."""
        return Names(messages.service_types())


class rosparam:  # noqa: N801
    """``rosparam``: reading and listing parameters."""

    @staticmethod
    def get(name: str, graph: Optional[Graph] = None) -> Any:
        """A parameter's value, or a dict for a namespace (``rosparam get``).

        Raises:
            KeyError: if it is not set.
        """
        return _graph(graph).get_param(names.canonical(name))

    @staticmethod
    def set(name: str, value: Any, graph: Optional[Graph] = None) -> None:
        """Set a parameter (``rosparam set``)."""
        _graph(graph).set_param(names.canonical(name), value)

    @staticmethod
    def list(graph: Optional[Graph] = None) -> Names:
        """Every parameter's name (``rosparam list``)."""
        return Names(_graph(graph).param_names())
