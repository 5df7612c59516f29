"""duckielib: the shared library of the Duckiebot ROS course.

It is the infrastructure students' code plugs into, never the answers to graded exercises.
Importing ``duckielib`` is light: it loads no simulator, bag, plotting or ROS package. Those
live in their own modules and are imported when used.

Modules (one idea each):
    config: the robot's constants (:data:`DB21`).
    errors: :class:`DuckielibError` and its subclasses.
    messages: the ROS message and service types of the course.
    rostime: ROS :class:`~duckielib.rostime.Time` and :class:`~duckielib.rostime.Duration`.

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
