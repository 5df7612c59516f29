"""rosbag's Python API as nodes use it: a bag written during a run, read back three ways."""

from __future__ import annotations

import io
import json
import subprocess
import sys
import textwrap
import time as wallclock
from pathlib import Path

import pytest

from duckielib.bags import Bag as CourseBag
from duckielib.bags import BagWriter
from duckielib.libraries import rosbag
from duckielib.messages import Header, String, WheelEncoderStamped
from duckielib.ros import Graph, rospy
from duckielib.ros.log import ERROR
from duckielib.rostime import Time

SYSTEM_PYTHON = Path("/usr/bin/python3")
CHATTER = "/chatter"
TICKS = "/duckiebot/left_wheel_encoder_node/tick"
NS = 1_000_000_000


def talker():
    rospy.init_node("talker")
    chatter = rospy.Publisher("chatter", String, queue_size=10)
    ticks = rospy.Publisher(TICKS, WheelEncoderStamped, queue_size=10)
    rate = rospy.Rate(10)
    count = 0
    while not rospy.is_shutdown():
        chatter.publish(String(data=f"hello {count}"))
        if count:
            tick = WheelEncoderStamped(data=3 * count, resolution=135, type=1)
            # Stamped 5 ms before it is sent: the bag records the stamp as the time.
            tick.header.stamp = rospy.Time.now() - rospy.Duration(0, 5_000_000)
            tick.header.frame_id = "duckiebot/left_wheel_axis"
            ticks.publish(tick)
        count += 1
        rate.sleep()


def logger(path):
    """A node that records what it hears into a bag, as robot code does with rosbag."""
    import rosbag as api

    rospy.init_node("logger")
    with api.Bag(path, "w") as bag:

        def on_chatter(msg):
            bag.write("/chatter", msg)  # record time: now

        def on_tick(msg):
            bag.write(TICKS, msg, t=msg.header.stamp)

        rospy.Subscriber("chatter", String, on_chatter, queue_size=10)
        rospy.Subscriber(TICKS, WheelEncoderStamped, on_tick, queue_size=10)
        rospy.spin()


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A bag written by a node during 1 s of simulated time."""
    path = tmp_path_factory.mktemp("rosbag") / "run.bag"
    monkeypatch = pytest.MonkeyPatch()
    monkeypatch.setitem(sys.modules, "rosbag", rosbag)
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    try:
        graph.launch(logger, str(path))
        graph.launch(talker)
        graph.run(1.0)
        graph.shutdown()
    finally:
        monkeypatch.undo()
    assert [record.text for record in graph.log if record.level == ERROR] == []
    return path


#: What the talker sent in 1 s: (topic, record time in ns, values).
#: The first message, written at time 0, is recorded at 1 ns: ROS 1's smallest valid time.
EXPECTED = sorted(
    [(CHATTER, max(1, i * NS // 10), {"data": f"hello {i}"}) for i in range(11)]
    + [(TICKS, i * NS // 10 - 5_000_000, {"data": 3 * i}) for i in range(1, 11)],
    key=lambda item: item[1],
)


def test_a_node_writes_a_bag_on_simulated_time(recorded):
    with rosbag.Bag(str(recorded)) as bag:
        found = list(bag.read_messages())
        assert [(m.topic, m.timestamp.to_nsec()) for m in found] == [
            (topic, time_ns) for topic, time_ns, _ in EXPECTED
        ]
        assert all(type(m.timestamp) is rospy.Time for m in found)
        for (topic, msg, t), (_, _, values) in zip(found, EXPECTED):
            assert {key: getattr(msg, key) for key in values} == values
            assert isinstance(msg, String if topic == CHATTER else WheelEncoderStamped)
            if topic == TICKS:
                assert msg.header.stamp.to_nsec() == t.to_nsec()
                assert msg.header.frame_id == "duckiebot/left_wheel_axis"
                assert msg.resolution == 135
        assert bag.get_message_count() == 21
        assert bag.get_message_count(CHATTER) == 11
        assert bag.get_message_count([CHATTER, TICKS, "/nothing"]) == 21
        assert bag.get_start_time() == 1e-9
        assert bag.get_end_time() == 1.0
        info = bag.get_type_and_topic_info()
        assert info.msg_types == {
            "duckietown_msgs/WheelEncoderStamped": WheelEncoderStamped._md5sum,
            "std_msgs/String": String._md5sum,
        }
        assert sorted(info.topics) == [CHATTER, TICKS]
        chatter = info.topics[CHATTER]
        assert (chatter.msg_type, chatter.message_count, chatter.connections) == (
            "std_msgs/String",
            11,
            1,
        )
        assert chatter.frequency == pytest.approx(10.0)
        assert info.topics[TICKS].message_count == 10
        only = bag.get_type_and_topic_info(topic_filters=TICKS)
        assert list(only.topics) == [TICKS]
        assert len(only.msg_types) == 2  # every type of the bag, as rosbag gives


def test_the_projects_bag_reader_reads_the_same(recorded):
    bag = CourseBag(recorded)
    assert {name: info.count for name, info in bag.topics.items()} == {CHATTER: 11, TICKS: 10}
    found = [(m.topic, m.time_ns, m.message) for m in bag.messages()]
    assert [(topic, time_ns) for topic, time_ns, _ in found] == [
        (topic, time_ns) for topic, time_ns, _ in EXPECTED
    ]
    for (_, _, msg), (_, _, values) in zip(found, EXPECTED):
        assert {key: getattr(msg, key) for key in values} == values
    assert bag.compression == "none"


#: Reads a bag with Debian's rosbag and prints every message as JSON.
DEBIAN_READ = textwrap.dedent(
    """
    import json, sys
    import rosbag

    def plain(value):
        if hasattr(value, "to_nsec"):
            return value.to_nsec()
        if hasattr(value, "__slots__"):
            return {name: plain(getattr(value, name)) for name in value.__slots__}
        return value

    with rosbag.Bag(sys.argv[1]) as bag:
        info = bag.get_type_and_topic_info()
        found = [[topic, t.to_nsec(), msg._type, plain(msg)]
                 for topic, msg, t in bag.read_messages()]
        print(json.dumps({
            "count": bag.get_message_count(),
            "start": bag.get_start_time(),
            "end": bag.get_end_time(),
            "types": info.msg_types,
            "topics": {name: list(topic) for name, topic in info.topics.items()},
            "messages": found,
        }))
    """
)

#: Writes a bag with Debian's rosbag and genpy's std_msgs.
DEBIAN_WRITE = textwrap.dedent(
    """
    import sys
    import genpy, rosbag
    from std_msgs.msg import String

    with rosbag.Bag(sys.argv[1], "w", compression="bz2") as bag:
        for i in range(5):
            bag.write("/notes", String(data="note %d" % i), genpy.Time(7, i * 250000000))
    """
)


def debian(script, *args, tmp_path):
    """Run a script with Debian's Python and its ROS packages, or skip saying why."""
    if not SYSTEM_PYTHON.exists():
        pytest.skip("Debian's /usr/bin/python3 is not installed; run `make ros`.")
    probe = subprocess.run(
        [str(SYSTEM_PYTHON), "-c", "import rosbag"],
        env={"PATH": "/usr/bin:/bin", "HOME": str(tmp_path)},
        capture_output=True,
        text=True,
        check=False,
    )
    if probe.returncode != 0:
        pytest.skip("Debian's rosbag Python API is not installed; run `make ros`.")
    result = subprocess.run(
        [str(SYSTEM_PYTHON), "-c", script, *map(str, args)],
        env={"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "LANG": "C.UTF-8"},
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    return result.stdout


@pytest.mark.ros
def test_debians_rosbag_reads_the_nodes_bag(recorded, tmp_path):
    report = json.loads(debian(DEBIAN_READ, recorded, tmp_path=tmp_path))
    assert report["count"] == 21
    assert (report["start"], report["end"]) == (1e-9, 1.0)
    assert report["types"] == {
        "duckietown_msgs/WheelEncoderStamped": WheelEncoderStamped._md5sum,
        "std_msgs/String": String._md5sum,
    }
    assert report["topics"][CHATTER][:3] == ["std_msgs/String", 11, 1]
    assert report["topics"][CHATTER][3] == pytest.approx(10.0)
    assert report["topics"][TICKS][:3] == ["duckietown_msgs/WheelEncoderStamped", 10, 1]
    with rosbag.Bag(str(recorded)) as bag:
        ours = bag.get_type_and_topic_info()
        assert sorted(ours.topics) == sorted(report["topics"])
        for name, topic in ours.topics.items():
            assert list(topic[:3]) == report["topics"][name][:3]
            assert topic.frequency == pytest.approx(report["topics"][name][3], rel=1e-12)
    messages = report["messages"]
    assert [(topic, t) for topic, t, _, _ in messages] == [(topic, t) for topic, t, _ in EXPECTED]
    for (_, _, kind, msg), (_, time_ns, values) in zip(messages, EXPECTED):
        assert {key: msg[key] for key in values} == values
        if kind == "duckietown_msgs/WheelEncoderStamped":
            assert msg["header"]["stamp"] == time_ns
            assert msg["header"]["frame_id"] == "duckiebot/left_wheel_axis"


@pytest.mark.ros
def test_a_bag_debians_rosbag_wrote_reads_here(tmp_path):
    path = tmp_path / "notes.bag"
    debian(DEBIAN_WRITE, path, tmp_path=tmp_path)
    with rosbag.Bag(str(path)) as bag:
        found = [(topic, msg.data, t) for topic, msg, t in bag.read_messages("/notes")]
        assert bag.get_message_count() == 5
        assert bag.get_start_time() == 7.0
        assert bag.get_end_time() == 8.0
    assert found == [("/notes", f"note {i}", rospy.Time(7, i * 250_000_000)) for i in range(5)]
    assert all(isinstance(msg, String) for _, msg, _ in rosbag.Bag(str(path)).read_messages())


# -- the API's details --------------------------------------------------------------------------
def write_sample(path, **options):
    with rosbag.Bag(str(path), "w", **options) as bag:
        for i in range(4):
            bag.write("/a", String(data=f"a{i}"), rospy.Time(1 + i))
            tick = WheelEncoderStamped(data=i, header=Header(stamp=Time(1 + i, 5)))
            bag.write("/b", tick, tick.header.stamp)
    return path


def test_reading_filters_by_topic_time_and_connection(tmp_path):
    path = write_sample(tmp_path / "sample.bag", compression=rosbag.Compression.BZ2)
    with rosbag.Bag(path) as bag:
        assert bag.mode == "r"
        assert bag.compression == "none"  # as given: reading takes what the bag holds
        assert [m.message.data for m in bag.read_messages(topics="/a")] == [
            "a0",
            "a1",
            "a2",
            "a3",
        ]
        assert [m.topic for m in bag.read_messages(topics=["/b", "/missing"])] == ["/b"] * 4
        assert len(list(bag.read_messages(topics=[]))) == 8  # an empty list: every topic
        assert len(list(bag.read_messages(topics="/a/"))) == 4  # names are made canonical
        window = bag.read_messages(start_time=rospy.Time(2), end_time=rospy.Time(3, 5))
        assert [(m.topic, m.timestamp.to_nsec()) for m in window] == [
            ("/a", 2 * NS),
            ("/b", 2 * NS + 5),
            ("/a", 3 * NS),
            ("/b", 3 * NS + 5),
        ]
        stamped = bag.read_messages(
            connection_filter=lambda topic, kind, md5sum, definition, header: kind.endswith(
                "Stamped"
            )
        )
        assert {m.topic for m in stamped} == {"/b"}
        first = next(iter(bag.read_messages(return_connection_header=True)))
        assert first.connection_header["type"] == "std_msgs/String"
        assert first.connection_header["md5sum"] == String._md5sum
        assert first.connection_header["message_definition"] == String._full_text
        topic, msg, t = next(iter(bag))
        assert (topic, msg.data, t) == ("/a", "a0", rospy.Time(1))
    assert CourseBag(path).compression == "bz2"


def test_raw_messages_copy_a_bag(tmp_path):
    source = write_sample(tmp_path / "sample.bag")
    copy = tmp_path / "copy.bag"
    with rosbag.Bag(source) as bag, rosbag.Bag(copy, "w") as out:
        for topic, raw, t in bag.read_messages(raw=True):
            _, _, md5sum, position, cls = raw
            assert (position, cls._md5sum) == (None, md5sum)
            out.write(topic, raw, t, raw=True)
    a, b = CourseBag(source), CourseBag(copy)
    assert b.raw_messages(["/a", "/b"]) == a.raw_messages(["/a", "/b"])


def test_appending_adds_messages_and_reading_while_writing_sees_them(tmp_path):
    path = write_sample(tmp_path / "sample.bag")
    with rosbag.Bag(path, "a") as bag:
        assert bag.get_message_count() == 8
        bag.write("/c", String(data="late"), rospy.Time(9))
        assert bag.get_message_count("/c") == 1
        assert [m.message.data for m in bag.read_messages("/c")] == ["late"]
        assert bag.get_end_time() == 9.0
        assert path.exists()
    with rosbag.Bag(path) as bag:
        assert bag.get_message_count() == 9
        assert [m.topic for m in bag.read_messages()][-1] == "/c"
    fresh = tmp_path / "fresh.bag"
    with rosbag.Bag(fresh, "a") as bag:  # "a" creates a missing bag
        bag.write("/a", String(data="x"), rospy.Time(1))
    assert CourseBag(fresh).message_count == 1
    with rosbag.Bag(path, "w") as bag:  # "w" replaces a bag
        bag.write("/z", String(data="only"), rospy.Time(1))
    assert list(CourseBag(path).topics) == ["/z"]


def test_outside_a_node_the_record_time_is_the_wall_clock(tmp_path):
    before = wallclock.time_ns()
    with rosbag.Bag(tmp_path / "wall.bag", "w") as bag:
        bag.write("/a", String(data="x"))
    after = wallclock.time_ns()
    (message,) = rosbag.Bag(tmp_path / "wall.bag").read_messages()
    assert before <= message.timestamp.to_nsec() <= after


def test_mistakes_raise_what_rosbag_raises(tmp_path):
    with pytest.raises(FileNotFoundError):
        rosbag.Bag(tmp_path / "missing.bag")
    not_a_bag = tmp_path / "notes.txt"
    not_a_bag.write_text("hello")
    with pytest.raises(rosbag.ROSBagException, match="not a ROS 1 bag"):
        rosbag.Bag(not_a_bag)
    with pytest.raises(ValueError, match="'none' or 'bz2'"):
        rosbag.Bag(tmp_path / "x.bag", "w", compression=rosbag.Compression.LZ4)
    with pytest.raises(ValueError, match="mode"):
        rosbag.Bag(tmp_path / "x.bag", "rw")
    bag = rosbag.Bag(tmp_path / "empty.bag", "w")
    with pytest.raises(TypeError, match="ROS message"):
        bag.write("/a", "hello")
    with pytest.raises(TypeError, match=r"rospy\.Time"):
        bag.write("/a", String(data="x"), 1.5)
    with pytest.raises(ValueError, match="topic"):
        bag.write("", String(data="x"), rospy.Time(1))
    bag.close()
    bag.close()  # twice does nothing
    with pytest.raises(ValueError, match="closed"):
        bag.read_messages()
    with pytest.raises(ValueError, match="closed"):
        bag.write("/a", String(data="x"), rospy.Time(1))
    with rosbag.Bag(tmp_path / "empty.bag") as empty:
        assert empty.get_message_count() == 0
        with pytest.raises(rosbag.ROSBagException, match="no messages"):
            empty.get_start_time()
    with rosbag.Bag(tmp_path / "empty.bag") as reading, pytest.raises(ValueError, match="reading"):
        reading.write("/a", String(data="x"), rospy.Time(1))
    assert rosbag.bag.ROSBagException is rosbag.ROSBagException
    assert issubclass(rosbag.ROSBagUnindexedException, rosbag.ROSBagException)


def test_a_bag_whose_recording_was_interrupted(tmp_path):
    path = tmp_path / "killed.bag"
    writer = BagWriter(path)
    for i in range(3):
        writer.write("/a", String(data=f"a{i}"), (1 + i) * NS)
    writer.flush()
    writer.abandon()
    with pytest.raises(rosbag.ROSBagUnindexedException, match="duckie bag repair"):
        rosbag.Bag(path)
    with rosbag.Bag(path, allow_unindexed=True) as bag:
        assert [m.message.data for m in bag.read_messages()] == ["a0", "a1", "a2"]
    with pytest.raises(rosbag.ROSBagUnindexedException):
        rosbag.Bag(path, "a")


def test_the_real_packages_module_paths_name_the_same_objects(monkeypatch):
    from importlib.metadata import entry_points

    for entry in entry_points(group="duckielib.ros_libraries"):
        monkeypatch.setitem(sys.modules, entry.name, entry.load())
    namespace = {}
    exec(  # robot code's imports, as written on a Duckiebot
        "import rosbag.bag\n"
        "from rosbag.bag import ROSBagException\n"
        "from cv_bridge.core import CvBridge, CvBridgeError\n"
        "import message_filters\n",
        namespace,
    )
    assert namespace["rosbag"].bag.Bag is rosbag.Bag
    assert namespace["ROSBagException"] is rosbag.ROSBagException
    assert namespace["CvBridgeError"].__module__ == "duckielib.libraries.cv_bridge"
    assert namespace["message_filters"].ApproximateTimeSynchronizer is not None
