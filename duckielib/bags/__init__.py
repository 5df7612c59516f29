"""ROS 1 bags: record, read, repair and analyse them, from the simulator or a real robot.

This package is the only place rosbags is imported. Bags written here open in ``rosbag
info``/``rosbag play`` and Foxglove; bags recorded on a Duckiebot open here with the message
definitions embedded in them. :class:`Bag` (and so everything that reads a bag) also opens
MCAP files and ROS 2 bag folders, as a ROS 1 copy made once; :func:`convert_bag` writes a bag
as MCAP or a ROS 2 bag, for today's viewers.

Modules (one idea each):
    reader: :class:`Bag`, a bag opened for reading, every record checked.
    writer: :class:`BagWriter`, a bag written whole (uncompressed or BZ2).
    seam: the only code relying on rosbags' internals, checked at first use; the course's
        types as a rosbags typestore.
    recorder: :class:`BagRecorder`, ``rosbag record`` for the in-process graph.
    repair: :func:`repair_bag`, every complete message of a killed recording.
    records: the bag's records in file order, even from a damaged file.
    analysis: topics as arrays, odometry replayed from encoder ticks, pose tracks.
    samples: :func:`sample_bag`, bags that come with the course.
    convert: :func:`convert_bag`, to and from MCAP and ROS 2 bags.

A damaged bag is never read in part as if it were whole: reading checks every record and
the index's counts, and raises a :class:`~duckielib.errors.BagError` saying where the damage
is and how many messages it costs; :func:`repair_bag` (``duckie bag repair``) recovers every
message that can still be read.

Example::

    from duckielib.bags import Bag, read_topic, replay_odometry

    bag = Bag("run.bag")
    bag.topics                            # names, types, counts
    ticks = read_topic(bag, "/duckiebot/left_wheel_encoder_node/tick")
    ticks["data"], ticks.t                # any type's fields as arrays, times in seconds
    track = replay_odometry(bag, globals())   # in a notebook: its WheelPairing, delta_phi, ...
    track.final_pose

Outside a notebook, pass the solution as a module:
``replay_odometry(bag, load_solution("my_solution.py"))`` (:func:`~duckielib.solution.load_solution`
loads what ``duckie export`` wrote).
"""

from __future__ import annotations

from duckielib.bags.analysis import (
    EncoderStream,
    PoseTrack,
    TopicArrays,
    encoder_topics,
    pose_tracks,
    read_encoders,
    read_topic,
    replay_odometry,
)
from duckielib.bags.convert import convert_bag
from duckielib.bags.reader import Bag, BagMessage, TopicInfo
from duckielib.bags.recorder import BagRecorder, record
from duckielib.bags.repair import RepairReport, repair_bag
from duckielib.bags.samples import SAMPLES, sample_bag
from duckielib.bags.seam import course_typestore
from duckielib.bags.writer import BagWriter

__all__ = [
    "convert_bag",
    "Bag",
    "BagMessage",
    "BagRecorder",
    "BagWriter",
    "EncoderStream",
    "PoseTrack",
    "RepairReport",
    "SAMPLES",
    "TopicArrays",
    "TopicInfo",
    "course_typestore",
    "encoder_topics",
    "pose_tracks",
    "read_encoders",
    "read_topic",
    "record",
    "repair_bag",
    "replay_odometry",
    "sample_bag",
]
