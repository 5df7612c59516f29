"""A mission's bag, state by state: the poses during each state, and its turns on the spot.

The mission node publishes the name of each state as it starts it, and ``done`` at the end,
on ``mission_node/state``. These functions cut a run's bag at those times:

- :func:`poses_by_state`: a pose topic's x, y and unwrapped theta during each state;
- :func:`path_length`: how long a path through some points is;
- :func:`turns_on_the_spot`: how long the mission asked to turn with v = 0, and how gently.

Times are the bag's record times in seconds; lengths in metres, angles in radians.

Laptop side; never deployed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import List, Tuple, Union

import numpy as np

from duckielib.bags.analysis import pose_tracks
from duckielib.bags.reader import Bag, PathLike
from duckielib.errors import BagError

__all__ = ["TurnsOnTheSpot", "path_length", "poses_by_state", "turns_on_the_spot"]


def _topic_ending(bag: Bag, suffix: str) -> str:
    """The bag's topic whose name ends with ``suffix``."""
    for name in bag.topics:
        if name.endswith(suffix):
            return name
    raise BagError(f"The bag has no topic ending in {suffix!r}: was it recorded by a mission run?")


def poses_by_state(
    bag: Union[Bag, PathLike], node: str
) -> List[Tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """x, y and the unwrapped theta of a node's pose topic during each state of the mission.

    Args:
        bag: the run's bag.
        node: the node whose ``Pose2DStamped`` topic to read: ``"odometry_node"`` (where the
            odometry believed the robot was) or ``"simulator_node"`` (the truth).

    Returns:
        One ``(x, y, theta)`` of arrays per state, in the mission's order; theta is unwrapped
        (no jump of 2*pi), so that a turn's total shows at once.

    Raises:
        BagError: if the bag has no such pose topic or no mission states.
    """
    bag = bag if isinstance(bag, Bag) else Bag(bag)
    tracks = [track for track in pose_tracks(bag, "record") if f"/{node}/" in track.label]
    if not tracks:
        raise BagError(f"The bag has no pose topic of {node}.")
    track = tracks[0]
    starts = [item.time for item in bag.read(_topic_ending(bag, "mission_node/state"))]
    by_state = []
    for start, end in zip(starts, starts[1:]):  # each state's start, then "done"
        inside = (track.t >= start) & (track.t <= end)
        by_state.append((track.x[inside], track.y[inside], np.unwrap(track.theta[inside])))
    return by_state


def path_length(x: np.ndarray, y: np.ndarray) -> float:
    """The length of a path through the points (x, y), in metres (0 for fewer than two)."""
    return float(np.sum(np.hypot(np.diff(x), np.diff(y))))


@dataclass(frozen=True)
class TurnsOnTheSpot:
    """The turns on the spot (v = 0, omega not 0) a mission asked for.

    Attributes:
        count: how many turns (a run of such commands is one turn).
        seconds: how long they were asked for in all, s.
        longest: the longest turn, s.
        weak: how long the commands asked for less than the given turn rate, s.
    """

    count: int
    seconds: float
    longest: float
    weak: float


def turns_on_the_spot(bag: Union[Bag, PathLike], below: float) -> TurnsOnTheSpot:
    """The turns on the spot in a run's commands (``car_cmd_switch_node/cmd``).

    Each command holds until the next one (the last one for no time).

    Args:
        bag: the run's bag.
        below: a turn rate, rad/s: :attr:`TurnsOnTheSpot.weak` counts the time asking for
            less than this.

    Raises:
        BagError: if the bag has no commands.
    """
    bag = bag if isinstance(bag, Bag) else Bag(bag)
    messages = bag.read(_topic_ending(bag, "car_cmd_switch_node/cmd"))
    t = np.array([item.time for item in messages])
    v = np.array([item.message.v for item in messages])
    omega = np.array([item.message.omega for item in messages])
    held = np.diff(t, append=t[-1])
    turning = (v == 0) & (omega != 0)
    first = turning & ~np.concatenate([[False], turning[:-1]])  # where each turn starts
    turn = np.cumsum(first) * turning  # 1 during the first turn, 2 during the second...
    longest = max((held[turn == k].sum() for k in range(1, int(turn.max()) + 1)), default=0.0)
    return TurnsOnTheSpot(
        count=int(first.sum()),
        seconds=float(held[turning].sum()),
        longest=float(longest),
        weak=float(held[turning & (np.abs(omega) < below)].sum()),
    )
