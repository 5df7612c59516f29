"""Fit the simulator's motors to a robot: each wheel's speed for each command, from a bag.

A bag that holds the wheel commands and both encoders' ticks says, for every command held
long enough, how fast each wheel really turned. :func:`calibrate_bag` finds those steady
stretches (a command held 1 s or more; its second half, once the wheel has settled) and
measures each wheel's speed there. The commands that drive straight or turn the wheels opposite
ways give each motor's speed curve: the dead band (the largest command that does not turn the
wheel, extended from the two slowest speeds) and a knot at every command measured, extended in
a straight line to duty 1. The arcs (both wheels the same way, at different commands) give
the ground's resistance to turning, the value that best predicts how far their slow wheel was
dragged along (without arcs, straight runs set against turns in place give it roughly; with
straight runs only, it is left at 0). The fitted profile keeps the realistic profile's other
imperfections (wheel size and track, slip, encoder jitter, the encoder driver's counting rule:
encoders alone cannot measure them) and is checked by replaying the bag's commands into it
(:mod:`.replay`).

``duckie calibrate BAG -o robot.json`` writes the profile; ``duckie mission --noise
robot.json`` then drives a simulated robot that behaves like yours.

Laptop side; never deployed.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from duckielib.bags import Bag
from duckielib.errors import BagError
from duckielib.sim.noise import NoiseProfile
from duckielib.sim.replay import ReplayReport, aligned_encoders, replay_bag, wheel_commands

__all__ = [
    "CALIBRATION_DRIVE",
    "Calibration",
    "Held",
    "calibrate_bag",
    "CALIBRATION_SAMPLE_ROBOT",
    "calibration_driver",
    "held_commands",
    "record_calibration_drive",
    "record_calibration_sample",
    "steady_speeds",
]

#: The shortest command that counts as held, and the part of it measured (its second half).
HOLD_S = 1.0
#: Commands closer than this are the same level of the speed curve.
LEVEL_STEP = 0.02
#: How many different moving levels each wheel needs for a fit.
LEVELS_NEEDED = 3
#: A wheel slower than this (rad/s) over a held command did not turn.
STILL = 0.1
#: The last part of a held command left out of its measure, in seconds: encoders that count by
#: the command's sign count the next command's way as soon as it comes.
EDGE_S = 0.1
#: The speed the fitted kinematics gain makes right, m/s (the course's driving speed).
GAIN_SPEED = 0.2
#: The largest turning resistance tried (s/rad).
TURNING_MAX = 3.0
_WHAT_TO_RECORD = (
    f"Record at least {LEVELS_NEEDED} different wheel commands on both wheels, each held for "
    "1 s or more (for example 0.2, 0.35 and 0.5), then arcs mixing them (0.2 on one wheel, "
    "0.5 on the other), and calibrate again."
)

PathLike = Union[str, "os.PathLike[str]"]

#: The wheel commands to record for a calibration, as (left duty, right duty, seconds): five
#: speeds straight ahead, turns in place both ways, and arcs mixing the speeds, each held 2 s
#: with a 1 s stop after it. About 50 s; the robot needs about 2 m of free floor ahead.
CALIBRATION_DRIVE: Tuple[Tuple[float, float, float], ...] = tuple(
    step
    for left, right in (
        (0.15, 0.15), (0.2, 0.2), (0.3, 0.3), (0.4, 0.4), (0.55, 0.55),
        (-0.3, 0.3), (0.3, -0.3), (-0.45, 0.45), (0.45, -0.45),
        (0.2, 0.4), (0.4, 0.2), (0.3, 0.55), (0.55, 0.3),
    )
    for step in ((left, right, 2.0), (0.0, 0.0, 1.0))
)  # fmt: skip
Curve = Tuple[Tuple[float, float], ...]


@dataclass(frozen=True)
class Calibration:
    """A fitted profile, what it was fitted on, and how well it replays the bag.

    Attributes:
        profile: the fitted noise profile (save it with ``profile.save("robot.json")``).
        points: each wheel's measured ``(|duty|, rad/s)`` pairs, one per held command.
        replay: the bag replayed into the fitted profile.
        arcs: how many held commands were arcs (they fit the turning resistance).
    """

    profile: NoiseProfile
    points: Dict[str, List[Tuple[float, float]]]
    replay: ReplayReport
    arcs: int = 0

    def figures(self) -> Dict[str, Union[str, int, float]]:
        """The fit as ``name: value`` pairs (what ``duckie calibrate`` prints)."""
        figures: Dict[str, Union[str, int, float]] = {"bag": self.replay.bag}
        curve = self.profile.speed_curve or ()
        gains = {"left": self.profile.left_gain, "right": self.profile.right_gain}
        figures["calibration_dead_band"] = round(curve[0][0], 4) if curve else 0.0
        for wheel in ("left", "right"):
            figures[f"calibration_held_commands_{wheel}"] = len(self.points[wheel])
            for duty in (0.3, 0.5, 1.0):
                speed = gains[wheel] * _speed_on(curve, duty)
                figures[f"calibration_speed_at_{duty:g}_{wheel}"] = round(speed, 3)
        figures["calibration_right_gain"] = self.profile.right_gain
        figures["calibration_kinematics_gain"] = self.profile.kinematics_gain
        figures["calibration_held_arcs"] = self.arcs
        figures["calibration_turning_resistance"] = self.profile.turning_resistance
        figures["calibration_tick_rate_rms"] = round(self.replay.tick_rate_rms, 3)
        figures["calibration_travel_ratio_left"] = round(self.replay.left.travel_ratio, 4)
        figures["calibration_travel_ratio_right"] = round(self.replay.right.travel_ratio, 4)
        return figures


def _speed_on(curve: Curve, duty: float) -> float:
    from duckielib.sim.robot import steady_speed

    return steady_speed(curve, duty) if curve else 0.0


@dataclass(frozen=True)
class Held:
    """A command held 1 s or more, and the wheels' steady speeds over its second half.

    Attributes:
        left_duty: the left wheel's command.
        right_duty: the right wheel's command.
        left_speed: the left wheel's speed, rad/s, positive forward.
        right_speed: the right wheel's speed, rad/s, positive forward.
    """

    left_duty: float
    right_duty: float
    left_speed: float
    right_speed: float

    @property
    def arc(self) -> bool:
        """Whether both wheels were driven the same way at different commands."""
        return self.left_duty * self.right_duty >= 0 and (
            abs(self.left_duty - self.right_duty) >= LEVEL_STEP
        )


def held_commands(
    bag: Union[Bag, PathLike],
    command_topic: Optional[str] = None,
    left_topic: Optional[str] = None,
    right_topic: Optional[str] = None,
) -> List[Held]:
    """Every command held 1 s or more but stops, with both wheels' speeds (module doc)."""
    bag = bag if isinstance(bag, Bag) else Bag(bag)
    commands = wheel_commands(bag, command_topic)
    streams, _ = aligned_encoders(bag, left_topic, right_topic)  # on the commands' clock
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
    held: List[Held] = []
    for begin_index, end in zip(changes, ends):
        begin = float(commands.t[begin_index])
        left, right = float(commands.left[begin_index]), float(commands.right[begin_index])
        middle = (begin + end) / 2
        if end - begin < HOLD_S or left == right == 0:
            continue
        if any(stream.t[0] > middle or stream.t[-1] < end for stream in streams):
            continue
        speeds = []
        last = end - EDGE_S
        for stream in streams:
            ticks = np.interp([middle, last], stream.t, stream.ticks.astype(float))
            resolution = float(stream.resolution[0])
            speeds.append((ticks[1] - ticks[0]) / (last - middle) * math.tau / resolution)
        held.append(Held(left, right, speeds[0], speeds[1]))
    return held


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
    return _points(held_commands(bag, command_topic, left_topic, right_topic))


def _points(held: List[Held]) -> Dict[str, List[Tuple[float, float]]]:
    """Each wheel's ``(|duty|, rad/s)`` from held commands, along each wheel's command."""
    points: Dict[str, List[Tuple[float, float]]] = {"left": [], "right": []}
    for command in held:
        for wheel, duty, speed in (
            ("left", command.left_duty, command.left_speed),
            ("right", command.right_duty, command.right_speed),
        ):
            if duty != 0:
                points[wheel].append((abs(duty), math.copysign(1.0, duty) * speed))
    return points


def _curve_points(held: List[Held], right_gain: float, turning: float) -> List[Tuple[float, float]]:
    """The left motor's ``(|duty|, rad/s)`` alone, from the commands that drive straight.

    A straight command gives its mean speed, a turn in place half its wheels' difference
    before the ground's resistance; the right motor is ``right_gain`` times the left one.
    """
    points = []
    scale = 2.0 / (1.0 + right_gain)
    for command in held:
        mean = 0.5 * (command.left_speed + command.right_speed)
        if abs(command.left_duty - command.right_duty) < LEVEL_STEP:
            sign = math.copysign(1.0, command.right_duty)
            points.append((abs(command.right_duty), scale * sign * mean))
        elif abs(command.left_duty + command.right_duty) < LEVEL_STEP:
            half_difference = 0.5 * (command.right_speed - command.left_speed)
            free = half_difference * (1.0 + turning * abs(mean))
            sign = math.copysign(1.0, command.right_duty)
            points.append((abs(command.right_duty), scale * sign * free))
    return points


def _predicted(
    command: Held, curve: Curve, right_gain: float, turning: float
) -> Tuple[float, float]:
    """The wheels' steady speeds (rad/s, forward) the fitted model gives for a command."""
    from duckielib.sim.robot import loaded_speeds

    left = math.copysign(_speed_on(curve, abs(command.left_duty)), command.left_duty)
    right = math.copysign(
        right_gain * _speed_on(curve, abs(command.right_duty)), command.right_duty
    )
    return loaded_speeds(left, right, turning)


def _fit_model(held: List[Held], bag: str) -> Tuple[Curve, float, float]:
    """The motors' speed curve, the right motor's gain and the turning resistance.

    They are the ones that together best predict every held command's wheel speeds (least
    squares, searched on a coarse grid and then around its best point).
    """
    moving = [
        command for command in held if not command.arc and (command.left_duty or command.right_duty)
    ]
    first_points = _curve_points(moving, 1.0, 0.0)
    if not first_points:
        raise BagError(
            f"{bag} holds no command that drives both wheels straight or turns in place, held "
            "1 s or more. " + _WHAT_TO_RECORD
        )
    _fit_curve(first_points, bag)  # a sentence if too few levels

    def error(right_gain: float, turning: float) -> Tuple[float, Curve]:
        curve = _fit_curve(_curve_points(moving, right_gain, turning), bag)
        total = 0.0
        for command in held:
            left, right = _predicted(command, curve, right_gain, turning)
            total += (left - command.left_speed) ** 2 + (right - command.right_speed) ** 2
        return total, curve

    turnings = [step * 0.05 for step in range(round(TURNING_MAX / 0.05) + 1)]
    if all(abs(command.left_duty - command.right_duty) < LEVEL_STEP for command in held):
        turnings = [0.0]  # only straight runs: the ground's resistance to turns is not seen
    best = (math.inf, 1.0, 0.0)
    for gain_step in range(-30, 31):
        for turning in turnings:
            total, _ = error(1.0 + gain_step * 0.01, turning)
            if total < best[0] - 1e-12:
                best = (total, 1.0 + gain_step * 0.01, turning)
    _, gain, turning = best
    span_gain, span_turning = 0.01, 0.05 if len(turnings) > 1 else 0.0
    for _ in range(2):  # refine: a finer grid around the best point, twice
        for gain_step in range(-10, 11):
            for turning_step in range(-10, 11):
                candidate_gain = gain + gain_step * span_gain / 10
                candidate_turning = max(0.0, turning + turning_step * span_turning / 10)
                total, _ = error(candidate_gain, candidate_turning)
                if total < best[0] - 1e-12:
                    best = (total, candidate_gain, candidate_turning)
        _, gain, turning = best
        span_gain, span_turning = span_gain / 10, span_turning / 10
    _, curve = error(gain, turning)
    return curve, round(gain, 4), round(turning, 4)


def _fit_curve(points: List[Tuple[float, float]], bag: str) -> Curve:
    """A motor's speed curve through its measured points (module doc)."""
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
            f"{bag} holds too few different commands that drive straight or turn in place and "
            f"turn the wheels, each held 1 s or more, to fit the motors (found {len(moving)}; "
            f"commands held: {held}). " + _WHAT_TO_RECORD
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


def _kinematics_gain(profile: NoiseProfile) -> float:
    """The kinematics gain with which the robot drives :data:`GAIN_SPEED` when asked.

    The kinematics node turns the speed asked into the duty ``gain * (v / R) / k``; the gain
    is the one whose duty turns the wheels (the mean of both motors) at the speed that moves
    the robot's true wheels at ``v``.
    """
    from duckielib.config import DB21
    from duckielib.sim.robot import steady_speed

    curve = profile.speed_curve or ()
    mean_gain = 0.5 * (profile.left_gain + profile.right_gain)
    asked = GAIN_SPEED / DB21.radius  # rad/s, as the kinematics node computes it
    wanted = GAIN_SPEED / (DB21.radius * profile.wheel_radius_scale)
    low, high = 0.0, 1.0
    if mean_gain * steady_speed(curve, high) < wanted:
        return round(min(10.0, high * DB21.k / asked), 3)  # even duty 1 is too slow
    for _ in range(40):
        middle = 0.5 * (low + high)
        if mean_gain * steady_speed(curve, middle) < wanted:
            low = middle
        else:
            high = middle
    return round(max(0.1, high * DB21.k / asked), 3)


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
    held = held_commands(bag, command_topic, left_topic, right_topic)
    curve, right_gain, turning = _fit_model(held, bag.path.name)
    profile = NoiseProfile.realistic(
        name=name,
        left_gain=1.0,
        right_gain=right_gain,
        breakaway_pwm=None,
        speed_curve=curve,
        turning_resistance=turning,
    )
    profile = profile.replace(name=name, kinematics_gain=_kinematics_gain(profile))
    replay = replay_bag(bag, profile, 0, command_topic, left_topic, right_topic)
    arcs = sum(command.arc for command in held)
    return Calibration(profile, _points(held), replay, arcs)


def calibration_driver(drive: Sequence[Tuple[float, float, float]] = CALIBRATION_DRIVE) -> None:
    """A node that drives the wheels through ``drive``, then stops them and returns.

    It publishes each (left, right) duty cycle on ``wheels_driver_node/wheels_cmd`` at 10 Hz
    for its seconds, as a wheel calibration on a real Duckiebot would (record that topic and
    both encoders' ticks with ``rosbag record``). Launch it on the virtual Duckiebot with
    ``bot.launch(calibration_driver)``.
    """
    import rospy

    from duckielib.ros.backend import message_classes

    WheelsCmdStamped = message_classes(rospy).WheelsCmdStamped  # noqa: N806 - a class
    rospy.init_node("calibration_driver")
    wheels = rospy.Publisher("wheels_driver_node/wheels_cmd", WheelsCmdStamped, queue_size=1)

    def stop() -> None:
        wheels.publish(WheelsCmdStamped(vel_left=0.0, vel_right=0.0))

    rospy.on_shutdown(stop)
    rate = rospy.Rate(10)
    for left, right, seconds in drive:
        end = rospy.get_time() + seconds
        while not rospy.is_shutdown() and rospy.get_time() < end - 1e-6:
            message = WheelsCmdStamped(vel_left=left, vel_right=right)
            message.header.stamp = rospy.Time.now()
            wheels.publish(message)
            rate.sleep()
    stop()


def record_calibration_drive(
    path: PathLike,
    noise: Union[str, NoiseProfile] = "realistic",
    seed: int = 0,
    drive: Sequence[Tuple[float, float, float]] = CALIBRATION_DRIVE,
) -> Path:
    """Drive :func:`calibration_driver` on a virtual Duckiebot and record the bag to calibrate.

    The bag holds the wheel commands and both encoders' ticks, as ``rosbag record`` would on a
    real robot. Returns its path.

    Raises:
        BagError: if the bag exists already.
    """
    from duckielib.bags.recorder import BagRecorder
    from duckielib.ros import Graph
    from duckielib.sim.duckiebot import VirtualDuckiebot
    from duckielib.sim.world import World

    world = World(tiles_x=12, tiles_y=12)
    start = (world.width / 2, world.height / 2, 0.0)
    bot = VirtualDuckiebot(
        seed=seed, noise=noise, graph=Graph(echo_logs=False), world=world, start_pose=start
    )
    topics = [
        bot.namespace + "wheels_driver_node/wheels_cmd",
        bot.namespace + "left_wheel_encoder_node/tick",
        bot.namespace + "right_wheel_encoder_node/tick",
    ]
    recorder = BagRecorder(path, topics, graph=bot.graph)
    try:
        bot.launch(calibration_driver, list(drive))
        bot.run(sum(seconds for _, _, seconds in drive) + 1.0)
    finally:
        recorder.close()
        bot.shutdown()
    return recorder.path


#: The robot of the course's ``calibration_drive`` sample bag (:mod:`duckielib.bags.samples`):
#: the realistic profile with weaker motors (a dead band up to duty 0.15), a right motor 7 %
#: weaker, and a ground that resists turns more.
CALIBRATION_SAMPLE_ROBOT: Dict[str, Any] = {
    "name": "calibration_sample",
    "speed_curve": ((0.15, 0.0), (0.2, 1.5), (0.3, 3.0), (0.4, 5.2), (0.55, 7.8), (1.0, 13.0)),
    "breakaway_pwm": 89,
    "right_gain": 0.93,
    "turning_resistance": 0.9,
}


def record_calibration_sample(path: PathLike) -> Path:
    """Record the ``calibration_drive`` sample bag's drive, uncompressed, to ``path``."""
    return record_calibration_drive(path, NoiseProfile.realistic(**CALIBRATION_SAMPLE_ROBOT))
