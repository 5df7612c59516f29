"""The student contract: every graded function and class, its notebook and its parameters.

:data:`CONTRACT` names each part of a solution as the student met it in the notebooks;
the library's runners, the autograder and the robot nodes call a solution's parts by these
names and parameters.

This module imports only the standard library: it runs on the robot (Python 3.8).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, Tuple

from duckielib.errors import DuckielibError

__all__ = [
    "CONTRACT",
    "EXPORT_TAG",
    "MISSION_PARTS",
    "ODOMETRY_PARTS",
    "PRELUDE",
    "Part",
    "SolutionError",
    "finish_notebook",
]

#: The cell tag that marks a cell for export.
EXPORT_TAG = "export"

#: The modules an exported solution imports for its parts (and nothing else).
PRELUDE = "import math\n\nimport numpy as np\n"


@dataclass(frozen=True)
class Part:
    """One graded function or class of the contract.

    Attributes:
        name: its name, as in the notebook.
        notebook: the notebook (its assignment folder) where the student writes it.
        parameters: the parameter names, in order (for a class, those of ``__init__``).
        summary: what it computes, with units.
        methods: for a class, its methods' names and parameters (without ``self``).
    """

    name: str
    notebook: str
    parameters: Tuple[str, ...]
    summary: str
    methods: Tuple[Tuple[str, Tuple[str, ...]], ...] = ()

    @property
    def is_class(self) -> bool:
        """Whether the part is a class."""
        return bool(self.methods)

    @property
    def signature(self) -> str:
        """The part as the notebook shows it, for example ``delta_phi(ticks, ...)``."""
        text = f"{'class ' if self.is_class else ''}{self.name}({', '.join(self.parameters)})"
        for method, parameters in self.methods:
            text += f" with {method}({', '.join(parameters)})"
        return text


def _parts(*parts: Part) -> Dict[str, Part]:
    return {part.name: part for part in parts}


#: Every part of a solution, by name, in the order of the course.
CONTRACT: Dict[str, Part] = _parts(
    Part(
        "robot_topic",
        "02_ros_concepts",
        ("relative_name",),
        "the absolute name /VEHICLE_NAME/relative_name of one of the robot's topics",
    ),
    Part("wrap_angle", "03_frames", ("theta",), "theta in radians, wrapped into [0, 2 pi)"),
    Part(
        "rotation_matrix",
        "03_frames",
        ("theta",),
        "the 2x2 matrix that rotates a vector by theta radians counter-clockwise",
    ),
    Part(
        "world_from_robot",
        "03_frames",
        ("robot_pose", "point"),
        "a point (x, y) of the robot's frame in the world frame, shape (2,), metres",
    ),
    Part(
        "world_from_start",
        "03_frames",
        ("pose", "start"),
        "a pose (x, y, theta) of the start frame as a world pose, theta in [0, 2 pi)",
    ),
    Part(
        "forward_kinematics",
        "04_kinematics",
        ("omega_left", "omega_right", "R", "baseline"),
        "wheel speeds (rad/s) to (v in m/s, omega in rad/s)",
    ),
    Part(
        "inverse_kinematics",
        "04_kinematics",
        ("v", "omega", "R", "baseline"),
        "(v in m/s, omega in rad/s) to wheel speeds (omega_left, omega_right) in rad/s",
    ),
    Part(
        "duty_cycles",
        "04_kinematics",
        ("v", "omega", "R", "baseline", "gain", "trim", "k", "limit"),
        "(v, omega) to the wheels' duty cycles (u_left, u_right), as the kinematics node does",
    ),
    Part(
        "delta_phi",
        "05_odometry",
        ("ticks", "prev_ticks", "resolution"),
        "(change of wheel angle in radians, ticks to keep)",
    ),
    Part(
        "estimate_pose",
        "05_odometry",
        ("R", "baseline", "x_prev", "y_prev", "theta_prev", "delta_phi_left", "delta_phi_right"),
        "the next pose (x, y, theta), metres and radians, theta in [0, 2 pi)",
    ),
    Part(
        "WheelPairing",
        "05_odometry",
        ("resolution",),
        "pairs the two wheels' readings into (delta_phi_left, delta_phi_right) updates",
        methods=(("add", ("wheel", "ticks")),),
    ),
    Part(
        "angle_error",
        "06_driving",
        ("target", "theta"),
        "the signed turn from heading theta to heading target, radians in [-pi, pi)",
    ),
    Part(
        "distance_along",
        "06_driving",
        ("start", "pose"),
        "how far pose is from start along start's heading, in metres (negative: behind)",
    ),
    Part(
        "AngleTracker",
        "06_driving",
        ("theta0",),
        "the total angle turned since heading theta0, in radians, across the wrap at 2 pi",
        methods=(("update", ("theta",)),),
    ),
    Part(
        "PID",
        "07_control",
        ("kp", "ki", "kd", "limit"),
        "a discrete PID controller with an output limit and anti-windup",
        methods=(("update", ("error", "dt")), ("reset", ())),
    ),
    Part(
        "go_to_point",
        "07_control",
        ("pose", "target", "v_max", "k_omega"),
        "the command (v in m/s, omega in rad/s) that drives from pose towards a point",
    ),
    Part(
        "light_service_node",
        "08_leds",
        (),
        "a node offering ~set_color (ChangePattern) that sets the LEDs through the emitter",
    ),
    Part(
        "mission_node",
        "09_mission",
        ("mission",),
        "a node that carries out a mission state by state, each with its LED colour",
    ),
)

#: The parts the odometry runners need.
ODOMETRY_PARTS = ("delta_phi", "estimate_pose", "WheelPairing")

#: What a mission needs: the odometry, the driving and control parts, and the two nodes.
MISSION_PARTS = (
    *ODOMETRY_PARTS,
    "angle_error",
    "distance_along",
    "AngleTracker",
    "PID",
    "go_to_point",
    "light_service_node",
    "mission_node",
)


class SolutionError(DuckielibError):
    """A solution cannot be exported or loaded, lacks a part, or a part fails.

    The message names the notebook to finish or fix.
    """


def finish_notebook(part: Part) -> str:
    """The start of an error's sentence that sends the student to ``part``'s notebook."""
    return f"Finish notebook {part.notebook}"
