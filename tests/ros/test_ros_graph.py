"""The ROS graph: its history of connections, ros_graph's snapshots of it (now and over the
run), and plot_ros_graph's rqt_graph-like drawing of them (matplotlib's Agg backend, headless)."""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")

import pytest
from matplotlib.figure import Figure
from matplotlib.text import Annotation

from duckielib.bags import BagRecorder
from duckielib.messages import ChangePattern, String
from duckielib.plots.canvas import NotebookFigure
from duckielib.plots.rosgraph import EDGE_GID, LEGEND_GID, plot_ros_graph
from duckielib.ros import Graph, GraphSnapshot, ros_graph, rospy, rosservice, rostopic
from duckielib.ros.context import node_context
from duckielib.ros.rosgraph import HIDDEN, GraphEdge, GraphNode, GraphService, GraphTopic
from duckielib.sim import VirtualDuckiebot

VEH = "/duckiebot/"
SET_PATTERN = VEH + "led_emitter_node/set_pattern"


def talker():
    """The tutorials' hello world: three messages on chatter, then the node returns."""
    rospy.init_node("talker")
    pub = rospy.Publisher("chatter", String, queue_size=10)
    for count in range(3):
        rospy.sleep(0.5)
        pub.publish(String(data=f"hello world {count}"))


def listener(heard):
    rospy.init_node("listener")
    rospy.Subscriber("chatter", String, lambda message: heard.append(message.data), queue_size=10)
    rospy.spin()


def blinker():
    """A node that asks the LED emitter for red, then returns."""
    rospy.init_node("blinker")
    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=1.0)
    set_pattern = rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)
    set_pattern(String("RED"))
    set_pattern(String("GREEN"))


@pytest.fixture
def graph():
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    yield graph
    graph.shutdown()


@pytest.fixture
def chatter(graph):
    """A graph where the talker has said its three lines and finished; the listener runs on."""
    heard = []
    graph.launch(talker)
    graph.launch(listener, heard)
    graph.run(3.0)
    assert heard == ["hello world 0", "hello world 1", "hello world 2"]
    assert "/talker" not in graph.nodes
    return graph


@pytest.fixture
def bot(monkeypatch):
    monkeypatch.delenv("VEHICLE_NAME", raising=False)
    bot = VirtualDuckiebot(seed=3, graph=Graph(stdout=io.StringIO(), stderr=io.StringIO()))
    yield bot
    bot.shutdown()


def test_over_the_run_a_finished_talker_still_publishes_chatter(chatter):
    snapshot = ros_graph(chatter)
    assert isinstance(snapshot, GraphSnapshot)
    assert snapshot.nodes == (GraphNode("/listener", True), GraphNode("/talker", False))
    assert snapshot.topics == (GraphTopic("/chatter", "std_msgs/String"),)
    assert snapshot.services == ()
    assert snapshot.edges == (
        GraphEdge("/talker", "/chatter", "publish"),
        GraphEdge("/chatter", "/listener", "subscribe"),
    )
    assert snapshot.publishers("/chatter") == ["/talker"]
    assert snapshot.subscribers("/chatter") == ["/listener"]
    assert not snapshot.node("/talker").running
    assert snapshot.time == 3.0
    assert snapshot.over_run
    assert repr(snapshot) == (
        "<GraphSnapshot over the run until t=3.000 s: 2 nodes (1 finished), 1 topic, "
        "0 services, 2 edges>"
    )


def test_now_chatter_has_no_publisher(chatter):
    snapshot = ros_graph(chatter, over_run=False)
    assert snapshot.nodes == (GraphNode("/listener", True),)
    assert snapshot.topics == (GraphTopic("/chatter", "std_msgs/String"),)
    assert snapshot.edges == (GraphEdge("/chatter", "/listener", "subscribe"),)
    assert snapshot.publishers("/chatter") == []
    with pytest.raises(KeyError, match="no node /talker"):
        snapshot.node("/talker")


def test_the_default_graph_is_the_current_one(chatter):
    assert ros_graph() == ros_graph(chatter)


def test_connections_are_recorded_once_not_per_message(chatter):
    history = chatter.history
    assert history.publishes == {("/talker", "/chatter")}
    assert history.subscribes == {("/listener", "/chatter")}
    assert history.topic_types == {"/chatter": "std_msgs/String"}
    assert sorted(history.nodes) == ["/listener", "/talker"]
    assert history.nodes["/talker"].is_shutdown


def test_a_finished_node_is_gone_now_but_kept_over_the_run(graph):
    graph.launch(talker)
    graph.run(3.0)
    assert ros_graph(graph, over_run=False) == GraphSnapshot(
        (), (), (), (), time=3.0, over_run=False
    )
    snapshot = ros_graph(graph)
    assert snapshot.nodes == (GraphNode("/talker", False),)
    assert snapshot.edges == (GraphEdge("/talker", "/chatter", "publish"),)


def test_the_notebooks_own_node_counts_as_a_client(bot):
    rospy.init_node("notebook")
    set_pattern = rospy.ServiceProxy(SET_PATTERN, ChangePattern)
    for color in ("RED", "GREEN", "BLUE"):
        set_pattern(String(color))
    assert bot.graph.history.calls == {("/notebook", SET_PATTERN)}
    snapshot = ros_graph(bot.graph, over_run=False, services=[SET_PATTERN])
    assert snapshot.edges == (
        GraphEdge("/notebook", SET_PATTERN, "call"),
        GraphEdge(SET_PATTERN, VEH + "led_emitter_node", "serve"),
    )
    assert snapshot.clients(SET_PATTERN) == ["/notebook"]
    assert snapshot.servers(SET_PATTERN) == [VEH + "led_emitter_node"]
    assert snapshot.services == (GraphService(SET_PATTERN, "duckietown_msgs/ChangePattern"),)


def test_the_virtual_duckiebots_drivers_and_a_client(bot):
    bot.launch(blinker)
    bot.run(0.5)
    snapshot = ros_graph(bot.graph)
    edges = set(snapshot.edges)
    kinematics, wheels = VEH + "kinematics_node", VEH + "wheels_driver_node"
    assert GraphEdge(kinematics, wheels + "/wheels_cmd", "publish") in edges
    assert GraphEdge(wheels + "/wheels_cmd", wheels, "subscribe") in edges
    assert GraphEdge(VEH + "car_cmd_switch_node/cmd", kinematics, "subscribe") in edges
    assert GraphEdge(SET_PATTERN, VEH + "led_emitter_node", "serve") in edges
    assert GraphEdge(VEH + "blinker", SET_PATTERN, "call") in edges
    assert snapshot.publishers(VEH + "left_wheel_encoder_node/tick") == [
        VEH + "left_wheel_encoder_node"
    ]
    # Nobody publishes the joystick's topic on the virtual robot: it is drawn all the same.
    assert snapshot.publishers(VEH + "joy_mapper_node/car_cmd") == []
    wheels_cmd = GraphTopic(wheels + "/wheels_cmd", "duckietown_msgs/WheelsCmdStamped")
    assert wheels_cmd in snapshot.topics
    assert len(snapshot.topics) == 12  # the wall contact too: the simulator's, as its truth
    assert [service.name for service in snapshot.services] == [
        VEH + "led_emitter_node/set_custom_pattern",
        SET_PATTERN,
    ]
    assert [node.name for node in snapshot.nodes if not node.running] == [VEH + "blinker"]
    assert len(snapshot.nodes) == 10
    # Now, the finished blinker's call is no connection any more.
    now = ros_graph(bot.graph, over_run=False)
    assert [edge for edge in now.edges if edge.kind == "call"] == []
    assert VEH + "blinker" not in [node.name for node in now.nodes]


def test_the_tools_nodes_are_hidden_by_default(bot, tmp_path):
    assert HIDDEN == (
        "/rostopic_[0-9]*",
        "/rosservice_[0-9]*",
        "/record_[0-9]*",
        "/rqt_image_view_[0-9]*",
    )
    before = ros_graph(bot.graph)
    rosservice.call(SET_PATTERN, pattern_name=String("RED"))
    rostopic.echo(VEH + "left_wheel_encoder_node/tick")
    with BagRecorder(
        tmp_path / "run.bag", topics=[VEH + "kinematics_node/velocity"], graph=bot.graph
    ):
        bot.run(0.1)
    after = ros_graph(bot.graph)
    assert after.nodes == before.nodes
    assert after.edges == before.edges
    recorder, *tools = after.hidden
    assert recorder.startswith("/record_")  # numbered across graphs
    assert tools == ["/rosservice_1", "/rostopic_2"]
    everything = ros_graph(bot.graph, hide=())
    shown = {node.name: node.running for node in everything.nodes}
    assert [shown[name] for name in after.hidden] == [False, False, False]
    assert GraphEdge("/rosservice_1", SET_PATTERN, "call") in everything.edges
    assert GraphEdge(VEH + "left_wheel_encoder_node/tick", "/rostopic_2", "subscribe") in (
        everything.edges
    )
    assert GraphEdge(VEH + "kinematics_node/velocity", recorder, "subscribe") in everything.edges
    assert everything.hidden == ()


def test_a_topic_only_hidden_nodes_used_is_hidden_with_them(chatter):
    with node_context(chatter.host_node("probe")):
        rospy.Subscriber("/probe_only", String, queue_size=1)
        rospy.Subscriber("/chatter", String, queue_size=1)
    snapshot = ros_graph(chatter, hide=("/probe",))  # its topic is not hidden by name
    assert [topic.name for topic in snapshot.topics] == ["/chatter"]
    assert snapshot.subscribers("/chatter") == ["/listener"]
    assert snapshot.hidden == ("/probe",)
    shown = ros_graph(chatter)
    assert [topic.name for topic in shown.topics] == ["/chatter", "/probe_only"]
    assert shown.subscribers("/chatter") == ["/listener", "/probe"]


def test_only_chosen_topics_and_the_nodes_at_their_ends(bot):
    bot.launch(blinker)
    bot.run(0.5)
    wheels_cmd = VEH + "wheels_driver_node/wheels_cmd"
    snapshot = ros_graph(bot.graph, topics=[wheels_cmd])
    assert snapshot.nodes == (
        GraphNode(VEH + "kinematics_node", True),
        GraphNode(VEH + "wheels_driver_node", True),
    )
    assert [topic.name for topic in snapshot.topics] == [wheels_cmd]
    assert snapshot.services == ()
    assert len(snapshot.edges) == 2
    both = ros_graph(bot.graph, topics=[wheels_cmd], services=[SET_PATTERN])
    assert [service.name for service in both.services] == [SET_PATTERN]
    assert [node.name for node in both.nodes] == [
        VEH + "blinker",
        VEH + "kinematics_node",
        VEH + "led_emitter_node",
        VEH + "wheels_driver_node",
    ]
    with pytest.raises(rospy.ROSException, match="Unknown topic /wheels_cmd: the graph never had"):
        ros_graph(bot.graph, topics=["/wheels_cmd"])


def test_a_chosen_topic_nobody_uses_now_is_still_there(chatter):
    chatter.nodes["/listener"].shutdown("done listening")
    snapshot = ros_graph(chatter, over_run=False, topics=["chatter"])
    assert snapshot.topics == (GraphTopic("/chatter", "std_msgs/String"),)
    assert snapshot.nodes == ()
    assert snapshot.edges == ()


# -- the drawing ----------------------------------------------------------------------------
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
    assert len(arrows(ax)) == len(snapshot.edges) == 18  # 17 between the drivers, 1 call
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
