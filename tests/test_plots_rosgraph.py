"""plot_ros_graph: the rqt_graph-like drawing of a graph (matplotlib's Agg backend, headless)."""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")

import pytest
from matplotlib.figure import Figure
from matplotlib.text import Annotation

from duckielib.messages import ChangePattern, String
from duckielib.plots.canvas import NotebookFigure
from duckielib.plots.rosgraph import EDGE_GID, LEGEND_GID, plot_ros_graph
from duckielib.ros import Graph, ros_graph, rospy
from duckielib.ros.context import node_context
from duckielib.ros.rosgraph import GraphEdge, GraphNode, GraphSnapshot, GraphTopic
from duckielib.sim import VirtualDuckiebot


def talker():
    rospy.init_node("talker")
    pub = rospy.Publisher("chatter", String, queue_size=10)
    for count in range(3):
        rospy.sleep(0.5)
        pub.publish(String(data=f"hello world {count}"))


def listener():
    rospy.init_node("listener")
    rospy.Subscriber("chatter", String, lambda message: None, queue_size=10)
    rospy.spin()


@pytest.fixture
def graph():
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    yield graph
    graph.shutdown()


@pytest.fixture
def chatter(graph):
    graph.launch(talker)
    graph.launch(listener)
    graph.run(3.0)
    return graph


def boxes(ax):
    """The label of each node, topic and service drawn, with its centre."""
    return {
        text.get_text(): text.get_position()
        for text in ax.texts
        if (text.get_gid() or "").startswith("ros-graph-")
        and text.get_gid() not in (EDGE_GID, LEGEND_GID)
    }


def arrows(ax):
    return [
        text for text in ax.texts if isinstance(text, Annotation) and text.get_gid() == EDGE_GID
    ]


def legend(ax):
    return " ".join(text.get_text() for text in ax.texts if text.get_gid() == LEGEND_GID)


def rendered(ax) -> bytes:
    figure = ax.figure
    assert isinstance(figure, Figure)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png")
    return buffer.getvalue()


def test_a_finished_talker_its_topic_and_the_listener_top_to_bottom(chatter):
    ax = plot_ros_graph(chatter)
    assert isinstance(ax.figure, NotebookFigure)
    where = boxes(ax)
    assert sorted(where) == ["/chatter\nstd_msgs/String", "/listener", "/talker\n(finished)"]
    talker_y = where["/talker\n(finished)"][1]
    topic_y = where["/chatter\nstd_msgs/String"][1]
    assert talker_y > topic_y > where["/listener"][1]  # y up: each row under the one before
    assert len(arrows(ax)) == len(ros_graph(chatter).edges) == 2
    for part in ("node", "topic", "service", "finished node", "over the whole run (t = 3.0 s)"):
        assert part in legend(ax)
    finished = next(text for text in ax.texts if text.get_text() == "/talker\n(finished)")
    assert finished.get_bbox_patch().get_facecolor()[:3] == pytest.approx(
        (0.933, 0.933, 0.933), abs=0.01
    )
    assert rendered(ax).startswith(b"\x89PNG")


def test_now_the_topic_is_drawn_without_a_publisher(chatter):
    ax = plot_ros_graph(chatter, over_run=False)
    assert sorted(boxes(ax)) == ["/chatter\nstd_msgs/String", "/listener"]
    assert len(arrows(ax)) == 1
    assert "now (t = 3.0 s)" in legend(ax)


def test_a_snapshot_on_given_axes(chatter):
    snapshot = ros_graph(chatter)
    ax = NotebookFigure().add_subplot()
    assert plot_ros_graph(snapshot, ax=ax) is ax
    assert "/talker\n(finished)" in boxes(ax)


def test_the_virtual_duckiebot_relative_to_its_namespace(monkeypatch):
    monkeypatch.delenv("VEHICLE_NAME", raising=False)
    bot = VirtualDuckiebot(graph=Graph(stdout=io.StringIO(), stderr=io.StringIO()))
    try:
        with node_context(bot.graph.host_node("blinker", "/duckiebot")):
            rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)(String("RED"))
        snapshot = ros_graph(bot.graph)
        ax = plot_ros_graph(bot.graph)
    finally:
        bot.shutdown()
    where = boxes(ax)
    assert len(where) == len(snapshot.nodes) + len(snapshot.topics) + len(snapshot.services)
    assert len(arrows(ax)) == len(snapshot.edges) == 17  # 16 between the drivers, 1 call
    assert "names relative to /duckiebot/" in legend(ax)
    kinematics = where["kinematics_node"][1]
    wheels_cmd = where["wheels_driver_node/wheels_cmd\nduckietown_msgs/WheelsCmdStamped"][1]
    set_pattern = where["led_emitter_node/set_pattern\nduckietown_msgs/ChangePattern"][1]
    assert kinematics > wheels_cmd > where["wheels_driver_node"][1]
    assert where["blinker"][1] > set_pattern > where["led_emitter_node"][1]
    dashed = [arrow for arrow in arrows(ax) if arrow.arrow_patch.get_linestyle() == "--"]
    assert len(dashed) == 3  # blinker -> set_pattern, both services -> led_emitter_node
    assert rendered(ax).startswith(b"\x89PNG")


def test_full_names_when_the_nodes_share_no_namespace(graph):
    with node_context(graph.host_node("driver", "/duckiebot")):
        rospy.Subscriber("/duckiebot/cmd", String, queue_size=1)
    with node_context(graph.host_node("joystick")):
        rospy.Publisher("/duckiebot/cmd", String, queue_size=1)
    ax = plot_ros_graph(graph)
    assert sorted(boxes(ax)) == [
        "/duckiebot/cmd\nstd_msgs/String",
        "/duckiebot/driver",
        "/joystick",
    ]
    assert "names relative" not in legend(ax)
    relative = plot_ros_graph(graph, namespace="duckiebot")
    assert sorted(boxes(relative)) == ["/joystick", "cmd\nstd_msgs/String", "driver"]


def test_a_loop_is_laid_out_with_each_vertex_once(graph):
    """controller -> /cmd -> wheels -> /executed -> controller, and a logger of /executed."""
    with node_context(graph.host_node("controller")):
        rospy.Publisher("/cmd", String, queue_size=1)
        rospy.Subscriber("/executed", String, queue_size=1)
    with node_context(graph.host_node("wheels")):
        rospy.Subscriber("/cmd", String, queue_size=1)
        rospy.Publisher("/executed", String, queue_size=1)
    with node_context(graph.host_node("logger")):
        rospy.Subscriber("/executed", String, queue_size=1)
    ax = plot_ros_graph(graph)
    labels = [
        text.get_text()
        for text in ax.texts
        if text.get_gid() in ("ros-graph-node", "ros-graph-topic")
    ]
    assert sorted(labels) == [
        "/cmd\nstd_msgs/String",
        "/controller",
        "/executed\nstd_msgs/String",
        "/logger",
        "/wheels",
    ]
    where = boxes(ax)
    y = {label.split("\n")[0]: position[1] for label, position in where.items()}
    assert y["/controller"] > y["/cmd"] > y["/wheels"] > y["/executed"] > y["/logger"]
    assert len(arrows(ax)) == 5
    # The arrow that closes the loop goes round right of the boxes, back to the controller.
    rightmost = max(position[0] for position in where.values())
    rendered(ax)
    back = next(arrow for arrow in arrows(ax) if arrow.xy == where["/controller"])
    path = back.arrow_patch.get_path().vertices
    in_data = ax.transData.inverted().transform(path)
    assert in_data[:, 0].max() > rightmost + 0.1


def test_a_topic_nobody_uses_and_an_empty_graph_are_drawn(graph):
    lonely = GraphSnapshot(
        nodes=(GraphNode("/talker", False),),
        topics=(GraphTopic("/chatter", "std_msgs/String"), GraphTopic("/news", "std_msgs/String")),
        services=(),
        edges=(GraphEdge("/talker", "/chatter", "publish"),),
    )
    ax = plot_ros_graph(lonely)
    assert sorted(boxes(ax)) == [
        "/chatter\nstd_msgs/String",
        "/news\nstd_msgs/String",
        "/talker\n(finished)",
    ]
    assert len(arrows(ax)) == 1
    empty = plot_ros_graph(graph)
    assert boxes(empty) == {}
    assert "(no nodes yet)" in [text.get_text() for text in empty.texts]
    assert rendered(empty).startswith(b"\x89PNG")
