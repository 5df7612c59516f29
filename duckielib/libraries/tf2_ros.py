"""tf2_ros: broadcast coordinate frames and look up transforms between them, as on a Duckiebot.

Use it exactly as ROS's ``tf2_ros``, for example to say where the robot is in its odometry frame
and to ask where it is in the world::

    import tf2_ros

    broadcaster = tf2_ros.TransformBroadcaster()
    broadcaster.sendTransform(odom_to_base)          # a geometry_msgs/TransformStamped

    buffer = tf2_ros.Buffer()
    listener = tf2_ros.TransformListener(buffer)     # fills the buffer from /tf and /tf_static
    t = buffer.lookup_transform("world", "base", rospy.Time(0), rospy.Duration(1.0))

A transform stamped with ``header.frame_id`` "odom" and ``child_frame_id`` "base" tells where
"base" is in "odom": it turns coordinates in "base" into coordinates in "odom". The frames form a
tree; :meth:`Buffer.lookup_transform` composes the transforms along it, from the source frame up
to the frames' common parent and down to the target frame, at one time:

- ``rospy.Time(0)`` asks for the latest time at which every transform of the chain is known;
- between two stamps of a transform, translation is interpolated linearly and rotation by
  spherical linear interpolation (slerp);
- a time before the oldest or after the newest stamp kept raises
  :class:`ExtrapolationException` (the buffer keeps ``cache_time``, 10 s by default);
- static transforms (``/tf_static``) hold at every time.

The messages travel on the in-process graph (:mod:`duckielib.ros.rospy`); a ``timeout`` waits
in simulated time.

Differences from the real ones, on purpose: a transform refused by the buffer (repeated stamp,
data older than the cache, bad values) is reported once per frame and reason rather than each
time; a ``timeout`` may also be given in seconds; ``Buffer.transform`` (which needs
``tf2_geometry_msgs``) and ``BufferClient`` are not provided. :class:`StaticTransformBroadcaster`
keeps every static transform sent and publishes them all, as the C++ one does (Debian's Python
one of ROS Noetic latches only the last call's).

Laptop side; never deployed (the robot has the real tf2_ros).
"""

# Over 600 lines: it stands in for ROS's tf2_ros, one module robot code imports by that name: the
# buffer with its interpolation and exceptions, the listener and the broadcasters.

from __future__ import annotations

import bisect
import math
from typing import Any, Dict, List, Optional, Sequence, Set, Tuple, Union

from duckielib import rostime
from duckielib.messages import get_message_class
from duckielib.ros import rospy
from duckielib.ros.context import current_node

__all__ = [
    "Buffer",
    "TransformListener",
    "TransformBroadcaster",
    "StaticTransformBroadcaster",
    "TransformException",
    "LookupException",
    "ConnectivityException",
    "ExtrapolationException",
    "InvalidArgumentException",
    "TimeoutException",
    "TransformStamped",
    "TFMessage",
]

#: The message of one transform: ``header`` (stamp, parent frame), ``child_frame_id``,
#: ``transform`` (translation, rotation).
TransformStamped: Any = get_message_class("geometry_msgs/TransformStamped")
#: The message of ``/tf`` and ``/tf_static``: a list of transforms.
TFMessage: Any = get_message_class("tf2_msgs/TFMessage")

#: How long a buffer keeps transforms by default, in seconds.
DEFAULT_CACHE_TIME = 10.0
#: A rotation is refused when its squared norm is further than this from 1.
_NORM_TOLERANCE = 1e-2


class TransformException(Exception):
    """A transform could not be looked up (the base of tf2's exceptions)."""


class LookupException(TransformException):
    """A frame named in a lookup does not exist."""


class ConnectivityException(TransformException):
    """The two frames are not in the same tree."""


class ExtrapolationException(TransformException):
    """The time asked for lies outside the stamps kept for a transform of the chain."""


class InvalidArgumentException(TransformException):
    """A frame name is not valid (empty, or starting with a '/')."""


class TimeoutException(TransformException):
    """A transform did not become available in time."""


# -- poses: (translation, rotation quaternion x y z w) --------------------------------------------
Vector = Tuple[float, float, float]
Quaternion = Tuple[float, float, float, float]
Pose = Tuple[Vector, Quaternion]

_IDENTITY: Pose = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))


def _multiply(a: Quaternion, b: Quaternion) -> Quaternion:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def _rotate(q: Quaternion, v: Vector) -> Vector:
    """``v`` rotated by ``q`` (normalised on the way)."""
    x, y, z, w = q
    n = x * x + y * y + z * z + w * w
    s = 2.0 / n if n > 0.0 else 0.0
    vx, vy, vz = v
    return (
        (1 - s * (y * y + z * z)) * vx + s * (x * y - z * w) * vy + s * (x * z + y * w) * vz,
        s * (x * y + z * w) * vx + (1 - s * (x * x + z * z)) * vy + s * (y * z - x * w) * vz,
        s * (x * z - y * w) * vx + s * (y * z + x * w) * vy + (1 - s * (x * x + y * y)) * vz,
    )


def _compose(outer: Pose, inner: Pose) -> Pose:
    """The pose ``inner`` (in a middle frame) expressed in the frame ``outer`` is given in."""
    t, q = outer
    moved = _rotate(q, inner[0])
    return (t[0] + moved[0], t[1] + moved[1], t[2] + moved[2]), _multiply(q, inner[1])


def _inverse(pose: Pose) -> Pose:
    (tx, ty, tz), (x, y, z, w) = pose
    q = (-x, -y, -z, w)
    t = _rotate(q, (tx, ty, tz))
    return (-t[0], -t[1], -t[2]), q


def _slerp(a: Quaternion, b: Quaternion, ratio: float) -> Quaternion:
    """The rotation ``ratio`` of the way from ``a`` to ``b``, the short way round."""
    dot = sum(p * q for p, q in zip(a, b))
    norms = math.sqrt(sum(p * p for p in a) * sum(q * q for q in b))
    if dot < 0.0:
        b, dot = (-b[0], -b[1], -b[2], -b[3]), -dot
    angle = math.acos(min(1.0, dot / norms)) if norms > 0.0 else 0.0
    if angle == 0.0:
        return a
    scale = 1.0 / math.sin(angle)
    wa, wb = math.sin((1.0 - ratio) * angle) * scale, math.sin(ratio * angle) * scale
    return (
        wa * a[0] + wb * b[0],
        wa * a[1] + wb * b[1],
        wa * a[2] + wb * b[2],
        wa * a[3] + wb * b[3],
    )


def _interpolate(a: Pose, b: Pose, ratio: float) -> Pose:
    ta, tb = a[0], b[0]
    translation = (
        ta[0] + (tb[0] - ta[0]) * ratio,
        ta[1] + (tb[1] - ta[1]) * ratio,
        ta[2] + (tb[2] - ta[2]) * ratio,
    )
    return translation, _slerp(a[1], b[1], ratio)


# -- times ----------------------------------------------------------------------------------------
def _seconds(ns: int) -> str:
    return f"{ns / rostime.NS_PER_S:.9f}"


def _time_ns(time: Any, what: str) -> int:
    if isinstance(time, rostime.Time):
        return time.to_nsec()
    raise TypeError(
        f"{what} takes a rospy.Time (rospy.Time(0) for the latest transform), not {time!r}."
    )


def _duration_ns(duration: Any, what: str) -> int:
    if isinstance(duration, rostime.Duration):
        return duration.to_nsec()
    if isinstance(duration, (int, float)) and not isinstance(duration, bool):
        return round(duration * rostime.NS_PER_S)
    raise TypeError(f"{what} is a rospy.Duration (or a number of seconds), not {duration!r}.")


def _stamp(ns: int) -> rospy.Time:
    return rospy.Time.from_nsec(ns)


#: The default timeout: do not wait.
_NO_WAIT = rospy.Duration(0)


# -- the transforms of one frame ------------------------------------------------------------------
class _Gap(Exception):
    """A frame's transform is not known at the time asked for."""

    def __init__(self, kind: str, asked_ns: int, known_ns: int) -> None:
        Exception.__init__(self, kind)
        self.kind, self.asked_ns, self.known_ns = kind, asked_ns, known_ns

    def explain(self, source: str, target: str) -> ExtrapolationException:
        """The exception a lookup from ``source`` to ``target`` raises for this gap."""
        between = f"the transform from frame [{source}] to frame [{target}]"
        asked, known = _seconds(self.asked_ns), _seconds(self.known_ns)
        if self.kind == "single":
            text = (
                f"Lookup would require extrapolation: {between} was asked for at time {asked}, "
                f"but only time {known} is in the buffer."
            )
        else:
            span = _seconds(abs(self.asked_ns - self.known_ns))
            edge = "latest" if self.kind == "future" else "earliest"
            text = (
                f"Lookup would require extrapolation {span}s into the {self.kind}: {between} was "
                f"asked for at time {asked}, but the {edge} data is at time {known}."
            )
        return ExtrapolationException(text)


class _Frame:
    """Where one frame is in its parent: one static transform, or stamped ones in time order."""

    def __init__(self, static: bool) -> None:
        self.static = static
        self.stamps: List[int] = []
        self.links: List[Tuple[str, Pose]] = []  # (parent frame, pose in it), as stamps
        self.authority = ""

    def insert(self, stamp_ns: int, parent: str, pose: Pose, keep_ns: int) -> Optional[str]:
        """Keep a transform; why it was refused ("old", "repeated"), or None."""
        if self.static:
            self.stamps, self.links = [stamp_ns], [(parent, pose)]
            return None
        if self.stamps and stamp_ns + keep_ns < self.stamps[-1]:
            return "old"
        index = bisect.bisect_left(self.stamps, stamp_ns)
        if index < len(self.stamps) and self.stamps[index] == stamp_ns:
            return "repeated"
        self.stamps.insert(index, stamp_ns)
        self.links.insert(index, (parent, pose))
        oldest_kept = self.stamps[-1] - keep_ns
        drop = bisect.bisect_left(self.stamps, oldest_kept)
        del self.stamps[:drop], self.links[:drop]
        return None

    def latest(self) -> Optional[Tuple[str, int]]:
        """The parent and the newest stamp (0 for a static transform), or None if empty."""
        if not self.links:
            return None
        return self.links[-1][0], 0 if self.static else self.stamps[-1]

    def at(self, time_ns: int) -> Tuple[str, Pose]:
        """The parent and the pose in it at a time (0: the newest).

        Raises:
            _Gap: if the time lies outside the stamps kept.
        """
        stamps, links = self.stamps, self.links
        if self.static or time_ns == 0:
            return links[-1]
        if len(stamps) == 1:
            if stamps[0] == time_ns:
                return links[0]
            raise _Gap("single", time_ns, stamps[0])
        if time_ns < stamps[0]:
            raise _Gap("past", time_ns, stamps[0])
        if time_ns > stamps[-1]:
            raise _Gap("future", time_ns, stamps[-1])
        index = bisect.bisect_left(stamps, time_ns)
        if stamps[index] == time_ns:
            return links[index]
        (parent, before), (parent_after, after) = links[index - 1], links[index]
        if parent != parent_after:
            return parent, before
        ratio = (time_ns - stamps[index - 1]) / (stamps[index] - stamps[index - 1])
        return parent, _interpolate(before, after, ratio)


# -- the buffer -----------------------------------------------------------------------------------
class Buffer:
    """The transforms received lately, for lookups between any two frames at any time kept.

    Args:
        cache_time: how long to keep transforms (a ``rospy.Duration``; 10 s by default): a
            lookup further back than that from the newest transform raises
            :class:`ExtrapolationException`.
        debug: accepted as tf2_ros's (it serves a debug service there).
    """

    def __init__(self, cache_time: Any = None, debug: bool = True) -> None:
        if cache_time is None:
            cache_time = rospy.Duration.from_sec(DEFAULT_CACHE_TIME)
        self.cache_time = cache_time
        self._keep_ns = _duration_ns(cache_time, "A tf2 buffer's cache_time")
        self._frames: Dict[str, _Frame] = {}  # child frame -> its transforms
        self._names: Dict[str, None] = {}  # every frame named so far, parents too
        self._reported: Set[Tuple[str, str]] = set()

    # -- filling -----------------------------------------------------------------------------
    def set_transform(self, transform: Any, authority: str = "default_authority") -> None:
        """Add a transform (a ``geometry_msgs/TransformStamped``) received from ``authority``.

        A transform with an empty or equal frame pair, a NaN value or a rotation that is not a
        unit quaternion is refused with an error in the log, as are repeated stamps and data
        older than ``cache_time`` (with a warning).
        """
        self._insert(transform, authority, static=False)

    def set_transform_static(self, transform: Any, authority: str = "default_authority") -> None:
        """Add a static transform: it holds at every time, and replaces the frame's previous one."""
        self._insert(transform, authority, static=True)

    def _report(self, level: str, child: str, reason: str, text: str) -> None:
        if (child, reason) in self._reported:
            return
        self._reported.add((child, reason))
        (rospy.logerr if level == "error" else rospy.logwarn)(text)

    def _insert(self, transform: Any, authority: str, static: bool) -> None:
        if getattr(transform, "_type", None) != "geometry_msgs/TransformStamped":
            raise TypeError(
                "A tf2 buffer takes geometry_msgs/TransformStamped messages, not "
                f"{type(transform).__name__}."
            )
        parent = transform.header.frame_id.lstrip("/")
        child = transform.child_frame_id.lstrip("/")
        t, r = transform.transform.translation, transform.transform.rotation
        pose: Pose = ((t.x, t.y, t.z), (r.x, r.y, r.z, r.w))
        problem = _invalid(parent, child, pose)
        if problem is not None:
            reason, text = problem
            self._report(
                "error", child, reason, f"Ignoring the transform from {authority!r}: {text}."
            )
            return
        frame = self._frames.get(child)
        if frame is None:
            frame = self._frames[child] = _Frame(static)
        stamp_ns = transform.header.stamp.to_nsec()
        refused = frame.insert(stamp_ns, parent, pose, self._keep_ns)
        if refused == "old":
            self._report(
                "warn",
                child,
                refused,
                f"Ignoring a transform of frame {child} at time {_seconds(stamp_ns)} from "
                f"{authority!r}: it is older than the buffer keeps (cache_time), as after a "
                "jump back in time.",
            )
            return
        if refused == "repeated":
            self._report(
                "warn",
                child,
                refused,
                f"Ignoring a transform of frame {child} at time {_seconds(stamp_ns)} from "
                f"{authority!r}: the buffer already has one at that time (stamp each "
                "transform with a new time, such as rospy.Time.now()).",
            )
            return
        frame.authority = authority
        self._names.setdefault(child)
        self._names.setdefault(parent)

    def clear(self) -> None:
        """Forget every transform but the static ones."""
        for frame in self._frames.values():
            if not frame.static:
                frame.stamps, frame.links = [], []

    # -- looking up ---------------------------------------------------------------------------
    def lookup_transform(
        self, target_frame: str, source_frame: str, time: Any, timeout: Any = _NO_WAIT
    ) -> Any:
        """The transform from ``source_frame`` to ``target_frame`` at ``time``.

        Args:
            target_frame: the frame to express things in.
            source_frame: the frame things are given in.
            time: a ``rospy.Time``; ``rospy.Time(0)`` for the latest available.
            timeout: how long to wait (simulated time) for the transform to become available:
                a ``rospy.Duration`` or seconds; by default, not at all.

        Returns:
            A ``geometry_msgs/TransformStamped`` with ``header.frame_id`` the target frame,
            ``child_frame_id`` the source frame and ``header.stamp`` the time used.

        Raises:
            LookupException: if a frame does not exist.
            ConnectivityException: if the frames are not in the same tree.
            ExtrapolationException: if ``time`` lies outside the data kept.
            InvalidArgumentException: if a frame name is empty or starts with '/'.
        """
        self._wait(lambda: self._check(target_frame, source_frame, time) is None, timeout)
        return self.lookup_transform_core(target_frame, source_frame, time)

    def lookup_transform_core(self, target_frame: str, source_frame: str, time: Any) -> Any:
        """:meth:`lookup_transform` without waiting."""
        time_ns = _time_ns(time, "lookup_transform()")
        pose, stamp_ns = self._lookup(target_frame, source_frame, time_ns, "lookup_transform")
        return _message(target_frame, source_frame, stamp_ns, pose)

    def lookup_transform_full(
        self,
        target_frame: str,
        target_time: Any,
        source_frame: str,
        source_time: Any,
        fixed_frame: str,
        timeout: Any = _NO_WAIT,
    ) -> Any:
        """The transform from a frame at one time to a frame at another, via a fixed frame.

        ``source_frame`` at ``source_time`` to ``target_frame`` at ``target_time``, assuming
        ``fixed_frame`` does not move in between; ``header.stamp`` is ``target_time``.

        Raises:
            TransformException: as :meth:`lookup_transform` (one of its subclasses).
        """
        args = (target_frame, target_time, source_frame, source_time, fixed_frame)
        self._wait(lambda: self._check_full(*args) is None, timeout)
        return self._lookup_full(*args)

    def can_transform(
        self,
        target_frame: str,
        source_frame: str,
        time: Any,
        timeout: Any = _NO_WAIT,
        return_debug_tuple: bool = False,
    ) -> Any:
        """Whether :meth:`lookup_transform` would succeed (waiting up to ``timeout`` for it).

        Returns:
            A bool, or ``(bool, why not)`` with ``return_debug_tuple``.
        """
        self._wait(lambda: self._check(target_frame, source_frame, time) is None, timeout)
        error = self._check(target_frame, source_frame, time)
        return _answer(error, return_debug_tuple)

    def can_transform_core(self, target_frame: str, source_frame: str, time: Any) -> Any:
        """``(whether :meth:`lookup_transform` would succeed now, why not)``."""
        return _answer(self._check(target_frame, source_frame, time), True)

    def can_transform_full(
        self,
        target_frame: str,
        target_time: Any,
        source_frame: str,
        source_time: Any,
        fixed_frame: str,
        timeout: Any = _NO_WAIT,
        return_debug_tuple: bool = False,
    ) -> Any:
        """Whether :meth:`lookup_transform_full` would succeed (waiting up to ``timeout``)."""
        args = (target_frame, target_time, source_frame, source_time, fixed_frame)
        self._wait(lambda: self._check_full(*args) is None, timeout)
        return _answer(self._check_full(*args), return_debug_tuple)

    def get_latest_common_time(self, target_frame: str, source_frame: str) -> Any:
        """The latest time at which the transform between the two frames is known.

        Returns:
            A ``rospy.Time``: ``rospy.Time(0)`` if every transform between them is static.

        Raises:
            TransformException: as :meth:`lookup_transform` (one of its subclasses).
        """
        what = "get_latest_common_time"
        for frame, arg in ((target_frame, "target_frame"), (source_frame, "source_frame")):
            _validate(frame, arg, what)
            self._exists(frame, arg, what)
        return _stamp(self._common_ns(target_frame, source_frame))

    def all_frames_as_string(self) -> str:
        """Each frame that has a parent, one line each ("Frame base exists with parent odom.")."""
        lines = []
        for child, frame in self._frames.items():
            latest = frame.latest()
            parent = latest[0] if latest else "NO_PARENT"
            lines.append(f"Frame {child} exists with parent {parent}.\n")
        return "".join(lines)

    def all_frames_as_yaml(self) -> str:
        """Each frame with a parent: its parent, broadcaster, rate and the stamps kept, as YAML."""
        lines = []
        for child, frame in self._frames.items():
            latest = frame.latest()
            if latest is None:
                continue
            newest = latest[1] / rostime.NS_PER_S
            oldest = 0.0 if frame.static else frame.stamps[0] / rostime.NS_PER_S
            rate = len(frame.stamps) / max(newest - oldest, 1e-4)
            lines += [
                f"{child}: ",
                f"  parent: '{latest[0]}'",
                f"  broadcaster: '{frame.authority}'",
                f"  rate: {rate:.3f}",
                f"  most_recent_transform: {newest:.3f}",
                f"  oldest_transform: {oldest:.3f}",
                f"  buffer_length: {newest - oldest:.3f}",
            ]
        return "".join(line + "\n" for line in lines)

    # -- the work -----------------------------------------------------------------------------
    def _wait(self, available: Any, timeout: Any) -> None:
        """Wait in simulated time until ``available()`` or the timeout runs out."""
        span = _duration_ns(timeout, "A tf2 timeout")
        if span <= 0 or available():
            return
        node = current_node("A tf2 lookup with a timeout")
        node.graph.block(node.graph.now_ns + span, available)

    def _check(self, target_frame: str, source_frame: str, time: Any) -> Optional[str]:
        """Why :meth:`lookup_transform_core` would fail now, or None."""
        try:
            time_ns = _time_ns(time, "can_transform()")
            self._lookup(target_frame, source_frame, time_ns, "can_transform")
        except TransformException as error:
            return str(error)
        return None

    def _check_full(self, *args: Any) -> Optional[str]:
        try:
            self._lookup_full(*args)
        except TransformException as error:
            return str(error)
        return None

    def _lookup_full(
        self,
        target_frame: str,
        target_time: Any,
        source_frame: str,
        source_time: Any,
        fixed_frame: str,
    ) -> Any:
        what = "lookup_transform_full"
        target_ns = _time_ns(target_time, f"{what}()")
        source_ns = _time_ns(source_time, f"{what}()")
        in_fixed, _ = self._lookup(fixed_frame, source_frame, source_ns, what)
        in_target, stamp_ns = self._lookup(target_frame, fixed_frame, target_ns, what)
        return _message(target_frame, source_frame, stamp_ns, _compose(in_target, in_fixed))

    def _exists(self, frame: str, arg: str, what: str) -> None:
        if frame not in self._names:
            raise LookupException(
                f'"{frame}" passed to {what} as {arg} does not exist: no transform received '
                "so far names that frame."
            )

    def _lookup(self, target: str, source: str, time_ns: int, what: str) -> Tuple[Pose, int]:
        """The pose of ``source`` in ``target`` at a time (0: the latest), and that time."""
        _validate(target, "target_frame", what)
        _validate(source, "source_frame", what)
        if target == source:
            frame = self._frames.get(source)
            latest = frame.latest() if frame is not None else None
            if time_ns == 0 and latest is not None:
                time_ns = latest[1]
            return _IDENTITY, time_ns
        self._exists(target, "target_frame", what)
        self._exists(source, "source_frame", what)
        if time_ns == 0:
            time_ns = self._common_ns(target, source)
        return self._walk(target, source, time_ns), time_ns

    def _parent_at(self, frame: str, time_ns: int) -> Optional[Tuple[str, Pose]]:
        """The parent of ``frame`` and its pose there at a time; None for a root."""
        found = self._frames.get(frame)
        if found is None or not found.links:
            return None
        return found.at(time_ns)

    def _walk(self, target: str, source: str, time_ns: int) -> Pose:
        # Up from the source: its pose in each of its ancestors, as far as known at that time.
        in_ancestor: Dict[str, Pose] = {source: _IDENTITY}
        gap: Optional[_Gap] = None
        frame = source
        while True:
            try:
                link = self._parent_at(frame, time_ns)
            except _Gap as error:
                gap = error
                break
            if link is None or link[0] in in_ancestor:
                break
            in_ancestor[link[0]] = _compose(link[1], in_ancestor[frame])
            frame = link[0]
        # Up from the target to the first of those ancestors: the common parent.
        target_pose, frame, steps = _IDENTITY, target, 0
        while frame not in in_ancestor:
            try:
                link = self._parent_at(frame, time_ns)
            except _Gap as error:
                raise error.explain(source, target) from None
            if link is None:
                if gap is not None:
                    raise gap.explain(source, target)
                raise _disconnected(target, source)
            if steps > len(self._frames):
                raise _loop(target)
            target_pose = _compose(link[1], target_pose)
            frame, steps = link[0], steps + 1
        return _compose(_inverse(target_pose), in_ancestor[frame])

    def _common_ns(self, target: str, source: str) -> int:
        """The latest time every transform between the two frames is known at (0: static)."""
        never = math.inf
        known_until: Dict[str, float] = {source: never}  # ancestor -> when links up to it end
        frame, newest = source, never
        while True:
            link = self._frames.get(frame)
            latest = link.latest() if link is not None else None
            if latest is None or latest[0] in known_until:
                break
            if latest[1]:
                newest = min(newest, latest[1])
            frame = latest[0]
            known_until[frame] = newest
        frame, newest, steps = target, never, 0
        while frame not in known_until:
            link = self._frames.get(frame)
            latest = link.latest() if link is not None else None
            if latest is None:
                raise _disconnected(target, source)
            if steps > len(self._frames):
                raise _loop(target)
            if latest[1]:
                newest = min(newest, latest[1])
            frame, steps = latest[0], steps + 1
        common = min(newest, known_until[frame])
        return 0 if common == never else int(common)


def _invalid(parent: str, child: str, pose: Pose) -> Optional[Tuple[str, str]]:
    """Why a transform cannot be kept (a short key, and a sentence for the log), or None."""
    if not parent:
        return "no parent", (
            f'the transform of frame "{child}" has no parent frame (header.frame_id is empty)'
        )
    if not child:
        return "no child", f'a transform from frame "{parent}" has no child_frame_id'
    if parent == child:
        return "itself", (
            f'frame_id and child_frame_id are both "{child}": a frame cannot be its own parent'
        )
    if not all(math.isfinite(value) for value in pose[0] + pose[1]):
        return "nan", f'the transform of frame "{child}" holds a NaN or infinite value'
    if abs(sum(value * value for value in pose[1]) - 1.0) > _NORM_TOLERANCE:
        return "rotation", (
            f'the rotation of frame "{child}" is not a unit quaternion {tuple(pose[1])} (the '
            "identity is x=0, y=0, z=0, w=1)"
        )
    return None


def _validate(frame: str, arg: str, what: str) -> None:
    if not isinstance(frame, str) or not frame:
        raise InvalidArgumentException(
            f"An empty frame name was passed to {what} as {arg}: name the frame, such as "
            '"base_link".'
        )
    if frame.startswith("/"):
        raise InvalidArgumentException(
            f'Invalid frame "{frame}" passed to {what} as {arg}: tf2 frame names cannot start '
            f'with a "/" (write "{frame.lstrip("/")}").'
        )


def _disconnected(target: str, source: str) -> ConnectivityException:
    return ConnectivityException(
        f"Could not find a connection between '{target}' and '{source}': they are not part of "
        "the same tree (the transforms received form two or more unconnected trees)."
    )


def _loop(frame: str) -> LookupException:
    return LookupException(
        f"The tf tree is invalid because it contains a loop: going up from frame {frame}, "
        "some frame turns out to be its own ancestor."
    )


def _answer(error: Optional[str], debug_tuple: bool) -> Any:
    if debug_tuple:
        return (error is None, error or "")
    return error is None


def _message(target: str, source: str, stamp_ns: int, pose: Pose) -> Any:
    message = TransformStamped()
    message.header.frame_id = target
    message.header.stamp = _stamp(stamp_ns)
    message.child_frame_id = source
    translation, rotation = message.transform.translation, message.transform.rotation
    translation.x, translation.y, translation.z = pose[0]
    rotation.x, rotation.y, rotation.z, rotation.w = pose[1]
    return message


# -- on the graph ---------------------------------------------------------------------------------
def _transforms(transform: Any, what: str) -> List[Any]:
    listed = list(transform) if isinstance(transform, (list, tuple)) else [transform]
    for each in listed:
        if getattr(each, "_type", None) != "geometry_msgs/TransformStamped":
            raise TypeError(
                f"{what}.sendTransform() takes a geometry_msgs/TransformStamped or a list of "
                f"them, not {type(each).__name__}."
            )
    return listed


class TransformBroadcaster:
    """Publish transforms on ``/tf``.

    Args:
        queue_size: the publisher's queue size.
    """

    def __init__(self, queue_size: int = 100) -> None:
        self.pub_tf = rospy.Publisher("/tf", TFMessage, queue_size=queue_size)

    def sendTransform(self, transform: Union[Any, Sequence[Any]]) -> None:  # noqa: N802
        """Publish a ``geometry_msgs/TransformStamped``, or a list of them, in one message."""
        self.pub_tf.publish(TFMessage(transforms=_transforms(transform, "TransformBroadcaster")))


class StaticTransformBroadcaster:
    """Publish static transforms on ``/tf_static``, latched for listeners that start later.

    Every static transform sent is kept (a new one of the same child frame replaces the
    old) and each message carries them all, so every listener gets every static frame.
    """

    def __init__(self) -> None:
        self.pub_tf = rospy.Publisher("/tf_static", TFMessage, queue_size=100, latch=True)
        self._sent: Dict[str, Any] = {}

    def sendTransform(self, transform: Union[Any, Sequence[Any]]) -> None:  # noqa: N802
        """Add a ``geometry_msgs/TransformStamped`` (or a list) and publish all kept so far."""
        for each in _transforms(transform, "StaticTransformBroadcaster"):
            self._sent[each.child_frame_id] = each
        self.pub_tf.publish(TFMessage(transforms=list(self._sent.values())))


class TransformListener:
    """Fill a :class:`Buffer` with the transforms published on ``/tf`` and ``/tf_static``.

    When the clock jumps back (a simulation restarted), the buffer's non-static transforms are
    cleared, as on a robot.

    Args:
        buffer: the buffer to fill.
        queue_size: the subscribers' queue size (None: no limit).
    """

    def __init__(
        self,
        buffer: Buffer,
        queue_size: Optional[int] = None,
        buff_size: int = 65536,
        tcp_nodelay: bool = False,
    ) -> None:
        self.buffer = buffer
        self.last_update: Optional[Any] = None
        self.tf_sub = rospy.Subscriber("/tf", TFMessage, self.callback, queue_size=queue_size)
        self.tf_static_sub = rospy.Subscriber(
            "/tf_static", TFMessage, self.static_callback, queue_size=queue_size
        )

    def unregister(self) -> None:
        """Stop listening."""
        self.tf_sub.unregister()
        self.tf_static_sub.unregister()

    def check_for_reset(self) -> None:
        """Clear the buffer if the clock went back since the last message."""
        now = rospy.Time.now()
        if self.last_update is not None and now < self.last_update:
            rospy.logwarn("Detected jump back in time. Clearing TF buffer.")
            self.buffer.clear()
        self.last_update = now

    def callback(self, data: Any) -> None:
        """Add the transforms of a ``/tf`` message to the buffer."""
        self.check_for_reset()
        who = _authority(data)
        for transform in data.transforms:
            self.buffer.set_transform(transform, who)

    def static_callback(self, data: Any) -> None:
        """Add the transforms of a ``/tf_static`` message to the buffer, as static ones."""
        self.check_for_reset()
        who = _authority(data)
        for transform in data.transforms:
            self.buffer.set_transform_static(transform, who)


def _authority(message: Any) -> str:
    header = getattr(message, "_connection_header", None) or {}
    return str(header.get("callerid", "default_authority"))
