"""Damaged and foreign bags, made by the tests: what students bring from robots and crashes.

Damage is made from a sound bag, byte by byte, as it happens to files: a recording cut short,
bytes changed inside a chunk, a damaged head (the bag header, in the first 4 KB), a header
whose chunk count says 0. Foreign bags are written with rosbags' own ``Writer`` and a rosbags
typestore (ROS 1 Noetic's definitions, or ROS 2 Humble's, whose md5 sums differ from ROS 1's),
so they are bags written elsewhere than by duckielib.
"""

from __future__ import annotations

import hashlib
import struct
from pathlib import Path

import numpy as np
from bagtools import LEFT, RIGHT
from rosbags.rosbag1 import Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from duckielib.bags import BagWriter
from duckielib.messages import Header, WheelEncoderStamped
from duckielib.rostime import Time

S = 1_000_000_000
#: Encoder messages per wheel and per chunk in :func:`encoder_bag`.
PER_CHUNK = 150
CHUNKS = 4
#: The six foreign types, as rosbags names them, and the topic each is written on.
FOREIGN = {
    "sensor_msgs/msg/Imu": "/imu",
    "sensor_msgs/msg/Range": "/range",
    "geometry_msgs/msg/PoseStamped": "/pose",
    "std_msgs/msg/Float64": "/float",
    "std_msgs/msg/Int32": "/count",
    "geometry_msgs/msg/Twist": "/cmd_vel",
}
#: A robot's own type, unknown to the course: every kind of field read_topic meets.
SONAR = "robot_msgs/msg/Sonar"
SONAR_DEFINITION = """\
Header header
float32[3] limits
geometry_msgs/Point[2] corners
string label
uint8[] raw
geometry_msgs/Point[] echoes
time fired
duration elapsed
bool ok
"""
#: A WheelEncoderStamped as another robot might define it, with its own md5 sum.
OTHER_ENCODER_DEFINITION = "float64 data\n"
OTHER_ENCODER_MD5 = hashlib.md5(OTHER_ENCODER_DEFINITION.strip().encode()).hexdigest()
#: std_msgs/Float64's md5 sum, and that of a Float64 some robot defined as ``int32 data``.
FLOAT_MD5 = "fdb28210bfa9d7c91146260178d9a584"
INT_AS_FLOAT_MD5 = hashlib.md5(b"int32 data").hexdigest()


def encoder(index, ticks, stamp_ns, resolution=135):
    return WheelEncoderStamped(
        header=Header(seq=index, stamp=Time.from_nsec(stamp_ns), frame_id="wheel"),
        data=ticks,
        resolution=resolution,
        type=1,
    )


def encoder_bag(path, compression="none", resolution=135, chunks=CHUNKS):
    """Both wheels driving straight, in ``chunks`` chunks of PER_CHUNK readings per wheel.

    Returns:
        The path, and the ``(start, end)`` byte offsets of each chunk.
    """
    with BagWriter(path, compression) as writer:
        for index in range(chunks * PER_CHUNK):
            t_ns = S + index * S // 30
            writer.write(LEFT, encoder(index, 3 * index, t_ns, resolution), t_ns)
            writer.write(RIGHT, encoder(index, 3 * index, t_ns, resolution), t_ns + 1_000_000)
            if (index + 1) % PER_CHUNK == 0:
                writer.flush()  # a chunk per PER_CHUNK readings
    spans = chunk_spans(path)
    assert len(spans) == chunks
    return path, spans


def chunk_spans(path):
    """The ``(start, end)`` byte offsets of a sound bag's chunk records, found independently.

    A record is a header length, header fields (``op`` among them), a data length and data.
    """
    data = Path(path).read_bytes()
    spans = []
    pos = 13
    while pos < len(data):
        (header_length,) = struct.unpack_from("<I", data, pos)
        header = data[pos + 4 : pos + 4 + header_length]
        (data_length,) = struct.unpack_from("<I", data, pos + 4 + header_length)
        end = pos + 8 + header_length + data_length
        if b"\x04\x00\x00\x00op=\x05" in header:
            spans.append((pos, end))
        pos = end
    return spans


def changed(source, target, offset, count=64):
    """A copy of ``source`` with ``count`` bytes from ``offset`` inverted."""
    data = bytearray(Path(source).read_bytes())
    data[offset : offset + count] = bytes(byte ^ 0xFF for byte in data[offset : offset + count])
    Path(target).write_bytes(bytes(data))
    return Path(target)


def cut(source, target, size):
    """A copy of the first ``size`` bytes of ``source``: a copy or a recording cut short."""
    Path(target).write_bytes(Path(source).read_bytes()[:size])
    return Path(target)


def damaged_head(source, target):
    """A copy of ``source`` whose bag header (the first 4 KB after the magic) is zeros."""
    data = bytearray(Path(source).read_bytes())
    data[13:4109] = bytes(4096)
    Path(target).write_bytes(bytes(data))
    return Path(target)


def no_chunks_in_header(source, target):
    """A copy of ``source`` whose header says the index lists no chunk, as if unfinished."""
    data = bytearray(Path(source).read_bytes())
    field = data.index(b"chunk_count=", 13, 4109) + len("chunk_count=")
    data[field : field + 4] = struct.pack("<I", 0)
    Path(target).write_bytes(bytes(data))
    return Path(target)


def _write_with_rosbags(path, store, items):
    """Write ``(topic, msgtype, message, time_ns)`` items with rosbags' own Writer."""
    writer = Writer(path)
    writer.open()
    try:
        connections = {}
        for topic, msgtype, message, time_ns in items:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=store)
            writer.write(connections[topic], time_ns, store.serialize_ros1(message, msgtype))
    finally:
        writer.close()
    return path


def foreign_store(kind):
    """A rosbags typestore: ``"noetic"`` (ROS 1's definitions) or ``"humble"`` (ROS 2's)."""
    return get_typestore(Stores.ROS1_NOETIC if kind == "noetic" else Stores.ROS2_HUMBLE)


def _header(store, index, stamp_ns):
    types = store.types
    stamp = types["builtin_interfaces/msg/Time"](sec=stamp_ns // S, nanosec=stamp_ns % S)
    fields = {"stamp": stamp, "frame_id": "base"}
    if "seq" in store.fielddefs["std_msgs/msg/Header"][1][0]:  # ROS 1's header has a seq
        fields["seq"] = index
    return types["std_msgs/msg/Header"](**fields)


def foreign_messages(store, index, stamp_ns):
    """One message of each foreign type, its values made from ``index``."""
    types = store.types
    vector = types["geometry_msgs/msg/Vector3"]
    quaternion = types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
    header = _header(store, index, stamp_ns)
    return {
        "sensor_msgs/msg/Imu": types["sensor_msgs/msg/Imu"](
            header=header,
            orientation=quaternion,
            orientation_covariance=np.arange(9, dtype=np.float64),
            angular_velocity=vector(x=1.0, y=2.0, z=float(index)),
            angular_velocity_covariance=np.zeros(9),
            linear_acceleration=vector(x=0.0, y=0.0, z=9.81),
            linear_acceleration_covariance=np.zeros(9),
        ),
        "sensor_msgs/msg/Range": types["sensor_msgs/msg/Range"](
            header=header,
            radiation_type=1,
            field_of_view=0.5,
            min_range=0.05,
            max_range=1.2,
            range=0.25 * index,
            **({"variance": 0.0} if "variance" in _names(store, "sensor_msgs/msg/Range") else {}),
        ),
        "geometry_msgs/msg/PoseStamped": types["geometry_msgs/msg/PoseStamped"](
            header=header,
            pose=types["geometry_msgs/msg/Pose"](
                position=types["geometry_msgs/msg/Point"](x=1.0, y=-2.0, z=0.5 * index),
                orientation=quaternion,
            ),
        ),
        "std_msgs/msg/Float64": types["std_msgs/msg/Float64"](data=1.5 * index),
        "std_msgs/msg/Int32": types["std_msgs/msg/Int32"](data=-index),
        "geometry_msgs/msg/Twist": types["geometry_msgs/msg/Twist"](
            linear=vector(x=0.1 * index, y=0.0, z=0.0), angular=vector(x=0.0, y=0.0, z=-1.0)
        ),
    }


def _names(store, msgtype):
    return [name for name, _ in store.fielddefs[msgtype][1]]


def foreign_bag(path, kind="noetic", count=3, zero_stamps=False):
    """The six foreign types, ``count`` messages each, written by rosbags.

    Message ``k`` is recorded at ``(10 + k) s + 7 ns``; stamped ones are stamped ``(10 + k) s
    + 5 ns``, or 0 with ``zero_stamps``.
    """
    store = foreign_store(kind)
    items = []
    for index in range(count):
        record_ns = (10 + index) * S + 7
        stamp_ns = 0 if zero_stamps else (10 + index) * S + 5
        for msgtype, message in foreign_messages(store, index, stamp_ns).items():
            items.append((FOREIGN[msgtype], msgtype, message, record_ns))
    return _write_with_rosbags(path, store, items)


def sonar_bag(path, count=2):
    """A robot's own type (:data:`SONAR_DEFINITION`), unknown to the course, written by rosbags."""
    store = foreign_store("noetic")
    store.register(get_types_from_msg(SONAR_DEFINITION, SONAR))
    types = store.types
    point = types["geometry_msgs/msg/Point"]
    items = []
    for index in range(count):
        message = types[SONAR](
            header=_header(store, index, (20 + index) * S),
            limits=np.array([0.1, 2.0, float(index)], dtype=np.float32),
            corners=[point(x=float(index), y=1.0, z=0.0), point(x=2.0, y=-1.0, z=0.0)],
            label=f"ping {index}",
            raw=np.array([1, 2, 3][: index + 1], dtype=np.uint8),
            echoes=[point(x=0.0, y=0.0, z=0.0)] * index,
            fired=types["builtin_interfaces/msg/Time"](sec=20 + index, nanosec=500_000_000),
            elapsed=types["builtin_interfaces/msg/Duration"](sec=0, nanosec=250_000_000),
            ok=bool(index),
        )
        items.append(("/sonar", SONAR, message, (20 + index) * S + 1))
    return _write_with_rosbags(path, store, items)


def other_encoder_definition_bag(path):
    """Encoder topics of type WheelEncoderStamped, but defined as ``float64 data``."""
    with BagWriter(path) as writer:
        for index in range(20):
            for offset, topic in enumerate((LEFT, RIGHT)):
                writer.write_raw(
                    topic,
                    "duckietown_msgs/WheelEncoderStamped",
                    OTHER_ENCODER_MD5,
                    OTHER_ENCODER_DEFINITION,
                    S + index * S // 30 + offset,
                    struct.pack("<d", 3.0 * index),
                )
    return path
