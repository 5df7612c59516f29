"""How rospy resolves names."""

from __future__ import annotations

import pytest

from duckielib.ros import names


@pytest.mark.parametrize(
    ("name", "namespace", "expected"),
    [
        ("/chatter", "/duckiebot/", "/chatter"),
        ("chatter", "/", "/chatter"),
        ("chatter", "/duckiebot/", "/duckiebot/chatter"),
        ("wheels_driver_node/wheels_cmd", "/duckiebot", "/duckiebot/wheels_driver_node/wheels_cmd"),
        ("~tick", "/duckiebot/", "/duckiebot/left_wheel_encoder_node/tick"),
        ("/a/b/", "/", "/a/b"),
    ],
)
def test_resolve(name, namespace, expected):
    assert names.resolve(name, namespace, "/duckiebot/left_wheel_encoder_node") == expected


def test_remapping_applies_to_the_resolved_name():
    remap = {"/duckiebot/chatter": "/other"}
    assert names.resolve("chatter", "/duckiebot/", None, remap) == "/other"
    assert names.resolve("/duckiebot/chatter", "/", None, remap) == "/other"
    assert names.resolve("talk", "/duckiebot/", None, remap) == "/duckiebot/talk"


def test_private_name_without_node_is_explained():
    with pytest.raises(ValueError, match=r"private name '~x' needs a node"):
        names.resolve("~x", "/")


@pytest.mark.parametrize("bad", ["", "1chatter", "chat ter", "a-b", "a//b"])
def test_illegal_names(bad):
    assert not names.is_legal_name(bad) or bad == ""
    with pytest.raises(ValueError, match="is not a legal ROS name"):
        names.resolve(bad or "a b")


def test_namespaces():
    assert names.normalize_namespace("duckiebot") == "/duckiebot/"
    assert names.normalize_namespace("/duckiebot/") == "/duckiebot/"
    assert names.normalize_namespace("") == "/"
    assert names.namespace_of("/duckiebot/talker") == "/duckiebot/"
    assert names.is_legal_base_name("odometry_node")
    assert not names.is_legal_base_name("a/b")
