"""tf and tf2_ros on the in-process graph: the transformations' numbers, the buffer's rules, nodes.

The numbers are checked against values worked out by hand and, where Debian's ROS packages are
installed, against the real ``tf.transformations`` and ``tf2_ros.Buffer`` run by Debian's
Python in a subprocess: both must give the same numbers and raise the same exceptions.
"""

from __future__ import annotations

import io
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from duckielib.libraries import tf, tf2_ros
from duckielib.libraries.tf import transformations as tft
from duckielib.messages import get_message_class
from duckielib.ros import Graph, rospy
from duckielib.ros.log import ERROR, WARN

TransformStamped = get_message_class("geometry_msgs/TransformStamped")
PointStamped = get_message_class("geometry_msgs/PointStamped")

DEBIAN_PYTHON = Path("/usr/bin/python3")
DEBIAN_TF2_ROS = Path("/usr/lib/python3/dist-packages/tf2_ros/__init__.py")
DEBIAN_TF = Path("/usr/lib/python3/dist-packages/tf/transformations.py")

S45 = math.sin(math.pi / 4)
AXES = [kind + order for kind in "sr" for order in ("xyz", "xyx", "xzy", "xzx", "yzx", "yzy")]
AXES += [kind + order for kind in "sr" for order in ("yxz", "yxy", "zxy", "zxz", "zyx", "zyz")]
ANGLES = [(0.1, 0.2, 0.3), (1.0, -2.0, 3.0), (0.5, math.pi / 2, -0.4), (0.3, 0.0, 0.2)]


def close(actual, expected, tol=1e-12):
    return np.allclose(np.asarray(actual, dtype=float), expected, atol=tol, rtol=0)


def yaw(angle):
    return [0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2)]


def stamped(parent, child, secs, xyz=(0.0, 0.0, 0.0), q=(0.0, 0.0, 0.0, 1.0)):
    t = TransformStamped()
    t.header.frame_id, t.child_frame_id = parent, child
    t.header.stamp = rospy.Time(secs)
    tr, rot = t.transform.translation, t.transform.rotation
    tr.x, tr.y, tr.z = xyz
    rot.x, rot.y, rot.z, rot.w = q
    return t


def pose(message):
    t, r = message.transform.translation, message.transform.rotation
    return [t.x, t.y, t.z], [r.x, r.y, r.z, r.w]


@pytest.fixture
def graph():
    graph = Graph(start_time=100.0, stdout=io.StringIO(), stderr=io.StringIO())
    yield graph
    graph.shutdown()


# -- tf.transformations ---------------------------------------------------------------------------
def test_quaternions_from_euler_angles_worked_by_hand():
    assert close(tft.quaternion_from_euler(0, 0, math.pi / 2), [0, 0, S45, S45])
    assert close(tft.quaternion_from_euler(math.pi / 2, 0, 0), [S45, 0, 0, S45])
    assert close(tft.quaternion_from_euler(0, math.pi / 2, 0), [0, S45, 0, S45])
    assert close(tft.quaternion_from_euler(0, 0, 0), [0, 0, 0, 1])
    assert isinstance(tft.quaternion_from_euler(0, 0, 1), np.ndarray)
    # Roll 90 then yaw 90 about the fixed axes: q_yaw * q_roll = [1/2, 1/2, 1/2, 1/2].
    assert close(tft.quaternion_from_euler(math.pi / 2, 0, math.pi / 2), [0.5, 0.5, 0.5, 0.5])
    # The same rotation about the moving axes takes the angles in the other order.
    both = tft.quaternion_from_euler(math.pi / 2, 0, math.pi / 2, axes="rzyx")
    assert close(both, [0.5, 0.5, 0.5, 0.5])


def test_euler_angles_from_quaternions_and_back():
    assert close(tft.euler_from_quaternion([0, 0, S45, S45]), [0, 0, math.pi / 2])
    assert close(tft.euler_from_quaternion([0.5, 0.5, 0.5, 0.5]), [math.pi / 2, 0, math.pi / 2])
    angles = tft.euler_from_quaternion(tft.quaternion_from_euler(0.1, -0.2, 3.0))
    assert isinstance(angles, tuple)
    assert close(angles, [0.1, -0.2, 3.0])
    # A quaternion and its negative are the same rotation; a non-unit one is normalised.
    assert close(tft.euler_from_quaternion([0, 0, -S45, -S45]), [0, 0, math.pi / 2])
    assert close(tft.euler_from_quaternion([0, 0, 2.0, 2.0]), [0, 0, math.pi / 2])


@pytest.mark.parametrize("axes", AXES)
def test_every_axes_order_round_trips(axes):
    for angles in ANGLES:
        matrix = tft.euler_matrix(*angles, axes=axes)
        q = tft.quaternion_from_euler(*angles, axes=axes)
        assert close(tft.quaternion_matrix(q), matrix)
        again = tft.euler_from_matrix(matrix, axes=axes)
        assert close(tft.euler_matrix(*again, axes=axes), matrix)
        assert close(tft.euler_from_quaternion(q, axes=axes), again)


def test_matrices_worked_by_hand():
    assert close(
        tft.quaternion_matrix([0, 0, S45, S45]),
        [[0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
    )
    assert close(tft.euler_matrix(0, 0, math.pi / 2), tft.quaternion_matrix(yaw(math.pi / 2)))
    assert close(tft.quaternion_matrix([0, 0, 0, 0]), np.identity(4))
    moved = tft.translation_matrix([1.0, 2.0, 3.0])
    assert close(moved, [[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]])
    assert close(tft.translation_from_matrix(moved), [1, 2, 3])
    assert close(tft.identity_matrix(), np.identity(4))
    both = tft.concatenate_matrices(moved, tft.quaternion_matrix(yaw(math.pi / 2)))
    assert close(both @ [1, 0, 0, 1], [1, 3, 3, 1])  # (1, 0, 0) turned to (0, 1, 0), moved
    assert close(tft.inverse_matrix(both) @ both, np.identity(4))
    for q in ([0.1, 0.2, 0.3, 0.9], [0.9, 0.1, -0.3, 0.05], [0.1, 0.95, 0.05, 0.02], yaw(3.0)):
        unit = np.asarray(q) / np.linalg.norm(q)
        assert close(tft.quaternion_from_matrix(tft.quaternion_matrix(q)), unit)


def test_composing_and_inverting_quaternions():
    # Yaw 30 degrees then yaw 60 degrees is yaw 90 degrees.
    assert close(tft.quaternion_multiply(yaw(math.pi / 3), yaw(math.pi / 6)), yaw(math.pi / 2))
    # Roll 90 first, then yaw 90 (fixed axes): q_yaw * q_roll.
    roll, turn = tft.quaternion_from_euler(math.pi / 2, 0, 0), yaw(math.pi / 2)
    assert close(tft.quaternion_multiply(turn, roll), [0.5, 0.5, 0.5, 0.5])
    q = [0.1, 0.2, 0.3, 0.9]
    assert close(tft.quaternion_multiply(q, tft.quaternion_inverse(q)), [0, 0, 0, 1])
    assert close(tft.quaternion_conjugate(q), [-0.1, -0.2, -0.3, 0.9])
    assert close(tft.quaternion_inverse([0, 0, 0, 2.0]), [0, 0, 0, 0.5])
    assert close(tft.quaternion_about_axis(math.pi / 2, [0, 0, 5]), yaw(math.pi / 2))
    assert close(tft.quaternion_slerp(yaw(0.0), yaw(1.0), 0.25), yaw(0.25))
    assert close(tft.quaternion_slerp(yaw(0.2), [-v for v in yaw(1.0)], 0.5), yaw(0.6))


def test_unknown_axes_and_functions_are_explained():
    with pytest.raises(ValueError, match=r'"sxyz" .* got \'xyz\''):
        tft.quaternion_from_euler(0, 0, 1, axes="xyz")
    with pytest.raises(ValueError, match="no axis twice in a row"):
        tft.euler_from_quaternion([0, 0, 0, 1], axes="sxxy")
    with pytest.raises(AttributeError, match="has no arcball_map_to_sphere: it has"):
        tft.arcball_map_to_sphere  # noqa: B018
    assert tft.quaternion_from_euler.__name__ == "quaternion_from_euler"
    assert tf.transformations is sys.modules["duckielib.libraries.tf.transformations"]


# -- tf2_ros.Buffer -------------------------------------------------------------------------------
def chain_buffer():
    """world -> odom (static), odom -> base at 10 and 11 s (turning 90 degrees), a -> b apart."""
    buffer = tf2_ros.Buffer()
    buffer.set_transform_static(stamped("world", "odom", 5, (1.0, 2.0, 0.0)), "test")
    buffer.set_transform(stamped("odom", "base", 10, (1.0, 0.0, 0.0)), "test")
    buffer.set_transform(stamped("odom", "base", 11, (2.0, 0.0, 0.0), yaw(math.pi / 2)), "test")
    buffer.set_transform(stamped("a", "b", 10, (1.0, 0.0, 0.0)), "test")
    return buffer


def test_a_lookup_composes_the_chain_at_the_latest_common_time():
    buffer = chain_buffer()
    found = buffer.lookup_transform("world", "base", rospy.Time(0))
    assert found.header.frame_id == "world"
    assert found.child_frame_id == "base"
    assert found.header.stamp == rospy.Time(11)
    assert close(pose(found)[0], [3, 2, 0])
    assert close(pose(found)[1], yaw(math.pi / 2))
    # The other way round: where the world's origin is, seen from the robot (turned 90 deg).
    back = buffer.lookup_transform("base", "world", rospy.Time(0))
    assert close(pose(back)[0], [-2, 3, 0])
    assert close(pose(back)[1], [0, 0, -S45, S45])
    # Static transforms hold at any time; a frame to itself is the identity.
    static = buffer.lookup_transform("odom", "world", rospy.Time(1000))
    assert static.header.stamp == rospy.Time(1000)
    assert close(pose(static)[0], [-1, -2, 0])
    same = buffer.lookup_transform("base", "base", rospy.Time(0))
    assert same.header.stamp == rospy.Time(11)
    assert close(pose(same)[1], [0, 0, 0, 1])
    assert buffer.get_latest_common_time("world", "base") == rospy.Time(11)
    assert buffer.get_latest_common_time("world", "odom") == rospy.Time(0)


def test_a_lookup_between_stamps_interpolates():
    buffer = chain_buffer()
    found = buffer.lookup_transform("world", "base", rospy.Time(10.5))
    assert found.header.stamp == rospy.Time(10.5)
    assert close(pose(found)[0], [2.5, 2, 0])
    assert close(pose(found)[1], yaw(math.pi / 4))  # slerp: half of the quarter turn
    quarter = buffer.lookup_transform("odom", "base", rospy.Time(10.25))
    assert close(pose(quarter)[0], [1.25, 0, 0])
    assert close(pose(quarter)[1], yaw(math.pi / 8))


def test_lookups_that_cannot_succeed_raise_tf2s_exceptions():
    buffer = chain_buffer()
    lookup = buffer.lookup_transform
    with pytest.raises(tf2_ros.LookupException, match='"nope" passed to lookup_transform as'):
        lookup("world", "nope", rospy.Time(0))
    with pytest.raises(tf2_ros.ConnectivityException, match="not part of the same tree"):
        lookup("world", "b", rospy.Time(0))
    with pytest.raises(tf2_ros.ExtrapolationException, match=r"1\.000000000s into the future"):
        lookup("world", "base", rospy.Time(12))
    with pytest.raises(tf2_ros.ExtrapolationException, match="into the past"):
        lookup("world", "base", rospy.Time(9))
    with pytest.raises(tf2_ros.ExtrapolationException, match=r"only time 10\.0+ is in"):
        lookup("a", "b", rospy.Time(11))
    with pytest.raises(tf2_ros.InvalidArgumentException, match='cannot start with a "/"'):
        lookup("/world", "base", rospy.Time(0))
    with pytest.raises(tf2_ros.InvalidArgumentException, match="empty frame name"):
        lookup("", "base", rospy.Time(0))
    with pytest.raises(TypeError, match=r"rospy\.Time\(0\) for the latest"):
        lookup("world", "base", 0)
    assert issubclass(tf2_ros.ExtrapolationException, tf2_ros.TransformException)
    assert tf.LookupException is tf2_ros.LookupException
    assert tf.Exception is tf2_ros.TransformException
    assert buffer.can_transform("world", "base", rospy.Time(10.7))
    ok, why = buffer.can_transform("world", "base", rospy.Time(20), return_debug_tuple=True)
    assert not ok
    assert "into the future" in why


def test_the_buffer_keeps_cache_time_and_refuses_bad_transforms(graph):
    buffer = tf2_ros.Buffer(cache_time=rospy.Duration(10))
    add = buffer.set_transform
    for secs in (10, 11, 25):
        add(stamped("a", "g", secs, (secs, 0.0, 0.0)), "test")
    with pytest.raises(tf2_ros.ExtrapolationException, match="only time 25"):
        buffer.lookup_transform("a", "g", rospy.Time(14))
    add(stamped("a", "g", 15, (15.0, 0.0, 0.0)), "test")  # exactly cache_time back: kept
    add(stamped("a", "g", 14.9, (14.9, 0.0, 0.0)), "test")  # older: refused
    add(stamped("a", "g", 15, (99.0, 0.0, 0.0)), "test")  # the same stamp again: refused
    assert close(pose(buffer.lookup_transform("a", "g", rospy.Time(15)))[0], [15, 0, 0])
    add(stamped("a", "g", 16, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0)), "test")
    add(stamped("a", "a", 16), "test")
    add(stamped("", "h", 16), "test")
    add(stamped("a", "h", 16, (math.nan, 0.0, 0.0)), "test")
    # Leading slashes are dropped from what is received.
    add(stamped("/c", "/d", 16), "test")
    assert buffer.can_transform("c", "d", rospy.Time(16))
    assert buffer.all_frames_as_string() == (
        "Frame g exists with parent a.\nFrame d exists with parent c.\n"
    )
    warnings = [r.text for r in graph.log if r.level == WARN]
    errors = [r.text for r in graph.log if r.level == ERROR]
    assert len(warnings) == 2
    assert "older than the buffer keeps" in warnings[0]
    assert "already has one at that time" in warnings[1]
    assert len(errors) == 4
    assert "not a unit quaternion" in errors[0]
    assert "cannot be its own parent" in errors[1]
    assert "has no parent frame" in errors[2]
    assert "NaN" in errors[3]
    buffer.clear()
    assert buffer.all_frames_as_string() == (
        "Frame g exists with parent NO_PARENT.\nFrame d exists with parent NO_PARENT.\n"
    )


def test_static_transforms_survive_clear_and_a_reparented_frame_moves():
    buffer = tf2_ros.Buffer()
    buffer.set_transform_static(stamped("map", "world", 1, (5.0, 0.0, 0.0)), "test")
    buffer.set_transform_static(stamped("earth", "world", 1, (7.0, 0.0, 0.0)), "test")
    buffer.clear()
    found = buffer.lookup_transform("earth", "world", rospy.Time(3))
    assert close(pose(found)[0], [7, 0, 0])
    with pytest.raises(tf2_ros.ConnectivityException):
        buffer.lookup_transform("map", "world", rospy.Time(0))


def test_a_full_lookup_travels_in_time_through_a_fixed_frame():
    buffer = tf2_ros.Buffer()
    for secs, x in ((10, 1.0), (12, 3.0)):
        buffer.set_transform(stamped("odom", "base", secs, (x, 0.0, 0.0)), "test")
    # Where the robot was at 10 s, seen from where it is at 12 s: 2 m behind.
    found = buffer.lookup_transform_full("base", rospy.Time(12), "base", rospy.Time(10), "odom")
    assert found.header.stamp == rospy.Time(12)
    assert close(pose(found)[0], [-2, 0, 0])


# -- on the graph ---------------------------------------------------------------------------------
def broadcaster_node(start=0.0):
    """world -> odom (static); odom -> base at 10 Hz, driving 1 m/s along x, turning 0.5 rad/s."""
    rospy.init_node("odometry")
    if start:
        rospy.sleep(start)
    static = tf2_ros.StaticTransformBroadcaster()
    static.sendTransform(stamped("world", "odom", 0, (1.0, 2.0, 0.0)))
    static.sendTransform(stamped("world", "camera", 0, (0.0, 0.0, 1.0)))
    broadcaster = tf.TransformBroadcaster()
    rate = rospy.Rate(10)
    begin = rospy.get_time()
    while not rospy.is_shutdown():
        now = rospy.Time.now()
        elapsed = now.to_sec() - begin
        rotation = tft.quaternion_from_euler(0, 0, 0.5 * elapsed)
        broadcaster.sendTransform((elapsed, 0.0, 0.0), rotation, now, "base", "odom")
        rate.sleep()


def test_a_listener_node_looks_up_a_chained_transform(graph):
    found = {}

    def listener_node():
        rospy.init_node("listener")
        buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(buffer)
        # Nothing is published yet: the timeout waits for the first transforms.
        first = buffer.lookup_transform("world", "base", rospy.Time(0), rospy.Duration(1.0))
        found["first"] = (first.header.stamp.to_sec(), pose(first))
        rospy.sleep(1.05)
        latest = buffer.lookup_transform("world", "base", rospy.Time(0))
        found["latest"] = (latest.header.stamp.to_sec(), pose(latest))
        between = buffer.lookup_transform("world", "base", rospy.Time(100.95))
        found["between"] = pose(between)
        found["camera"] = pose(buffer.lookup_transform("camera", "odom", rospy.Time(0)))
        for name, frame, when in (("unknown", "nope", 0), ("future", "base", 200)):
            try:
                buffer.lookup_transform("world", frame, rospy.Time(when))
            except tf2_ros.TransformException as error:
                found[name] = type(error)
        waited = rospy.get_time()
        found["gave_up"] = buffer.can_transform(
            "world", "base", rospy.Time(200), rospy.Duration(0.5)
        )
        found["waited"] = rospy.get_time() - waited

    graph.launch(listener_node)
    graph.launch(broadcaster_node, 0.5)
    graph.run(3.0)
    assert [r.text for r in graph.log if r.level >= WARN] == []
    # The first transforms are those of 100.5 s (the broadcaster starts then, elapsed 0).
    stamp, (xyz, q) = found["first"]
    assert stamp == pytest.approx(100.5)
    assert close(xyz, [1, 2, 0])
    assert close(q, [0, 0, 0, 1])
    # A second later (101.5 s): 1 m along x, turned 0.5 rad; world -> odom adds (1, 2, 0).
    stamp, (xyz, q) = found["latest"]
    assert stamp == pytest.approx(101.5)
    assert close(xyz, [2, 2, 0], 1e-9)
    assert close(q, yaw(0.5), 1e-9)
    # Half way between the stamps of 100.9 s and 101.0 s.
    xyz, q = found["between"]
    assert close(xyz, [1.45, 2, 0], 1e-9)
    assert close(q, yaw(0.225), 1e-9)
    assert close(found["camera"][0], [1, 2, -1])
    assert found["unknown"] is tf2_ros.LookupException
    assert found["future"] is tf2_ros.ExtrapolationException
    assert found["gave_up"] is False
    assert found["waited"] == pytest.approx(0.5, abs=1e-3)


def test_static_transforms_accumulate_for_late_listeners(graph):
    found = {}

    def late_listener():
        rospy.init_node("late")
        rospy.sleep(1.0)
        buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(buffer)
        rospy.sleep(0.1)
        found["frames"] = buffer.all_frames_as_string()
        msg = rospy.wait_for_message("/tf_static", tf2_ros.TFMessage, timeout=1.0)
        found["latched"] = sorted(t.child_frame_id for t in msg.transforms)

    def static_node():
        rospy.init_node("static")
        broadcaster = tf2_ros.StaticTransformBroadcaster()
        broadcaster.sendTransform(stamped("base", "camera", 0, (0.1, 0.0, 0.1)))
        broadcaster.sendTransform(
            [stamped("base", "imu", 0), stamped("base", "camera", 0, (0.2, 0.0, 0.1))]
        )
        rospy.spin()

    graph.launch(static_node)
    graph.launch(late_listener)
    graph.run(1.5)
    assert found["latched"] == ["camera", "imu"]
    assert found["frames"] == (
        "Frame camera exists with parent base.\nFrame imu exists with parent base.\n"
    )


def test_tfs_listener_and_broadcaster(graph):
    found = {}

    def tf_listener():
        rospy.init_node("old_listener")
        listener = tf.TransformListener()
        listener.waitForTransform("/world", "/base", rospy.Time(0), rospy.Duration(2.0))
        rospy.sleep(1.05)
        trans, rot = listener.lookupTransform("/world", "base", rospy.Time(0))
        found["lookup"] = (trans, rot)
        found["common"] = listener.getLatestCommonTime("world", "base").to_sec()
        found["exists"] = (listener.frameExists("base"), listener.frameExists("world"))
        point = PointStamped()
        point.header.frame_id = "base"
        point.header.stamp = rospy.Time(0)
        point.point.x = 1.0
        found["point"] = listener.transformPoint("world", point)
        found["can"] = listener.canTransform("world", "base", rospy.Time(300))
        try:
            listener.waitForTransform("world", "nope", rospy.Time(0), rospy.Duration(0.2))
        except tf.Exception as error:
            found["wait_error"] = str(error)

    graph.launch(tf_listener)
    graph.launch(broadcaster_node)
    graph.run(2.0)
    trans, rot = found["lookup"]
    assert isinstance(trans, list)
    assert found["common"] == pytest.approx(101.0)
    assert close(trans, [2, 2, 0], 1e-9)
    assert close(rot, yaw(0.5), 1e-9)
    assert found["exists"] == (True, False)  # as in tf: a tree's root has no parent to list
    point = found["point"]
    assert point.header.frame_id == "world"
    assert close([point.point.x, point.point.y], [2 + math.cos(0.5), 2 + math.sin(0.5)], 1e-9)
    assert found["can"] is False
    assert '"nope" passed to' in found["wait_error"]


def test_broadcasters_explain_wrong_arguments(graph):
    errors = {}

    def node():
        rospy.init_node("wrong")
        broadcaster = tf.TransformBroadcaster()
        try:
            broadcaster.sendTransform((0, 0, 0), (0, 0, 1.5), rospy.Time.now(), "base", "odom")
        except ValueError as error:
            errors["euler"] = str(error)
        try:
            broadcaster.sendTransform((0, 0, 0), (0, 0, 0, 1), rospy.get_time(), "base", "odom")
        except TypeError as error:
            errors["time"] = str(error)
        try:
            tf2_ros.TransformBroadcaster().sendTransform("base")
        except TypeError as error:
            errors["type"] = str(error)

    graph.launch(node)
    graph.run(0.1)
    assert "quaternion_from_euler(roll, pitch, yaw)" in errors["euler"]
    assert "rospy.Time.now()" in errors["time"]
    assert "geometry_msgs/TransformStamped or a list" in errors["type"]


def test_a_timeout_needs_a_node(graph):
    buffer = tf2_ros.Buffer()  # in the test's own code, which has no node on the graph
    with pytest.raises(rospy.ROSInitException, match="init_node"):
        buffer.lookup_transform("a", "b", rospy.Time(0), rospy.Duration(1))


# -- robot code's imports -------------------------------------------------------------------------
def test_robot_code_imports_tf_and_tf2_ros_by_name():
    script = (
        "import duckielib.ros\n"
        "import tf\n"
        "import tf.transformations\n"
        "from tf.transformations import euler_from_quaternion, quaternion_from_euler\n"
        "import tf2_ros\n"
        "import tf.transformations as tft\n"
        "print(tf.__name__, tf2_ros.__name__, tf.transformations is tft,\n"
        "      tft.quaternion_from_euler is quaternion_from_euler,\n"
        "      round(euler_from_quaternion(quaternion_from_euler(0, 0, 1.25))[2], 6),\n"
        "      tf.ExtrapolationException is tf2_ros.ExtrapolationException)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=False, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == [
        "duckielib.libraries.tf",
        "duckielib.libraries.tf2_ros",
        "True",
        "True",
        "1.25",
        "True",
    ]


# -- against Debian's tf and tf2_ros --------------------------------------------------------------
def debian(script: str, needs: Path) -> object:
    """What ``script`` prints as JSON, run by Debian's Python with its ROS packages."""
    if not (DEBIAN_PYTHON.exists() and needs.exists()):
        pytest.skip("Debian's tf and tf2_ros are not installed; run `make ros`.")
    result = subprocess.run(
        [str(DEBIAN_PYTHON), "-c", script],
        capture_output=True,
        text=True,
        check=False,
        timeout=120,
        cwd="/",
    )
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.splitlines()[-1])


TRANSFORMATIONS_SCRIPT = """
import json, math
import tf.transformations as tft
axes, angles, quaternions = json.loads({inputs!r})
out = {{}}
for ax in axes:
    for i, a in enumerate(angles):
        q = tft.quaternion_from_euler(*a, axes=ax)
        m = tft.euler_matrix(*a, axes=ax)
        out[ax + str(i)] = [q.tolist(), m.tolist(), list(tft.euler_from_quaternion(q, axes=ax)),
                            list(tft.euler_from_matrix(m, axes=ax))]
for i, q in enumerate(quaternions):
    m = tft.quaternion_matrix(q)
    out["q" + str(i)] = [m.tolist(), tft.quaternion_from_matrix(m).tolist(),
                         tft.quaternion_inverse(q).tolist(),
                         tft.quaternion_multiply(q, quaternions[0]).tolist(),
                         tft.quaternion_slerp(quaternions[0], q, 0.3).tolist(),
                         tft.quaternion_about_axis(0.7, q[:3]).tolist(),
                         tft.translation_matrix(q[:3]).tolist()]
print(json.dumps(out))
"""


@pytest.mark.ros
def test_transformations_agree_with_debians():
    angles = [*ANGLES, (2.0, math.pi, 1.0), (-0.7, -math.pi / 2, 0.9)]
    quaternions = [
        [0.1, 0.2, 0.3, 0.9],
        [0.5, -0.5, 0.5, -0.5],
        [0.0, 0.0, 0.0, 1.0],
        [0.9, 0.1, -0.3, 0.05],
        [0.1, 0.95, 0.05, 0.02],
        [0.01, 0.02, 0.99, 0.01],
    ]
    inputs = json.dumps([AXES, angles, quaternions])
    real = debian(TRANSFORMATIONS_SCRIPT.format(inputs=inputs), DEBIAN_TF)
    for ax in AXES:
        for i, a in enumerate(angles):
            q = tft.quaternion_from_euler(*a, axes=ax)
            m = tft.euler_matrix(*a, axes=ax)
            ours = [q, m, tft.euler_from_quaternion(q, axes=ax), tft.euler_from_matrix(m, axes=ax)]
            for mine, theirs in zip(ours, real[f"{ax}{i}"]):
                assert close(mine, theirs, 1e-9), (ax, a, mine, theirs)
    for i, q in enumerate(quaternions):
        m = tft.quaternion_matrix(q)
        ours = [
            m,
            tft.quaternion_from_matrix(m),
            tft.quaternion_inverse(q),
            tft.quaternion_multiply(q, quaternions[0]),
            tft.quaternion_slerp(quaternions[0], q, 0.3),
            tft.quaternion_about_axis(0.7, q[:3]),
            tft.translation_matrix(q[:3]),
        ]
        for mine, theirs in zip(ours, real[f"q{i}"]):
            assert close(mine, theirs, 1e-9), (q, mine, theirs)


#: Transforms: (static?, parent, child, stamp, translation, rotation).
SCENARIO = [
    (True, "world", "odom", 5, (1.0, 2.0, 0.0), (0.0, 0.0, 0.0, 1.0)),
    (False, "odom", "base", 10, (1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)),
    (False, "odom", "base", 11, (2.0, 0.5, 0.1), (0.1, 0.2, 0.3, 0.9273618495495703)),
    (False, "odom", "base", 12, (2.5, 1.0, 0.0), (0.0, 0.0, -S45, -S45)),
    (True, "base", "camera", 0, (0.1, 0.0, 0.2), (-0.5, 0.5, -0.5, 0.5)),
    (False, "a", "b", 10, (1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)),
    (False, "world", "map", 9, (0.0, 3.0, 0.0), (0.0, 0.0, 0.0, 1.0)),
    (False, "odom", "base", 11, (9.0, 9.0, 9.0), (0.0, 0.0, 0.0, 1.0)),  # repeated stamp
]
#: Lookups: (target, source, time).
QUERIES = [
    ("world", "base", 0),
    ("world", "base", 10.5),
    ("world", "base", 11.75),
    ("base", "world", 11.25),
    ("camera", "world", 11.5),
    ("world", "camera", 0),
    ("camera", "map", 0),
    ("map", "camera", 0),
    ("camera", "map", 10),
    ("world", "base", 12.5),
    ("world", "base", 9),
    ("world", "nope", 0),
    ("nope", "base", 0),
    ("world", "b", 0),
    ("a", "b", 11),
    ("base", "base", 0),
    ("odom", "world", 1000),
    ("/world", "base", 0),
]

BUFFER_SCRIPT = """
import json, rospy, tf2_ros
from geometry_msgs.msg import TransformStamped
scenario, queries = json.loads({inputs!r})
buffer = tf2_ros.Buffer(debug=False)
for static, parent, child, secs, xyz, q in scenario:
    t = TransformStamped()
    t.header.frame_id, t.child_frame_id, t.header.stamp = parent, child, rospy.Time(secs)
    tr, rot = t.transform.translation, t.transform.rotation
    tr.x, tr.y, tr.z = xyz
    rot.x, rot.y, rot.z, rot.w = q
    (buffer.set_transform_static if static else buffer.set_transform)(t, "test")
out = []
for target, source, secs in queries:
    try:
        found = buffer.lookup_transform(target, source, rospy.Time(secs))
    except tf2_ros.TransformException as error:
        out.append(type(error).__name__)
        continue
    t, r = found.transform.translation, found.transform.rotation
    out.append([found.header.stamp.to_sec(), found.header.frame_id, found.child_frame_id,
                [t.x, t.y, t.z], [r.x, r.y, r.z, r.w]])
print(json.dumps(out))
"""


@pytest.mark.ros
def test_buffer_lookups_agree_with_debians(graph):
    real = debian(BUFFER_SCRIPT.format(inputs=json.dumps([SCENARIO, QUERIES])), DEBIAN_TF2_ROS)
    buffer = tf2_ros.Buffer()
    for static, parent, child, secs, xyz, q in SCENARIO:
        add = buffer.set_transform_static if static else buffer.set_transform
        add(stamped(parent, child, secs, xyz, q), "test")
    for (target, source, secs), theirs in zip(QUERIES, real):
        if isinstance(theirs, str):  # the name of the exception Debian's raised
            with pytest.raises(getattr(tf2_ros, theirs)):
                buffer.lookup_transform(target, source, rospy.Time(secs))
            continue
        found = buffer.lookup_transform(target, source, rospy.Time(secs))
        stamp, frame, child, xyz, q = theirs
        assert found.header.stamp.to_sec() == pytest.approx(stamp, abs=1e-9)
        assert (found.header.frame_id, found.child_frame_id) == (frame, child)
        assert close(pose(found)[0], xyz, 1e-9), (target, source, secs)
        assert close(pose(found)[1], q, 1e-9), (target, source, secs)
