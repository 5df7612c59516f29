"""Fit the simulator's motors to a robot: each wheel's speed for each command, from a bag.

A bag that holds the wheel commands and both encoders' ticks says, for every command held
long enough, how fast each wheel really turned. :func:`calibrate_bag` finds those steady
stretches (a command held 1 s or more; its second half, once the wheel has settled), measures
each wheel's speed there, and fits each motor's speed curve through them: the dead band (the
largest command that does not turn the wheel, extended from the two slowest speeds) and a
knot at every command measured, extended in a straight line to duty 1. The fitted profile
keeps the realistic profile's other imperfections (slip, encoder jitter, the encoder driver's
counting rule) and is checked by replaying the bag's commands into it (:mod:`.replay`).

``duckie calibrate BAG -o robot.json`` writes the profile; ``duckie mission --noise
robot.json`` then drives a simulated robot that behaves like yours.

Laptop side; never deployed.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Dict, List, Optional, Tuple, Union

import numpy as np

from duckielib.bags import Bag, read_encoders
from duckielib.errors import BagError
from duckielib.sim.noise import NoiseProfile
from duckielib.sim.replay import ReplayReport, replay_bag, wheel_commands

__all__ = ["Calibration", "calibrate_bag", "steady_speeds"]

#: The shortest command that counts as held, and the part of it measured (its second half).
HOLD_S = 1.0
#: Commands closer than this are the same level of the speed curve.
LEVEL_STEP = 0.02
#: How many different moving levels each wheel needs for a fit.
LEVELS_NEEDED = 3
#: A wheel slower than this (rad/s) over a held command did not turn.
STILL = 0.1

PathLike = Union[str, "os.PathLike[str]"]
Curve = Tuple[Tuple[float, float], ...]


@dataclass(frozen=True)
class Calibration:
    """A fitted profile, what it was fitted on, and how well it replays the bag.

    Attributes:
        profile: the fitted noise profile (save it with ``profile.save("robot.json")``).
        points: each wheel's measured ``(|duty|, rad/s)`` pairs, one per held command.
        replay: the bag replayed into the fitted profile.
    """

    profile: NoiseProfile
    points: Dict[str, List[Tuple[float, float]]]
    replay: ReplayReport

    def figures(self) -> Dict[str, Union[str, int, float]]:
        """The fit as ``name: value`` pairs (what ``duckie calibrate`` prints)."""
        figures: Dict[str, Union[str, int, float]] = {"bag": self.replay.bag}
        curves = {"left": self.profile.speed_curve, "right": self.profile.right_speed_curve}
        for wheel in ("left", "right"):
            curve = curves[wheel] or ()
            figures[f"calibration_held_commands_{wheel}"] = len(self.points[wheel])
            figures[f"calibration_dead_band_{wheel}"] = round(curve[0][0], 4)
            for duty in (0.3, 0.5, 1.0):
                speed = _speed_on(curve, duty)
                figures[f"calibration_speed_at_{duty:g}_{wheel}"] = round(speed, 3)
        figures["calibration_tick_rate_rms"] = round(self.replay.tick_rate_rms, 3)
        figures["calibration_travel_ratio_left"] = round(self.replay.left.travel_ratio, 4)
        figures["calibration_travel_ratio_right"] = round(self.replay.right.travel_ratio, 4)
        return figures


def _speed_on(curve: Curve, duty: float) -> float:
    from duckielib.sim.robot import steady_speed

    return steady_speed(curve, duty) if curve else 0.0


def steady_speeds(
    bag: Union[Bag, PathLike],
    command_topic: Optional[str] = None,
    left_topic: Optional[str] = None,
    right_topic: Optional[str] = None,
) -> Dict[str, List[Tuple[float, float]]]:
    """Each wheel's ``(|duty|, rad/s)`` for every command held 1 s or more (module doc).

    The speed is measured over the command's second half, along the command's direction
    (a wheel that turned the other way has a negative speed).
    """
    bag = bag if isinstance(bag, Bag) else Bag(bag)
    commands = wheel_commands(bag, command_topic)
    streams = read_encoders(bag, left_topic, right_topic)
    changes = [0]
    for index in range(1, len(commands.t)):
        same = (
            abs(commands.left[index] - commands.left[index - 1]) < 1e-6
            and abs(commands.right[index] - commands.right[index - 1]) < 1e-6
        )
        if not same:
            changes.append(index)
    ends = [float(commands.t[index]) for index in changes[1:]] + [
        min(float(stream.t[-1]) for stream in streams)
    ]
    points: Dict[str, List[Tuple[float, float]]] = {"left": [], "right": []}
    for begin_index, end in zip(changes, ends):
        begin = float(commands.t[begin_index])
        if end - begin < HOLD_S:
            continue
        middle = (begin + end) / 2
        duties = {"left": commands.left[begin_index], "right": commands.right[begin_index]}
        for wheel, stream in zip(("left", "right"), streams):
            duty = float(duties[wheel])
            if duty == 0 or stream.t[0] > middle or stream.t[-1] < end:
                continue
            ticks = np.interp([middle, end], stream.t, stream.ticks.astype(float))
            resolution = float(stream.resolution[0])
            speed = (ticks[1] - ticks[0]) / (end - middle) * math.tau / resolution
            points[wheel].append((abs(duty), math.copysign(1.0, duty) * speed))
    return points


def _fit_curve(points: List[Tuple[float, float]], wheel: str, bag: str) -> Curve:
    """A wheel's speed curve through its measured points (module doc)."""
    levels: Dict[float, List[float]] = {}
    for duty, speed in sorted(points):
        key = next((level for level in levels if abs(level - duty) < LEVEL_STEP), duty)
        levels.setdefault(key, []).append(speed)
    means = sorted((duty, float(np.mean(speeds))) for duty, speeds in levels.items())
    moving = [(duty, speed) for duty, speed in means if speed > STILL]
    still = [duty for duty, speed in means if speed <= STILL]
    if len(moving) < LEVELS_NEEDED:
        held = ", ".join(f"{duty:.2f}" for duty, _ in means) or "none"
        raise BagError(
            f"{bag} holds too few different commands of the {wheel} wheel that turn it, each "
            f"held 1 s or more, to fit its motor (found {len(moving)}; commands held: {held}). "
            f"Record at least {LEVELS_NEEDED} different wheel commands, each held for 1 s or "
            "more (for example 0.2, 0.35 and 0.5 on both wheels, then the same while turning), "
            "and calibrate again."
        )
    (d0, s0), (d1, s1) = moving[0], moving[1]
    slope = (s1 - s0) / (d1 - d0) if d1 > d0 else 0.0
    dead_band = d0 - s0 / slope if slope > 0 else d0 * 0.5
    lowest = max(still, default=0.0)
    dead_band = min(max(dead_band, lowest, 0.005), d0 - 1e-3)
    knots = [(dead_band, 0.0)]
    for duty, speed in moving:
        knots.append((duty, max(speed, knots[-1][1])))  # a faster command never turns slower
    if knots[-1][0] < 1.0:
        (da, sa), (db, sb) = knots[-2], knots[-1]
        end_slope = max((sb - sa) / (db - da), 0.0) if db > da else 0.0
        knots.append((1.0, sb + end_slope * (1.0 - db)))
    return tuple((round(duty, 4), round(speed, 4)) for duty, speed in knots)


def calibrate_bag(
    bag: Union[Bag, PathLike],
    name: str = "calibrated",
    command_topic: Optional[str] = None,
    left_topic: Optional[str] = None,
    right_topic: Optional[str] = None,
) -> Calibration:
    """Fit each motor's speed curve to a bag and check the fit by replaying it (module doc).

    Args:
        bag: a :class:`~duckielib.bags.Bag` or a bag's path, with the wheel commands
            (``wheels_driver_node/wheels_cmd``) and both encoders' ticks.
        name: the fitted profile's name.
        command_topic: the wheel commands' topic (default: found by type and name).
        left_topic: the left encoder's topic (default: found by name).
        right_topic: the right encoder's topic (default: found by name).

    Raises:
        BagError: if the bag lacks the topics, or holds too few different held commands.
    """
    bag = bag if isinstance(bag, Bag) else Bag(bag)
    points = steady_speeds(bag, command_topic, left_topic, right_topic)
    curves = {wheel: _fit_curve(points[wheel], wheel, bag.path.name) for wheel in points}
    profile = NoiseProfile.realistic(
        name=name,
        left_gain=1.0,
        right_gain=1.0,
        breakaway_pwm=None,
        speed_curve=curves["left"],
        right_speed_curve=curves["right"],
    )
    replay = replay_bag(bag, profile, 0, command_topic, left_topic, right_topic)
    return Calibration(profile, points, replay)
