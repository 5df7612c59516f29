"""Our message classes against the ones Debian's genpy generates from the same text."""

from __future__ import annotations

import io

import pytest

from duckielib import messages
from duckielib.rostime import Time

pytestmark = pytest.mark.ros

EXAMPLES = [
    messages.WheelEncoderStamped(
        header=messages.Header(seq=7, stamp=Time(12, 345), frame_id="left_wheel"),
        data=-40123,
        resolution=135,
        type=messages.WheelEncoderStamped.ENCODER_TYPE_INCREMENTAL,
    ),
    messages.WheelsCmdStamped(vel_left=0.25, vel_right=-1.0),
    messages.Twist2DStamped(v=0.3, omega=-1.5),
    messages.Pose2DStamped(x=0.32, y=0.32, theta=1.5707963267948966),
    messages.LEDPattern(
        color_list=["red", "green", "blue", "white", "switchedoff"],
        rgb_vals=[messages.ColorRGBA(0.8, 0.0, 0.0, 1.0)] * 5,
        color_mask=[1, 1, 0, 1, 1],
        frequency=1.9,
        frequency_mask=[0, 0, 1, 0, 0],
    ),
    messages.BoolStamped(data=True),
    messages.CompressedImage(format="jpeg", data=bytes(range(256))),
    messages.Image(height=1, width=2, encoding="bgr8", step=6, data=b"\x01\x02\x03\x04\x05\x06"),
    messages.String(data="hello duckie"),
    messages.Empty(),
    messages.ChangePatternRequest(pattern_name=messages.String(data="RED")),
]


@pytest.fixture(scope="module")
def generate(ros_import):
    dynamic = ros_import("genpy.dynamic")

    def make(message_class):
        return dynamic.generate_dynamic(message_class._type, message_class._full_text)[
            message_class._type
        ]

    return make


@pytest.mark.parametrize("message", EXAMPLES, ids=lambda message: message._type)
def test_genpy_agrees_on_md5_and_bytes(generate, message):
    genpy_class = generate(type(message))
    assert genpy_class._md5sum == message._md5sum
    assert list(genpy_class.__slots__) == list(message.__slots__)
    assert genpy_class._slot_types == message._slot_types
    assert genpy_class._has_header == message._has_header

    ours = message.to_bytes()
    theirs = genpy_class()
    theirs.deserialize(ours)
    buffer = io.BytesIO()
    theirs.serialize(buffer)
    assert buffer.getvalue() == ours
    assert type(message).from_bytes(buffer.getvalue()).to_bytes() == ours


def test_installed_std_msgs_have_our_md5(ros_import):
    std_msgs = ros_import("std_msgs.msg")
    sensor_msgs = ros_import("sensor_msgs.msg")
    assert std_msgs.Header._md5sum == messages.Header._md5sum
    assert std_msgs.String._md5sum == messages.String._md5sum
    assert std_msgs.ColorRGBA._md5sum == messages.ColorRGBA._md5sum
    assert sensor_msgs.CompressedImage._md5sum == messages.CompressedImage._md5sum
    assert sensor_msgs.Image._md5sum == messages.Image._md5sum


def test_genpy_header_bytes_match(ros_import):
    std_msgs = ros_import("std_msgs.msg")
    genpy = ros_import("genpy")
    theirs = std_msgs.Header(seq=3, stamp=genpy.Time(5, 6), frame_id="map")
    buffer = io.BytesIO()
    theirs.serialize(buffer)
    ours = messages.Header(seq=3, stamp=Time(5, 6), frame_id="map")
    assert ours.to_bytes() == buffer.getvalue()


def test_classes_genpy_generated_work_on_the_graph(generate, ros_import):
    # A node that imports message modules a catkin build generated (genpy's classes), not ours.
    from duckielib.ros import Graph, rospy

    genpy_pose = generate(messages.Pose2DStamped)
    graph = Graph(stdout=io.StringIO())
    heard = []
    rospy.init_node("generated")
    pub = rospy.Publisher("pose", genpy_pose, queue_size=1)
    rospy.Subscriber("pose", genpy_pose, heard.append)
    pub.publish(genpy_pose(x=1.5, y=-2.0, theta=0.25))
    pub.publish(x=0.5)
    graph.run(0.0)
    assert [(msg.x, msg.y, msg.theta) for msg in heard] == [(1.5, -2.0, 0.25), (0.5, 0.0, 0.0)]
    graph.shutdown()


def test_a_generated_class_of_another_definition_is_refused_with_a_sentence(ros_import):
    from duckielib.ros import Graph, rospy

    dynamic = ros_import("genpy.dynamic")
    other = dynamic.generate_dynamic("duckietown_msgs/Pose2DStamped", "float64 x\nfloat64 y\n")[
        "duckietown_msgs/Pose2DStamped"
    ]
    unknown = dynamic.generate_dynamic("my_pkg/Reading", "float32 value\n")["my_pkg/Reading"]
    graph = Graph(stdout=io.StringIO())
    rospy.init_node("generated")
    with pytest.raises(ValueError, match=r"another definition than the robot's \(md5 sum"):
        rospy.Publisher("pose", other, queue_size=1)
    with pytest.raises(ValueError, match=r"Put its \.msg file in the msg/ folder"):
        rospy.Subscriber("reading", unknown, print)
    graph.shutdown()


@pytest.fixture(scope="module")
def generate_service(ros_import):
    """Make a service module as a catkin build does: genpy's code for a ``.srv`` text."""
    genmsg = ros_import("genmsg")
    loader = ros_import("genmsg.msg_loader")
    generator = ros_import("genpy.generator")

    def make(full_name: str, text: str, uses=()):
        context = genmsg.MsgContext.create_default()
        for used in uses:
            loader.load_msg_from_string(context, messages.definition(used), used)
        spec = loader.load_srv_from_string(context, text, full_name)
        module: dict = {}
        exec("\n".join(generator.srv_generator(context, spec, {})), module)
        return module

    return make


def test_service_classes_genpy_generated_work_on_the_graph(generate_service):
    from duckielib.ros import Graph, rospy

    text = messages.definition("duckietown_msgs/ChangePattern")
    generated = generate_service("duckietown_msgs/ChangePattern", text, ["std_msgs/String"])
    service, response = generated["ChangePattern"], generated["ChangePatternResponse"]
    graph = Graph(stdout=io.StringIO())
    rospy.init_node("generated")
    asked = []
    rospy.Service("set_pattern", service, lambda req: asked.append(req) or response())
    answer = rospy.ServiceProxy("set_pattern", service)(generated["ChangePatternRequest"]())
    assert answer._type == "duckietown_msgs/ChangePatternResponse"
    assert len(asked) == 1
    assert asked[0]._connection_header["callerid"] == "/generated"
    graph.shutdown()


def test_a_generated_service_of_a_type_unknown_is_refused_with_a_sentence(generate_service):
    from duckielib.ros import Graph, rospy

    generated = generate_service("my_pkg/AddTwoInts", "int64 a\nint64 b\n---\nint64 sum\n")
    graph = Graph(stdout=io.StringIO())
    rospy.init_node("generated")
    with pytest.raises(ValueError, match=r"Put its \.srv file in the srv/ folder"):
        rospy.Service("add", generated["AddTwoInts"], print)
    graph.shutdown()
