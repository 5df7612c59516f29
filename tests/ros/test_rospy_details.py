"""Details of rospy that node code relies on, as Debian's rospy behaves on a robot."""

from __future__ import annotations

import io
import sys

import numpy as np
import pytest

from duckielib.messages import Header, String
from duckielib.ros import Graph, rospy
from duckielib.ros.context import node_context
from duckielib.ros.dtros import DTROS, DTParam, NodeType, ParamType


@pytest.fixture
def graph():
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    yield graph
    graph.shutdown()


def test_a_stamp_compares_with_rospy_time():
    stamp = Header().stamp  # what a message carries
    assert stamp == rospy.Time(0)
    assert stamp < rospy.Time(1)
    assert rospy.Time(2, 5) > Header(stamp=rospy.Time(2)).stamp
    assert hash(stamp) == hash(rospy.Time(0))
    assert {stamp, rospy.Time(0)} == {stamp}
    assert rospy.Time(1) != rospy.Duration(1), "a time is not a duration"
    with pytest.raises(TypeError):
        _ = rospy.Time(1) < rospy.Duration(2)


def test_durations_divide_as_in_rospy():
    assert rospy.Duration(3) // 2 == rospy.Duration(1)  # seconds and nanoseconds apart
    assert rospy.Duration(3, 500_000_000) // 2 == rospy.Duration(1, 250_000_000)
    assert rospy.Duration(3.5) // 2.0 == rospy.Duration(1)
    assert rospy.Duration(7) // rospy.Duration(2) == 3
    assert rospy.Duration(3) / 2 == rospy.Duration(1.5)


def test_the_parameter_server_refuses_what_a_robots_refuses(graph):
    rospy.init_node("tuner")
    rospy.set_param("~gain", 1.5)
    rospy.set_param("~gains", {"left": [1, 2.5, "x", True]})
    assert rospy.get_param("~gains") == {"left": [1, 2.5, "x", True]}
    with pytest.raises(rospy.ROSException, match=r"cannot store a numpy\.float64.*float\(x\)"):
        rospy.set_param("~gain", np.float64(1.5))
    with pytest.raises(rospy.ROSException, match=r"numpy\.ndarray"):
        rospy.set_param("~path", np.zeros(3))
    with pytest.raises(rospy.ROSException, match="cannot store None"):
        rospy.set_param("~nothing", None)
    with pytest.raises(rospy.ROSException, match="32 bits"):
        rospy.set_param("~ticks", 2**40)
    assert rospy.get_param("~gain") == 1.5, "a refused value changes nothing"


def test_myargv_drops_remapping_arguments():
    argv = ["node.py", "--speed", "0.2", "chatter:=/news", "__name:=talker", "_rate:=5"]
    assert rospy.myargv(argv) == ["node.py", "--speed", "0.2"]


def test_init_node_reads_remappings_names_and_private_parameters_from_argv(graph):
    heard = []

    def talker():
        rospy.init_node("talker", argv=["talker.py", "~out:=/news", "__ns:=/duckiebot", "_hz:=4"])
        hz = rospy.get_param("~hz")
        pub = rospy.Publisher("~out", String, queue_size=10)
        rate = rospy.Rate(hz)
        for _ in range(4):
            pub.publish(String(data=rospy.get_name()))
            rate.sleep()

    def listener():
        rospy.init_node("listener")
        rospy.Subscriber("/news", String, lambda msg: heard.append((rospy.get_time(), msg.data)))
        rospy.spin()

    graph.launch(listener)
    graph.launch(talker)
    graph.run(2.0)
    assert heard == [(t, "/duckiebot/talker") for t in (0.0, 0.25, 0.5, 0.75)]
    assert graph.get_param("/duckiebot/talker/hz") == 4


def test_a_private_name_can_be_remapped_at_launch(graph):
    heard = []

    def talker():
        rospy.init_node("talker")
        rospy.Publisher("~chatter", String, queue_size=1, latch=True).publish(String(data="hi"))
        rospy.spin()

    listener = graph.host_node("listener")
    with node_context(listener):
        rospy.Subscriber("/x", String, heard.append)
    graph.launch(talker, remap={"~chatter": "/x"})
    graph.run(0.5)
    assert [msg.data for msg in heard] == ["hi"]


def test_a_subscribe_listener_hears_subscribers_come_and_go(graph):
    events = []

    class Greeter(rospy.SubscribeListener):
        def peer_subscribe(self, topic_name, topic_publish, peer_publish):
            events.append(("subscribe", topic_name))
            peer_publish(String(data="welcome"))  # to the newcomer only

        def peer_unsubscribe(self, topic_name, num_peers):
            events.append(("unsubscribe", topic_name, num_peers))

    rospy.init_node("greeter")
    rospy.Publisher("chatter", String, queue_size=10, subscriber_listener=Greeter())
    first, second = [], []
    sub = rospy.Subscriber("chatter", String, first.append)
    graph.run(0.0)
    rospy.Subscriber("chatter", String, second.append)
    graph.run(0.0)
    sub.unregister()
    assert [msg.data for msg in first] == ["welcome"]
    assert [msg.data for msg in second] == ["welcome"]
    assert events == [
        ("subscribe", "/chatter"),
        ("subscribe", "/chatter"),
        ("unsubscribe", "/chatter", 1),
    ]


def test_a_duckietown_node_with_help_parameters_and_a_switch(graph):
    class Driver(DTROS):
        def __init__(self):
            super().__init__(node_name="driver", node_type=NodeType.CONTROL, help="Drives.")
            self.gain = DTParam("~gain", default=2, param_type=ParamType.FLOAT, min_value=0)
            self.events = []

        def on_switch_off(self):
            self.events.append("off")

        def on_switch_on(self):
            self.events.append("on")

    graph.set_param("/driver/gain", 3)
    node = Driver()
    assert node.node_help == "Drives."
    assert node.gain.value == 3.0
    assert isinstance(node.gain.value, float)
    switch = rospy.ServiceProxy("/driver/switch", node.srv_switch.service_class)
    assert switch(False).success
    assert switch(True).success
    assert node.events == ["off", "on"]
    with pytest.raises(KeyError, match="not found"):
        DTParam("~missing")
    with pytest.raises(ValueError, match="below min_value"):
        DTParam("~speed", default=-1.0, param_type=ParamType.FLOAT, min_value=0.0)


def test_a_received_message_carries_its_connection_header(graph):
    heard = []

    def talker():
        rospy.init_node("talker")
        rospy.Publisher("chatter", String, queue_size=1, latch=True).publish(String(data="hi"))
        rospy.spin()

    graph.launch(talker)
    rospy.init_node("listener")
    rospy.Subscriber("chatter", String, heard.append)
    graph.run(0.1)
    header = heard[0]._connection_header
    assert header["callerid"] == "/talker"
    assert header["topic"] == "/chatter"
    assert header["type"] == "std_msgs/String"
    assert header["md5sum"] == String._md5sum
    assert header["latching"] == "1"


def test_each_publishers_messages_carry_its_own_connection_header(graph):
    # As in rospy: one connection per publisher, each with its node and the headers it gave.
    heard = []

    def talker(name, role, latch):
        def main():
            rospy.init_node(name)
            pub = rospy.Publisher(
                "chatter", String, queue_size=1, latch=latch, headers={"role": role}
            )
            rospy.sleep(0.05)
            pub.publish(String(data=name))
            rospy.spin()

        return main

    graph.launch(talker("left", "scout", latch=False))
    graph.launch(talker("right", "leader", latch=True))
    rospy.init_node("listener")
    rospy.Subscriber("chatter", String, heard.append)
    graph.run(0.1)
    seen = sorted(
        (
            msg.data,
            msg._connection_header["callerid"],
            msg._connection_header["role"],
            msg._connection_header["latching"],
        )
        for msg in heard
    )
    assert seen == [("left", "/left", "scout", "0"), ("right", "/right", "leader", "1")]


def test_a_shutdown_hook_may_sleep_and_call_another_nodes_service(graph):
    # On a robot's wall clock rospy.sleep in a hook sleeps and returns, and the other nodes
    # still answer while each ends: a hook that stops the LEDs through a service works.
    from duckielib.messages import get_service_class

    trigger = get_service_class("std_srvs/Trigger")
    TriggerResponse = trigger._response_class  # noqa: N806
    said = []

    def server():
        rospy.init_node("led_server")
        rospy.Service("lights_off", trigger, lambda request: TriggerResponse(True, "off"))
        rospy.spin()

    def driver():
        rospy.init_node("driver")
        lights_off = rospy.ServiceProxy("lights_off", trigger)

        def on_shutdown():
            rospy.sleep(1.0)
            said.append(lights_off().message)

        rospy.on_shutdown(on_shutdown)
        rospy.spin()

    graph.launch(server)  # launched first: shut down first
    graph.launch(driver)
    graph.run(0.5)
    graph.shutdown()
    assert said == ["off"]
    assert not [r for r in graph.log if r.level >= 40]


def test_throttled_identical_logs_say_what_changed_or_what_stayed_a_while(graph):
    def node():
        rospy.init_node("counter")
        for value in [1, 1, 1, 2, 2, 3] + [3] * 30:
            rospy.loginfo_throttle_identical(2.0, f"value {value}")
            rospy.logfatal_throttle(10.0, "fatal once in 10 s")
            rospy.sleep(0.1)

    graph.launch(node)
    graph.run(4.0)
    texts = [record.text for record in graph.log if "counter" in record.node]
    # The first of each new value, then the unchanged one again each 2 s (rospy's rule).
    assert [text for text in texts if text.startswith("value")] == [
        "value 1",
        "value 2",
        "value 3",
        "value 3",
    ]
    assert texts.count("fatal once in 10 s") == 1


def test_published_topics_and_remapped_names_as_rospy_gives_them(graph):
    found = {}

    def node():
        rospy.init_node("talker", anonymous=False)
        rospy.Publisher("chatter", String, queue_size=1)
        rospy.Publisher("/other/news", String, queue_size=1)
        found["all"] = rospy.get_published_topics()
        found["other"] = rospy.get_published_topics("/other")
        found["remapped"] = rospy.remap_name("chatter")
        found["as_is"] = rospy.remap_name("news")
        found["requested"] = rospy.SUBMODULES["core"].is_shutdown_requested()

    graph.launch(node, namespace="/duckiebot", remap={"chatter": "/talk"})
    graph.run(0.1)
    assert ["/talk", "std_msgs/String"] in found["all"]
    assert found["other"] == [["/other/news", "std_msgs/String"]]
    assert found["remapped"] == "/talk"
    assert found["as_is"] == "news"  # not remapped: left as given, as rospy does
    assert found["requested"] is False


def test_rospys_modules_import_by_their_names():
    from duckielib.ros.modules import modules_installed

    with modules_installed(replace_real=True):
        import rospy as served
        from rospy.exceptions import ROSInterruptException
        from rospy.msg import AnyMsg
        from rospy.names import ns_join
        from rospy.rostime import Duration, Time
        from rospy.timer import TimerEvent

        assert Time is served.Time
        assert Duration is served.Duration
        assert ROSInterruptException is served.ROSInterruptException
        assert AnyMsg is served.AnyMsg
        assert TimerEvent is served.TimerEvent
        assert ns_join("/duckiebot", "odometry_node") == "/duckiebot/odometry_node"
        assert served.Header is Header
        with pytest.raises(AttributeError, match=r"module 'rospy\.rostime' has no attribute 'x'"):
            served.rostime.x  # noqa: B018
    # Uninstalled, none of them is left for a real rospy to meet.
    from duckielib.ros.modules import _aliases, install_modules, uninstall_modules

    served = {id(module) for module in _aliases()["rospy"].values()}
    install_modules(replace_real=True)
    uninstall_modules()
    left = [name for name, module in sys.modules.items() if id(module) in served]
    assert not [name for name in left if not name.startswith("duckielib.")]


def test_a_duckietown_node_reports_its_health_and_lists_its_topics(graph):
    from duckielib.ros.dtros import NodeHealth, TopicType

    seen = {}

    class Detector(DTROS):
        def __init__(self):
            super().__init__(node_name="detector", node_type=NodeType.PERCEPTION)
            self.pub = rospy.Publisher(
                "~detections", String, queue_size=1, dt_topic_type=TopicType.PERCEPTION,
                dt_help="what it found",
            )  # fmt: skip
            self.sub = rospy.Subscriber("~image", String, lambda msg: None, queue_size=1)
            seen["rate"] = rospy.get_param("~rate", 5, dt_help="detections a second")

    def node():
        detector = Detector()
        detector.set_health(NodeHealth.WARNING, "no image yet")
        seen["pubs"] = [publisher.name for publisher in detector.publishers]
        seen["subs"] = [subscriber.name for subscriber in detector.subscribers]
        seen["health"] = detector.health
        with pytest.raises(TypeError, match="unexpected keyword argument 'help'"):
            rospy.get_param("~rate", 5, help="not rospy's")

    graph.launch(node)
    graph.run(0.1)
    assert seen == {
        "rate": 5,
        "pubs": ["/detector/detections"],
        "subs": ["/detector/image"],
        "health": NodeHealth.WARNING,
    }


def test_a_plain_script_calls_a_service_without_init_node(graph):
    from duckielib.messages import std_srvs

    def server():
        rospy.init_node("server")
        rospy.Service("/ready", std_srvs.srv.Trigger, lambda request: (True, "yes"))
        rospy.spin()

    graph.launch(server)
    graph.run(0.1)
    # As a script that calls `rosservice`-like, with no node of its own (rospy allows it).
    answer = rospy.ServiceProxy("/ready", std_srvs.srv.Trigger)()
    assert (answer.success, answer.message) == (True, "yes")


def test_duckietown_utils_helpers_import_from_the_librarys_modules():
    from duckielib.ros.modules import modules_installed

    with modules_installed(replace_real=True):
        from duckietown_utils import jpg
        from duckietown_utils.jpg import bgr_from_jpg
        from duckietown_utils.yaml_wrap import yaml_load_file

        assert jpg.bgr_from_jpg is bgr_from_jpg
        assert callable(yaml_load_file)
