"""duckielib: the shared library of the Duckiebot ROS course.

It is the infrastructure students' code plugs into, never the answers to graded exercises.
Importing ``duckielib`` is light: it loads no simulator, bag, plotting or ROS package. Those
live in their own modules and are imported when used.

Where code runs is a rule about folders. Everything here is deployed to the robot (Python
3.8, standard library and numpy only) except the laptop packages:

Robot and laptop:
    config: the robot's constants (:data:`DB21`).
    errors: :class:`DuckielibError` and its subclasses.
    rostime: ROS :class:`~duckielib.rostime.Time` and :class:`~duckielib.rostime.Duration`.
    leds: the LED patterns and colours.
    messages: the ROS message and service types of the course.
    ros: rospy's API on an in-process graph with simulated time.
    missions: missions as data, and the task's start pose.
    odometry: the odometry loop, calling a solution's own functions.
    solution: the student contract, exporting a solution and loading it.
    nodes: the course's nodes, their mains on a real ROS master, the wheels' guard.

Laptop only:
    sim: the pymunk simulator of the Duckiebot.
    bags: ROS 1 bags with rosbags, and what a mission's bag shows.
    plots: matplotlib pictures of runs and the notebooks' diagrams.
    tools: the ``duckie`` command, the mission runner, deployment, benchmarks.
    libraries: cv_bridge, rosbag, message_filters, tf and tf2_ros for robot code in process.
    lab: JupyterLab's settings for students.

Conventions, written down once: SI units (metres, seconds, radians); the robot frame has x
forward, y to the left, angles counter-clockwise positive seen from above; the task's heading
theta is kept in [0, 2*pi). Quantities in other units say so in their name (``ticks``,
``_deg``, ``_ns``).
"""

from __future__ import annotations

from duckielib.config import DB21, TILE_SIZE, RobotConfig
from duckielib.errors import DuckielibError

__all__ = ["DB21", "TILE_SIZE", "RobotConfig", "DuckielibError", "__version__"]

__version__ = "0.1.0"
