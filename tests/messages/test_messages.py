"""The course's message and service types: md5 sums, construction, checks, wire format."""

from __future__ import annotations

import copy
import io
import math
import pickle
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from duckielib import messages
from duckielib.errors import MessageError, UnknownTypeError
from duckielib.messages import (
    ChangePattern,
    ChangePatternRequest,
    ChangePatternResponse,
    ColorRGBA,
    CompressedImage,
    Header,
    LEDPattern,
    Pose2DStamped,
    SetCustomLEDPattern,
    String,
    Twist2DStamped,
    WheelEncoderStamped,
    WheelsCmdStamped,
)
from duckielib.rostime import Duration, Time

# The sums a real Duckiebot checks (spec/duckiebot-interface.md) and ROS's standard ones.
PUBLISHED_MD5 = {
    "duckietown_msgs/WheelEncoderStamped": "141b74ec2cc3bde8c38b5e3bdb694d12",
    "duckietown_msgs/WheelsCmdStamped": "edbf8d24194d839b1982a6a991b552c6",
    "duckietown_msgs/Twist2DStamped": "3fc0942a3082e78d7ded4a58ea1e2d0c",
    "duckietown_msgs/Pose2DStamped": "013fad68aad141d90a055e21fb791e63",
    "duckietown_msgs/LEDPattern": "47c8633688bbd1c94b1e15be083240b6",
    "duckietown_msgs/BoolStamped": "542e22b190dc8e6eb476d50dda88feb7",
    "std_msgs/Header": "2176decaecbce78abc3b96ef049fabed",
    "std_msgs/String": "992ce8a1687cec8c8bd883ec73ca41d1",
    "std_msgs/Empty": "d41d8cd98f00b204e9800998ecf8427e",
    "std_msgs/ColorRGBA": "a29a96539573343b1310c73607334b00",
    "std_msgs/Float32": "73fcbf46b49191e672908e50842a83d4",
    "std_msgs/Bool": "8b94c1b53db61fb6aed406028ad6332a",
    "sensor_msgs/CompressedImage": "8f7a12909da2c9d3332d540a0977563f",
    "sensor_msgs/Image": "060021388200f6f0f447d0fcd9c64743",
}
PUBLISHED_SERVICE_MD5 = {
    "duckietown_msgs/ChangePattern": "678f2d65b1bda577ab0910fd9c7414ba",
    "duckietown_msgs/SetCustomLEDPattern": "80c491edc501f8f5b2f80aaecfd31b21",
    "std_srvs/SetBool": "09fb03525b03e7ea1fd3992bafd87e16",
}


@pytest.mark.parametrize(("name", "md5"), sorted(PUBLISHED_MD5.items()))
def test_message_md5_equals_the_published_sum(name, md5):
    assert messages.get_message_class(name)._md5sum == md5


@pytest.mark.parametrize(("name", "md5"), sorted(PUBLISHED_SERVICE_MD5.items()))
def test_service_md5_equals_the_published_sum(name, md5):
    assert messages.get_service_class(name)._md5sum == md5


def test_every_type_of_the_course_is_defined():
    assert set(PUBLISHED_MD5) <= set(messages.message_types())
    assert set(PUBLISHED_SERVICE_MD5) <= set(messages.service_types())
    # The course's own definitions (a student's package, once imported, joins the registry).
    definitions = Path(messages.__file__).parent / "definitions"
    packages = {folder.name for folder in definitions.iterdir() if folder.is_dir()}
    assert packages <= {name.partition("/")[0] for name in messages.REGISTRY.messages}
    assert packages == {
        "actionlib_msgs",
        "duckietown_msgs",
        "geometry_msgs",
        "nav_msgs",
        "rosgraph_msgs",
        "sensor_msgs",
        "std_msgs",
        "std_srvs",
        "tf2_msgs",
    }


def test_rospy_style_imports_give_the_same_classes():
    from duckielib.messages.duckietown_msgs.msg import WheelEncoderStamped as Tick
    from duckielib.messages.duckietown_msgs.srv import ChangePattern as Change
    from duckielib.messages.duckietown_msgs.srv import ChangePatternRequest as Request
    from duckielib.messages.std_msgs.msg import String as Text

    assert Tick is WheelEncoderStamped
    assert Change is ChangePattern
    assert Request is ChangePatternRequest
    assert Text is String
    assert Request.__module__ == "duckielib.messages.duckietown_msgs.srv"
    assert Tick.__module__ == "duckielib.messages.duckietown_msgs.msg"


def test_genpy_class_attributes():
    assert WheelEncoderStamped._type == "duckietown_msgs/WheelEncoderStamped"
    assert WheelEncoderStamped.__slots__ == ("header", "data", "resolution", "type")
    assert WheelEncoderStamped._slot_types == ["std_msgs/Header", "int32", "uint16", "uint8"]
    assert WheelEncoderStamped._has_header is True
    assert String._has_header is False
    assert WheelEncoderStamped.ENCODER_TYPE_ABSOLUTE == 0
    assert WheelEncoderStamped.ENCODER_TYPE_INCREMENTAL == 1
    assert LEDPattern._slot_types[2] == "std_msgs/ColorRGBA[]"


def test_full_text_lists_dependencies_as_rospy_does():
    text = LEDPattern._full_text
    first, header, color = text.split("=" * 80 + "\n")
    assert first.startswith("# What the LED driver shows")
    assert "std_msgs/ColorRGBA[] rgb_vals" in first
    assert header.startswith("MSG: std_msgs/Header\n")
    assert color.startswith("MSG: std_msgs/ColorRGBA\n")
    assert color.rstrip("\n").endswith("float32 a")
    assert String._full_text == "string data\n"


def test_services_name_their_request_and_response():
    assert ChangePattern._type == "duckietown_msgs/ChangePattern"
    assert ChangePattern._request_class is ChangePatternRequest
    assert ChangePattern._response_class is ChangePatternResponse
    assert ChangePatternRequest._type == "duckietown_msgs/ChangePatternRequest"
    assert ChangePatternResponse.__slots__ == ()
    assert SetCustomLEDPattern._request_class().pattern == LEDPattern()


def test_defaults_are_ros_defaults():
    tick = WheelEncoderStamped()
    assert tick.header == Header(seq=0, stamp=Time(0), frame_id="")
    assert (tick.data, tick.resolution, tick.type) == (0, 0, 0)
    pattern = LEDPattern()
    assert pattern.color_list == []
    assert pattern.rgb_vals == []
    assert pattern.frequency == 0.0
    assert CompressedImage().data == b""
    assert isinstance(Pose2DStamped().theta, float)


def test_defaults_are_not_shared_between_instances():
    first, second = LEDPattern(), LEDPattern()
    first.color_list.append("red")
    first.header.seq = 4
    assert second.color_list == []
    assert second.header.seq == 0


def test_keyword_and_positional_construction_agree():
    header = Header(seq=1, stamp=Time(2, 3), frame_id="base")
    by_keyword = WheelsCmdStamped(header=header, vel_left=0.5, vel_right=-0.5)
    by_position = WheelsCmdStamped(header, 0.5, -0.5)
    assert by_keyword == by_position
    assert by_keyword.vel_left == 0.5
    assert by_keyword != WheelsCmdStamped(header=header, vel_left=0.5, vel_right=0.5)


def test_keyword_none_means_default():
    assert Twist2DStamped(v=None, omega=1.0).v == 0.0


def test_construction_mistakes_are_explained():
    with pytest.raises(TypeError, match="either every field in order or keywords"):
        Twist2DStamped(Header(), v=1.0)
    with pytest.raises(TypeError, match=r"takes all 3 fields in order \(header, v, omega\)"):
        Twist2DStamped(1.0, 2.0)
    with pytest.raises(AttributeError, match=r"has no field 'speed'; its fields are: header, v"):
        Twist2DStamped(speed=1.0)
    message = Twist2DStamped()
    with pytest.raises(AttributeError, match=r"has no field 'omegaa'"):
        message.omegaa = 1.0


@pytest.mark.parametrize(
    ("message_class", "field", "value", "expected"),
    [
        (
            Twist2DStamped,
            "v",
            "fast",
            r"Twist2DStamped.v must be a number \(float32\), but got 'fast'",
        ),
        (WheelEncoderStamped, "resolution", 70000, r"from 0 to 65535 \(uint16\), but got 70000"),
        (WheelEncoderStamped, "type", -1, r"from 0 to 255 \(uint8\), but got -1"),
        (WheelEncoderStamped, "data", 2**31, r"from -2147483648 to 2147483647 \(int32\)"),
        (WheelEncoderStamped, "data", 1.5, r"must be an integer .* but got 1.5 \(float\)"),
        (WheelsCmdStamped, "vel_left", 1e39, r"must be a number \(float32\), but got 1e\+39"),
        (String, "data", 5, r"String.data must be a str \(string\), but got 5 \(int\)"),
        (LEDPattern, "color_list", "red", r"must be a list of a str \(string\), but got 'red'"),
        (
            LEDPattern,
            "color_mask",
            [1, 200],
            r"must hold only an integer .* item 1 is, but got 200",
        ),
        (LEDPattern, "rgb_vals", [String()], r"must hold only a ColorRGBA message"),
        (WheelEncoderStamped, "header", String(), r"must be a Header message .*got String"),
        (Header, "stamp", 12.5, r"Header.stamp must be a rospy.Time \(time\), but got 12.5"),
        (CompressedImage, "data", [1, 256], r"item 1 is, but got 256"),
    ],
)
def test_bad_field_values_fail_at_once_with_a_clear_message(message_class, field, value, expected):
    message = message_class()
    with pytest.raises(MessageError, match=expected):
        setattr(message, field, value)
    with pytest.raises(MessageError, match=expected):
        message_class(**{field: value})


def test_numbers_of_other_numeric_types_are_accepted():
    numpy = pytest.importorskip("numpy")
    message = Twist2DStamped(v=numpy.float32(0.5), omega=2)
    assert message.omega == 2
    tick = WheelEncoderStamped(data=numpy.int64(-12), resolution=135)
    assert tick.to_bytes()[-7:-3] == (-12).to_bytes(4, "little", signed=True)
    image = CompressedImage(data=numpy.arange(4, dtype=numpy.uint8))
    assert image.data == b"\x00\x01\x02\x03"


def test_infinite_and_nan_floats_are_allowed_as_in_ros():
    message = Twist2DStamped(v=math.inf, omega=math.nan)
    assert math.isinf(Twist2DStamped.from_bytes(message.to_bytes()).v)


def test_byte_arrays_are_stored_as_bytes():
    image = CompressedImage(data=[255, 216, 255])
    assert image.data == b"\xff\xd8\xff"
    image.data = bytearray(b"\x00\x01")
    assert image.data == b"\x00\x01"


def test_list_items_appended_later_are_checked_before_sending():
    pattern = LEDPattern()
    pattern.color_list.append(42)
    with pytest.raises(MessageError, match=r"LEDPattern\.color_list must hold only a str"):
        pattern.to_bytes()
    pattern.color_list[0] = "red"
    pattern.rgb_vals.append(ColorRGBA(r=1.0))
    pattern.rgb_vals[0].g = 1.0
    pattern.to_bytes()
    pattern.rgb_vals.append(ColorRGBA())
    object.__setattr__(pattern.rgb_vals[1], "b", "blue")
    with pytest.raises(MessageError, match=r"ColorRGBA\.b must be a number"):
        pattern.serialize(io.BytesIO())


def test_wire_format_of_an_encoder_tick():
    tick = WheelEncoderStamped(
        header=Header(seq=1, stamp=Time(2, 3), frame_id="ab"), data=-2, resolution=135, type=1
    )
    expected = (
        (1).to_bytes(4, "little")
        + (2).to_bytes(4, "little")
        + (3).to_bytes(4, "little")
        + (2).to_bytes(4, "little")
        + b"ab"
        + (-2).to_bytes(4, "little", signed=True)
        + (135).to_bytes(2, "little")
        + b"\x01"
    )
    assert tick.to_bytes() == expected
    buffer = io.BytesIO()
    tick.serialize(buffer)
    assert buffer.getvalue() == expected
    assert WheelEncoderStamped().deserialize(expected) == tick


def test_nested_arrays_round_trip():
    pattern = LEDPattern(
        header=Header(seq=9, stamp=Time(100, 5), frame_id=""),
        color_list=["red", "switchedoff", "é"],
        rgb_vals=[ColorRGBA(0.8, 0.0, 0.0, 1.0), ColorRGBA(0.0, 0.0, 0.0, 1.0)],
        color_mask=[1, 0, -1],
        frequency=1.9,
        frequency_mask=[0, 1],
    )
    again = LEDPattern.from_bytes(pattern.to_bytes())
    assert again.color_list == ["red", "switchedoff", "é"]
    assert again.rgb_vals[0].r == pytest.approx(0.8)
    assert again.color_mask == [1, 0, -1]
    assert again.frequency == pytest.approx(1.9)
    assert again.header.stamp == Time(100, 5)


def test_cut_or_padded_bytes_are_refused():
    data = WheelEncoderStamped(data=5).to_bytes()
    with pytest.raises(MessageError, match="cut short"):
        WheelEncoderStamped.from_bytes(data[:-2])
    with pytest.raises(MessageError, match="1 bytes too many; is it really this type"):
        WheelEncoderStamped.from_bytes(data + b"\x00")
    with pytest.raises(MessageError, match="cut short"):
        CompressedImage.from_bytes(CompressedImage(data=b"abcdef").to_bytes()[:-3])


def test_print_reads_like_rostopic_echo():
    tick = WheelEncoderStamped(
        header=Header(seq=3, stamp=Time(12, 5), frame_id="left"), data=42, resolution=135, type=1
    )
    assert str(tick) == "\n".join(
        [
            "header:",
            "  seq: 3",
            "  stamp:",
            "    secs: 12",
            "    nsecs: 5",
            '  frame_id: "left"',
            "data: 42",
            "resolution: 135",
            "type: 1",
        ]
    )
    pattern = LEDPattern(rgb_vals=[ColorRGBA(r=1.0)], color_mask=[1, 0])
    text = str(pattern)
    assert "rgb_vals:\n  -\n    r: 1.0\n    g: 0.0" in text
    assert "color_list: []" in text
    assert "color_mask: [1, 0]" in text
    long_image = str(CompressedImage(data=bytes(range(100))))
    assert (
        "data: [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, ...] (100 items)"
        in long_image
    )
    assert str(messages.Empty()) == ""


def test_repr_is_one_line_and_names_the_fields():
    assert repr(Twist2DStamped(v=0.5)) == (
        "Twist2DStamped(header=Header(seq=0, stamp=Time[0], frame_id=''), v=0.5, omega=0.0)"
    )


def test_copy_and_pickle_keep_values_and_independence():
    pattern = LEDPattern(color_list=["red"], rgb_vals=[ColorRGBA(r=1.0)])
    clone = copy.deepcopy(pattern)
    assert clone == pattern
    clone.rgb_vals[0].r = 0.0
    assert pattern.rgb_vals[0].r == 1.0
    assert pickle.loads(pickle.dumps(pattern)) == pattern


def test_messages_are_unhashable_like_genpy():
    with pytest.raises(TypeError):
        hash(String())


def test_unknown_type_names_say_which_exist():
    with pytest.raises(UnknownTypeError, match="'duckietown_msgs/Nope'; the duckietown_msgs types"):
        messages.get_message_class("duckietown_msgs/Nope")
    with pytest.raises(UnknownTypeError, match="did you mean 'std_srvs/Trigger'"):
        messages.get_service_class("std_msgs/Trigger")
    with pytest.raises(UnknownTypeError, match="did you mean 'std_msgs/String'"):
        messages.get_message_class("std_msgs/Strng")
    with pytest.raises(UnknownTypeError, match="; the packages are: actionlib_msgs, "):
        messages.get_message_class("my_msgs/Nope")


def test_definition_returns_the_source_text():
    assert "uint8 ENCODER_TYPE_INCREMENTAL=1" in messages.definition(
        "duckietown_msgs/WheelEncoderStamped"
    )
    assert "---" in messages.definition("duckietown_msgs/ChangePattern")


def test_duration_fields_use_signed_seconds():
    from duckielib.messages.message import make_message_class
    from duckielib.messages.spec import parse_message

    spec = parse_message("duration wait\ntime[2] window\n", "test_msgs/Timing")
    timing_class = make_message_class(spec, "0" * 32, spec.text, messages.get_message_class)
    timing = timing_class(wait=Duration(-1.5), window=[Time(1), Time(2)])
    data = timing.to_bytes()
    assert data[:8] == (-2).to_bytes(4, "little", signed=True) + (500_000_000).to_bytes(4, "little")
    assert len(data) == 8 + 16  # a fixed-size array has no length prefix
    assert timing_class.from_bytes(data) == timing
    with pytest.raises(MessageError, match="exactly 2 items"):
        timing.window = [Time(1)]


int32s = st.integers(-(2**31), 2**31 - 1)
float32s = st.floats(width=32, allow_nan=False)


@given(
    seq=st.integers(0, 2**32 - 1),
    secs=st.integers(0, 2**32 - 1),
    nsecs=st.integers(0, 999_999_999),
    frame=st.text(max_size=20),
    data=int32s,
    resolution=st.integers(0, 65535),
)
def test_encoder_ticks_round_trip(seq, secs, nsecs, frame, data, resolution):
    tick = WheelEncoderStamped(
        header=Header(seq=seq, stamp=Time(secs, nsecs), frame_id=frame),
        data=data,
        resolution=resolution,
        type=1,
    )
    assert WheelEncoderStamped.from_bytes(tick.to_bytes()) == tick


@given(colours=st.lists(st.tuples(float32s, float32s, float32s, float32s), max_size=6))
def test_led_patterns_round_trip(colours):
    pattern = LEDPattern(rgb_vals=[ColorRGBA(*colour) for colour in colours])
    assert LEDPattern.from_bytes(pattern.to_bytes()) == pattern
