"""tf: ROS 1's first transform library, as Duckietown's odometry nodes use it.

Use it exactly as ROS's ``tf``, for example to broadcast where the robot is in its odometry
frame::

    import tf
    from tf.transformations import quaternion_from_euler

    broadcaster = tf.TransformBroadcaster()
    q = quaternion_from_euler(0, 0, theta)                    # roll, pitch, yaw -> x, y, z, w
    broadcaster.sendTransform((x, y, 0), q, rospy.Time.now(), "base", "odom")

    listener = tf.TransformListener()
    listener.waitForTransform("world", "base", rospy.Time(0), rospy.Duration(1.0))
    (trans, rot) = listener.lookupTransform("world", "base", rospy.Time(0))

As on ROS Noetic, it stands on tf2: the broadcaster publishes ``tf2_msgs/TFMessage`` on
``/tf``, the listener fills a :class:`duckielib.libraries.tf2_ros.Buffer` (its lookups,
interpolation and exceptions are tf2's), and ``tf.LookupException`` and its kin are tf2_ros's.
Frame names may start with a '/', which is dropped, as tf did.

:data:`transformations` (``tf.transformations``) holds the rotation and matrix functions, with
ROS's conventions: quaternions are numpy arrays ``[x, y, z, w]``, matrices 4x4 homogeneous
numpy arrays, Euler angles radians in one of 24 axis orders (``"sxyz"``, the default, is roll
about the fixed x axis, then pitch about y, then yaw about z; ``"r..."`` orders rotate about
the moving axes).

Differences from the real one, on purpose: ``tf.transformations`` has the functions robot code
uses (listed in :data:`TRANSFORMATIONS`), not the whole of Christoph Gohlke's module (no
projections, reflections, shears, arcballs); axes are given by name, not as tuples;
``lookupTwist`` and ``transformPointCloud`` are missing.

Laptop side; never deployed (the robot has the real tf).
"""

# Over 600 lines: it stands in for ROS's tf, one module robot code imports by that name, with
# `tf.transformations` (the rotation and matrix functions, about 300 lines) built inside it.

from __future__ import annotations

import math
import sys
import types
from functools import reduce
from typing import Any, Callable, Dict, List, Sequence, Tuple

import numpy as np

from duckielib import rostime
from duckielib.libraries import tf2_ros
from duckielib.messages import get_message_class

__all__ = [
    "TransformBroadcaster",
    "Transformer",
    "TransformerROS",
    "TransformListener",
    "Exception",
    "LookupException",
    "ConnectivityException",
    "ExtrapolationException",
    "transformations",
    "TRANSFORMATIONS",
]

LookupException = tf2_ros.LookupException
ConnectivityException = tf2_ros.ConnectivityException
ExtrapolationException = tf2_ros.ExtrapolationException

# -- tf.transformations ---------------------------------------------------------------------------
#: Below this, a number counts as zero (a quaternion's squared norm, a cosine at gimbal lock).
_EPS = np.finfo(float).eps * 4.0
_AXIS = {"x": 0, "y": 1, "z": 2}


def _static_order(axes: Any, caller: str) -> Tuple[Tuple[int, int, int], bool]:
    """The axes of an Euler order as rotations about fixed axes, first applied first.

    Returns:
        The three axis numbers, and whether the angles come in reverse order ("r" orders:
        rotating ``rABC`` by ``(a, b, c)`` is static ``sCBA`` by ``(c, b, a)``).
    """
    valid = (
        isinstance(axes, str)
        and len(axes) == 4
        and axes[0] in "sr"
        and all(letter in _AXIS for letter in axes[1:])
        and axes[1] != axes[2] != axes[3]
    )
    if not valid:
        raise ValueError(
            f'{caller} takes axes such as "sxyz" (roll, pitch, yaw about the fixed x, y, z '
            'axes, the default) or "rzyx": "s" (static) or "r" (rotating), then three of x, y '
            f"and z with no axis twice in a row; got {axes!r}."
        )
    order = [_AXIS[letter] for letter in axes[1:]]
    rotating = axes[0] == "r"
    if rotating:
        order.reverse()
    return (order[0], order[1], order[2]), rotating


def _parity(first: int, second: int) -> float:
    """+1 if ``second`` follows ``first`` in x, y, z, x order, else -1."""
    return 1.0 if (second - first) % 3 == 1 else -1.0


def _axis_matrix(axis: int, angle: float) -> np.ndarray:
    """The 3x3 rotation by ``angle`` about axis x (0), y (1) or z (2)."""
    c, s = math.cos(angle), math.sin(angle)
    m = np.identity(3)
    j, k = (axis + 1) % 3, (axis + 2) % 3
    m[j, j], m[j, k], m[k, j], m[k, k] = c, -s, s, c
    return m


def _axis_quaternion(axis: int, angle: float) -> np.ndarray:
    q = np.zeros(4)
    q[axis], q[3] = math.sin(angle / 2.0), math.cos(angle / 2.0)
    return q


def _identity_matrix() -> np.ndarray:
    """The 4x4 identity matrix."""
    return np.identity(4)


def _translation_matrix(direction: Sequence[float]) -> np.ndarray:
    """The 4x4 matrix that translates by ``direction`` (x, y, z)."""
    m = np.identity(4)
    m[:3, 3] = np.asarray(direction, dtype=np.float64)[:3]
    return m


def _translation_from_matrix(matrix: Any) -> np.ndarray:
    """The translation (x, y, z) of a 4x4 matrix."""
    return np.array(matrix, dtype=np.float64, copy=True)[:3, 3]


def _euler_matrix(ai: float, aj: float, ak: float, axes: str = "sxyz") -> np.ndarray:
    """The 4x4 rotation matrix of Euler angles (radians) in the order ``axes``.

    With the default ``"sxyz"``: roll ``ai`` about x, then pitch ``aj`` about y, then yaw
    ``ak`` about z, all fixed axes.

    Raises:
        ValueError: for an unknown axes name.
    """
    (a, b, c), rotating = _static_order(axes, "euler_matrix()")
    first, second, third = (ak, aj, ai) if rotating else (ai, aj, ak)
    m = np.identity(4)
    m[:3, :3] = _axis_matrix(c, third) @ _axis_matrix(b, second) @ _axis_matrix(a, first)
    return m


def _euler_from_matrix(matrix: Any, axes: str = "sxyz") -> Tuple[float, float, float]:
    """The Euler angles (radians) of a rotation matrix (3x3 or 4x4), in the order ``axes``.

    At gimbal lock (pitch at +-90 degrees for ``"sxyz"``) the last angle applied is 0.

    Raises:
        ValueError: for an unknown axes name.
    """
    (a, b, c), rotating = _static_order(axes, "euler_from_matrix()")
    m = np.asarray(matrix, dtype=np.float64)[:3, :3]
    if a != c:  # three different axes (Tait-Bryan angles)
        s = _parity(a, b)
        cos_second = math.hypot(m[a, a], m[b, a])
        second = math.atan2(-s * m[c, a], cos_second)
        if cos_second > _EPS * 4.0:
            first = math.atan2(s * m[c, b], m[c, c])
            third = math.atan2(s * m[b, a], m[a, a])
        else:
            first, third = math.atan2(-s * m[b, c], m[b, b]), 0.0
    else:  # first and last about the same axis (proper Euler angles)
        t = 3 - a - b
        s = _parity(a, b)
        sin_second = math.hypot(m[a, b], m[a, t])
        # Of the two solutions, the one whose middle angle has the sign of the axes' order.
        second = math.atan2(s * sin_second, m[a, a])
        if sin_second > _EPS * 4.0:
            first = math.atan2(s * m[a, b], m[a, t])
            third = math.atan2(s * m[b, a], -m[t, a])
        else:
            first, third = math.atan2(-s * m[b, t], m[b, b]), 0.0
    return (third, second, first) if rotating else (first, second, third)


def _quaternion_from_euler(ai: float, aj: float, ak: float, axes: str = "sxyz") -> np.ndarray:
    """The quaternion ``[x, y, z, w]`` of Euler angles (radians) in the order ``axes``.

    ``quaternion_from_euler(0, 0, yaw)`` is the heading ``yaw`` of a robot on the floor.

    Raises:
        ValueError: for an unknown axes name.
    """
    (a, b, c), rotating = _static_order(axes, "quaternion_from_euler()")
    first, second, third = (ak, aj, ai) if rotating else (ai, aj, ak)
    q = _multiply(_axis_quaternion(c, third), _axis_quaternion(b, second))
    return _multiply(q, _axis_quaternion(a, first))


def _euler_from_quaternion(quaternion: Sequence[float], axes: str = "sxyz") -> Tuple[float, ...]:
    """The Euler angles (radians) of a quaternion ``[x, y, z, w]``, in the order ``axes``.

    ``euler_from_quaternion(q)[2]`` is the yaw (heading) of ``q``.

    Raises:
        ValueError: for an unknown axes name.
    """
    return _euler_from_matrix(_quaternion_matrix(quaternion), axes)


def _multiply(q1: Any, q0: Any) -> np.ndarray:
    x1, y1, z1, w1 = (float(v) for v in q1[:4])
    x0, y0, z0, w0 = (float(v) for v in q0[:4])
    return np.array(
        [
            w1 * x0 + x1 * w0 + y1 * z0 - z1 * y0,
            w1 * y0 - x1 * z0 + y1 * w0 + z1 * x0,
            w1 * z0 + x1 * y0 - y1 * x0 + z1 * w0,
            w1 * w0 - x1 * x0 - y1 * y0 - z1 * z0,
        ]
    )


def _quaternion_multiply(quaternion1: Sequence[float], quaternion0: Sequence[float]) -> np.ndarray:
    """The product ``quaternion1 * quaternion0``: rotation 0, then rotation 1 (fixed axes)."""
    return _multiply(quaternion1, quaternion0)


def _quaternion_conjugate(quaternion: Sequence[float]) -> np.ndarray:
    """``[-x, -y, -z, w]``: the opposite rotation, for a unit quaternion."""
    q = np.array(quaternion[:4], dtype=np.float64)
    q[:3] = -q[:3]
    return q


def _quaternion_inverse(quaternion: Sequence[float]) -> np.ndarray:
    """The inverse of a quaternion (its conjugate divided by its squared norm)."""
    q = _quaternion_conjugate(quaternion)
    return q / np.dot(q, q)


def _quaternion_matrix(quaternion: Sequence[float]) -> np.ndarray:
    """The 4x4 rotation matrix of a quaternion ``[x, y, z, w]`` (normalised on the way).

    A zero quaternion gives the identity.
    """
    q = np.array(quaternion[:4], dtype=np.float64)
    n = float(np.dot(q, q))
    if n < _EPS:
        return np.identity(4)
    x, y, z, w = q * math.sqrt(2.0 / n)
    return np.array(
        [
            [1.0 - y * y - z * z, x * y - z * w, x * z + y * w, 0.0],
            [x * y + z * w, 1.0 - x * x - z * z, y * z - x * w, 0.0],
            [x * z - y * w, y * z + x * w, 1.0 - x * x - y * y, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def _quaternion_from_matrix(matrix: Any) -> np.ndarray:
    """The quaternion ``[x, y, z, w]`` of a rotation matrix (3x3, or 4x4 homogeneous)."""
    m = np.asarray(matrix, dtype=np.float64)[:3, :3]
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    q = np.empty(4)
    if trace > 0.0:
        s = 2.0 * math.sqrt(trace + 1.0)
        q[:] = (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, s / 4
        return q
    i = int(np.argmax([m[0, 0], m[1, 1], m[2, 2]]))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * math.sqrt(1.0 + m[i, i] - m[j, j] - m[k, k])
    q[i] = s / 4.0
    q[j] = (m[i, j] + m[j, i]) / s
    q[k] = (m[i, k] + m[k, i]) / s
    q[3] = (m[k, j] - m[j, k]) / s
    return q


def _quaternion_about_axis(angle: float, axis: Sequence[float]) -> np.ndarray:
    """The quaternion ``[x, y, z, w]`` of a rotation by ``angle`` (radians) about ``axis``."""
    q = np.zeros(4)
    q[:3] = np.asarray(axis, dtype=np.float64)[:3]
    length = float(np.linalg.norm(q))
    if length > _EPS:
        q *= math.sin(angle / 2.0) / length
    q[3] = math.cos(angle / 2.0)
    return q


def _quaternion_slerp(
    quat0: Sequence[float],
    quat1: Sequence[float],
    fraction: float,
    spin: int = 0,
    shortestpath: bool = True,
) -> np.ndarray:
    """The rotation ``fraction`` of the way from ``quat0`` to ``quat1`` (spherical linear).

    Args:
        quat0: the quaternion at fraction 0.
        quat1: the quaternion at fraction 1.
        fraction: how far along, 0 to 1.
        spin: extra half-turns to make on the way.
        shortestpath: go the short way round.
    """
    q0 = np.array(quat0[:4], dtype=np.float64)
    q1 = np.array(quat1[:4], dtype=np.float64)
    q0 /= np.linalg.norm(q0)
    q1 /= np.linalg.norm(q1)
    if fraction == 0.0:
        return q0
    if fraction == 1.0:
        return q1
    d = float(np.dot(q0, q1))
    if abs(abs(d) - 1.0) < _EPS:
        return q0
    if shortestpath and d < 0.0:
        d, q1 = -d, -q1
    angle = math.acos(max(-1.0, min(1.0, d))) + spin * math.pi
    if abs(angle) < _EPS:
        return q0
    scale = 1.0 / math.sin(angle)
    return (math.sin((1.0 - fraction) * angle) * q0 + math.sin(fraction * angle) * q1) * scale


def _concatenate_matrices(*matrices: Any) -> np.ndarray:
    """The product of the matrices, in order (the identity for none)."""
    return reduce(np.dot, matrices, np.identity(4))


def _inverse_matrix(matrix: Any) -> np.ndarray:
    """The inverse of a square matrix."""
    return np.linalg.inv(matrix)


#: The functions of ``tf.transformations``, by name.
TRANSFORMATIONS: Dict[str, Callable[..., Any]] = {
    "identity_matrix": _identity_matrix,
    "translation_matrix": _translation_matrix,
    "translation_from_matrix": _translation_from_matrix,
    "euler_matrix": _euler_matrix,
    "euler_from_matrix": _euler_from_matrix,
    "euler_from_quaternion": _euler_from_quaternion,
    "quaternion_from_euler": _quaternion_from_euler,
    "quaternion_matrix": _quaternion_matrix,
    "quaternion_from_matrix": _quaternion_from_matrix,
    "quaternion_multiply": _quaternion_multiply,
    "quaternion_conjugate": _quaternion_conjugate,
    "quaternion_inverse": _quaternion_inverse,
    "quaternion_about_axis": _quaternion_about_axis,
    "quaternion_slerp": _quaternion_slerp,
    "concatenate_matrices": _concatenate_matrices,
    "inverse_matrix": _inverse_matrix,
}


def _transformations_module() -> types.ModuleType:
    name = f"{__name__}.transformations"
    module = types.ModuleType(
        name,
        "tf.transformations: rotations as quaternions [x, y, z, w], Euler angles and 4x4 "
        "homogeneous matrices, with ROS's conventions.",
    )
    for public, function in TRANSFORMATIONS.items():
        function.__name__ = function.__qualname__ = public
        function.__module__ = name
        setattr(module, public, function)

    def missing(attribute: str) -> Any:
        if attribute.startswith("__"):
            raise AttributeError(attribute)
        raise AttributeError(
            f"tf.transformations here has no {attribute}: it has "
            f"{', '.join(sorted(TRANSFORMATIONS))}."
        )

    module.__getattr__ = missing  # type: ignore[method-assign]
    module.__all__ = sorted(TRANSFORMATIONS)  # type: ignore[attr-defined]
    sys.modules[name] = module  # so that importing it by name finds it
    return module


#: ``tf.transformations``: the functions of :data:`TRANSFORMATIONS` as a module.
transformations = _transformations_module()


# -- transformers ---------------------------------------------------------------------------------
def _frame(name: str) -> str:
    return name.lstrip("/")


def _as_lists(message: Any) -> Tuple[List[float], List[float]]:
    t, r = message.transform.translation, message.transform.rotation
    return [t.x, t.y, t.z], [r.x, r.y, r.z, r.w]


class Transformer:
    """A store of transforms and lookups between frames, filled by hand with :meth:`setTransform`.

    Args:
        interpolate: accepted as tf's (tf2 always interpolates).
        cache_time: how long to keep transforms (a ``rospy.Duration``; 10 s by default).
    """

    def __init__(self, interpolate: bool = True, cache_time: Any = None) -> None:
        self._buffer = tf2_ros.Buffer(cache_time)

    def setTransform(  # noqa: N802
        self, transform: Any, authority: str = "default_authority"
    ) -> None:
        """Add a ``geometry_msgs/TransformStamped``."""
        self._buffer.set_transform(transform, authority)

    def allFramesAsString(self) -> str:  # noqa: N802
        """One line per frame with a parent."""
        return self._buffer.all_frames_as_string()

    def canTransform(self, target_frame: str, source_frame: str, time: Any) -> bool:  # noqa: N802
        """Whether :meth:`lookupTransform` would succeed now."""
        return bool(self._buffer.can_transform(_frame(target_frame), _frame(source_frame), time))

    def canTransformFull(  # noqa: N802
        self,
        target_frame: str,
        target_time: Any,
        source_frame: str,
        source_time: Any,
        fixed_frame: str,
    ) -> bool:
        """Whether :meth:`lookupTransformFull` would succeed now."""
        return bool(
            self._buffer.can_transform_full(
                _frame(target_frame),
                target_time,
                _frame(source_frame),
                source_time,
                _frame(fixed_frame),
            )
        )

    def waitForTransform(  # noqa: N802
        self,
        target_frame: str,
        source_frame: str,
        time: Any,
        timeout: Any,
        polling_sleep_duration: Any = None,
    ) -> None:
        """Wait up to ``timeout`` (simulated time) until the transform can be looked up.

        Raises:
            tf.Exception: if it still cannot when the time is up (the message says why).
        """
        ok, why = self._buffer.can_transform(
            _frame(target_frame), _frame(source_frame), time, timeout, return_debug_tuple=True
        )
        if not ok:
            raise tf2_ros.TransformException(why)

    def waitForTransformFull(  # noqa: N802
        self,
        target_frame: str,
        target_time: Any,
        source_frame: str,
        source_time: Any,
        fixed_frame: str,
        timeout: Any,
        polling_sleep_duration: Any = None,
    ) -> None:
        """:meth:`waitForTransform` for :meth:`lookupTransformFull`.

        Raises:
            tf.Exception: if the transform cannot be looked up when the time is up.
        """
        ok, why = self._buffer.can_transform_full(
            _frame(target_frame),
            target_time,
            _frame(source_frame),
            source_time,
            _frame(fixed_frame),
            timeout,
            return_debug_tuple=True,
        )
        if not ok:
            raise tf2_ros.TransformException(why)

    def clear(self) -> None:
        """Forget every transform but the static ones."""
        self._buffer.clear()

    def getFrameStrings(self) -> List[str]:  # noqa: N802
        """The frames that have a parent (a tree's root is not listed, as in tf)."""
        return [
            line.split()[1]
            for line in self._buffer.all_frames_as_string().splitlines()
            if not line.endswith("NO_PARENT.")
        ]

    def frameExists(self, frame_id: str) -> bool:  # noqa: N802
        """Whether ``frame_id`` has a parent (False for a tree's root, as in tf)."""
        return _frame(frame_id) in self.getFrameStrings()

    def getLatestCommonTime(self, source_frame: str, dest_frame: str) -> Any:  # noqa: N802
        """The latest time the transform between two frames is known at (a ``rospy.Time``).

        Raises:
            tf.Exception: as :meth:`lookupTransform` (one of its subclasses).
        """
        return self._buffer.get_latest_common_time(_frame(source_frame), _frame(dest_frame))

    def lookupTransform(  # noqa: N802
        self, target_frame: str, source_frame: str, time: Any
    ) -> Tuple[List[float], List[float]]:
        """The transform from ``source_frame`` to ``target_frame`` at ``time``.

        Args:
            target_frame: the frame to express things in.
            source_frame: the frame things are given in.
            time: a ``rospy.Time``; ``rospy.Time(0)`` for the latest available.

        Returns:
            ``([x, y, z], [x, y, z, w])``: the source frame's origin and orientation in the
            target frame.

        Raises:
            tf.LookupException: if a frame does not exist.
            tf.ConnectivityException: if the frames are not in the same tree.
            tf.ExtrapolationException: if ``time`` lies outside the data kept.
        """
        message = self._buffer.lookup_transform(_frame(target_frame), _frame(source_frame), time)
        return _as_lists(message)

    def lookupTransformFull(  # noqa: N802
        self,
        target_frame: str,
        target_time: Any,
        source_frame: str,
        source_time: Any,
        fixed_frame: str,
    ) -> Tuple[List[float], List[float]]:
        """The transform from a frame at one time to a frame at another, via a fixed frame.

        ``source_frame`` at ``source_time`` to ``target_frame`` at ``target_time``, assuming
        ``fixed_frame`` does not move in between.

        Raises:
            tf.Exception: as :meth:`lookupTransform` (one of its subclasses).
        """
        message = self._buffer.lookup_transform_full(
            _frame(target_frame),
            target_time,
            _frame(source_frame),
            source_time,
            _frame(fixed_frame),
        )
        return _as_lists(message)

    def getTFPrefix(self) -> str:  # noqa: N802
        """The tf prefix: always empty, as in tf2."""
        return ""

    def setUsingDedicatedThread(self, value: bool) -> None:  # noqa: N802
        """Accepted as tf's: the graph delivers transforms while a node waits."""


class TransformerROS(Transformer):
    """A :class:`Transformer` that also transforms geometry_msgs points, vectors and poses."""

    def fromTranslationRotation(  # noqa: N802
        self, translation: Sequence[float], rotation: Sequence[float]
    ) -> np.ndarray:
        """The 4x4 matrix of a translation (x, y, z) and a rotation (x, y, z, w)."""
        return np.dot(_translation_matrix(translation), _quaternion_matrix(rotation))

    def asMatrix(self, target_frame: str, hdr: Any) -> np.ndarray:  # noqa: N802
        """The 4x4 matrix from the frame of a header (``frame_id`` at ``stamp``) to another.

        Raises:
            tf.Exception: as :meth:`lookupTransform` (one of its subclasses).
        """
        translation, rotation = self.lookupTransform(target_frame, hdr.frame_id, hdr.stamp)
        return self.fromTranslationRotation(translation, rotation)

    def _stamped(self, kind: str, target_frame: str, message: Any) -> Any:
        result: Any = get_message_class(f"geometry_msgs/{kind}")()
        result.header.stamp = message.header.stamp
        result.header.frame_id = target_frame
        return result

    def transformPoint(self, target_frame: str, ps: Any) -> Any:  # noqa: N802
        """A ``geometry_msgs/PointStamped`` expressed in ``target_frame``."""
        matrix = self.asMatrix(target_frame, ps.header)
        x, y, z, _ = np.dot(matrix, [ps.point.x, ps.point.y, ps.point.z, 1.0])
        result = self._stamped("PointStamped", target_frame, ps)
        result.point.x, result.point.y, result.point.z = float(x), float(y), float(z)
        return result

    def transformVector3(self, target_frame: str, v3s: Any) -> Any:  # noqa: N802
        """A ``geometry_msgs/Vector3Stamped`` expressed in ``target_frame`` (rotated only)."""
        matrix = self.asMatrix(target_frame, v3s.header)
        x, y, z, _ = np.dot(matrix, [v3s.vector.x, v3s.vector.y, v3s.vector.z, 0.0])
        result = self._stamped("Vector3Stamped", target_frame, v3s)
        result.vector.x, result.vector.y, result.vector.z = float(x), float(y), float(z)
        return result

    def _rotated(self, matrix: np.ndarray, q: Any) -> List[float]:
        rotated = np.dot(matrix, _quaternion_matrix([q.x, q.y, q.z, q.w]))
        return [float(v) for v in _quaternion_from_matrix(rotated)]

    def transformQuaternion(self, target_frame: str, ps: Any) -> Any:  # noqa: N802
        """A ``geometry_msgs/QuaternionStamped`` expressed in ``target_frame``."""
        matrix = self.asMatrix(target_frame, ps.header)
        result = self._stamped("QuaternionStamped", target_frame, ps)
        q = result.quaternion
        q.x, q.y, q.z, q.w = self._rotated(matrix, ps.quaternion)
        return result

    def transformPose(self, target_frame: str, ps: Any) -> Any:  # noqa: N802
        """A ``geometry_msgs/PoseStamped`` expressed in ``target_frame``."""
        matrix = self.asMatrix(target_frame, ps.header)
        p = ps.pose.position
        x, y, z, _ = np.dot(matrix, [p.x, p.y, p.z, 1.0])
        result = self._stamped("PoseStamped", target_frame, ps)
        position, q = result.pose.position, result.pose.orientation
        position.x, position.y, position.z = float(x), float(y), float(z)
        q.x, q.y, q.z, q.w = self._rotated(matrix, ps.pose.orientation)
        return result


class TransformListener(TransformerROS):
    """A :class:`TransformerROS` filled with the transforms published on ``/tf`` and ``/tf_static``.

    Args:
        interpolate: accepted as tf's (tf2 always interpolates).
        cache_time: how long to keep transforms (a ``rospy.Duration``; 10 s by default).
    """

    def __init__(self, interpolate: bool = True, cache_time: Any = None) -> None:
        TransformerROS.__init__(self, interpolate, cache_time)
        self._listener = tf2_ros.TransformListener(self._buffer)


class TransformBroadcaster:
    """Publish transforms on ``/tf`` from a translation and a rotation.

    Args:
        queue_size: the publisher's queue size.
    """

    def __init__(self, queue_size: int = 100) -> None:
        self.tf2_broadcaster = tf2_ros.TransformBroadcaster(queue_size)

    def sendTransform(  # noqa: N802
        self,
        translation: Sequence[float],
        rotation: Sequence[float],
        time: Any,
        child: str,
        parent: str,
    ) -> None:
        """Say where frame ``child`` is in frame ``parent`` at ``time``.

        Args:
            translation: the child's origin in the parent, ``(x, y, z)``.
            rotation: the child's orientation in the parent, a quaternion ``(x, y, z, w)``.
            time: a ``rospy.Time``, usually ``rospy.Time.now()``.
            child: the child frame's name.
            parent: the parent frame's name.

        Raises:
            ValueError: if the translation is not 3 numbers or the rotation not 4.
            TypeError: if ``time`` is not a ``rospy.Time``.
        """
        if not isinstance(time, rostime.Time):
            raise TypeError(
                "tf.TransformBroadcaster.sendTransform() takes the time as a rospy.Time, such as "
                f"rospy.Time.now(), not {time!r}."
            )
        translation, rotation = list(translation), list(rotation)
        if len(translation) != 3:
            raise ValueError(
                "tf.TransformBroadcaster.sendTransform() takes the translation as (x, y, z), "
                f"3 numbers, not {len(translation)}."
            )
        if len(rotation) != 4:
            raise ValueError(
                "tf.TransformBroadcaster.sendTransform() takes the rotation as a quaternion "
                f"(x, y, z, w), 4 numbers, not {len(rotation)}: make one from angles with "
                "tf.transformations.quaternion_from_euler(roll, pitch, yaw)."
            )
        message = tf2_ros.TransformStamped()
        message.header.frame_id = parent
        message.header.stamp = time
        message.child_frame_id = child
        t, r = message.transform.translation, message.transform.rotation
        t.x, t.y, t.z = (float(v) for v in translation)
        r.x, r.y, r.z, r.w = (float(v) for v in rotation)
        self.sendTransformMessage(message)

    def sendTransformMessage(self, transform: Any) -> None:  # noqa: N802
        """Publish a ``geometry_msgs/TransformStamped`` on ``/tf``."""
        self.tf2_broadcaster.sendTransform([transform])


#: ``tf.Exception``: the base of tf's exceptions (tf2_ros's ``TransformException``).
Exception = tf2_ros.TransformException
