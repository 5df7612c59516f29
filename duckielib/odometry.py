"""Wheel odometry with a solution's own functions: the loop every odometry runner shares.

:class:`Odometry` takes the encoder readings of both wheels, one at a time and in time order,
and keeps the robot's pose. The work is the student's: the solution's ``WheelPairing`` turns
readings into pairs of wheel-angle changes (using the solution's ``delta_phi``), and its
``estimate_pose`` moves the pose. This class only calls them, checks what they return and
names the notebook to fix when they fail. The bag replay, the odometry node of the mission and
the robot all use it.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

from typing import Any, Optional, Sequence

from duckielib.config import DB21
from duckielib.missions import TASK_START, Pose
from duckielib.solution import SolutionError, call_part, check_part

__all__ = ["Odometry"]


class Odometry:
    """Dead reckoning from encoder readings with a solution's functions.

    Args:
        solution: holds ``WheelPairing`` and ``estimate_pose`` (and ``delta_phi``, which the
            pairing uses): a module from :func:`~duckielib.solution.load_solution`, or a
            notebook's ``globals()``.
        resolution: encoder ticks per wheel revolution.
        radius: wheel radius R, in metres.
        baseline: distance between the wheels, in metres.
        start: the pose (x, y, theta) at the first pair of readings; metres, radians.

    Attributes:
        pose: the current pose (x, y, theta).

    Raises:
        SolutionError: if the solution lacks a part or cannot create its pairing.
    """

    def __init__(
        self,
        solution: Any,
        resolution: int = DB21.resolution,
        radius: float = DB21.radius,
        baseline: float = DB21.baseline,
        start: Sequence[float] = TASK_START,
    ) -> None:
        self._estimate_pose = check_part(solution, "estimate_pose")
        pairing_class = check_part(solution, "WheelPairing")
        check_part(solution, "delta_phi")
        self._pairing = call_part("WheelPairing", pairing_class, int(resolution))
        self.radius = float(radius)
        self.baseline = float(baseline)
        x, y, theta = (float(value) for value in start)
        self.pose: Pose = (x, y, theta)

    def add(self, wheel: str, ticks: int) -> Optional[Pose]:
        """Take one encoder reading; return the new pose when it completes a pair, else None.

        Args:
            wheel: ``"left"`` or ``"right"``.
            ticks: the wheel's cumulative tick count, as in the encoder message.

        Raises:
            SolutionError: if the pairing or ``estimate_pose`` is unfinished, fails, or returns
                something else than the contract says.
        """
        pair = call_part("WheelPairing.add", self._pairing.add, wheel, ticks)
        if pair is None:
            return None
        try:
            delta_left, delta_right = (float(value) for value in pair)
        except (TypeError, ValueError):
            raise SolutionError(
                "Fix notebook 05_odometry: WheelPairing.add must return None or two numbers "
                f"(delta_phi_left, delta_phi_right), not {pair!r}."
            ) from None
        x, y, theta = self.pose
        pose = call_part(
            "estimate_pose",
            self._estimate_pose,
            self.radius,
            self.baseline,
            x,
            y,
            theta,
            delta_left,
            delta_right,
        )
        self.pose = _pose(pose, "estimate_pose")
        return self.pose


def _pose(value: Any, source: str) -> Pose:
    try:
        x, y, theta = (float(item) for item in value)
    except (TypeError, ValueError):
        raise SolutionError(
            f"Fix notebook 05_odometry: {source} must return three numbers (x, y, theta), "
            f"not {value!r}."
        ) from None
    return x, y, theta
