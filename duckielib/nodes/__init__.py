"""The course's nodes: their code, their mains on a real ROS master, and the wheels' guard.

- :mod:`~duckielib.nodes.course`: the library's own nodes (odometry, camera republisher),
  written once against the rospy API, so they run on the in-process graph and on a robot;
- :mod:`~duckielib.nodes.mains`: the mains of ``robot_nodes``' executables, which run the
  student's solution on a real ROS master;
- :mod:`~duckielib.nodes.safety`: the guard that stops the wheels however a node ends.

Deployed to the robot: standard library and numpy only, Python 3.8.
"""

from duckielib.nodes.course import camera_republisher_node, odometry_node

__all__ = ["camera_republisher_node", "odometry_node"]
