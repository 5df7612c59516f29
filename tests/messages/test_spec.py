"""Parsing ``.msg``/``.srv`` text and ROS's md5 and full-text rules."""

from __future__ import annotations

import hashlib

import pytest

from duckielib.errors import MessageDefinitionError
from duckielib.messages.spec import SpecRegistry, parse_message, parse_service


def test_fields_constants_and_comments():
    spec = parse_message(
        "# a comment\n"
        "uint8 A=1  # trailing comment\n"
        "string GREETING=hello # not a comment in a string constant\n"
        "\n"
        "Header header\n"
        "float64[9] covariance   # fixed array\n"
        "ColorRGBA[] colours\n"
        "std_msgs/String name\n",
        "my_msgs/Thing",
    )
    assert [(c.type, c.name, c.value) for c in spec.constants] == [
        ("uint8", "A", 1),
        ("string", "GREETING", "hello # not a comment in a string constant"),
    ]
    assert [(f.name, f.type) for f in spec.fields] == [
        ("header", "std_msgs/Header"),
        ("covariance", "float64[9]"),
        ("colours", "my_msgs/ColorRGBA[]"),
        ("name", "std_msgs/String"),
    ]
    covariance = spec.fields[1]
    assert (covariance.is_array, covariance.array_length, covariance.is_primitive) == (
        True,
        9,
        True,
    )
    assert spec.dependencies == ["std_msgs/Header", "my_msgs/ColorRGBA", "std_msgs/String"]
    assert spec.has_header


def test_md5_text_follows_ros_rules():
    registry = SpecRegistry()
    registry.add_message(
        parse_message("uint32 seq\ntime stamp\nstring frame_id\n", "std_msgs/Header")
    )
    registry.add_message(parse_message("float32 x\n", "my_msgs/Point"))
    registry.add_message(
        parse_message("Header header\nPoint[] points  # list\nint8 K = 3\n", "my_msgs/Path")
    )
    point_md5 = hashlib.md5(b"float32 x").hexdigest()
    assert registry.md5sum("my_msgs/Point") == point_md5
    assert registry.md5_text("my_msgs/Path") == (
        f"int8 K=3\n2176decaecbce78abc3b96ef049fabed header\n{point_md5} points"
    )


def test_service_md5_hashes_request_then_response():
    registry = SpecRegistry()
    registry.add_service(parse_service("int32 a\n---\nint32 sum\n", "my_srvs/Add"))
    assert registry.md5sum("my_srvs/Add") == hashlib.md5(b"int32 aint32 sum").hexdigest()
    assert registry.md5sum("my_srvs/AddRequest") == hashlib.md5(b"int32 a").hexdigest()


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("int32\n", r"Line 1 .* should read 'type name'"),
        ("int32 a b\n", "should read 'type name'"),
        ("int32 1abc\n", "invalid field name '1abc'"),
        ("flt-32 x\n", "invalid type 'flt-32'"),
        ("int32 a\nint32 a\n", r"Line 2 .* repeats the field name 'a'"),
        ("time T=3\n", "declares a constant of type 'time'"),
        ("int32 X=abc\n", "has a value that does not fit its type"),
    ],
)
def test_bad_definitions_name_the_line(text, expected):
    with pytest.raises(MessageDefinitionError, match=expected):
        parse_message(text, "my_msgs/Bad")


def test_service_without_separator_is_refused():
    with pytest.raises(MessageDefinitionError, match="no '---' line"):
        parse_service("int32 a\n", "my_srvs/Broken")
