"""Missions as data: the states of a task, each with its LED colour and its moves.

The multi-state task of the course (spec: "square then circle"), its later "D" variant and the
two tasks of Part 2 (1.25 m straight and back, a quarter turn clockwise and back) are not four
programs but four values of :class:`Mission`. A student's mission node reads a mission
and carries it out state by state; the runner and the grader read the same value to know what
should have happened (states and colours in order, how long each stop lasts, where the robot
should end). Adding a mission means writing one more value, not another state machine.

Conventions (as everywhere in the course): metres, seconds, radians; an angle is positive
counter-clockwise, so a clockwise quarter turn is ``Rotate(-pi / 2)``. The world frame is the
mat's: the task starts at (0.32, 0.32, pi/2).

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Dict, Tuple, Union

from duckielib.errors import ConfigError
from duckielib.leds import PATTERNS

__all__ = [
    "Arc",
    "D_SHAPE",
    "MISSIONS",
    "Mission",
    "Pose",
    "ROTATION",
    "ReturnToStart",
    "Rotate",
    "SQUARE_THEN_CIRCLE",
    "STRAIGHT",
    "State",
    "Stop",
    "Straight",
    "TASK_START",
    "describe_move",
    "mission_named",
]

#: A pose in the world frame: (x, y, theta) in metres and radians.
Pose = Tuple[float, float, float]

#: Where the task starts on the mat: (x, y, theta) in metres and radians. The one definition
#: of the start pose; the simulator, the odometry, the bag tools and ``duckie`` use it.
TASK_START: Pose = (0.32, 0.32, math.pi / 2)


@dataclass(frozen=True)
class Stop:
    """Stand still (wheels stopped) for ``seconds``."""

    seconds: float


@dataclass(frozen=True)
class Rotate:
    """Turn on the spot by ``angle`` radians (positive counter-clockwise)."""

    angle: float


@dataclass(frozen=True)
class Straight:
    """Drive ``distance`` metres along the current heading (negative: backwards)."""

    distance: float


@dataclass(frozen=True)
class Arc:
    """Drive along a circle of ``radius`` metres, turning by ``angle`` radians.

    A negative angle curves to the right (clockwise); ``Arc(0.2, -2 * pi)`` is a full
    clockwise circle that ends where it began.
    """

    radius: float
    angle: float


@dataclass(frozen=True)
class ReturnToStart:
    """Go back to the mission's start position and heading, by the robot's own odometry."""


Move = Union[Stop, Rotate, Straight, Arc, ReturnToStart]


def describe_move(move: Move) -> str:
    """A move in a few words, with its numbers in units people read (degrees, metres)."""
    if isinstance(move, Stop):
        return f"stop {move.seconds:g} s"
    if isinstance(move, Rotate):
        return f"rotate {math.degrees(move.angle):+.0f}°"
    if isinstance(move, Straight):
        return f"straight {move.distance:g} m"
    if isinstance(move, Arc):
        return f"arc r={move.radius:g} m, {math.degrees(move.angle):+.0f}°"
    return "back to the start"


@dataclass(frozen=True)
class State:
    """One state of a mission: a name, the LED pattern shown while in it, and its moves.

    Attributes:
        name: what the state is, for people and for ``summary.json`` (``"wait"``, ``"square"``).
        color: the LED emitter's pattern name shown during the state (``"RED"``, ...).
        moves: what the robot does, in order.
    """

    name: str
    color: str
    moves: Tuple[Move, ...]

    def __post_init__(self) -> None:
        if self.color not in PATTERNS:
            raise ConfigError(
                f"State {self.name!r}: {self.color!r} is not an LED pattern; use one of "
                f"{', '.join(sorted(PATTERNS))}."
            )
        for move in self.moves:
            if not isinstance(move, (Stop, Rotate, Straight, Arc, ReturnToStart)):
                raise ConfigError(f"State {self.name!r}: {move!r} is not a move.")

    @property
    def is_stop(self) -> bool:
        """Whether the state only stands still."""
        return bool(self.moves) and all(isinstance(move, Stop) for move in self.moves)

    @property
    def stop_seconds(self) -> float:
        """How long the state stands still in total, in seconds."""
        return sum(move.seconds for move in self.moves if isinstance(move, Stop))


@dataclass(frozen=True)
class Mission:
    """A task: its states in order and where it starts.

    Attributes:
        name: the mission's name (``duckie mission --mission NAME``).
        states: the states, in order.
        start: the start pose (x, y, theta) on the mat, metres and radians.
        description: one line for people.
    """

    name: str
    states: Tuple[State, ...]
    start: Tuple[float, float, float] = TASK_START
    description: str = ""

    @property
    def colors(self) -> Tuple[str, ...]:
        """The LED pattern of each state, in order."""
        return tuple(state.color for state in self.states)

    def with_stop_color(self, color: str) -> Mission:
        """The same mission with ``color`` shown in every stop state (the student's choice)."""
        return Mission(
            self.name,
            tuple(
                State(state.name, color, state.moves) if state.is_stop else state
                for state in self.states
            ),
            self.start,
            self.description,
        )


def _wait(seconds: float = 5.0) -> State:
    return State("wait", "RED", (Stop(seconds),))


_SIDE = 1.25
_QUARTER = math.pi / 2

#: The exercise's task: wait, three sides of a 1.25 m square, wait, back to the start, wait,
#: a clockwise circle back towards the start.
SQUARE_THEN_CIRCLE = Mission(
    "square_then_circle",
    (
        _wait(),
        State(
            "square",
            "GREEN",
            (
                Rotate(-_QUARTER),
                Straight(_SIDE),
                Rotate(_QUARTER),
                Straight(_SIDE),
                Rotate(_QUARTER),
                Straight(_SIDE),
            ),
        ),
        _wait(),
        State("return", "BLUE", (ReturnToStart(),)),
        _wait(),
        State("circle", "YELLOW", (Arc(0.2, -2 * math.pi),)),
    ),
    description="wait, three sides of a 1.25 m square, wait, return, wait, a clockwise circle",
)

#: The later variant: the square replaced by a "D" (the 1.25 m back, a straight top and bottom
#: and two clockwise quarter arcs of 0.4 m for the bowl), ending where it began.
D_SHAPE = Mission(
    "d_shape",
    (
        _wait(),
        State(
            "d",
            "GREEN",
            (
                Straight(_SIDE),
                Rotate(-_QUARTER),
                Straight(0.5),
                Arc(0.4, -_QUARTER),
                Straight(_SIDE - 2 * 0.4),
                Arc(0.4, -_QUARTER),
                Straight(0.5),
                Rotate(-_QUARTER),
            ),
        ),
        _wait(),
        State("return", "BLUE", (ReturnToStart(),)),
        _wait(),
        State("circle", "YELLOW", (Arc(0.2, -2 * math.pi),)),
    ),
    description="wait, a D of 1.25 m, wait, return, wait, a clockwise circle",
)

#: The straight-line task of Part 2: 1.25 m forward along the start heading, then back to the
#: start, facing the way it started.
STRAIGHT = Mission(
    "straight",
    (
        _wait(),
        State("forward", "GREEN", (Straight(_SIDE),)),
        _wait(),
        State("back", "BLUE", (ReturnToStart(),)),
    ),
    description="wait, 1.25 m forward, wait, back to the start",
)

#: The rotation task of Part 2: a quarter turn clockwise on the spot, then back.
ROTATION = Mission(
    "rotation",
    (
        _wait(),
        State("clockwise", "GREEN", (Rotate(-_QUARTER),)),
        _wait(),
        State("back", "BLUE", (Rotate(_QUARTER),)),
    ),
    description="wait, a quarter turn clockwise, wait, a quarter turn back",
)

#: Every mission by name.
MISSIONS: Dict[str, Mission] = {
    mission.name: mission for mission in (SQUARE_THEN_CIRCLE, D_SHAPE, STRAIGHT, ROTATION)
}


def mission_named(name: str) -> Mission:
    """The mission called ``name``.

    Raises:
        ConfigError: if there is none, naming the missions there are.
    """
    try:
        return MISSIONS[name]
    except KeyError:
        raise ConfigError(
            f"There is no mission {name!r}; choose one of {', '.join(sorted(MISSIONS))}."
        ) from None
