"""Writing and reading bags: round trips through rosbags, foreign types, bad files."""

from __future__ import annotations

import pytest
from bagtools import LEFT, encoder, write_encoders
from rosbags.rosbag1 import Reader

from duckielib.bags import Bag, BagWriter, course_typestore
from duckielib.bags.seam import rosbags_type
from duckielib.errors import BagError
from duckielib.messages import LEDPattern, Pose2DStamped, String

POINT_DEFINITION = "float64 x\nfloat64 y\nfloat64 z\n"
POINT_MD5 = "4a842b65f413084dc2b10fb484ea7f17"


@pytest.mark.parametrize("compression", ["none", "bz2"])
def test_written_bags_read_back_exactly_with_rosbags(tmp_path, compression):
    path = tmp_path / "run.bag"
    pose = Pose2DStamped(x=1.25, y=-0.5, theta=3.0)
    pattern = LEDPattern(color_list=["red"] * 5, frequency=2.0, frequency_mask=[1, 0, 0, 0, 1])
    with BagWriter(path, compression) as writer:
        writer.write("/duckiebot/pose", pose, 1_000_000_001)
        writer.write("/duckiebot/led", pattern, 2_500_000_000)
        writer.write(LEFT, encoder(-41, 3_000_000_000), 3_000_000_000)
    store = course_typestore()
    with Reader(path) as reader:
        read = [(c.topic, t, c.digest, raw) for c, t, raw in reader.messages()]
    assert [(topic, t) for topic, t, _, _ in read] == [
        ("/duckiebot/pose", 1_000_000_001),
        ("/duckiebot/led", 2_500_000_000),
        (LEFT, 3_000_000_000),
    ]
    assert read[0][3] == pose.to_bytes()
    assert read[0][2] == Pose2DStamped._md5sum
    decoded = store.deserialize_ros1(read[0][3], rosbags_type("duckietown_msgs/Pose2DStamped"))
    assert (decoded.x, decoded.y, decoded.theta) == (1.25, -0.5, 3.0)
    led = store.deserialize_ros1(read[1][3], rosbags_type("duckietown_msgs/LEDPattern"))
    assert list(led.color_list) == ["red"] * 5
    assert list(led.frequency_mask) == [1, 0, 0, 0, 1]
    bag = Bag(path)
    assert bag.compression == compression
    assert [item.message for item in bag.messages()] == [pose, pattern, encoder(-41, 3_000_000_000)]


@pytest.mark.parametrize("compression", ["none", "bz2"])
def test_the_writer_writes_the_same_bytes_as_rosbags_own_write(tmp_path, compression):
    topics = [("/duckiebot/pose", Pose2DStamped), (LEFT, type(encoder(0, 0))), ("/s", String)]
    messages = [
        (topics[i % 3], 10_000_000 * i + (999_999_999 if i == 7 else 0) + 1) for i in range(400)
    ]  # from 1 ns: ROS 1's smallest valid time (a time 0 is written as 1 ns, tested below)
    ours, theirs = tmp_path / "ours.bag", tmp_path / "theirs.bag"
    with BagWriter(ours, compression) as writer:
        writer._writer.chunk_threshold = 4096  # several chunks, each with its index
        connections = {}
        items = []
        for (topic, cls), t_ns in messages:
            if topic not in connections:
                connections[topic] = writer.connection(
                    topic, cls._type, cls._md5sum, cls._full_text
                )
            items.append((connections[topic], t_ns, cls().to_bytes()))
            if len(items) <= 100:
                writer.write_connection(*items[-1])
        for start in range(100, 400, 75):  # batches that cross chunk boundaries
            writer.write_many(items[start : start + 75])
    plain = BagWriter(theirs, compression)
    try:
        plain._writer.chunk_threshold = 4096
        for (topic, cls), t_ns in messages:
            connection = plain.connection(topic, cls._type, cls._md5sum, cls._full_text)
            plain._writer.write(connection, t_ns, cls().to_bytes())  # rosbags' own write
    finally:
        plain.close()
    assert ours.read_bytes() == theirs.read_bytes()
    assert Bag(ours).message_count == 400
    with BagWriter(tmp_path / "other.bag") as other, pytest.raises(
        BagError, match=r"/s is not a connection of other\.bag"
    ):
        other.write_connection(connections["/s"], 0, b"")


def test_a_bad_item_stops_a_batch_and_keeps_the_items_before_it(tmp_path):
    path = tmp_path / "batch.bag"
    with BagWriter(path) as writer:
        connection = writer.connection("/s", String._type, String._md5sum, String._full_text)
        items = [(connection, t_ns, String(data=str(t_ns)).to_bytes()) for t_ns in (5, 6, -7, 8)]
        with pytest.raises(BagError, match="whole number of nanoseconds >= 0, not -7"):
            writer.write_many(items)
        assert writer.count == 2
    assert [(item.time_ns, item.message.data) for item in Bag(path).read("/s")] == [
        (5, "5"),
        (6, "6"),
    ]


def test_foreign_types_decode_from_the_bags_own_definition(tmp_path):
    path = tmp_path / "foreign.bag"
    import struct

    with BagWriter(path) as writer:
        data = struct.pack("<ddd", 1.0, 2.0, 3.5)
        writer.write_raw("/point", "geometry_msgs/Point", POINT_MD5, POINT_DEFINITION, 5, data)
    bag = Bag(path)
    assert bag.topics["/point"].type == "geometry_msgs/Point"
    point = bag.read("/point")[0].message
    assert (point.x, point.y, point.z) == (1.0, 2.0, 3.5)


def test_info_summarises_like_rosbag_info(tmp_path):
    path = write_encoders(tmp_path / "e.bag", [(0, 5), (10**9, 9)], [(5 * 10**8, 7)])
    text = Bag(path).info()
    assert "duration:    1.0s" in text
    assert "messages:    3" in text
    assert "duckietown_msgs/WheelEncoderStamped [141b74ec2cc3bde8c38b5e3bdb694d12]" in text
    assert f"{LEFT}         2 msgs    : duckietown_msgs/WheelEncoderStamped" in text


def test_writer_refuses_lz4_an_existing_file_and_bad_times(tmp_path):
    with pytest.raises(BagError, match="lz4"):
        BagWriter(tmp_path / "a.bag", "lz4")
    (tmp_path / "b.bag").write_bytes(b"x")
    with pytest.raises(BagError, match="exists already"):
        BagWriter(tmp_path / "b.bag")
    with BagWriter(tmp_path / "c.bag") as writer, pytest.raises(BagError, match="nanoseconds"):
        writer.write("/s", String("x"), -1)


def test_writer_finishes_the_bag_when_the_code_writing_it_fails(tmp_path):
    path = tmp_path / "crash.bag"
    with pytest.raises(ZeroDivisionError), BagWriter(path) as writer:  # noqa: PT012
        writer.write("/s", String("kept"), 1)
        raise ZeroDivisionError
    assert [item.message.data for item in Bag(path).read("/s")] == ["kept"]


def test_bad_files_get_one_clear_sentence(tmp_path):
    with pytest.raises(BagError, match="There is no file"):
        Bag(tmp_path / "missing.bag")
    text = tmp_path / "notes.txt"
    text.write_text("hello")
    with pytest.raises(BagError, match="is not a ROS 1 bag"):
        Bag(text)
    empty = tmp_path / "empty.bag"
    BagWriter(empty).close()
    bag = Bag(empty)
    assert bag.message_count == 0
    assert bag.topics == {}
    assert "(none: the bag is empty)" in bag.info()
    with pytest.raises(BagError, match="has no topic /x; its topics are: none"):
        bag.topic("/x")


def test_an_unindexed_bag_suggests_repair(tmp_path):
    path = tmp_path / "killed.bag"
    writer = BagWriter(path)
    writer.write("/s", String("a"), 1)
    writer.flush()  # on disk, but never closed: no index
    with pytest.raises(BagError, match="duckie bag repair"):
        Bag(path)
    writer.close()


def test_a_record_time_of_0_is_written_as_ros_smallest_valid_time(tmp_path):
    """rosbag play drops a message recorded at time 0 ("invalid time"): it becomes 1 ns."""
    with BagWriter(tmp_path / "zero.bag") as writer:
        writer.write("/s", String(data="first"), 0)
        writer.write("/s", String(data="second"), 5)
    bag = Bag(tmp_path / "zero.bag")
    assert [item.time_ns for item in bag.read("/s")] == [1, 5]
    assert bag.start_ns == 1
    with BagWriter(tmp_path / "negative.bag") as writer, pytest.raises(
        BagError, match="whole number of nanoseconds >= 0, not -1"
    ):
        writer.write("/s", String(data="x"), -1)
