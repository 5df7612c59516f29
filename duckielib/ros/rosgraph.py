"""What ``rqt_graph`` shows: the nodes, topics and services of a graph and who connects to what.

``rqt_graph`` draws the live graph of a robot: a node that has finished is gone from it. A
notebook often wants the whole story instead: the talker that sent ten messages and returned
still published ``/chatter``. The graph remembers every connection its nodes ever made
(:class:`~duckielib.ros.node.ConnectionHistory`), so :func:`ros_graph` can give either::

    from duckielib.ros import ros_graph

    ros_graph()                 # everything over the run, finished nodes marked as such
    ros_graph(over_run=False)   # only what is connected now, as rqt_graph on a robot
    ros_graph(topics=["/chatter"]).publishers("/chatter")

The result is a :class:`GraphSnapshot`, plain data; :func:`duckielib.plots.rosgraph.plot_ros_graph`
draws it.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

import fnmatch
from dataclasses import dataclass
from typing import Dict, Iterable, List, Optional, Set, Tuple

from duckielib.ros import names
from duckielib.ros.exceptions import ROSException
from duckielib.ros.graph import Graph, current_graph

__all__ = [
    "EDGE_ENDS",
    "HIDDEN",
    "GraphEdge",
    "GraphNode",
    "GraphService",
    "GraphSnapshot",
    "GraphTopic",
    "ros_graph",
]

#: The names :func:`ros_graph` hides by default (shell patterns, as :mod:`fnmatch` reads them):
#: the nodes the course's own tools create, which no student wrote. ``rostopic.echo`` and
#: ``rostopic.hz`` run a node ``/rostopic_N``, ``rosservice.call`` a node ``/rosservice_N``,
#: a bag recorder (``duckielib.bags.record``) a node ``/record_N``, and the notebook's image
#: view (``duckielib.plots.ImageView``) a node ``/rqt_image_view_N``.
HIDDEN: Tuple[str, ...] = (
    "/rostopic_[0-9]*",
    "/rosservice_[0-9]*",
    "/record_[0-9]*",
    "/rqt_image_view_[0-9]*",
)

#: What each kind of edge joins, (source, target): a publisher node to its topic, a topic to a
#: subscriber node, a client node to the service it called, a service to the node serving it.
EDGE_ENDS: Dict[str, Tuple[str, str]] = {
    "publish": ("node", "topic"),
    "subscribe": ("topic", "node"),
    "call": ("node", "service"),
    "serve": ("service", "node"),
}


@dataclass(frozen=True)
class GraphNode:
    """A node: its global name, and whether it still runs (False: it has finished)."""

    name: str
    running: bool


@dataclass(frozen=True)
class GraphTopic:
    """A topic: its global name and message type (``package/Type``)."""

    name: str
    type: str


@dataclass(frozen=True)
class GraphService:
    """A service: its global name and service type (``package/Type``)."""

    name: str
    type: str


@dataclass(frozen=True)
class GraphEdge:
    """An arrow of the graph, from ``source`` to ``target``.

    ``kind`` says what the two names are (see :data:`EDGE_ENDS`): ``"publish"`` goes from a
    node to a topic, ``"subscribe"`` from a topic to a node, ``"call"`` from a node to a
    service, ``"serve"`` from a service to the node that offers it.
    """

    source: str
    target: str
    kind: str


@dataclass(frozen=True)
class GraphSnapshot:
    """The nodes, topics and services of a graph, and the edges between them.

    Nodes, topics and services are sorted by name; edges by kind, then by their ends' names.

    Attributes:
        nodes: the nodes, running or finished.
        topics: the topics.
        services: the services.
        edges: the arrows between them.
        time: the graph's simulated time when the snapshot was taken, in seconds.
        over_run: True if it holds everything since the graph started, False if only what
            was connected at ``time``.
        hidden: the names of the nodes left out (see :data:`HIDDEN`).
    """

    nodes: Tuple[GraphNode, ...]
    topics: Tuple[GraphTopic, ...]
    services: Tuple[GraphService, ...]
    edges: Tuple[GraphEdge, ...]
    time: float = 0.0
    over_run: bool = True
    hidden: Tuple[str, ...] = ()

    def __repr__(self) -> str:
        finished = sum(not node.running for node in self.nodes)
        when = "over the run until" if self.over_run else "at"
        counts = ", ".join(
            f"{len(items)} {word}{'' if len(items) == 1 else 's'}"
            for items, word in (
                (self.topics, "topic"),
                (self.services, "service"),
                (self.edges, "edge"),
            )
        )
        return (
            f"<GraphSnapshot {when} t={self.time:.3f} s: {len(self.nodes)} "
            f"node{'' if len(self.nodes) == 1 else 's'} ({finished} finished), {counts}>"
        )

    def node(self, name: str) -> GraphNode:
        """The node named ``name`` (a global name).

        Raises:
            KeyError: if the snapshot has no such node.
        """
        for node in self.nodes:
            if node.name == name:
                return node
        raise KeyError(f"no node {name} in this snapshot")

    def _ends(self, kind: str, name: str, outgoing: bool) -> List[str]:
        if outgoing:
            return [edge.target for edge in self.edges if edge.kind == kind and edge.source == name]
        return [edge.source for edge in self.edges if edge.kind == kind and edge.target == name]

    def publishers(self, topic: str) -> List[str]:
        """The nodes that publish ``topic``, sorted."""
        return self._ends("publish", topic, outgoing=False)

    def subscribers(self, topic: str) -> List[str]:
        """The nodes that subscribe to ``topic``, sorted."""
        return self._ends("subscribe", topic, outgoing=True)

    def clients(self, service: str) -> List[str]:
        """The nodes that called ``service``, sorted."""
        return self._ends("call", service, outgoing=False)

    def servers(self, service: str) -> List[str]:
        """The node that offers ``service`` (a list: empty if nobody offers it now)."""
        return self._ends("serve", service, outgoing=True)


def _connections(
    graph: Graph, over_run: bool
) -> Tuple[Set[GraphEdge], Dict[str, str], Dict[str, str]]:
    """The graph's edges, topic types and service types: connected now, plus the history."""
    edges: Set[GraphEdge] = set()
    topic_types: Dict[str, str] = {}
    service_types: Dict[str, str] = {}
    history = graph.history
    if over_run:
        topic_types.update(history.topic_types)
        service_types.update(history.service_types)
        for node, topic in history.publishes:
            edges.add(GraphEdge(node, topic, "publish"))
        for node, topic in history.subscribes:
            edges.add(GraphEdge(topic, node, "subscribe"))
        for node, service in history.serves:
            edges.add(GraphEdge(service, node, "serve"))
    for topic, record in graph.topics.items():
        topic_types[topic] = record.type
        for publisher in record.publishers:
            edges.add(GraphEdge(publisher.node.name, topic, "publish"))
        for subscriber in record.subscribers:
            edges.add(GraphEdge(topic, subscriber.node.name, "subscribe"))
    for service, server in graph.services.items():
        service_types[service] = server.type
        edges.add(GraphEdge(service, server.node.name, "serve"))
    running = {name for name, node in graph.nodes.items() if not node.is_shutdown}
    for node, service in history.calls:
        # Now, a call is a connection while its caller runs and the service is offered.
        if over_run or (node in running and service in graph.services):
            service_types.setdefault(service, history.service_types.get(service, ""))
            edges.add(GraphEdge(node, service, "call"))
    return edges, topic_types, service_types


def _ends_of(edge: GraphEdge) -> Tuple[Tuple[str, str], Tuple[str, str]]:
    """The edge's two vertices, each as (what it is, its name)."""
    source, target = EDGE_ENDS[edge.kind]
    return (source, edge.source), (target, edge.target)


def _chosen(
    names_given: Optional[Iterable[str]], known: Dict[str, str], ever: Dict[str, str], what: str
) -> Set[str]:
    """The global names of ``names_given``, each added to ``known`` with its type.

    Raises:
        ROSException: for a name the graph never had.
    """
    chosen = set()
    for given in names_given or ():
        name = names.canonical(names.resolve(given, "/"))
        if name not in known and name not in ever:
            everything = ", ".join(sorted(set(known) | set(ever))) or "none yet"
            raise ROSException(
                f"Unknown {what} {given}: the graph never had it. Known: {everything}."
            )
        known.setdefault(name, ever.get(name, ""))
        chosen.add(name)
    return chosen


def ros_graph(
    graph: Optional[Graph] = None,
    over_run: bool = True,
    topics: Optional[Iterable[str]] = None,
    services: Optional[Iterable[str]] = None,
    hide: Iterable[str] = HIDDEN,
) -> GraphSnapshot:
    """The nodes, topics and services of a graph and who connects to what, as ``rqt_graph``.

    Args:
        graph: the graph (default: the current one).
        over_run: True to include what nodes did before they finished (they are marked as not
            running); False for only what is connected now, as ``rqt_graph`` on a live robot.
        topics: only these topics and the nodes at their ends; None for all. A name without
            a leading slash is taken from the root (``chatter`` is ``/chatter``).
        services: only these services and the nodes at their ends. None means every service
            when ``topics`` is None too, and no service when ``topics`` names some.
        hide: shell patterns of node, topic and service names to leave out, such as
            ``"/duckiebot/camera_node*"``; by default the nodes of the course's tools
            (:data:`HIDDEN`). A topic or service that only hidden nodes used goes with them.
            Give ``()`` to show everything.

    Returns:
        The snapshot.

    Raises:
        ROSException: if ``topics`` or ``services`` names one the graph never had.
    """
    graph = graph if graph is not None else current_graph()
    history = graph.history
    edges, types, service_types = _connections(graph, over_run)
    running = {name for name, node in graph.nodes.items() if not node.is_shutdown}
    nodes = running | {name for edge in edges for kind, name in _ends_of(edge) if kind == "node"}
    if over_run:
        nodes |= set(history.nodes)
    patterns = tuple(hide)

    def hidden(name: str) -> bool:
        return any(fnmatch.fnmatchcase(name, pattern) for pattern in patterns)

    selected = topics is not None or services is not None
    if selected:
        shown = {
            "topic": _chosen(topics, types, history.topic_types, "topic"),
            "service": _chosen(services, service_types, history.service_types, "service"),
        }
    else:
        shown = {
            "topic": {name for name in types if not hidden(name)},
            "service": {name for name in service_types if not hidden(name)},
        }
    shown["node"] = {name for name in nodes if not hidden(name)}
    kept = {edge for edge in edges if all(name in shown[kind] for kind, name in _ends_of(edge))}
    ends = {vertex for edge in kept for vertex in _ends_of(edge)}
    if selected:  # the chosen topics and services, and the nodes at their ends
        shown["node"] = {name for kind, name in ends if kind == "node"}
        reaching = [
            ends_of
            for ends_of in map(_ends_of, edges)
            if any(name in shown[kind] for kind, name in ends_of if kind != "node")
        ]
        left_out = {
            name for pair in reaching for kind, name in pair if kind == "node" and hidden(name)
        }
    else:  # a topic or service that only hidden nodes used goes with them
        for kind in ("topic", "service"):
            had_users = {name for edge in edges for what, name in _ends_of(edge) if what == kind}
            shown[kind] -= {name for name in had_users if (kind, name) not in ends}
        left_out = {name for name in nodes if hidden(name)}
    return GraphSnapshot(
        nodes=tuple(GraphNode(name, name in running) for name in sorted(shown["node"])),
        topics=tuple(GraphTopic(name, types[name]) for name in sorted(shown["topic"])),
        services=tuple(
            GraphService(name, service_types[name]) for name in sorted(shown["service"])
        ),
        edges=tuple(sorted(kept, key=lambda edge: (edge.kind, edge.source, edge.target))),
        time=graph.time,
        over_run=over_run,
        hidden=tuple(sorted(left_out)),
    )
