"""Analysing bags: topics as arrays, wheel odometry replayed from encoder ticks, final poses.

Any type. :func:`read_topic` reads a topic of any type to arrays of its fields, from the
message definition the bag holds (``sensor_msgs/Imu``, ``std_msgs/Float64``, a robot's own
types); the rules for nested fields, fixed-length arrays and strings are in its docstring.
Encoder ticks are read fast, straight from their bytes, once their md5 sum shows they are
Duckietown's ``WheelEncoderStamped``.

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

# Over 600 lines: topics as arrays, encoder streams, pose tracks and replayed odometry share the
# time-base rules and the reading of a bag; `read_topic` and its decoding (about 200 lines) are the
# seam should it grow.

from __future__ import annotations

import math
import operator
import struct
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from duckielib import messages as course_messages
from duckielib.bags.reader import Bag, BagMessage, PathLike, TopicInfo
from duckielib.config import DB21
from duckielib.errors import BagError, MessageDefinitionError, UnknownTypeError
from duckielib.messages.spec import PRIMITIVE_TYPES, MessageSpec, parse_message
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
    "encoder_resolution",
    "odometry_of_streams",
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
        fields: every numeric field, by dotted name (``"x"``, ``"header.seq"``,
            ``"linear.x"``), shape (N,); times and durations in seconds (float). See
            :func:`read_topic` for arrays.
        notes: what a careful reader should know about the times.
        skipped: the fields left out of ``fields`` (strings and variable-length arrays), by
            dotted name, with their ROS type (``"string"``, ``"uint8[]"``).
    """

    topic: str
    type: str
    t: np.ndarray
    time_base: str
    record_t: np.ndarray
    stamp_t: Optional[np.ndarray]
    fields: Dict[str, np.ndarray] = field(default_factory=dict)
    notes: List[str] = field(default_factory=list)
    skipped: Dict[str, str] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.t)

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.fields[name]
        except KeyError:
            if name in self.skipped:
                raise KeyError(
                    f"{self.topic}'s field {name!r} is a {self.skipped[name]}, which read_topic "
                    "leaves out of its arrays; read the messages themselves with "
                    "Bag(path).read(topic)."
                ) from None
            known = ", ".join(self.fields) or "none"
            raise KeyError(
                f"{self.topic} has no numeric field {name!r}; it has: {known}."
            ) from None


#: Primitive types read as numbers (``byte`` and ``char`` are ROS 1's old names for int8, uint8).
_NUMBER_TYPES = PRIMITIVE_TYPES - {"string", "time", "duration"}
_TIME_TYPES = ("time", "duration")


@dataclass(frozen=True)
class _Leaf:
    """A field that becomes one array: its dotted name, how to get it, and whether a time."""

    name: str
    get: Callable[[Any], Any]
    is_time: bool


def _definitions(info: TopicInfo) -> Dict[str, MessageSpec]:
    """Every type a topic's full definition defines, by name: the topic's type and its parts.

    Raises:
        BagError: if the bag holds no definition, or one that cannot be read.
    """
    text = info.message_definition
    if not text.strip():
        try:
            cls = course_messages.get_message_class(info.type)
        except UnknownTypeError:
            cls = None
        if cls is None or cls._md5sum != info.md5sum:
            raise BagError(
                f"{info.name} ({info.type}) was recorded without its message definition, so "
                "its fields cannot be known."
            )
        text = cls._full_text
    sections: List[Tuple[str, List[str]]] = [(info.type, [])]
    lines = text.split("\n")
    index = 0
    while index < len(lines):
        line = lines[index]
        if len(line) >= 3 and set(line.strip()) == {"="}:
            name = lines[index + 1].strip() if index + 1 < len(lines) else ""
            name = name[len("MSG:") :].strip() if name.startswith("MSG:") else name
            sections.append(("std_msgs/Header" if name == "Header" else name, []))
            index += 2
            continue
        sections[-1][1].append(line)
        index += 1
    try:
        return {name: parse_message("\n".join(body), name) for name, body in sections}
    except MessageDefinitionError as error:
        raise BagError(
            f"The definition of {info.type} recorded for {info.name} cannot be read: {error}"
        ) from None


def _getter(path: Tuple[Union[str, int], ...]) -> Callable[[Any], Any]:
    """A function getting a field from a message: attribute names, and indices in arrays."""
    if all(isinstance(step, str) for step in path):
        return operator.attrgetter(".".join(str(step) for step in path))

    def get(message: Any) -> Any:
        value = message
        for step in path:
            value = value[step] if isinstance(step, int) else getattr(value, step)
        return value

    return get


def _plan(
    specs: Dict[str, MessageSpec],
    type_name: str,
    prefix: str = "",
    path: Tuple[Union[str, int], ...] = (),
) -> Tuple[List[_Leaf], Dict[str, str]]:
    """The fields of a type that become arrays, and those left out, with their ROS types."""
    spec = specs.get(type_name)
    if spec is None:
        raise BagError(
            f"The message definition recorded for {prefix.rstrip('.') or 'a topic'} lacks the "
            f"definition of {type_name}, so the bag cannot be read as arrays."
        )
    leaves: List[_Leaf] = []
    skipped: Dict[str, str] = {}
    for item in spec.fields:
        name = prefix + item.name
        if item.base_type == "string" or (item.is_array and item.array_length is None):
            skipped[name] = item.type
            continue
        if item.is_array:
            length = item.array_length or 0
            elements = [(f"{name}.{i}", (*path, item.name, i)) for i in range(length)]
        else:
            elements = [(name, (*path, item.name))]
        for element, steps in elements:
            if item.base_type in _NUMBER_TYPES:
                leaves.append(_Leaf(element, _getter(steps), False))
            elif item.base_type in _TIME_TYPES:
                leaves.append(_Leaf(element, _getter(steps), True))
            else:
                more, left_out = _plan(specs, item.base_type, element + ".", steps)
                leaves += more
                skipped.update(left_out)
    return leaves, skipped


def _time_ns(value: Any) -> int:
    """A time or duration in integer nanoseconds: duckielib's (secs, nsecs) or rosbags'."""
    to_nsec = getattr(value, "to_nsec", None)
    if to_nsec is not None:
        return int(to_nsec())
    return int(value.sec) * NS_PER_S + int(value.nanosec)


def _column(leaf: _Leaf, messages: List[BagMessage]) -> np.ndarray:
    get = leaf.get
    if leaf.is_time:
        return np.array([_time_ns(get(item.message)) for item in messages], np.int64) / NS_PER_S
    if not messages:
        return np.array([], dtype=np.float64)
    return np.array([get(item.message) for item in messages])


def read_topic(bag: Union[Bag, PathLike], topic: str, time_base: str = "auto") -> TopicArrays:
    """Read one topic of a bag into arrays, one entry per message, whatever its type.

    The fields come from the message definition the bag holds, so types the course does not
    know read as well (``sensor_msgs/Imu``, ``std_msgs/Float64``, a robot's own types):

    - numbers (and ``bool``) become arrays, named by their path: ``data``, ``linear.x``,
      ``header.seq``, ``orientation.w``;
    - times and durations become float seconds: ``header.stamp``;
    - a fixed-length array becomes one array per element, named by its index:
      ``orientation_covariance.0`` to ``orientation_covariance.8`` (messages in it too:
      ``points.0.x``);
    - strings and variable-length arrays (``string``, ``uint8[]``, ``Point[]``) are left out:
      their names and types are in ``skipped``. Read them from the messages themselves, with
      ``Bag(path).read(topic)``.

    Args:
        bag: a :class:`~duckielib.bags.Bag` or a bag's path.
        topic: the topic's name.
        time_base: ``"auto"`` (header stamps unless all 0), ``"header"`` or ``"record"``.

    Raises:
        BagError: if the bag or topic is missing, the bag is damaged, the topic was recorded
            with two definitions of its type, or the time base cannot be used.
    """
    _check_time_base(time_base)
    bag = _open(bag)
    info = bag.topic(topic)
    sums = sorted({item.md5sum for item in bag.connections_of(topic)})
    if len(sums) > 1:
        raise BagError(
            f"{topic} in {bag.path.name} was recorded with {len(sums)} definitions of "
            f"{info.type} (md5 sums {', '.join(sums)}), so its messages have no common fields; "
            "read them one by one with Bag(path).read(topic)."
        )
    leaves, skipped = _plan(_definitions(info), info.type)
    messages = bag.read(topic)
    record_ns = np.array([item.time_ns for item in messages], dtype=np.int64)
    stamp = next((leaf for leaf in leaves if leaf.name == "header.stamp" and leaf.is_time), None)
    stamp_ns = None
    if stamp is not None:
        stamp_ns = np.array([_time_ns(stamp.get(item.message)) for item in messages], np.int64)
    times, base, notes = _choose_times(topic, record_ns, stamp_ns, time_base)
    return TopicArrays(
        topic=topic,
        type=info.type,
        t=times / NS_PER_S,
        time_base=base,
        record_t=record_ns / NS_PER_S,
        stamp_t=None if stamp_ns is None else stamp_ns / NS_PER_S,
        fields={leaf.name: _column(leaf, messages) for leaf in leaves},
        notes=notes,
        skipped=skipped,
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


def _check_encoder_topic(bag: Bag, topic: str) -> None:
    """Check that every connection of ``topic`` carries the course's WheelEncoderStamped.

    Raises:
        BagError: if it carries another type, or another definition of it (md5 sum).
    """
    course_md5 = course_messages.get_message_class(_ENCODER_TYPE)._md5sum
    for info in bag.connections_of(topic):
        if info.type != _ENCODER_TYPE:
            raise BagError(f"{topic} carries {info.type}, not {_ENCODER_TYPE}.")
        if info.md5sum != course_md5:
            raise BagError(
                f"{topic} in {bag.path.name} carries {_ENCODER_TYPE} with md5 sum "
                f"{info.md5sum}, but Duckietown's (and the course's) {_ENCODER_TYPE} has md5 "
                f"sum {course_md5}: whoever recorded the bag defined the message differently, "
                "so its bytes are not the encoder ticks (data, resolution, type) odometry "
                f"needs. See what its messages hold with read_topic(bag, {topic!r})."
            )


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
        BagError: if a topic is missing, is not of type WheelEncoderStamped or has another
            definition of it (md5 sum) than Duckietown's, or if the bag is damaged.
    """
    _check_time_base(time_base)
    bag = _open(bag)
    if left_topic is None or right_topic is None:
        found_left, found_right = encoder_topics(bag)
        left_topic = left_topic or found_left
        right_topic = right_topic or found_right
    for topic in (left_topic, right_topic):
        _check_encoder_topic(bag, topic)
    raw = bag.raw_messages([left_topic, right_topic])
    by_topic = {
        topic: [item for item in raw if item[0] == topic] for topic in (left_topic, right_topic)
    }
    decoded = {}
    for topic, items in by_topic.items():
        try:
            decoded[topic] = _decode_encoders(items)
        except struct.error:
            raise BagError(
                f"A message on {topic} in {bag.path.name} is too short to be a "
                f"{_ENCODER_TYPE}: the bag is damaged."
            ) from None
    # One base for both wheels: header stamps only if both have them.
    base = time_base
    if time_base == "auto" and any(not decoded[t][1].any() for t in decoded if len(decoded[t][1])):
        base = "record"
    streams = []
    for topic in (left_topic, right_topic):
        record_ns, stamp_ns, ticks, resolution = decoded[topic]
        times, chosen, notes = _choose_times(topic, record_ns, stamp_ns, base)
        order = np.argsort(times, kind="stable")
        stream = EncoderStream(
            topic, times[order] / NS_PER_S, ticks[order], resolution[order], chosen, notes
        )
        _check_no_spike(stream, bag.path.name)
        streams.append(stream)
    return streams[0], streams[1]


#: The most ticks a wheel may turn in a second before a count is called damaged: five times
#: what a DB21's motor gives at full duty (about 27 rad/s, 580 ticks/s), and a margin of
#: ticks for stamps that come close together.
SPIKE_TICKS_PER_S = 3000
SPIKE_MARGIN_TICKS = 200


def _check_no_spike(stream: EncoderStream, bag_name: str) -> None:
    """Raise if one count jumps away and back again faster than any motor turns a wheel.

    A ROS 1 bag carries no checksum: bytes flipped inside a tick's data read as a count
    that is wrong by thousands. A count that leaves its neighbours, which agree with each
    other, by more than a wheel can turn in the time between is such a count. (A driver that
    restarts counts from 0 and stays there: that is a jump that does not come back.)

    Raises:
        BagError: saying which message, when, and by how much.
    """
    t, ticks = stream.t, stream.ticks.astype(np.float64)
    if len(t) < 3:
        return

    def limit(dt: np.ndarray) -> np.ndarray:
        return SPIKE_MARGIN_TICKS + SPIKE_TICKS_PER_S * np.abs(dt)

    before = ticks[1:-1] - ticks[:-2]
    after = ticks[2:] - ticks[1:-1]
    across = ticks[2:] - ticks[:-2]
    spikes = (
        (np.abs(before) > limit(t[1:-1] - t[:-2]))
        & (np.abs(after) > limit(t[2:] - t[1:-1]))
        & (np.sign(before) != np.sign(after))
        & (np.abs(across) <= limit(t[2:] - t[:-2]))
    )
    found = np.flatnonzero(spikes)
    if not len(found):
        return
    index = int(found[0]) + 1
    jump = int(before[index - 1])
    gap_ms = 1000 * float(t[index] - t[index - 1])
    raise BagError(
        f"{stream.topic} in {bag_name} is damaged at {t[index]:.3f} s ({stream.time_base} "
        f"time): that message says {int(ticks[index]):,} ticks, {jump:+,} from the one "
        f"{gap_ms:.0f} ms before it, and the next one is back: no motor turns a wheel that "
        f"fast. A ROS 1 bag carries no checksum, so bytes changed inside a message read as a "
        f"wrong count; {len(found)} such message(s) in all. Record the run again, or leave "
        "them out of the bag."
    )


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


def encoder_resolution(bag: Bag, left: EncoderStream, right: EncoderStream) -> int:
    """The encoders' resolution (ticks per wheel revolution), the same in every message.

    Raises:
        BagError: if a message says 0, or the messages say several resolutions: a problem of
            the bag, which the solution's odometry must not be blamed for.
    """
    for stream in (left, right):
        zero = int(np.count_nonzero(stream.resolution == 0))
        if zero:
            raise BagError(
                f"{zero} of the {len(stream.resolution)} encoder messages on {stream.topic} in "
                f"{bag.path.name} carry resolution 0 (ticks per wheel revolution), so no wheel "
                "angle can be computed from their ticks. This is a problem of the bag (the "
                "encoder driver that recorded it did not fill in its resolution), not of your "
                "code: replay a bag whose encoder messages carry their resolution (135 on a "
                "DB21)."
            )
    values = sorted({int(value) for value in np.concatenate([left.resolution, right.resolution])})
    if len(values) > 1:
        raise BagError(
            f"The encoder messages of {bag.path.name} carry {len(values)} resolutions "
            f"({', '.join(map(str, values))} ticks per wheel revolution), but both wheels' "
            "odometry needs one. This is a problem of the bag, not of your code."
        )
    return values[0]


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
        BagError: if the bag has no encoder topics, one wheel has no message, or the encoder
            messages do not say one resolution (ticks per revolution) above 0.
        SolutionError: if the solution lacks a part, has not finished it, or a part fails.
    """
    bag = _open(bag)
    left, right = read_encoders(bag, left_topic, right_topic, time_base)
    for stream in (left, right):
        if not len(stream.t):
            raise BagError(f"{stream.topic} has no message, so no odometry can be computed.")
    resolution = encoder_resolution(bag, left, right)
    return odometry_of_streams(left, right, solution, resolution, start, radius, baseline, label)


def odometry_of_streams(
    left: EncoderStream,
    right: EncoderStream,
    solution: Any,
    resolution: int,
    start: Sequence[float] = TASK_START,
    radius: float = DB21.radius,
    baseline: float = DB21.baseline,
    label: str = "odometry",
) -> PoseTrack:
    """Dead reckoning from two wheels' readings, with a solution's odometry.

    :func:`replay_odometry` for readings already read (or simulated): ``resolution`` ticks per
    revolution; the other arguments as there.
    """
    odometry = Odometry(solution, resolution, radius, baseline, start)
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
