"""Damaged and foreign bags: what each library call says and returns (bags from damaged.py).

A damaged bag is never read in part as if whole: a read raises a sentence naming the damage
(its chunk and byte offset, how many messages it costs) and ``duckie bag repair``; the repair
reads around the damage and says what it skipped. Foreign types read to arrays of their
fields from the definitions the bag holds.
"""

from __future__ import annotations

import inspect
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import bagtools
import damaged
import numpy as np
import pytest
from bagtools import LEFT, RIGHT
from damaged import CHUNKS, PER_CHUNK, S

import duckielib.bags
from duckielib.bags import Bag, BagWriter, read_encoders, read_topic, repair_bag, replay_odometry
from duckielib.errors import BagError
from duckielib.messages import WheelEncoderStamped
from duckielib.solution import SolutionError

TOTAL = 2 * CHUNKS * PER_CHUNK  # messages in an encoder bag
REPAIR = re.compile(r"duckie bag repair \S+ FIXED\.bag")


@pytest.fixture(params=["none", "bz2"])
def middle_damaged(request, tmp_path):
    """An encoder bag with 64 bytes changed in the middle of its second chunk (of four)."""
    path, spans = damaged.encoder_bag(tmp_path / "sound.bag", request.param)
    start, end = spans[1]
    return damaged.changed(path, tmp_path / "damaged.bag", (start + end) // 2), spans


def test_a_bag_damaged_in_a_chunk_is_read_whole_or_not_at_all(middle_damaged):
    path, spans = middle_damaged
    bag = Bag(path)  # its index is intact: it opens, and says what the index lists
    assert bag.message_count == TOTAL
    for read in (
        lambda: read_topic(bag, LEFT),
        lambda: read_encoders(bag),
        lambda: replay_odometry(bag, bagtools),
        lambda: bag.read(RIGHT),
        lambda: list(bag.messages()),
    ):
        with pytest.raises(BagError) as caught:
            read()
        message = str(caught.value)
        start, end = spans[1]
        assert f"is damaged in chunk 2 of {CHUNKS} (bytes {start} to {end}, which holds " in message
        assert f"{2 * PER_CHUNK} messages)" in message
        found = re.search(r"at byte (\d+)", message)
        assert found
        assert start <= int(found.group(1)) < end
        counted = re.search(r"only (\d+) of the (\d+) messages its index lists", message)
        assert counted, message
        assert int(counted.group(1)) < int(counted.group(2))
        assert "Nothing is returned rather than a part." in message
        assert REPAIR.search(message)


def test_info_and_check_say_where_a_bag_is_damaged(middle_damaged):
    path, _ = middle_damaged
    bag = Bag(path)
    problem = bag.check()
    assert problem is not None
    assert f"in chunk 2 of {CHUNKS}" in problem
    assert REPAIR.search(problem)
    text = bag.info()
    assert "\ndamage:      damaged.bag is damaged in chunk 2" in text
    assert "duckie bag repair" in " ".join(text.split())
    assert "damage:" not in Bag(path.with_name("sound.bag")).info()
    assert Bag(path.with_name("sound.bag")).check() is None


def test_repair_reads_around_damage_in_a_chunk(middle_damaged, tmp_path):
    path, spans = middle_damaged
    compressed = Bag(path).compression == "bz2"
    report = repair_bag(path, tmp_path / "fixed.bag")
    fixed = Bag(tmp_path / "fixed.bag")
    assert fixed.check() is None
    if compressed:  # the damaged bz2 chunk is lost whole, the three others are kept
        assert report.messages == TOTAL - 2 * PER_CHUNK
        assert len(report.damages) == 1
        assert report.damages[0].startswith(
            f"at byte {spans[1][0]}, the bz2 chunk there cannot be decompressed, so its "
            "messages are lost"
        )
    else:  # only the records the 64 bytes touched are lost
        assert TOTAL - 3 <= report.messages < TOTAL
    text = str(report)
    lost = f"{TOTAL - report.messages} of the {TOTAL} messages its index lists were lost in the"
    assert f"{lost} damage or left out next to it." in text
    assert "1 damaged stretch was skipped" in text
    assert "was not damaged" not in text
    assert report.damaged
    assert not report.was_indexed
    left, right = read_encoders(fixed)
    assert len(left.t) + len(right.t) == report.messages
    assert np.all(np.diff(left.ticks) > 0), "every recovered reading, in order"


def test_damage_in_the_index_alone_is_reported_and_the_messages_are_read_whole(tmp_path):
    path, spans = damaged.encoder_bag(tmp_path / "sound.bag", chunks=1)
    index = spans[0][1] + 200  # in the index records after the chunk: record times, offsets
    broken = damaged.changed(path, tmp_path / "index.bag", index)
    bag = Bag(broken)
    left, right = read_encoders(bag)  # the messages are whole: they read
    assert len(left.t) == len(right.t) == PER_CHUNK
    problem = bag.check()
    assert problem.startswith(
        "index.bag is damaged after its chunks, among its index records: at byte "
    )
    assert "does not list the messages that chunk holds" in problem
    assert f"the {TOTAL // 4} messages its index lists on its 2 topics were all found" in problem
    assert "damage:" in bag.info()
    report = repair_bag(broken, tmp_path / "fixed.bag")
    assert report.messages == TOTAL // 4
    assert report.damaged
    assert "1 damaged stretch was skipped" in str(report)
    assert "was not damaged" not in str(report)
    assert Bag(tmp_path / "fixed.bag").check() is None


def test_a_bag_cut_short_says_so_and_its_start_is_recovered(tmp_path):
    path, spans = damaged.encoder_bag(tmp_path / "sound.bag")
    short = damaged.cut(path, tmp_path / "short.bag", (spans[2][0] + spans[2][1]) // 2)
    with pytest.raises(BagError) as caught:
        Bag(short)
    assert "cut short" in str(caught.value)
    assert REPAIR.search(str(caught.value))
    report = repair_bag(short, tmp_path / "fixed.bag")
    assert 2 * 2 * PER_CHUNK < report.messages < 3 * 2 * PER_CHUNK
    text = str(report)
    assert "Its index was lost: its header says the index starts at byte" in text
    assert "The file was cut short: the file ends inside the chunk at byte" in text
    assert report.damages == []
    assert Bag(tmp_path / "fixed.bag").check() is None


def test_a_damaged_head_is_skipped_and_every_message_after_it_recovered(tmp_path):
    path, _ = damaged.encoder_bag(tmp_path / "sound.bag")
    head = damaged.damaged_head(path, tmp_path / "head.bag")
    with pytest.raises(BagError) as caught:
        Bag(head)
    assert "its bag header (the first record, in the file's first 4 KB) is damaged" in str(
        caught.value
    )
    assert REPAIR.search(str(caught.value))
    report = repair_bag(head, tmp_path / "fixed.bag")
    assert report.counts == {LEFT: TOTAL // 2, RIGHT: TOTAL // 2}
    assert report.header_damaged
    assert report.bytes_skipped == 4096
    text = str(report)
    assert f"Recovered {TOTAL} messages on 2 topics" in text
    assert "Its bag header (the first record, in the file's first 4 KB) was damaged" in text
    assert "1 damaged stretch was skipped (4096 bytes in all)" in text
    assert "No complete message" not in text
    assert "was not damaged" not in text
    original = [item.message for item in Bag(path).messages()]
    assert [item.message for item in Bag(tmp_path / "fixed.bag").messages()] == original


def test_a_header_that_lists_no_chunk_is_not_an_empty_bag(tmp_path):
    path, spans = damaged.encoder_bag(tmp_path / "sound.bag")
    unlisted = damaged.no_chunks_in_header(path, tmp_path / "unlisted.bag")
    with pytest.raises(BagError) as caught:
        Bag(unlisted)
    message = str(caught.value)
    assert f"the index lists 0 chunks, but the file holds {CHUNKS}" in message
    assert f"starts at byte {spans[0][0]}" in message
    assert "empty" not in message
    assert REPAIR.search(message)
    report = repair_bag(unlisted, tmp_path / "fixed.bag")
    assert report.messages == TOTAL
    assert report.damaged
    assert not report.was_indexed
    text = str(report)
    assert f"its header lists 0 chunks, its index {CHUNKS} chunks with {TOTAL} messages" in text
    assert "was not damaged" not in text


def test_an_unindexed_recording_is_reported_as_such(tmp_path):
    path = tmp_path / "run.bag.active"
    writer = BagWriter(path)
    for index in range(10):
        writer.write(LEFT, damaged.encoder(index, index, S + index), S + index)
    writer.flush()  # on disk, never closed: no index
    report = repair_bag(path, tmp_path / "fixed.bag")
    writer.close()
    assert report.messages == 10
    assert "It had no index: its recording was interrupted before it was closed." in str(report)
    assert "was not damaged" not in str(report)


def test_an_undamaged_bag_is_reported_as_undamaged(tmp_path):
    path, _ = damaged.encoder_bag(tmp_path / "sound.bag", "bz2")
    report = repair_bag(path, tmp_path / "copy.bag")
    assert report.was_indexed
    assert not report.damaged
    assert str(report).endswith(
        "The bag was not damaged: it was closed properly, and the copy is whole."
    )


@pytest.mark.parametrize("kind", ["noetic", "humble"])
def test_foreign_types_read_to_arrays_of_their_fields(tmp_path, kind):
    bag = Bag(damaged.foreign_bag(tmp_path / "foreign.bag", kind))
    stamps = [10.000000005, 11.000000005, 12.000000005]
    imu = read_topic(bag, "/imu")
    assert imu.time_base == "header"
    np.testing.assert_allclose(imu.t, stamps, rtol=0, atol=1e-6)
    np.testing.assert_allclose(imu["header.stamp"], stamps, rtol=0, atol=1e-6)
    assert imu["orientation.w"].tolist() == [1.0, 1.0, 1.0]
    assert imu["angular_velocity.z"].tolist() == [0.0, 1.0, 2.0]
    assert [imu[f"orientation_covariance.{i}"][0] for i in range(9)] == list(range(9))
    assert "orientation_covariance" not in imu.fields
    assert imu.skipped == {"header.frame_id": "string"}
    with pytest.raises(KeyError, match=r"'header\.frame_id' is a string, which read_topic leaves"):
        imu["header.frame_id"]
    assert ("header.seq" in imu.fields) == (kind == "noetic"), "ROS 2's header has no seq"
    assert read_topic(bag, "/range")["range"].tolist() == [0.0, 0.25, 0.5]
    assert read_topic(bag, "/range")["radiation_type"].tolist() == [1, 1, 1]
    pose = read_topic(bag, "/pose")
    assert pose["pose.position.z"].tolist() == [0.0, 0.5, 1.0]
    assert pose["pose.orientation.w"].tolist() == [1.0, 1.0, 1.0]
    assert pose.time_base == "header"
    assert read_topic(bag, "/float")["data"].tolist() == [0.0, 1.5, 3.0]
    count = read_topic(bag, "/count")
    assert count["data"].tolist() == [0, -1, -2]
    assert count["data"].dtype.kind == "i"
    twist = read_topic(bag, "/cmd_vel")
    assert sorted(twist.fields) == sorted(
        f"{part}.{axis}" for part in ("linear", "angular") for axis in "xyz"
    )
    assert twist["linear.x"].tolist() == pytest.approx([0.0, 0.1, 0.2])
    assert twist.time_base == "record"
    np.testing.assert_allclose(twist.t, [10.000000007, 11.000000007, 12.000000007], atol=1e-6)
    if kind == "humble":  # other md5 sums than ROS 1's: decoded from the bag's definitions
        message = bag.read("/imu")[0].message
        assert type(message).__module__.startswith("rosbags")


def test_zero_stamps_of_a_foreign_type_fall_back_to_record_times(tmp_path):
    bag = Bag(damaged.foreign_bag(tmp_path / "zero.bag", "humble", zero_stamps=True))
    imu = read_topic(bag, "/imu")
    assert imu.time_base == "record"
    assert imu.notes == ["/imu: every header stamp is 0, so record times are used."]
    assert imu["header.stamp"].tolist() == [0.0, 0.0, 0.0]
    with pytest.raises(BagError, match="Every header stamp on /imu is 0"):
        read_topic(bag, "/imu", time_base="header")


def test_a_robots_own_type_reads_by_the_stated_rules(tmp_path):
    sonar = read_topic(damaged.sonar_bag(tmp_path / "sonar.bag"), "/sonar")
    assert sonar.type == "robot_msgs/Sonar"
    assert list(sonar.fields) == [
        "header.seq",
        "header.stamp",
        "limits.0",
        "limits.1",
        "limits.2",
        "corners.0.x",
        "corners.0.y",
        "corners.0.z",
        "corners.1.x",
        "corners.1.y",
        "corners.1.z",
        "fired",
        "elapsed",
        "ok",
    ]
    assert sonar["limits.2"].tolist() == [0.0, 1.0]
    assert sonar["corners.0.x"].tolist() == [0.0, 1.0]
    assert sonar["fired"].tolist() == [20.5, 21.5]
    assert sonar["elapsed"].tolist() == [0.25, 0.25]
    assert sonar["ok"].tolist() == [False, True]
    assert sonar.skipped == {
        "header.frame_id": "string",
        "label": "string",
        "raw": "uint8[]",
        "echoes": "geometry_msgs/Point[]",
    }


def test_a_topic_recorded_with_two_definitions_is_decoded_by_each(tmp_path):
    with BagWriter(tmp_path / "values.bag") as writer:
        writer.write_raw(
            "/level",
            "std_msgs/Float64",
            damaged.FLOAT_MD5,
            "float64 data\n",
            S,
            damaged.struct.pack("<d", 2.5),
        )
        writer.write_raw(
            "/level",
            "std_msgs/Float64",
            damaged.INT_AS_FLOAT_MD5,
            "int32 data\n",
            2 * S,
            damaged.struct.pack("<i", -4),
        )
    bag = Bag(tmp_path / "values.bag")
    assert [item.message.data for item in bag.read("/level")] == [2.5, -4]
    assert sorted(info.md5sum for info in bag.connections_of("/level")) == sorted(
        [damaged.FLOAT_MD5, damaged.INT_AS_FLOAT_MD5]
    )
    with pytest.raises(BagError, match=r"/level in values\.bag was recorded with 2 definitions"):
        read_topic(bag, "/level")


def test_an_encoder_topic_with_another_definition_is_refused_with_both_md5_sums(tmp_path):
    path = damaged.other_encoder_definition_bag(tmp_path / "other.bag")
    for call in (lambda: read_encoders(path), lambda: replay_odometry(path, bagtools)):
        with pytest.raises(BagError) as caught:
            call()
        message = str(caught.value)
        assert message.startswith(
            f"{LEFT} in other.bag carries duckietown_msgs/WheelEncoderStamped"
        )
        assert f"md5 sum {damaged.OTHER_ENCODER_MD5}" in message
        assert f"md5 sum {WheelEncoderStamped._md5sum}" in message
        assert "defined the message differently" in message
    assert read_topic(path, LEFT)["data"].tolist()[:3] == [0.0, 3.0, 6.0]


def test_resolution_zero_is_blamed_on_the_bag_not_on_notebook_05(tmp_path):
    path, _ = damaged.encoder_bag(tmp_path / "zero.bag", resolution=0, chunks=1)
    with pytest.raises(BagError) as caught:
        replay_odometry(path, bagtools)
    message = str(caught.value)
    assert not isinstance(caught.value, SolutionError)
    assert message.startswith(
        f"{PER_CHUNK} of the {PER_CHUNK} encoder messages on {LEFT} in zero.bag carry "
        "resolution 0 (ticks per wheel revolution)"
    )
    assert "a problem of the bag" in message
    assert "not of your code" in message
    assert "05" not in message


def test_the_package_docstring_calls_replay_odometry_as_it_is_defined():
    calls = re.findall(r"replay_odometry\(([^()]*(?:\([^()]*\))?[^()]*)\)", duckielib.bags.__doc__)
    assert calls
    parameters = list(inspect.signature(replay_odometry).parameters)
    assert parameters[:2] == ["bag", "solution"]
    for arguments in calls:
        names = [part.strip() for part in re.split(r",(?![^(]*\))", arguments)]
        assert len(names) == 2, f"replay_odometry({arguments}) passes (bag, solution)"
        assert names[0] == "bag"


ROSBAG_READ = """
import json, sys
import rosbag
with rosbag.Bag(sys.argv[1]) as bag:
    print(json.dumps(sum(1 for _ in bag.read_messages())))
"""

ROSBAG_WRITE = """
import sys
import rosbag, rospy
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64
with rosbag.Bag(sys.argv[1], "w", compression=sys.argv[2], chunk_threshold=4096) as bag:
    for i in range(300):
        t = rospy.Time(10 + i // 10, (i % 10) * 100000000)
        bag.write("/level", Float64(data=0.5 * i), t)
        imu = Imu()
        imu.header.seq, imu.header.stamp, imu.orientation.w = i, t, 1.0
        bag.write("/imu", imu, t)
"""


def _debian(script, *arguments):
    """Run a script with Debian's Python and its ROS 1 packages; skip the test without them."""
    python = Path("/usr/bin/python3")
    if not python.exists():
        pytest.skip("/usr/bin/python3 is missing; install Debian's ROS 1 with `make ros`.")
    result = subprocess.run(
        [str(python), "-c", script, *map(str, arguments)],
        capture_output=True,
        text=True,
        env={"PATH": "/usr/bin:/bin", "LANG": "C.UTF-8"},
        check=False,
        timeout=120,
    )
    if "No module named 'rosbag'" in result.stderr or "No module named 'rospy'" in result.stderr:
        pytest.skip("Debian's rosbag is not installed; install it with `make ros`.")
    assert result.returncode == 0, result.stderr
    return result.stdout


@pytest.mark.ros
def test_debian_rosbag_reads_every_repaired_bag_whole(tmp_path):
    sound, spans = damaged.encoder_bag(tmp_path / "sound.bag")
    broken = {
        "head": damaged.damaged_head(sound, tmp_path / "head.bag"),
        "chunk": damaged.changed(sound, tmp_path / "chunk.bag", sum(spans[1]) // 2),
        "unlisted": damaged.no_chunks_in_header(sound, tmp_path / "unlisted.bag"),
    }
    for name, path in broken.items():
        report = repair_bag(path, tmp_path / f"{name}.fixed.bag")
        assert json.loads(_debian(ROSBAG_READ, tmp_path / f"{name}.fixed.bag")) == report.messages
    assert report.messages == TOTAL, "the unlisted chunks lose nothing"


@pytest.mark.ros
@pytest.mark.parametrize("compression", ["none", "bz2"])
def test_bags_written_by_debian_rosbag_are_checked_read_and_repaired(tmp_path, compression):
    path = tmp_path / "debian.bag"
    _debian(ROSBAG_WRITE, path, compression)
    bag = Bag(path)
    assert bag.chunk_count > 4
    assert bag.check() is None
    imu = read_topic(bag, "/imu")
    assert imu["header.seq"].tolist() == list(range(300))
    assert imu.time_base == "header"
    assert read_topic(bag, "/level")["data"].tolist() == [0.5 * i for i in range(300)]
    start, end = damaged.chunk_spans(path)[3]
    message = path.read_bytes().find(b"op=\x02", start, end)  # a message's header, if not bz2
    at = message if message > 0 else (start + end) // 2
    broken = damaged.changed(path, tmp_path / "broken.bag", at, 8)
    with pytest.raises(BagError, match=r"is damaged in chunk 4 of \d+ \(bytes"):
        read_topic(broken, "/level")
    report = repair_bag(broken, tmp_path / "fixed.bag")
    assert report.damages
    assert json.loads(_debian(ROSBAG_READ, tmp_path / "fixed.bag")) == report.messages
    assert Bag(tmp_path / "fixed.bag").check() is None


@pytest.mark.parametrize("command", ["info", "plot", "odometry", "repair"])
def test_a_fifo_named_like_a_bag_is_said_for_what_it_is_and_never_opened(tmp_path, command):
    # Opening a FIFO for reading blocks until someone writes to it: every command must
    # refuse it from its kind alone, at once.
    fifo = tmp_path / "run.bag"
    os.mkfifo(fifo)
    extra = {"repair": [str(tmp_path / "fixed.bag")], "plot": ["-o", "poses.png"]}.get(command, [])
    done = subprocess.run(
        [sys.executable, "-m", "duckielib.tools.cli", "bag", command, str(fifo), *extra],
        check=False,
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,
    )
    assert done.returncode == 1
    assert done.stderr.strip() == (
        f"duckie: {fifo} is a FIFO (a named pipe), not a bag file: it was not opened. Give "
        "the bag's own file."
    )
    assert sorted(path.name for path in tmp_path.iterdir()) == ["run.bag"]  # nothing written


def test_a_count_no_motor_can_make_is_damage_said_with_where_it_is(tmp_path):
    # A ROS 1 bag has no checksum: bytes changed inside one tick's data read as a count wrong
    # by tens of thousands, which moved the odometry 112 m. A wheel at full duty turns about
    # 580 ticks/s; a jump there and back in 33 ms is damage.
    period = 33_333_333
    left = [(n * period, 6 * n) for n in range(90)]
    right = [(n * period + 1000, 6 * n) for n in range(90)]
    left[30] = (left[30][0], 77_031 + 180)
    bag = bagtools.write_encoders(tmp_path / "flipped.bag", left, right)
    with pytest.raises(BagError) as raised:
        read_encoders(bag)
    assert str(raised.value).startswith(
        "/duckiebot/left_wheel_encoder_node/tick in flipped.bag is damaged at 1.000 s (header "
        "time): that message says 77,211 ticks, +77,037 from the one 33 ms before it, and the "
        "next one is back: no motor turns a wheel that fast."
    )
    done = subprocess.run(
        [sys.executable, "-m", "duckielib.tools.cli", "bag", "odometry", str(bag)],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 1
    assert "is damaged at 1.000 s" in done.stderr


def test_a_driver_that_restarts_its_count_is_not_damage(tmp_path):
    # The count drops to 0 and goes on from there: a jump that does not come back.
    period = 33_333_333
    left = [(n * period, 6 * n if n < 30 else 6 * (n - 30)) for n in range(90)]
    right = [(n * period + 1000, 6 * n) for n in range(90)]
    stream, _ = read_encoders(bagtools.write_encoders(tmp_path / "restart.bag", left, right))
    assert stream.ticks[29:32].tolist() == [174, 0, 6]
