"""A run's 2D poses in the types robotics viewers draw without set-up.

The Duckiebot's poses are ``duckietown_msgs/Pose2DStamped`` (x, y, theta in the plane), a type
Foxglove, Lichtblick and RViz list but do not draw. For each such message,
:class:`ViewerPoses` makes the same pose in two standard types:

- a frame on ``/tf`` (``tf2_msgs/TFMessage``), child of the pose's own frame (``world``),
  named after its topic: ``/duckiebot/odometry_node/pose`` places the frame
  ``duckiebot/odometry_node/pose``. A 3D panel draws every frame as axes, so the true pose and
  the odometry's estimate show side by side.
- a ``geometry_msgs/PoseStamped`` on the topic with ``_3d`` added
  (``/duckiebot/odometry_node/pose_3d``), which a 3D panel draws as an arrow and keeps as a
  trail.

The heading theta becomes a rotation about the vertical axis (a unit quaternion, z up).
The original messages are kept unchanged beside them.

Laptop side; never deployed.
"""

from __future__ import annotations

import math
from typing import Any, List, NamedTuple

from duckielib.messages import get_message_class
from duckielib.rostime import NS_PER_S, Time

__all__ = ["POSE_2D", "ViewerMessage", "ViewerPoses", "frame_of", "pose_3d_topic"]

#: The type whose messages get a viewer's form.
POSE_2D = "duckietown_msgs/Pose2DStamped"

#: The parent frame of a pose whose header names none.
WORLD_FRAME = "world"


class ViewerMessage(NamedTuple):
    """One message made for viewers: its topic, type, md5 sum, definition and bytes."""

    topic: str
    type: str
    md5sum: str
    definition: str
    data: bytes


def frame_of(topic: str) -> str:
    """The TF frame a pose topic places: its name without the leading slash."""
    return topic.strip("/")


def pose_3d_topic(topic: str) -> str:
    """The topic of a pose's ``geometry_msgs/PoseStamped`` form: ``_3d`` added."""
    return topic + "_3d"


class ViewerPoses:
    """Turn ``duckietown_msgs/Pose2DStamped`` messages into a TF frame and a PoseStamped."""

    def __init__(self) -> None:
        # Classes made from the definitions: their fields are not known to a type checker.
        self._pose_2d: Any = get_message_class(POSE_2D)
        self._pose_stamped: Any = get_message_class("geometry_msgs/PoseStamped")
        self._transform: Any = get_message_class("geometry_msgs/TransformStamped")
        self._tf: Any = get_message_class("tf2_msgs/TFMessage")

    def messages(
        self, topic: str, type_name: str, data: bytes, time_ns: int
    ) -> List[ViewerMessage]:
        """The viewer's forms of one recorded message (none when it is not a 2D pose).

        Args:
            topic: the message's topic.
            type_name: its type (``duckietown_msgs/Pose2DStamped`` is the one turned).
            data: its serialized bytes.
            time_ns: its record time, used when its header carries no stamp.
        """
        if type_name != POSE_2D:
            return []
        pose = self._pose_2d.from_bytes(data)
        stamp = pose.header.stamp
        if not stamp.to_nsec():
            stamp = Time(time_ns // NS_PER_S, time_ns % NS_PER_S)
        parent = pose.header.frame_id or WORLD_FRAME
        half = pose.theta / 2.0
        z, w = math.sin(half), math.cos(half)

        stamped = self._pose_stamped()
        stamped.header.seq = pose.header.seq
        stamped.header.stamp = stamp
        stamped.header.frame_id = parent
        stamped.pose.position.x, stamped.pose.position.y = pose.x, pose.y
        stamped.pose.orientation.z, stamped.pose.orientation.w = z, w

        transform = self._transform()
        transform.header.stamp = stamp
        transform.header.frame_id = parent
        transform.child_frame_id = frame_of(topic)
        transform.transform.translation.x = pose.x
        transform.transform.translation.y = pose.y
        transform.transform.rotation.z, transform.transform.rotation.w = z, w
        return [
            self._made("/tf", self._tf(transforms=[transform])),
            self._made(pose_3d_topic(topic), stamped),
        ]

    @staticmethod
    def _made(topic: str, message: Any) -> ViewerMessage:
        return ViewerMessage(
            topic, message._type, message._md5sum, message._full_text, message.to_bytes()
        )
