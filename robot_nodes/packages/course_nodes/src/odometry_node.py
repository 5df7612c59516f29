#!/usr/bin/env python3
"""The odometry node: where the robot thinks it is, computed by your notebook 05 functions.

A ROS node is one program among the many that run on the robot; they talk by publishing
messages on named topics. This one listens to the two wheel encoders
(``left_wheel_encoder_node/tick``, ``right_wheel_encoder_node/tick``), feeds the readings to
your ``WheelPairing`` and ``estimate_pose``, and publishes the pose they compute on ``~pose``
(``/ROBOT/odometry_node/pose``, a ``duckietown_msgs/Pose2DStamped``).

``roslaunch`` starts it (see ``launch/course.launch``); the code is
``duckielib.nodes.mains.odometry_main``, and your solution is the file ``DUCKIE_SOLUTION`` names.
"""

from duckielib.nodes.mains import odometry_main

if __name__ == "__main__":
    odometry_main()
