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


def chunked_mcap(bag, path, chunk_size=100_000):
    """``bag`` as an MCAP file with ROS 1 schemas in chunks of about ``chunk_size`` bytes,
    written by the reference writer itself (as a tool other than the course's would)."""
    from mcap.writer import Writer

    with path.open("wb") as file:
        writer = Writer(file, chunk_size=chunk_size)
        writer.start(profile="ros1", library="another writer")
        channels = {}
        for topic, time_ns, data in bag.raw_messages(bag.topics):
            if topic not in channels:
                info = bag.topics[topic]
                schema = writer.register_schema(
                    name=info.type, encoding="ros1msg", data=info.message_definition.encode()
                )
                channels[topic] = writer.register_channel(
                    topic=topic, message_encoding="ros1", schema_id=schema
                )
            writer.add_message(channels[topic], log_time=time_ns, data=data, publish_time=time_ns)
        writer.finish()
    return path


def chunk_contents(path, number):
    """(topic, log time) -> count of the messages in chunk ``number``, from the file's own
    message index (the records after each chunk), read by the reference stream reader."""
    from collections import Counter

    from mcap.records import Chunk, MessageIndex
    from mcap.stream_reader import StreamReader

    with path.open("rb") as file:
        topics = {cid: c.topic for cid, c in make_reader(file).get_summary().channels.items()}
    seen, found = -1, Counter()
    for record in StreamReader(str(path), emit_chunks=True).records:
        if isinstance(record, Chunk):
            seen += 1
        elif isinstance(record, MessageIndex) and seen == number:
            found.update((topics.get(record.channel_id), t) for t, _ in record.records)
    return found


def mcap_records(path):
    """(topic, log time, bytes) of every message of a sound MCAP file, by the reference reader."""
    with path.open("rb") as file:
        reader = make_reader(file, validate_crcs=True)
        return [(c.topic, m.log_time, m.data) for _, c, m in reader.iter_messages()]


def test_a_damaged_chunk_is_said_with_its_times_and_losses_and_repair_keeps_the_rest(
    mission, tmp_path, capsys
):
    whole = chunked_mcap(mission, tmp_path / "whole.mcap")
    with whole.open("rb") as file:
        chunks = sorted(
            make_reader(file).get_summary().chunk_indexes, key=lambda c: c.chunk_start_offset
        )
    assert len(chunks) >= 4
    second = chunks[1]
    data = bytearray(whole.read_bytes())
    middle = second.chunk_start_offset + second.chunk_length // 2
    data[middle : middle + 4] = b"\xff\xff\xff\xff"  # four bytes of its compressed data
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(bytes(data))
    original = mcap_records(whole)
    in_second = chunk_contents(whole, 1)
    kept = [r for r in original if (r[0], r[1]) not in in_second]
    lost = len(original) - len(kept)
    assert lost == sum(in_second.values()) > 100

    assert main(["bag", "info", str(damaged)]) == 1
    said = capsys.readouterr().err
    start, end = second.message_start_time / 1e9, second.message_end_time / 1e9
    assert said.startswith(
        f"duckie: {damaged} is a damaged MCAP file: the chunk at byte "
        f"{second.chunk_start_offset:,} (record times {start:.3f} s to {end:.3f} s) cannot be "
        "read (CRCValidationError"
    )
    assert f"; {lost} of its {len(original)} messages are lost (" in said
    assert said.rstrip().endswith(
        f"`duckie bag repair {damaged} NEW.bag` recovers the {len(kept)} messages that can be read."
    )
    assert main(["bag", "odometry", str(damaged)]) == 1  # every reader refuses it the same way
    assert capsys.readouterr().err.startswith(f"duckie: {damaged} is a damaged MCAP file")

    assert main(["bag", "repair", str(damaged), str(tmp_path / "fixed.bag")]) == 0
    report = capsys.readouterr().out
    assert report.startswith(f"Recovered {len(kept)} messages on ")
    assert f"{lost} of the {len(original)} messages its summary lists were lost" in report
    fixed = Bag(tmp_path / "fixed.bag")
    assert sorted(fixed.raw_messages(fixed.topics)) == sorted(kept)


def test_a_cut_mcap_file_is_read_up_to_its_end_by_repair(mission, tmp_path, capsys):
    whole = chunked_mcap(mission, tmp_path / "whole.mcap")
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size * 2 // 3])
    assert main(["bag", "info", str(cut)]) == 1
    said = capsys.readouterr().err
    assert said.startswith(f"duckie: {cut} is a damaged MCAP file: it cannot be read past byte ")
    assert "its summary is lost: it was cut short or never closed" in said
    assert main(["bag", "repair", str(cut), str(tmp_path / "fixed.bag")]) == 0
    assert "It had no summary (an MCAP file's index)" in capsys.readouterr().out
    fixed = Bag(tmp_path / "fixed.bag")
    recovered = sorted(fixed.raw_messages(fixed.topics))
    original = mcap_records(whole)
    assert 0 < len(recovered) < len(original)
    assert recovered == sorted(original[: len(recovered)])  # the file's first messages, whole
    assert main(["bag", "repair", str(whole), str(tmp_path / "copy.bag")]) == 0
    assert capsys.readouterr().out.rstrip().endswith("closed properly, and the copy is whole.")
    copy = Bag(tmp_path / "copy.bag")
    assert records_of(copy) == records_of(mission)
    # The other writer left no md5 sums: each is computed from the schema's definition.
    assert {t: copy.topics[t].md5sum for t in copy.topics} == {
        t: mission.topics[t].md5sum for t in mission.topics
    }


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_damaged_ros2_bag_folder_is_said_with_its_file(mission, tmp_path, capsys, storage):
    folder = convert_bag(mission.path, tmp_path / "run", storage=storage)
    (stored,) = [f for f in folder.iterdir() if f.name != "metadata.yaml"]
    assert stored.name == f"run.{'mcap' if storage == 'mcap' else 'db3'}"
    data = bytearray(stored.read_bytes())
    if storage == "mcap":
        stored.write_bytes(bytes(data[: len(data) // 2]))
        expected = (
            f"duckie: {folder} (a ROS 2 bag folder): run.mcap is a damaged MCAP file: it cannot "
            "be read past byte "
        )
    else:
        data[len(data) // 2 : len(data) // 2 + 64] = b"\xff" * 64
        stored.write_bytes(bytes(data))
        expected = f"duckie: {folder} is a ROS 2 bag folder whose database run.db3 is damaged"
    assert main(["bag", "info", str(folder)]) == 1
    assert capsys.readouterr().err.startswith(expected)


def test_duckie_mission_writes_the_run_as_mcap_beside_its_bag(tmp_path, capsys):
    out = tmp_path / "run"
    command = ["mission", "--mission", "straight", "--no-animation", "--no-figure", "--mcap"]
    assert main([*command, "--out", str(out)]) == 0
    assert (
        capsys.readouterr()
        .out.rstrip()
        .endswith(
            f"wrote {out / 'mission.mcap'}: the same run as MCAP, its poses also as frames of a "
            "3D panel, for Foxglove, Lichtblick or PlotJuggler 4"
        )
    )
    with (out / "mission.mcap").open("rb") as file:
        summary = make_reader(file).get_summary()
    bag = Bag(out / "mission.bag")
    poses = [topic for topic in bag.topics if bag.topics[topic].type.endswith("Pose2DStamped")]
    per_topic = summary.statistics.channel_message_counts
    counts = {channel.topic: per_topic[cid] for cid, channel in summary.channels.items()}
    assert {topic: counts[topic] for topic in bag.topics} == {
        topic: info.count for topic, info in bag.topics.items()
    }
    assert counts["/tf"] == sum(bag.topics[topic].count for topic in poses) > 1000
    assert all(counts[topic + "_3d"] == bag.topics[topic].count for topic in poses)
    assert main([*command, "--out", str(out)]) == 0  # again, over the last run's files


def ros1_decoder(schema):
    """A decoder of one ``ros1msg`` schema, built by rosbags from the schema's own text."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(schema.data.decode(), schema.name))
    ros2_name = schema.name.replace("/", "/msg/", 1)
    return lambda data: store.deserialize_ros1(data, ros2_name)


def test_poses_become_tf_frames_and_pose_stamped_for_3d_panels(mission, tmp_path):
    import math

    target = convert_bag(mission.path, tmp_path / "run.mcap", poses_3d=True)
    truth = "/duckiebot/simulator_node/ground_truth_pose"
    decoders, by_topic = {}, {}
    with target.open("rb") as file:  # read back by the reference reader, decoded by rosbags
        reader = make_reader(file)
        for schema, channel, message in reader.iter_messages(
            topics=[truth, truth + "_3d", "/tf"], log_time_order=True
        ):
            if schema.id not in decoders:
                decoders[schema.id] = ros1_decoder(schema)
            decode = decoders[schema.id]
            by_topic.setdefault(channel.topic, []).append((message.log_time, decode(message.data)))
    poses, stamped = by_topic[truth], by_topic[truth + "_3d"]
    frames = [
        (t, tf.transforms[0])
        for t, tf in by_topic["/tf"]
        if tf.transforms[0].child_frame_id == truth.strip("/")
    ]
    assert len(poses) == len(stamped) == len(frames) == mission.topics[truth].count
    for (t, pose), (t3, pose_3d), (tf_t, frame) in zip(poses, stamped, frames):
        assert t == t3 == tf_t
        assert frame.header.frame_id == pose_3d.header.frame_id == "world"
        stamp = pose.header.stamp  # or, where it is 0 ("no time" in ROS), the record time
        said = (stamp.sec * 10**9 + stamp.nanosec) or t
        assert frame.header.stamp == pose_3d.header.stamp
        assert frame.header.stamp.sec * 10**9 + frame.header.stamp.nanosec == said
        assert (frame.transform.translation.x, frame.transform.translation.y) == (pose.x, pose.y)
        assert (pose_3d.pose.position.x, pose_3d.pose.position.y) == (pose.x, pose.y)
        q = frame.transform.rotation
        assert (q.x, q.y) == (0.0, 0.0)
        assert math.isclose(2 * math.atan2(q.z, q.w), pose.theta, abs_tol=1e-12)
        o = pose_3d.pose.orientation
        assert (o.x, o.y, o.z, o.w) == (q.x, q.y, q.z, q.w)
    turned = max(abs(pose.theta) for _, pose in poses)
    assert turned > 3.0  # a real heading, not the start's 0
    odometry = {tf.transforms[0].child_frame_id for _, tf in by_topic["/tf"]}
    assert odometry == {truth.strip("/"), "duckiebot/odometry_node/pose"}
    with AnyReader([convert_bag(target, tmp_path / "ros2", poses_3d=True)]) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}  # rosbag2's own types
    assert types["/tf"] == "tf2_msgs/msg/TFMessage"
    assert types[truth + "_3d"] == "geometry_msgs/msg/PoseStamped"
