"""The command-line habits, on the live in-process graph."""

from __future__ import annotations

import io

import pytest

from duckielib.messages import ChangePattern, ChangePatternResponse, String, WheelEncoderStamped
from duckielib.ros import (
    Graph,
    rosmsg,
    rosnode,
    rosparam,
    rospy,
    rosservice,
    rossrv,
    rostopic,
)


def encoder():
    rospy.init_node("left_wheel_encoder_node")
    pub = rospy.Publisher("~tick", WheelEncoderStamped, queue_size=1)
    rate = rospy.Rate(30)
    ticks = 10_000
    while not rospy.is_shutdown():
        ticks += 2
        pub.publish(WheelEncoderStamped(data=ticks, resolution=135, type=1))
        rate.sleep()


def emitter():
    rospy.init_node("led_emitter_node")
    rospy.Service("~set_pattern", ChangePattern, lambda request: ChangePatternResponse())
    rospy.Subscriber("/chatter", String, lambda message: None, queue_size=1)
    rospy.spin()


@pytest.fixture
def graph():
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    graph.launch(encoder, namespace="/duckiebot")
    graph.launch(emitter, namespace="/duckiebot")
    graph.set_param("/duckiebot/kinematics_node/gain", 1.0)
    graph.run(0.1)
    yield graph
    graph.shutdown()


def test_rostopic_list_type_info(graph):
    tick = "/duckiebot/left_wheel_encoder_node/tick"
    assert rostopic.list() == ["/chatter", tick]
    assert repr(rostopic.list()) == f"/chatter\n{tick}"
    assert rostopic.type(tick) == "duckietown_msgs/WheelEncoderStamped"
    assert rostopic.info(tick) == (
        "Type: duckietown_msgs/WheelEncoderStamped\n\n"
        "Publishers:\n * /duckiebot/left_wheel_encoder_node\n\nSubscribers:\n None"
    )
    assert rostopic.info("/chatter") == (
        "Type: std_msgs/String\n\nPublishers:\n None\n\n"
        "Subscribers:\n * /duckiebot/led_emitter_node"
    )
    with pytest.raises(rospy.ROSException, match="Unknown topic /tick: no node publishes"):
        rostopic.info("/tick")


def test_a_second_type_on_a_subscribed_topic_is_refused(graph):
    rospy.init_node("talker")
    with pytest.raises(
        rospy.ROSException,
        match=r"/chatter carries std_msgs/String \(used by /duckiebot/led_emitter_node\)",
    ):
        rospy.Publisher("/chatter", WheelEncoderStamped, queue_size=1)


def test_rostopic_echo_runs_the_graph(graph):
    text = rostopic.echo("/duckiebot/left_wheel_encoder_node/tick", count=2)
    assert text.count("---") == 2
    assert "data: 10010\nresolution: 135\ntype: 1\n---\nheader:\n  seq: 6" in text
    assert not any(name.startswith("/rostopic") for name in rosnode.list())
    with pytest.raises(rospy.ROSException, match="Only 0 of 1 messages arrived on /chatter"):
        rostopic.echo("/chatter", timeout=0.5)


def test_rostopic_hz_measures_the_simulated_rate(graph):
    text = rostopic.hz("/duckiebot/left_wheel_encoder_node/tick", duration=2.0)
    assert text.startswith("average rate: 30.0")
    assert "window: 60" in text


def test_rosnode(graph):
    assert rosnode.list() == ["/duckiebot/led_emitter_node", "/duckiebot/left_wheel_encoder_node"]
    info = rosnode.info("/duckiebot/led_emitter_node")
    assert "Subscriptions:\n * /chatter [std_msgs/String]" in info
    assert "Services:\n * /duckiebot/led_emitter_node/set_pattern" in info
    assert "Publications:\n None" in info


def test_rosservice(graph):
    name = "/duckiebot/led_emitter_node/set_pattern"
    assert rosservice.list() == [name]
    assert rosservice.type(name) == "duckietown_msgs/ChangePattern"
    assert rosservice.info(name) == (
        "Node: /duckiebot/led_emitter_node\nType: duckietown_msgs/ChangePattern\nArgs: pattern_name"
    )
    assert rosservice.call(name, pattern_name=String("RED")) == ""
    assert graph.services[name].call_count == 1


def test_rosmsg_and_rossrv():
    assert rosmsg.show("duckietown_msgs/WheelEncoderStamped") == "\n".join(
        [
            "uint8 ENCODER_TYPE_ABSOLUTE=0",
            "uint8 ENCODER_TYPE_INCREMENTAL=1",
            "std_msgs/Header header",
            "  uint32 seq",
            "  time stamp",
            "  string frame_id",
            "int32 data",
            "uint16 resolution",
            "uint8 type",
        ]
    )
    assert rossrv.show("duckietown_msgs/ChangePattern") == (
        "std_msgs/String pattern_name\n  string data\n---"
    )
    assert "duckietown_msgs/LEDPattern" in rosmsg.list()
    with pytest.raises(KeyError, match="no service type 'nope/Nope'"):
        rossrv.show("nope/Nope")


def test_rosparam(graph):
    assert rosparam.get("/duckiebot/kinematics_node") == {"gain": 1.0}
    rosparam.set("/duckiebot/kinematics_node/trim", -0.02)
    assert rosparam.list() == [
        "/duckiebot/kinematics_node/gain",
        "/duckiebot/kinematics_node/trim",
    ]
