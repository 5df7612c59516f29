"""The equivalent of ``rqt_graph``: nodes, topics and services, drawn top to bottom.

:func:`plot_ros_graph` draws a :class:`~duckielib.ros.rosgraph.GraphSnapshot` (see
:func:`duckielib.ros.ros_graph`): nodes as ellipses, topics as rectangles, services as
green rounded boxes. Solid arrows go from a publisher to its topic and on to each
subscriber; dashed ones from a node that called a service to the service and on to the node
that offers it. A node that has finished is grey, with its connections still drawn.

The layout is layered, as ``rqt_graph``'s, but from top to bottom rather than left to right,
so that a robot's long chains (encoders, odometry, a controller, the kinematics, the wheels)
fit a notebook's width: every arrow points down, except those that close a loop (a controller
that commands the wheels and subscribes to what they report makes one), which go round right
of the drawing.

Like every module of :mod:`duckielib.plots`, the library's only package that imports
matplotlib, it runs on the laptop only.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Dict, Iterable, List, Optional, Set, Tuple, Union

from matplotlib.patches import ConnectionStyle
from matplotlib.path import Path

from duckielib.plots.canvas import NotebookFigure
from duckielib.ros import names
from duckielib.ros.graph import Graph
from duckielib.ros.rosgraph import EDGE_ENDS, HIDDEN, GraphEdge, GraphSnapshot, ros_graph

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.text import Text

__all__ = ["plot_ros_graph"]

#: A vertex of the drawing: (``"node"``, ``"topic"`` or ``"service"``, its global name).
Vertex = Tuple[str, str]

#: How each kind of vertex is drawn: the box around its label.
_BOXES = {
    "node": {"boxstyle": "ellipse,pad=0.25", "facecolor": "#cfe2f3", "edgecolor": "#3d6e99"},
    "topic": {"boxstyle": "square,pad=0.35", "facecolor": "#fce5cd", "edgecolor": "#b45f06"},
    "service": {"boxstyle": "round4,pad=0.35", "facecolor": "#d9ead3", "edgecolor": "#38761d"},
}
#: A finished node: grey box, grey text, grey arrows.
_FINISHED_BOX = {"boxstyle": "ellipse,pad=0.25", "facecolor": "#eeeeee", "edgecolor": "#999999"}
_FINISHED_GREY = "#8a8a8a"
#: The gids of the drawing's parts, to find them among the axes' texts.
VERTEX_GID = "ros-graph-{kind}"
EDGE_GID = "ros-graph-edge"
LEGEND_GID = "ros-graph-legend"

#: Sizes, in inches: a character of a label, the room between boxes in a row, a row, the room
#: between rows, the title's line, the legend's two lines, a lane for an arrow that closes a
#: loop, how far right of the other arrows such an arrow leaves and enters its boxes, the
#: narrowest figure.
_CHAR_IN = 0.066
_GAP_IN = 0.3
_ROW_IN = 0.5
_ROW_GAP_IN = 0.45
_TITLE_IN = 0.45
_LEGEND_IN = 0.6
_LANE_IN = 0.14
_DROP_IN = 0.07
_MIN_WIDTH_IN = 7.5
_FONT_SIZE = 8
#: How many times the layers are re-ordered to uncross arrows.
_SWEEPS = 4


# -- layout ---------------------------------------------------------------------------------------
def _ends(edge: GraphEdge) -> Tuple[Vertex, Vertex]:
    """An edge's two vertices, (kind, name) each."""
    source_kind, target_kind = EDGE_ENDS[edge.kind]
    return (source_kind, edge.source), (target_kind, edge.target)


def _acyclic(
    vertices: List[Vertex], links: List[Tuple[Vertex, Vertex]]
) -> Tuple[List[Tuple[Vertex, Vertex]], List[Vertex]]:
    """The links with each one that closes a loop turned around, and a depth-first order.

    A depth-first search from the vertices nobody points to (then from any left), in sorted
    order, meets a loop's last link as one pointing back to a vertex still being searched.
    """
    successors: Dict[Vertex, List[Vertex]] = {vertex: [] for vertex in vertices}
    for source, target in links:
        successors[source].append(target)
    pointed_to = {target for _, target in links}
    searching: Set[Vertex] = set()
    seen: Set[Vertex] = set()
    order: List[Vertex] = []
    backwards: Set[Tuple[Vertex, Vertex]] = set()

    def search(vertex: Vertex) -> None:
        searching.add(vertex)
        seen.add(vertex)
        order.append(vertex)
        for after in sorted(successors[vertex]):
            if after in searching:
                backwards.add((vertex, after))
            elif after not in seen:
                search(after)
        searching.discard(vertex)

    for start in [vertex for vertex in vertices if vertex not in pointed_to] + vertices:
        if start not in seen:
            search(start)
    forward = [(t, s) if (s, t) in backwards else (s, t) for s, t in links]
    return forward, order


def _layers(vertices: List[Vertex], forward: List[Tuple[Vertex, Vertex]]) -> Dict[Vertex, int]:
    """Each vertex's row: one below its furthest predecessor (the longest path to it).

    Then, from the bottom, each vertex that points somewhere moves down to the row just above
    the first vertex it points to, so that a publisher stands just above its topic rather than
    far up.
    """
    before: Dict[Vertex, List[Vertex]] = {vertex: [] for vertex in vertices}
    after: Dict[Vertex, List[Vertex]] = {vertex: [] for vertex in vertices}
    for source, target in forward:
        before[target].append(source)
        after[source].append(target)
    layer: Dict[Vertex, int] = {}

    def depth(vertex: Vertex) -> int:
        if vertex not in layer:
            layer[vertex] = 1 + max((depth(earlier) for earlier in before[vertex]), default=-1)
        return layer[vertex]

    for vertex in vertices:
        depth(vertex)
    for vertex in sorted(vertices, key=layer.__getitem__, reverse=True):
        if after[vertex]:
            layer[vertex] = min(layer[later] for later in after[vertex]) - 1
    return layer


def _rows(
    vertices: List[Vertex], links: List[Tuple[Vertex, Vertex]]
) -> Tuple[List[List[Vertex]], Dict[Vertex, int]]:
    """The vertices in rows, top to bottom, each ordered left to right to uncross arrows.

    Loops are broken, rows given by the longest path, then a few sweeps sort each row by the
    mean place of its neighbours in the rows already placed (the barycenter).

    Returns:
        The rows, and each vertex's row.
    """
    forward, order = _acyclic(vertices, links)
    layer = _layers(vertices, forward)
    rows: List[List[Vertex]] = [[] for _ in range(max(layer.values(), default=-1) + 1)]
    for vertex in order:
        rows[layer[vertex]].append(vertex)
    neighbours: Tuple[Dict[Vertex, List[Vertex]], Dict[Vertex, List[Vertex]]] = (
        {vertex: [] for vertex in vertices},
        {vertex: [] for vertex in vertices},
    )
    for source, target in forward:
        neighbours[0][target].append(source)
        neighbours[1][source].append(target)
    for sweep in range(_SWEEPS):
        down = sweep % 2 == 0
        linked = neighbours[0 if down else 1]
        for row in rows[1:] if down else rows[-2::-1]:
            place = {v: i - (len(r) - 1) / 2 for r in rows for i, v in enumerate(r)}
            keys = {
                vertex: sum(place[other] for other in linked[vertex]) / len(linked[vertex])
                if linked[vertex]
                else place[vertex]
                for vertex in row
            }
            row.sort(key=keys.__getitem__)
    return rows, layer


# -- names ----------------------------------------------------------------------------------------
def _shared_namespace(all_names: Iterable[str]) -> str:
    """The namespace every name lives in (``/duckiebot/``), or ``/`` if they share none."""
    shared: Optional[List[str]] = None
    for name in all_names:
        parts = names.namespace_of(name).strip("/").split("/")
        if shared is None:
            shared = parts
        else:
            count = 0
            while count < min(len(shared), len(parts)) and shared[count] == parts[count]:
                count += 1
            shared = shared[:count]
    return names.normalize_namespace("/".join(shared or []))


def _relative(name: str, namespace: str) -> str:
    return name[len(namespace) :] if namespace != "/" and name.startswith(namespace) else name


def _labels(snapshot: GraphSnapshot, namespace: str) -> Dict[Vertex, str]:
    labels = {
        ("node", node.name): _relative(node.name, namespace)
        + ("" if node.running else "\n(finished)")
        for node in snapshot.nodes
    }
    for kind, items in (("topic", snapshot.topics), ("service", snapshot.services)):
        for item in items:
            labels[(kind, item.name)] = f"{_relative(item.name, namespace)}\n{item.type}"
    return labels


# -- drawing --------------------------------------------------------------------------------------
def _width_in(text: str, kind: str) -> float:
    """About how wide a label's box is, in inches (an ellipse is wider than its text's box)."""
    width = _CHAR_IN * max(len(line) for line in text.split("\n")) + 0.3
    return width * 1.4 if kind == "node" else width


def _place(
    rows: List[List[Vertex]], labels: Dict[Vertex, str], lanes: int
) -> Tuple[Dict[Vertex, Tuple[float, float]], List[Tuple[float, float]], float, float]:
    """Where each vertex goes, in inches from the top left corner (y up, so negative).

    Each row is centred on the widest row's middle. Right of them are ``lanes`` lanes for
    the arrows that close loops; under them, the legend.

    Returns:
        Each vertex's centre, each row's (top, bottom), the drawing's width and height.
    """
    where: Dict[Vertex, Tuple[float, float]] = {}
    spans: List[Tuple[float, float]] = []
    widths = [
        sum(_width_in(labels[vertex], vertex[0]) for vertex in row) + _GAP_IN * (len(row) - 1)
        for row in rows
    ]
    widest = max(widths, default=0.0) + _GAP_IN
    # A small graph stands in the middle of the narrowest figure.
    margin = max(0.0, (_MIN_WIDTH_IN - widest - lanes * _LANE_IN) / 2)
    top = -_TITLE_IN
    for row, row_width in zip(rows, widths):
        left = margin + (widest - row_width) / 2
        for vertex in row:
            width = _width_in(labels[vertex], vertex[0])
            where[vertex] = (left + width / 2, top - _ROW_IN / 2)
            left += width + _GAP_IN
        spans.append((top, top - _ROW_IN))
        top -= _ROW_IN + _ROW_GAP_IN
    width = max(widest + lanes * _LANE_IN, _MIN_WIDTH_IN)
    height = -top - _ROW_GAP_IN + _LEGEND_IN
    return where, spans, width, height


class _Detour(ConnectionStyle.Arc3):
    """The path of an arrow that closes a loop, so that it crosses no box.

    It leaves its source downwards, goes right in the gap under the source's row to a lane
    right of the drawing, up the lane to the gap above its target's row, left, and down into
    its target. ``below``, ``lane`` and ``above`` are in the axes' data coordinates (inches);
    the arrow clips the path at the two boxes.
    """

    def __init__(self, ax: Axes, below: float, lane: float, above: float) -> None:
        super().__init__()
        self.ax, self.route = ax, (below, lane, above)

    def connect(self, posA: Tuple[float, float], posB: Tuple[float, float]) -> Path:  # noqa: N803
        """The path from ``posA`` to ``posB``, both in display coordinates."""
        (x_a, y_a), (x_b, y_b) = self.ax.transData.inverted().transform([posA, posB])
        x_a, x_b = x_a + _DROP_IN, x_b + _DROP_IN
        below, lane, above = self.route
        points = [(x_a, y_a), (x_a, below), (lane, below), (lane, above), (x_b, above), (x_b, y_b)]
        codes = [Path.MOVETO] + [Path.LINETO] * (len(points) - 1)  # clipped right only with codes
        return Path(self.ax.transData.transform(points), codes)


def _draw_edges(
    ax: Axes,
    snapshot: GraphSnapshot,
    boxes: Dict[Vertex, Text],
    layer: Dict[Vertex, int],
    spans: List[Tuple[float, float]],
    lanes_left: float,
) -> None:
    """An arrow per edge, from box edge to box edge; one that closes a loop goes round right."""
    running = {node.name: node.running for node in snapshot.nodes}
    back = 0
    for edge in snapshot.edges:
        source, target = _ends(edge)
        service = edge.kind in ("call", "serve")
        finished = any(kind == "node" and not running[name] for kind, name in (source, target))
        style: object = "arc3"
        if layer[source] > layer[target]:
            shift = 0.08 + 0.06 * (back % 4)  # side by side in the gaps between rows
            lane = lanes_left + (back + 0.5) * _LANE_IN
            below, above = spans[layer[source]][1] - shift, spans[layer[target]][0] + shift
            style = _Detour(ax, below, lane, above)
            back += 1
        ax.annotate(
            "",
            boxes[target].get_position(),
            boxes[source].get_position(),
            arrowprops={
                "arrowstyle": "-|>",
                "mutation_scale": 12,
                "color": _FINISHED_GREY if finished else ("tab:blue" if service else "#333333"),
                "linestyle": "--" if service else "-",
                "shrinkA": 1,
                "shrinkB": 1,
                "patchA": boxes[source].get_bbox_patch(),
                "patchB": boxes[target].get_bbox_patch(),
                "connectionstyle": style,
            },
            gid=EDGE_GID,
            zorder=4,  # drawn after the boxes, which places them: the arrows end at their edges
        )


def _legend(ax: Axes, bottom: float) -> None:
    """Two lines at the bottom: a sample of each box, then what the arrows mean."""
    x = 0.3
    samples = (
        ("node", "node", _BOXES["node"]),
        ("topic", "topic", _BOXES["topic"]),
        ("service", "service", _BOXES["service"]),
        ("node", "finished node", _FINISHED_BOX),
    )
    for kind, text, box in samples:
        color = _FINISHED_GREY if box is _FINISHED_BOX else "black"
        sample = ax.text(x + 0.1, bottom + 0.42, text, ha="left", va="center", fontsize=7)
        sample.set(color=color, bbox=dict(box), gid=LEGEND_GID)
        x += _width_in(text, kind) * 0.9 + 0.35
    ax.text(
        0.3,
        bottom + 0.15,
        "solid arrows: publisher → topic → subscriber;   "
        "dashed arrows: client → service → server (the node that offers it)",
        ha="left",
        va="center",
        fontsize=7,
        gid=LEGEND_GID,
    )


def plot_ros_graph(
    graph: Union[Graph, GraphSnapshot, None] = None,
    *,
    over_run: bool = True,
    topics: Optional[Iterable[str]] = None,
    services: Optional[Iterable[str]] = None,
    hide: Iterable[str] = HIDDEN,
    namespace: Optional[str] = None,
    ax: Optional[Axes] = None,
) -> Axes:
    """Draw the nodes, topics and services of a graph and who connects to what, as ``rqt_graph``.

    Args:
        graph: the graph (default: the current one), or a snapshot of it made by
            :func:`~duckielib.ros.ros_graph` (``over_run``, ``topics``, ``services`` and
            ``hide`` then do not apply).
        over_run: True to draw everything since the graph started, finished nodes in grey;
            False for only what is connected now.
        topics: only these topics and the nodes at their ends (see
            :func:`~duckielib.ros.ros_graph`); None for all.
        services: only these services and the nodes at their ends.
        hide: shell patterns of names to leave out; by default the nodes of the course's tools
            (:data:`~duckielib.ros.rosgraph.HIDDEN`).
        namespace: names are shown relative to it; None for the namespace every name shares
            (``/duckiebot/`` on the virtual Duckiebot), ``"/"`` for full names.
        ax: the axes to draw on (in inches from the top left); a new figure, sized to the
            graph, when None.

    Returns:
        The axes drawn on.
    """
    if isinstance(graph, GraphSnapshot):
        snapshot = graph
    else:
        snapshot = ros_graph(graph, over_run, topics=topics, services=services, hide=hide)
    full = [node.name for node in snapshot.nodes] + [item.name for item in snapshot.topics]
    full += [item.name for item in snapshot.services]
    namespace = (
        _shared_namespace(full) if namespace is None else names.normalize_namespace(namespace)
    )
    labels = _labels(snapshot, namespace)
    rows, layer = _rows(sorted(labels), [_ends(edge) for edge in snapshot.edges])
    loops = sum(layer[source] > layer[target] for source, target in map(_ends, snapshot.edges))
    where, spans, width, height = _place(rows, labels, loops)
    if ax is None:
        ax = NotebookFigure(figsize=(width, height)).add_axes((0, 0, 1, 1))
    finished = {("node", node.name) for node in snapshot.nodes if not node.running}
    boxes = {
        vertex: ax.text(
            x,
            y,
            labels[vertex],
            ha="center",
            va="center",
            fontsize=_FONT_SIZE,
            color=_FINISHED_GREY if vertex in finished else "black",
            bbox=dict(_FINISHED_BOX if vertex in finished else _BOXES[vertex[0]]),
            gid=VERTEX_GID.format(kind=vertex[0]),
            zorder=3,
        )
        for vertex, (x, y) in where.items()
    }
    _draw_edges(ax, snapshot, boxes, layer, spans, width - loops * _LANE_IN)
    when = "over the whole run" if snapshot.over_run else "now"
    title = f"Nodes, topics and services {when} (t = {snapshot.time:.1f} s)"
    if namespace != "/":
        title += f"; names relative to {namespace}"
    if snapshot.hidden:
        count = len(snapshot.hidden)
        left_out = ", ".join(snapshot.hidden) if count <= 3 else f"{count} nodes of the tools"
        title += f"; not shown: {left_out}"
    ax.text(0.2, -_TITLE_IN / 2, title, ha="left", va="center", fontsize=9, gid=LEGEND_GID)
    if not where:
        ax.text(width / 2, -height / 2, "(no nodes yet)", ha="center", va="center", fontsize=9)
    _legend(ax, -height)
    ax.set_xlim(0, width)
    ax.set_ylim(-height, 0)
    ax.axis("off")
    return ax
