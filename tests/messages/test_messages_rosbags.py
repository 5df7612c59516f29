"""Our definitions read by rosbags, the library that writes and reads the course's bags."""

from __future__ import annotations

import pytest
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from duckielib import messages
from duckielib.rostime import Duration, Time

#: Types with quoted string constants (FSMState's LANE_FOLLOWING="LANE_FOLLOWING"): ROS keeps
#: the quotes in the text it hashes, rosbags drops them, so its md5 sum of these is not ROS's.
QUOTED_CONSTANTS = [
    name
    for name in messages.message_types()
    if any(
        constant.type == "string" and constant.value_text[:1] in ("'", '"')
        for constant in messages.REGISTRY.message(name).constants
    )
]


def _rosbags_name(name: str) -> str:
    package, short_name = name.split("/")
    return f"{package}/msg/{short_name}"


@pytest.fixture(scope="module")
def typestore():
    store = get_typestore(Stores.ROS1_NOETIC)
    # The types rosbags does not know (duckietown_msgs, tf2_msgs), from our definitions.
    for name in messages.message_types():
        if _rosbags_name(name) in store.fielddefs:
            continue
        definition = messages.get_message_class(name)._full_text.split("=" * 80)[0]
        store.register(get_types_from_msg(definition, _rosbags_name(name)))
    return store


@pytest.mark.parametrize(
    "name",
    [
        pytest.param(
            name,
            marks=pytest.mark.xfail(
                name in QUOTED_CONSTANTS,
                reason="rosbags drops the quotes of string constants",
                strict=True,
            ),
        )
        for name in messages.message_types()
    ],
)
def test_rosbags_computes_the_same_md5(typestore, name):
    _, md5 = typestore.generate_msgdef(_rosbags_name(name), ros_version=1)
    assert md5 == messages.get_message_class(name)._md5sum


def test_rosbags_reads_and_writes_the_same_bytes(typestore):
    pattern = messages.LEDPattern(
        header=messages.Header(seq=4, stamp=Time(1700000000, 250), frame_id="leds"),
        color_list=["red", "white"],
        rgb_vals=[messages.ColorRGBA(0.8, 0.0, 0.0, 1.0), messages.ColorRGBA(0.8, 0.8, 0.8, 1.0)],
        color_mask=[1, 1, 1, 1, 1],
        frequency=0.0,
        frequency_mask=[0, 0, 0, 0, 0],
    )
    name = "duckietown_msgs/msg/LEDPattern"
    decoded = typestore.deserialize_ros1(pattern.to_bytes(), name)
    assert decoded.header.stamp.sec == 1700000000
    assert decoded.color_list == ["red", "white"]
    assert decoded.rgb_vals[1].g == pytest.approx(0.8)
    assert list(decoded.color_mask) == [1, 1, 1, 1, 1]
    assert bytes(typestore.serialize_ros1(decoded, name)) == pattern.to_bytes()

    tick = messages.WheelEncoderStamped(data=-123456, resolution=135, type=1)
    decoded = typestore.deserialize_ros1(tick.to_bytes(), "duckietown_msgs/msg/WheelEncoderStamped")
    assert (decoded.data, decoded.resolution, decoded.type) == (-123456, 135, 1)


def _filled(message_class, salt: int):
    """An instance of ``message_class`` with every field set to a value other than its default."""
    values = {}
    for number, (key, codec) in enumerate(message_class._codecs.items()):
        field, seed = codec.field, salt + number
        if not field.is_primitive:
            item = _filled(codec.element.message_class, seed)
            value = (
                [item, _filled(codec.element.message_class, seed + 7)] if field.is_array else item
            )
        elif field.base_type == "string":
            value = f"é{seed}"
        elif field.base_type == "bool":
            value = True
        elif field.base_type in ("time", "duration"):
            value = Time(seed, 1000 + seed) if field.base_type == "time" else Duration(-seed, 5)
        elif field.base_type.startswith("float"):
            value = seed + 0.25
        else:
            value = seed % 100 + 1
        if field.is_array and field.is_primitive:
            value = [value] * (field.array_length or 3)
        values[key] = value
    return message_class(**values)


@pytest.mark.parametrize("name", messages.message_types())
def test_every_type_writes_and_reads_the_bytes_rosbags_does(typestore, name):
    message_class = messages.get_message_class(name)
    message = _filled(message_class, salt=3)
    data = message.to_bytes()
    decoded = typestore.deserialize_ros1(data, _rosbags_name(name))
    assert bytes(typestore.serialize_ros1(decoded, _rosbags_name(name))) == data
    assert message_class.from_bytes(data) == message
    assert message_class.from_bytes(message_class().to_bytes()) == message_class()
