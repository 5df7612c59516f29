"""Analysing bags: topics as arrays, wheel odometry replayed from encoder ticks, final poses.

Time bases. Every message in a bag has two times: its record time (when the recorder got it)
and, for stamped types, its header stamp (when the data was taken, by the publisher's clock).
On a real robot they differ by clock skew, and some bags have all stamps 0. Each function here
takes ``time_base``: ``"header"``, ``"record"``, or ``"auto"`` (header stamps unless they are
all 0), and says in ``notes`` when the two disagree.

Odometry. :func:`replay_odometry` feeds a bag's encoder ticks, in time order, to a solution's
odometry (its ``WheelPairing``, ``delta_phi`` and ``estimate_pose``, see
:mod:`duckielib.solution`), so a student's own code can be replayed on any bag, simulated or
recorded on a robot.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from duckielib.bags.io import Bag, PathLike
from duckielib.config import DB21
from duckielib.errors import BagError
from duckielib.missions import TASK_START
from duckielib.odometry import Odometry
from duckielib.rostime import NS_PER_S

__all__ = [
    "EncoderStream",
    "PoseTrack",
    "TopicArrays",
    "TIME_BASES",
    "encoder_topics",
    "pose_tracks",
    "read_encoders",
    "read_topic",
    "replay_odometry",
]

#: The time bases a reader can use.
TIME_BASES = ("auto", "header", "record")

#: Header stamps further than this from the record time (seconds) earn a note.
SKEW_NOTE_S = 0.05

_ENCODER_TYPE = "duckietown_msgs/WheelEncoderStamped"
_POSE_TYPE = "duckietown_msgs/Pose2DStamped"
_HEADER = struct.Struct("<IIII")  # seq, stamp secs, stamp nsecs, frame_id length
_ENCODER_TAIL = struct.Struct("<iHB")  # data, resolution, type


def _open(bag: Union[Bag, PathLike]) -> Bag:
    return bag if isinstance(bag, Bag) else Bag(bag)


def _check_time_base(time_base: str) -> None:
    if time_base not in TIME_BASES:
        raise BagError(f"time_base must be one of {', '.join(TIME_BASES)}, not {time_base!r}.")


def _choose_times(
    topic: str, record_ns: np.ndarray, stamp_ns: Optional[np.ndarray], time_base: str
) -> Tuple[np.ndarray, str, List[str]]:
    """The times to use (ns), the base chosen, and notes on stamps vs record times."""
    notes: List[str] = []
    if stamp_ns is None:
        if time_base == "header":
            raise BagError(f"{topic} has no header stamps; use time_base='record'.")
        return record_ns, "record", notes
    if len(stamp_ns) and not stamp_ns.any():
        notes.append(f"{topic}: every header stamp is 0, so record times are used.")
        if time_base == "header":
            raise BagError(f"Every header stamp on {topic} is 0; use time_base='record'.")
        return record_ns, "record", notes
    if len(stamp_ns):
        skew = np.abs(stamp_ns.astype(np.float64) - record_ns) / NS_PER_S
        if skew.max() > SKEW_NOTE_S:
            notes.append(
                f"{topic}: header stamps differ from record times by {np.median(skew):.3f} s "
                f"(median) and up to {skew.max():.3f} s."
            )
    if time_base == "record":
        return record_ns, "record", notes
    return stamp_ns, "header", notes


@dataclass
class TopicArrays:
    """One topic's messages as arrays, one entry per message.

    Attributes:
        topic: the topic's name.
        type: its message type.
        t: the chosen times, in seconds, shape (N,).
        time_base: ``"header"`` or ``"record"``: which times ``t`` holds.
        record_t: record times, in seconds, shape (N,).
        stamp_t: header stamps, in seconds, shape (N,), or None for types without a header.
        fields: every numeric field, by dotted name (``"x"``, ``"header.seq"``), shape (N,).
        notes: what a careful reader should know about the times.
    """

    topic: str
    type: str
    t: np.ndarray
    time_base: str
    record_t: np.ndarray
    stamp_t: Optional[np.ndarray]
    fields: Dict[str, np.ndarray] = field(default_factory=dict)
    notes: List[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.t)

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.fields[name]
        except KeyError:
            known = ", ".join(self.fields) or "none"
            raise KeyError(
                f"{self.topic} has no numeric field {name!r}; it has: {known}."
            ) from None


def _numeric_leaves(message: Any, prefix: str = "") -> Dict[str, float]:
    leaves: Dict[str, float] = {}
    for name in getattr(message, "__slots__", ()):
        value = getattr(message, name)
        key = prefix + name
        if isinstance(value, (bool, int, float)):
            leaves[key] = value
        elif hasattr(value, "to_nsec"):
            leaves[key] = value.to_nsec() / NS_PER_S
        elif hasattr(value, "__slots__"):
            leaves.update(_numeric_leaves(value, key + "."))
    return leaves


def read_topic(bag: Union[Bag, PathLike], topic: str, time_base: str = "auto") -> TopicArrays:
    """Read one topic of a bag into arrays.

    Args:
        bag: a :class:`~duckielib.bags.Bag` or a bag's path.
        topic: the topic's name.
        time_base: ``"auto"`` (header stamps unless all 0), ``"header"`` or ``"record"``.

    Raises:
        BagError: if the bag or topic is missing, or the time base cannot be used.
    """
    _check_time_base(time_base)
    bag = _open(bag)
    info = bag.topic(topic)
    records = bag.read(topic)
    record_ns = np.array([item.time_ns for item in records], dtype=np.int64)
    has_header = bool(records) and hasattr(records[0].message, "header")
    stamp_ns = None
    if has_header:
        stamp_ns = np.array(
            [item.message.header.stamp.to_nsec() for item in records], dtype=np.int64
        )
    times, base, notes = _choose_times(topic, record_ns, stamp_ns, time_base)
    rows = [_numeric_leaves(item.message) for item in records]
    names = list(rows[0]) if rows else []
    fields = {name: np.array([row[name] for row in rows]) for name in names}
    return TopicArrays(
        topic=topic,
        type=info.type,
        t=times / NS_PER_S,
        time_base=base,
        record_t=record_ns / NS_PER_S,
        stamp_t=None if stamp_ns is None else stamp_ns / NS_PER_S,
        fields=fields,
        notes=notes,
    )


@dataclass
class EncoderStream:
    """One wheel's encoder messages.

    Attributes:
        topic: the topic's name.
        t: the chosen times, in seconds, shape (N,).
        ticks: the cumulative signed counts, shape (N,), int64.
        resolution: ticks per wheel revolution, shape (N,).
        time_base: ``"header"`` or ``"record"``.
        notes: what to know about the times.
    """

    topic: str
    t: np.ndarray
    ticks: np.ndarray
    resolution: np.ndarray
    time_base: str
    notes: List[str] = field(default_factory=list)


def encoder_topics(bag: Bag) -> Tuple[str, str]:
    """The bag's left and right encoder topics (``.../left_wheel_encoder_node/tick``).

    Raises:
        BagError: if the bag does not have exactly one of each.
    """
    found = bag.topics_of_type(_ENCODER_TYPE)
    pair = []
    for side in ("left", "right"):
        matches = [name for name in found if f"{side}_wheel_encoder" in name]
        if len(matches) != 1:
            have = ", ".join(found) or "none"
            raise BagError(
                f"{bag.path.name} needs one {side} encoder topic "
                f"(.../{side}_wheel_encoder_node/tick of type {_ENCODER_TYPE}); "
                f"its encoder topics are: {have}."
            )
        pair.append(matches[0])
    return pair[0], pair[1]


def _decode_encoders(raw: Sequence[Tuple[str, int, bytes]]) -> Tuple[np.ndarray, ...]:
    """Record times, stamps, ticks and resolutions of WheelEncoderStamped bytes, fast."""
    count = len(raw)
    record_ns = np.empty(count, dtype=np.int64)
    stamp_ns = np.empty(count, dtype=np.int64)
    ticks = np.empty(count, dtype=np.int64)
    resolution = np.empty(count, dtype=np.int64)
    header = _HEADER.unpack_from
    tail = _ENCODER_TAIL.unpack_from
    for index, (_, time_ns, data) in enumerate(raw):
        _, secs, nsecs, frame_length = header(data, 0)
        value, res, _ = tail(data, 16 + frame_length)
        record_ns[index] = time_ns
        stamp_ns[index] = secs * NS_PER_S + nsecs
        ticks[index] = value
        resolution[index] = res
    return record_ns, stamp_ns, ticks, resolution


def read_encoders(
    bag: Union[Bag, PathLike],
    left_topic: Optional[str] = None,
    right_topic: Optional[str] = None,
    time_base: str = "auto",
) -> Tuple[EncoderStream, EncoderStream]:
    """Both wheels' encoder streams of a bag.

    Args:
        bag: a :class:`~duckielib.bags.Bag` or a bag's path.
        left_topic: the left encoder topic (default: found by name).
        right_topic: the right encoder topic (default: found by name).
        time_base: ``"auto"``, ``"header"`` or ``"record"``; both wheels use the same base.

    Raises:
        BagError: if a topic is missing or not of type WheelEncoderStamped.
    """
    _check_time_base(time_base)
    bag = _open(bag)
    if left_topic is None or right_topic is None:
        found_left, found_right = encoder_topics(bag)
        left_topic = left_topic or found_left
        right_topic = right_topic or found_right
    for topic in (left_topic, right_topic):
        if bag.topic(topic).type != _ENCODER_TYPE:
            raise BagError(f"{topic} carries {bag.topic(topic).type}, not {_ENCODER_TYPE}.")
    raw = bag.raw_messages([left_topic, right_topic])
    by_topic = {
        topic: [item for item in raw if item[0] == topic] for topic in (left_topic, right_topic)
    }
    decoded = {topic: _decode_encoders(items) for topic, items in by_topic.items()}
    # One base for both wheels: header stamps only if both have them.
    base = time_base
    if time_base == "auto" and any(not decoded[t][1].any() for t in decoded if len(decoded[t][1])):
        base = "record"
    streams = []
    for topic in (left_topic, right_topic):
        record_ns, stamp_ns, ticks, resolution = decoded[topic]
        times, chosen, notes = _choose_times(topic, record_ns, stamp_ns, base)
        order = np.argsort(times, kind="stable")
        streams.append(
            EncoderStream(
                topic, times[order] / NS_PER_S, ticks[order], resolution[order], chosen, notes
            )
        )
    return streams[0], streams[1]


@dataclass
class PoseTrack:
    """A robot's poses over time, in the world frame.

    Attributes:
        t: times, in seconds, shape (N,).
        x, y: positions, in metres, shape (N,).
        theta: headings, in radians, shape (N,).
        label: what the track is (for plots), for example ``"odometry"``.
        notes: what to know about the times.
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    label: str = "pose"
    notes: List[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.t)

    @property
    def final_pose(self) -> Tuple[float, float, float]:
        """The last pose (x, y, theta), in metres and radians."""
        if not len(self.t):
            raise BagError(f"The track {self.label!r} has no poses.")
        return float(self.x[-1]), float(self.y[-1]), float(self.theta[-1])

    def distance_to(self, reference: Sequence[float]) -> float:
        """Distance in metres from the final position to ``reference`` (x, y[, theta])."""
        x, y, _ = self.final_pose
        return math.hypot(x - reference[0], y - reference[1])


def pose_tracks(bag: Union[Bag, PathLike], time_base: str = "auto") -> List[PoseTrack]:
    """Every Pose2DStamped topic of a bag as a :class:`PoseTrack` labelled with its topic."""
    bag = _open(bag)
    tracks = []
    for topic in bag.topics_of_type(_POSE_TYPE):
        arrays = read_topic(bag, topic, time_base)
        tracks.append(
            PoseTrack(
                arrays.t, arrays["x"], arrays["y"], arrays["theta"], topic, list(arrays.notes)
            )
        )
    return tracks


def replay_odometry(
    bag: Union[Bag, PathLike],
    solution: Any,
    start: Sequence[float] = TASK_START,
    radius: float = DB21.radius,
    baseline: float = DB21.baseline,
    left_topic: Optional[str] = None,
    right_topic: Optional[str] = None,
    time_base: str = "auto",
    label: str = "odometry",
) -> PoseTrack:
    """Dead reckoning from a bag's encoder ticks, with a solution's odometry.

    The readings of both wheels are fed, in time order, to the solution's ``WheelPairing``;
    each pair it returns moves the pose through the solution's ``estimate_pose``.

    Args:
        bag: a :class:`~duckielib.bags.Bag` or a bag's path.
        solution: what holds ``delta_phi``, ``estimate_pose`` and ``WheelPairing``: a module
            (see :func:`~duckielib.solution.load_solution`) or, in a notebook, ``globals()``.
        start: the pose (x, y, theta) at the first pair of readings; metres, radians.
        radius: wheel radius R, in metres.
        baseline: distance between the wheels, in metres.
        left_topic: the left encoder topic (default: found by name).
        right_topic: the right encoder topic (default: found by name).
        time_base: ``"auto"``, ``"header"`` or ``"record"``.
        label: the track's label.

    Returns:
        The poses: one per pair of readings, the first at ``start``.

    Raises:
        BagError: if the bag has no encoder topics, or one wheel has no message.
        SolutionError: if the solution lacks a part, has not finished it, or a part fails.
    """
    left, right = read_encoders(bag, left_topic, right_topic, time_base)
    for stream in (left, right):
        if not len(stream.t):
            raise BagError(f"{stream.topic} has no message, so no odometry can be computed.")
    odometry = Odometry(solution, int(left.resolution[0]), radius, baseline, start)
    times_all = np.concatenate([left.t, right.t])
    wheels = np.concatenate([np.zeros(len(left.t), np.int64), np.ones(len(right.t), np.int64)])
    order = np.lexsort((wheels, times_all))  # by time, the left wheel first at equal times
    names = ("left", "right")
    times: List[float] = []
    poses: List[Tuple[float, float, float]] = []
    for t, wheel, ticks in zip(
        times_all[order].tolist(),
        wheels[order].tolist(),
        np.concatenate([left.ticks, right.ticks])[order].tolist(),
    ):
        pose = odometry.add(names[wheel], ticks)
        if pose is not None:
            times.append(t)
            poses.append(pose)
    array = np.array(poses, dtype=np.float64).reshape(-1, 3)
    return PoseTrack(
        np.array(times), array[:, 0], array[:, 1], array[:, 2], label, left.notes + right.notes
    )
