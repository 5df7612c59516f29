"""The course's infrastructure nodes, written once against the rospy API.

A node here is a main function, as ``roslaunch`` would start it: it calls ``init_node``, sets
up its topics and spins. It takes the ``rospy`` to run with (the in-process graph's, or the
real one on a robot) and uses the message classes that belong to that rospy
(:func:`~duckielib.ros.backend.message_classes`), so the same function runs in a notebook, in
``duckie mission`` and on a Duckiebot, whatever was imported before it.

The work that is graded stays the student's: :func:`odometry_node` only feeds encoder readings
to the solution's own ``WheelPairing`` and ``estimate_pose`` (through
:class:`~duckielib.odometry.Odometry`) and publishes what they compute.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

import time
from typing import Any, List, Sequence

from duckielib.missions import TASK_START
from duckielib.odometry import Odometry
from duckielib.ros.backend import message_classes
from duckielib.solution import SolutionError

__all__ = ["camera_republisher_node", "odometry_node"]


def odometry_node(rospy: Any, solution: Any, start: Sequence[float] = TASK_START) -> None:
    """Dead reckoning with a solution's functions: encoder ticks in, the pose out on ``~pose``.

    Run it in the robot's namespace (``/VEH/``). It reads the wheel radius and baseline from
    ``kinematics_node/`` and the resolution from ``left_wheel_encoder_node/``, as the robot
    publishes them, and publishes a ``duckietown_msgs/Pose2DStamped`` in the world frame on
    ``~pose`` each time a pair of readings completes, stamped with the time of the reading
    that completed it.

    Args:
        rospy: the rospy module to run with.
        solution: the solution whose ``WheelPairing`` and ``estimate_pose`` do the work.
        start: the pose (x, y, theta) the robot starts from, in metres and radians.

    Raises:
        SolutionError: when a function of the solution fails or returns a number that is not
            finite. The node then stops at once (its ``~pose`` would be wrong from then on):
            it shuts down and raises that first failure, instead of logging one error per
            encoder reading.
    """
    msg = message_classes(rospy)
    rospy.init_node("odometry_node")
    _wait_for_params(rospy, ["left_wheel_encoder_node/resolution", "kinematics_node/radius"])
    odometry = Odometry(
        solution,
        resolution=int(rospy.get_param("left_wheel_encoder_node/resolution")),
        radius=float(rospy.get_param("kinematics_node/radius")),
        baseline=float(rospy.get_param("kinematics_node/baseline")),
        start=start,
    )
    publisher = rospy.Publisher("~pose", msg.Pose2DStamped, queue_size=10)
    # One message, refilled for each pose: publish() serializes it before it returns.
    out = msg.Pose2DStamped()
    out.header.frame_id = "world"

    failures: List[SolutionError] = []

    def on_tick(reading: Any, wheel: str) -> None:
        if failures:
            return  # readings queued before the shutdown took effect
        try:
            pose = odometry.add(wheel, reading.data)
        except SolutionError as error:
            # Every later pose would be wrong too: stop at the first failure, and say it once.
            failures.append(error)
            rospy.signal_shutdown(f"the solution's odometry failed: {error}")
            return
        if pose is None:
            return
        out.x, out.y, out.theta = pose
        out.header.stamp = reading.header.stamp
        publisher.publish(out)

    for wheel in ("left", "right"):
        rospy.Subscriber(
            f"{wheel}_wheel_encoder_node/tick",
            msg.WheelEncoderStamped,
            on_tick,
            callback_args=wheel,
            queue_size=10,
        )
    rospy.spin()
    if failures:
        raise failures[0]


def _wait_for_params(rospy: Any, names: Sequence[str]) -> None:
    """Wait until the robot's drivers have set ``names`` (a node may start before them)."""
    waiting = False
    while not all(rospy.has_param(name) for name in names) and not rospy.is_shutdown():
        if not waiting:
            rospy.loginfo(f"Waiting for the robot's drivers to set {', '.join(names)}...")
            waiting = True
        time.sleep(0.1)  # wall clock: before the drivers run, simulated time may not move


def camera_republisher_node(rospy: Any, every: int = 1) -> None:
    """Republish the camera's JPEG frames on ``~image/compressed``, every ``every``-th one.

    A laptop that watches the robot's camera subscribes here instead of to the driver, and
    ``every=3`` sends it 10 of the camera's 30 frames a second.

    Args:
        rospy: the rospy module to run with.
        every: republish one frame in this many (1: all of them).
    """
    msg = message_classes(rospy)
    rospy.init_node("camera_republisher_node")
    publisher = rospy.Publisher("~image/compressed", msg.CompressedImage, queue_size=1)
    count = [0]

    def on_image(image: Any) -> None:
        count[0] += 1
        if (count[0] - 1) % max(1, every) == 0:
            publisher.publish(image)

    rospy.Subscriber("camera_node/image/compressed", msg.CompressedImage, on_image, queue_size=1)
    rospy.spin()
