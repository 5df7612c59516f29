"""A mission's bag in today's formats (MCAP, ROS 2 bags) and back, read by their own readers."""

from __future__ import annotations

import os

import pytest
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader

from duckielib.bags import Bag, read_encoders, sample_bag
from duckielib.bags.convert import bag_kind, convert_bag
from duckielib.errors import BagError
from duckielib.tools.cli import main


@pytest.fixture(scope="module")
def mission():
    return Bag(sample_bag("square_then_circle_realistic"))


def records_of(bag):
    """Every message of a ROS 1 bag: (topic, record time, bytes), in a stable order."""
    return sorted(bag.raw_messages(bag.topics))


def without_seq(bag):
    # A Header's seq is the first 4 bytes of a stamped message; ROS 2 has no seq.
    return sorted((topic, t, data[4:]) for topic, t, data in bag.raw_messages(bag.topics))


def test_mcap_with_ros1_schemas_keeps_every_byte_and_time(mission, tmp_path):
    target = convert_bag(mission.path, tmp_path / "run.mcap")
    with target.open("rb") as file:  # the format's reference reader
        reader = make_reader(file)
        summary = reader.get_summary()
        found = [
            (channel.topic, message.log_time, message.data, schema.name, schema.encoding)
            for schema, channel, message in reader.iter_messages()
        ]
    assert summary.statistics.message_count == mission.message_count == 10360
    assert {schema.encoding for schema in summary.schemas.values()} == {"ros1msg"}
    assert {channel.message_encoding for channel in summary.channels.values()} == {"ros1"}
    assert sorted(item[:3] for item in found) == records_of(mission)
    pose = next(item for item in found if item[0].endswith("odometry_node/pose"))
    assert pose[3] == "duckietown_msgs/Pose2DStamped"
    back = Bag(convert_bag(target, tmp_path / "back.bag"))
    assert records_of(back) == records_of(mission)
    assert {t: back.topics[t].md5sum for t in back.topics} == {
        t: mission.topics[t].md5sum for t in mission.topics
    }


@pytest.mark.parametrize(
    ("name", "options"),
    [("run.mcap", {"schema": "ros2"}), ("run", {}), ("run_sqlite", {"storage": "sqlite3"})],
)
def test_ros2_forms_keep_every_message_and_time(mission, tmp_path, name, options):
    target = convert_bag(mission.path, tmp_path / name, **options)
    with AnyReader([target]) as reader:  # rosbags' own reader of ROS 2 bags
        assert reader.message_count == mission.message_count
        assert {c.msgtype for c in reader.connections} >= {"duckietown_msgs/msg/Pose2DStamped"}
        times = sorted(timestamp for _, timestamp, _ in reader.messages())
    assert times == sorted(t for _, t, _ in records_of(mission))
    back = Bag(convert_bag(target, tmp_path / "back.bag"))
    assert without_seq(back) == without_seq(mission)
    assert bag_kind(target) == ("mcap" if name.endswith(".mcap") else "ros2")


def test_bad_targets_and_sources_are_said_and_nothing_is_left(mission, tmp_path, capsys):
    (tmp_path / "taken.mcap").write_text("mine")
    assert main(["bag", "convert", str(mission.path), str(tmp_path / "taken.mcap")]) == 1
    assert main(["bag", "convert", str(mission.path), str(tmp_path / "run.txt")]) == 1
    fifo = tmp_path / "pipe.mcap"
    os.mkfifo(fifo)
    assert main(["bag", "convert", str(fifo), str(tmp_path / "out.bag")]) == 1
    (tmp_path / "notes.mcap").write_text("not a bag at all")
    with pytest.raises(BagError, match=r"neither a ROS 1 bag, an MCAP file nor a ROS 2 bag"):
        convert_bag(tmp_path / "notes.mcap", tmp_path / "out.bag")
    truncated = tmp_path / "cut.mcap"
    whole = convert_bag(mission.path, tmp_path / "whole.mcap").read_bytes()
    truncated.write_bytes(whole[: len(whole) // 2])
    with pytest.raises(BagError, match=r"cut\.mcap is "):
        convert_bag(truncated, tmp_path / "out.bag")
    err = capsys.readouterr().err.splitlines()
    taken = tmp_path / "taken.mcap"
    assert err[0] == f"duckie: {taken} exists already; choose another name or delete it first."
    assert "run.txt: name the target run.bag (ROS 1), run.mcap (MCAP) or run" in err[1]
    assert "pipe.mcap is a FIFO (a named pipe), not a bag file" in err[2]
    assert (tmp_path / "taken.mcap").read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "cut.mcap",
        "notes.mcap",
        "pipe.mcap",
        "taken.mcap",
        "whole.mcap",
    ]


@pytest.mark.parametrize(
    ("name", "options", "format_"),
    [
        ("run.mcap", {}, "an MCAP file"),
        ("run2.mcap", {"schema": "ros2"}, "an MCAP file"),
        ("run", {"storage": "sqlite3"}, "a ROS 2 bag folder"),
    ],
)
def test_every_reader_of_the_course_opens_mcap_and_ros2_bags(
    mission, tmp_path, capsys, name, options, format_
):
    source = convert_bag(mission.path, tmp_path / name, **options)
    bag = Bag(source)
    assert bag.path == source
    assert bag.message_count == mission.message_count
    assert without_seq(bag) == without_seq(mission)
    left, _ = read_encoders(source)
    original_left, _ = read_encoders(mission)
    assert left.ticks.tolist() == original_left.ticks.tolist()
    assert main(["bag", "info", str(source)]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[:2] == [
        f"path:        {source}",
        f"format:      {format_}, read as a ROS 1 bag",
    ]


def test_a_damaged_mcap_file_is_said_by_the_commands_that_read_it(mission, tmp_path, capsys):
    whole = convert_bag(mission.path, tmp_path / "whole.mcap").read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole[: len(whole) // 3])
    assert main(["bag", "info", str(cut)]) == 1
    assert capsys.readouterr().err.startswith(f"duckie: {cut} is ")


def test_duckie_mission_writes_the_run_as_mcap_beside_its_bag(tmp_path, capsys):
    out = tmp_path / "run"
    command = ["mission", "--mission", "straight", "--no-animation", "--no-figure", "--mcap"]
    assert main([*command, "--out", str(out)]) == 0
    assert (
        capsys.readouterr()
        .out.rstrip()
        .endswith(
            f"wrote {out / 'mission.mcap'}: the same run as MCAP, for Foxglove, Lichtblick or "
            "PlotJuggler 4"
        )
    )
    with (out / "mission.mcap").open("rb") as file:
        count = make_reader(file).get_summary().statistics.message_count
    assert count == Bag(out / "mission.bag").message_count > 1000
    assert main([*command, "--out", str(out)]) == 0  # again, over the last run's files
