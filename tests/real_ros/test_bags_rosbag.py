"""Our bags against Debian's ROS 1 ``rosbag``: each reads what the other writes.

Debian's tools run in their own ``/usr/bin/python3`` process with a clean environment, as a
user would run them, so the project's interpreter never imports them. They report what they
read as JSON, which the tests compare with what was written.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import textwrap
from pathlib import Path

import numpy as np
import pytest

from duckielib.bags import Bag, BagWriter, repair_bag, replay_odometry
from duckielib.messages import Header, Pose2DStamped, String, WheelEncoderStamped
from duckielib.rostime import Time
from duckielib.solution import load_solution

pytestmark = pytest.mark.ros

ROSBAG = Path("/usr/bin/rosbag")
SYSTEM_PYTHON = Path("/usr/bin/python3")
LEFT = "/db1/left_wheel_encoder_node/tick"
RIGHT = "/db1/right_wheel_encoder_node/tick"
POSE = "/db1/velocity_to_pose_node/pose"
NOTES = "/db1/notes"
ENCODER_TYPE = "duckietown_msgs/WheelEncoderStamped"
#: A record time with every digit used, so a lost nanosecond shows.
T0_NS = 1_700_000_000_123_456_789
PERIOD_NS = 33_333_333
RIGHT_OFFSET_NS = 4_000_017

#: Reads a bag with Debian's rosbag API and prints every message as JSON.
READ_SCRIPT = textwrap.dedent(
    """
    import json, sys
    import rosbag

    def plain(value):
        if hasattr(value, "to_nsec"):
            return value.to_nsec()
        if hasattr(value, "__slots__"):
            return {name: plain(getattr(value, name)) for name in value.__slots__}
        return value

    found = []
    with rosbag.Bag(sys.argv[1]) as bag:
        for topic, msg, t in bag.read_messages(raw=False):
            found.append([topic, t.to_nsec(), msg._type, msg._md5sum, plain(msg)])
    print(json.dumps(found))
    """
)

#: Writes, with Debian's rosbag and a genpy class made from our definition, one bag per
#: compression holding the encoder readings and notes of a JSON spec.
WRITE_SCRIPT = textwrap.dedent(
    """
    import json, sys
    import genpy
    import genpy.dynamic
    import rosbag
    from std_msgs.msg import String

    spec = json.load(open(sys.argv[1]))
    name = "duckietown_msgs/WheelEncoderStamped"
    Encoder = genpy.dynamic.generate_dynamic(name, spec["full_text"])[name]

    def time(ns):
        return genpy.Time(ns // 1_000_000_000, ns % 1_000_000_000)

    for compression, path in spec["bags"].items():
        with rosbag.Bag(path, "w", compression=compression) as bag:
            for topic, time_ns, seq, stamp_ns, frame_id, data in spec["encoders"]:
                msg = Encoder()
                msg.header.seq = seq
                msg.header.stamp = time(stamp_ns)
                msg.header.frame_id = frame_id
                msg.data = data
                msg.resolution = 135
                msg.type = Encoder.ENCODER_TYPE_INCREMENTAL
                bag.write(topic, msg, time(time_ns))
            for topic, time_ns, text in spec["notes"]:
                bag.write(topic, String(data=text), time(time_ns))
    print(json.dumps({"md5sum": Encoder._md5sum}))
    """
)


def debian_env(tmp_path: Path) -> dict:
    """A clean environment for Debian's tools: no venv, no PYTHONPATH."""
    home = tmp_path / "ros_home"
    home.mkdir(exist_ok=True)
    return {
        "PATH": "/usr/bin:/bin",
        "HOME": os.environ.get("HOME", str(home)),
        "ROS_HOME": str(home),
        "LANG": "C.UTF-8",
        "LC_ALL": "C.UTF-8",
    }


def run_debian(args: list, tmp_path: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [str(arg) for arg in args],
        env=debian_env(tmp_path),
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )


@pytest.fixture(scope="module")
def debian_rosbag(tmp_path_factory):
    """Skip, saying how to install them, unless Debian's rosbag tool and module are there."""
    if not ROSBAG.exists():
        pytest.skip(f"{ROSBAG} is missing: install Debian's ROS 1 packages with `make ros`.")
    tmp = tmp_path_factory.mktemp("debian_check")
    check = run_debian([SYSTEM_PYTHON, "-c", "import rosbag, genpy, std_msgs.msg"], tmp)
    if check.returncode != 0:
        last = (check.stderr.strip().splitlines() or ["no output"])[-1]
        pytest.skip(
            f"Debian's rosbag module cannot be imported by {SYSTEM_PYTHON} ({last}); "
            "install Debian's ROS 1 packages with `make ros`."
        )


def read_with_rosbag(path: Path, tmp_path: Path) -> list:
    """Every message of a bag as Debian's rosbag API reads it: [topic, t_ns, type, md5, fields]."""
    script = tmp_path / "read_bag.py"
    script.write_text(READ_SCRIPT)
    result = run_debian([SYSTEM_PYTHON, script, path], tmp_path)
    assert result.returncode == 0, f"rosbag's read_messages failed on {path}:\n{result.stderr}"
    return json.loads(result.stdout)


def rosbag_info(path: Path, tmp_path: Path) -> dict:
    """``rosbag info``'s topics as {name: (count, type)}; the command must exit 0."""
    result = run_debian([ROSBAG, "info", path], tmp_path)
    assert result.returncode == 0, f"rosbag info failed on {path}:\n{result.stderr}"
    topics = {}
    in_topics = False
    for line in result.stdout.splitlines():
        if line.startswith("topics:"):
            in_topics = True
        elif line and not line[0].isspace():
            in_topics = False
        entry = line.removeprefix("topics:").split()
        if in_topics and entry:
            name, count, _, _, kind = entry[:5]
            topics[name] = (int(count), kind)
    return topics


def plain(value):
    """A message as plain values, the way READ_SCRIPT prints genpy's."""
    if hasattr(value, "to_nsec"):
        return value.to_nsec()
    if hasattr(value, "__slots__"):
        return {name: plain(getattr(value, name)) for name in value.__slots__}
    return value


def up_then_down(count: int, start: int, up: int, down: int) -> list:
    """Cumulative ticks that rise for half the readings, then fall (below zero)."""
    half = count // 2
    return [
        start + up * index if index < half else start + up * half - down * (index - half)
        for index in range(count)
    ]


def encoder(seq: int, stamp_ns: int, ticks: int, frame_id: str) -> WheelEncoderStamped:
    return WheelEncoderStamped(
        header=Header(seq=seq, stamp=Time.from_nsec(stamp_ns), frame_id=frame_id),
        data=ticks,
        resolution=135,
        type=WheelEncoderStamped.ENCODER_TYPE_INCREMENTAL,
    )


def encoder_readings(count: int) -> list:
    """(topic, record ns, seq, stamp ns, frame_id, ticks) of both wheels, by record time."""
    readings = []
    for topic, offset, ticks in (
        (LEFT, 0, up_then_down(count, -20, 6, 11)),
        (RIGHT, RIGHT_OFFSET_NS, up_then_down(count, 35, 5, 9)),
    ):
        frame = topic.split("/")[2]
        for index, value in enumerate(ticks):
            time_ns = T0_NS + offset + index * PERIOD_NS
            readings.append((topic, time_ns, index, time_ns - 2_500_001, frame, value))
    readings.sort(key=lambda reading: reading[1])
    return readings


def mixed_messages() -> list:
    """(topic, record ns, message) on two encoder topics, a pose topic and a string topic."""
    written = [
        (topic, time_ns, encoder(seq, stamp_ns, ticks, frame))
        for topic, time_ns, seq, stamp_ns, frame, ticks in encoder_readings(45)
    ]
    # One reading fewer on the right, so a count mixed up between topics shows.
    written = [item for item in written if not (item[0] == RIGHT and item[2].header.seq == 44)]
    for index in range(15):
        time_ns = T0_NS + 1_000_003 + index * 3 * PERIOD_NS
        pose = Pose2DStamped(
            header=Header(seq=index, stamp=Time.from_nsec(time_ns - 7), frame_id="map"),
            x=0.32 + 0.01 * index,
            y=0.32 - 0.1 / 3 * index,
            theta=(math.pi / 2 + 0.7 * index) % (2 * math.pi),
        )
        written.append((POSE, time_ns, pose))
    notes = ["start", "", "wheels: ünïcödé ok", "a" * 300, "stop"]
    for index, text in enumerate(notes):
        written.append((NOTES, T0_NS + 500_000_001 * index + 11, String(data=text)))
    written.sort(key=lambda item: item[1])
    return written


def expected_rows(written: list) -> list:
    return [
        [topic, time_ns, message._type, message._md5sum, plain(message)]
        for topic, time_ns, message in written
    ]


@pytest.mark.parametrize("compression", ["none", "bz2"])
def test_rosbag_reads_our_bag(debian_rosbag, tmp_path, compression):
    written = mixed_messages()
    path = tmp_path / f"ours_{compression}.bag"
    writer = BagWriter(path, compression)
    try:
        for topic, time_ns, message in written:
            writer.write(topic, message, time_ns)
    finally:
        writer.close()

    assert rosbag_info(path, tmp_path) == {
        LEFT: (45, ENCODER_TYPE),
        RIGHT: (44, ENCODER_TYPE),
        POSE: (15, "duckietown_msgs/Pose2DStamped"),
        NOTES: (5, "std_msgs/String"),
    }
    assert read_with_rosbag(path, tmp_path) == expected_rows(written)


@pytest.fixture(scope="module")
def debian_bags(debian_rosbag, tmp_path_factory):
    """Bags written by Debian's rosbag (none, bz2, lz4) and the readings they hold."""
    folder = tmp_path_factory.mktemp("debian_bags")
    readings = encoder_readings(300)
    notes = [(NOTES, T0_NS + index * 2_000_000_000 + 5, f"note {index}") for index in range(4)]
    bags = {
        compression: str(folder / f"{compression}.bag") for compression in ("none", "bz2", "lz4")
    }
    spec = {
        "full_text": WheelEncoderStamped._full_text,
        "bags": bags,
        "encoders": readings,
        "notes": notes,
    }
    (folder / "spec.json").write_text(json.dumps(spec))
    (folder / "write_bags.py").write_text(WRITE_SCRIPT)
    result = run_debian([SYSTEM_PYTHON, folder / "write_bags.py", folder / "spec.json"], folder)
    assert result.returncode == 0, f"Debian's rosbag could not write the bags:\n{result.stderr}"
    assert json.loads(result.stdout) == {"md5sum": WheelEncoderStamped._md5sum}
    return {name: Path(path) for name, path in bags.items()}, readings, notes


@pytest.mark.parametrize("compression", ["none", "bz2", "lz4"])
def test_we_read_rosbags_bag(debian_bags, tmp_path, compression):
    bags, readings, notes = debian_bags
    bag = Bag(bags[compression])

    assert bag.compression == compression
    assert bag.message_count == 600 + len(notes)
    assert bag.start_ns == T0_NS
    assert {name: (info.count, info.type) for name, info in bag.topics.items()} == {
        LEFT: (300, ENCODER_TYPE),
        RIGHT: (300, ENCODER_TYPE),
        NOTES: (4, "std_msgs/String"),
    }
    assert bag.topics[LEFT].md5sum == WheelEncoderStamped._md5sum
    assert bag.topics[RIGHT].md5sum == WheelEncoderStamped._md5sum
    assert bag.topics[NOTES].md5sum == String._md5sum
    assert bag.topics[LEFT].message_definition == WheelEncoderStamped._full_text

    for topic in (LEFT, RIGHT):
        got = [
            (
                item.topic,
                item.time_ns,
                item.message.header.seq,
                item.message.header.stamp.to_nsec(),
                item.message.header.frame_id,
                item.message.data,
                item.message.resolution,
                item.message.type,
            )
            for item in bag.read(topic)
        ]
        assert all(isinstance(item.message, WheelEncoderStamped) for item in bag.read(topic))
        want = [(*reading, 135, 1) for reading in readings if reading[0] == topic]
        assert got == want
        assert min(item[5] for item in got) < 0
    assert [(item.topic, item.time_ns, item.message.data) for item in bag.read(NOTES)] == [
        tuple(note) for note in notes
    ]

    ours = tmp_path / "same_messages.bag"
    writer = BagWriter(ours)
    try:
        for topic, time_ns, seq, stamp_ns, frame, ticks in readings:
            writer.write(topic, encoder(seq, stamp_ns, ticks, frame), time_ns)
        for topic, time_ns, text in notes:
            writer.write(topic, String(data=text), time_ns)
    finally:
        writer.close()
    solution = load_solution()  # the course's reference, exported from solutions/
    theirs_track = replay_odometry(bag, solution)
    ours_track = replay_odometry(Bag(ours), solution)
    assert len(theirs_track) == len(ours_track) > 250
    assert theirs_track.final_pose == ours_track.final_pose
    for name in ("t", "x", "y", "theta"):
        np.testing.assert_array_equal(getattr(theirs_track, name), getattr(ours_track, name))
    moved = np.hypot(theirs_track.x - 0.32, theirs_track.y - 0.32).max()
    assert moved > 0.1, "the replayed drive should move the robot"


@pytest.mark.parametrize("compression", ["none", "bz2"])
def test_rosbag_reads_repaired_bag(debian_rosbag, tmp_path, compression):
    readings = encoder_readings(80)
    written = [
        (topic, time_ns, encoder(seq, stamp_ns, ticks, frame))
        for topic, time_ns, seq, stamp_ns, frame, ticks in readings
    ]
    path = tmp_path / "whole.bag"
    sizes = []
    writer = BagWriter(path, compression)
    try:
        for index, (topic, time_ns, message) in enumerate(written):
            writer.write(topic, message, time_ns)
            if index % 40 == 39:
                writer.flush()
                sizes.append(path.stat().st_size)
    finally:
        writer.close()
    assert len(sizes) == 4, "the bag should hold four chunks"
    flushed_before_last = 120
    cut = (sizes[-2] + sizes[-1]) // 2
    broken = tmp_path / "broken.bag.active"
    broken.write_bytes(path.read_bytes()[:cut])
    fixed = tmp_path / "fixed.bag"

    report = repair_bag(broken, fixed)

    recovered = report.messages
    assert flushed_before_last <= recovered < len(written)
    info = rosbag_info(fixed, tmp_path)
    left = sum(1 for topic, _, _ in written[:recovered] if topic == LEFT)
    assert info == {LEFT: (left, ENCODER_TYPE), RIGHT: (recovered - left, ENCODER_TYPE)}
    assert read_with_rosbag(fixed, tmp_path) == expected_rows(written[:recovered])
