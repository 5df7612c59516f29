"""Fit the simulator's motors to a robot, from any bag of it driving.

A bag that holds the wheel commands and both encoders' ticks says how far each command really
turned each wheel, whether the commands were held (a calibration drive) or changed many times
a second (a controller closing its loop: a mission, lane following). :func:`calibrate_bag`
replays the bag's whole command sequence through the simulator's motors
(:mod:`.wheels`, the motors without the physics) and fits them by least squares: each wheel's
ticks window by window, the drift of each wheel and of the turn between them (the right
wheel's ticks minus the left's, which odometry's heading comes from) over the whole run. The
model is one speed curve (a dead band, then knots where the commands spent their time, then
the realistic curve's shape to duty 1), the right motor's gain on it and the tyres' scrub (how
much of a difference of the wheels' speeds the ground takes while the robot rolls; the scrub's
width and any further resistance keep the realistic values). What a bag cannot say (a curve
beyond the duties it drove, a ground never turned on) keeps the realistic robot's value: a
weak prior ties every parameter to it.
The fitted profile keeps the realistic profile's other imperfections (wheel size and track,
slip, encoder jitter, the encoder driver's counting rule: encoders alone cannot measure them)
and is checked by replaying the bag into it with the simulator itself (:mod:`.replay`), and
other bags of the robot too (``check``).

``duckie calibrate BAG -o robot.json`` writes the profile; ``duckie mission --noise
robot.json`` then drives a simulated robot that behaves like yours.

Laptop side; never deployed.
"""

# Over 600 lines: one fit of the motors to a bag (its runs, the motor model, the residuals and the
# least squares) beside the calibration drive it expects and the recorded samples that check it.

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from scipy.optimize import least_squares

from duckielib.bags import Bag
from duckielib.bags.analysis import encoder_resolution
from duckielib.errors import BagError
from duckielib.sim.noise import (
    REALISTIC_SCRUB_WIDTH,
    REALISTIC_SPEED_CURVE,
    REALISTIC_TURNING_SCRUB,
    NoiseProfile,
)
from duckielib.sim.replay import (
    WINDOW_S,
    ReplayReport,
    aligned_encoders,
    compared_readings,
    replay_bag,
    wheel_commands,
)
from duckielib.sim.wheels import CommandSteps, command_steps, counted_angles

__all__ = [
    "CALIBRATION_DRIVE",
    "Calibration",
    "Held",
    "calibrate_bag",
    "CALIBRATION_SAMPLE_ROBOT",
    "calibration_driver",
    "fit_profile",
    "held_commands",
    "record_calibration_drive",
    "record_calibration_sample",
    "record_other_robot_profile",
    "steady_speeds",
]

#: The shortest command that counts as held, and the part of it measured (its second half).
HOLD_S = 1.0
#: Commands closer than this are the same level.
LEVEL_STEP = 0.02
#: The last part of a held command left out of its measure, in seconds: encoders that count by
#: the command's sign count the next command's way as soon as it comes.
EDGE_S = 0.1
#: The speed the fitted kinematics gain makes right, m/s (the course's driving speed).
GAIN_SPEED = 0.2
#: A wheel counts as driven by a command of at least this duty cycle.
DRIVEN_DUTY = 0.02
#: The shares of the driven time below which the speed curve's knots lie (the duties the
#: bag's commands spent most time at), and the smallest gap between two knots.
KNOT_SHARES = (0.03, 0.25, 0.5, 0.75, 0.97)
KNOT_GAP = 0.04
#: The least driving a bag needs, in seconds with a wheel commanded and turning.
DRIVING_NEEDED_S = 1.0
#: The realistic profile's values, where a fit starts and where the bag says nothing:
#: (value, spread). A parameter the bag cannot see stays at its realistic value.
_PRIOR_DEAD_BAND = (0.12, 0.1)
_PRIOR_RIGHT_GAIN = (1.0, 0.2)
#: The right motor's gains the fit starts from, keeping the best fit.
_RIGHT_GAIN_STARTS = (0.85, 1.0, 1.15)
_PRIOR_SCRUB = (REALISTIC_TURNING_SCRUB, 3.0)
#: The largest scrub the fit tries: a little below its width (see NoiseProfile.turning_scrub).
_MOST_SCRUB = 0.99 * REALISTIC_SCRUB_WIDTH
_PRIOR_SPEED_SPREAD = 0.5  # of the realistic speed at a knot
#: The prior's weight against the bag's windows (each window one residual per wheel).
_PRIOR_WEIGHT = 0.3
#: The weight of the turn's drift (right minus left, accumulated) against the wheels' ticks.
_TURN_WEIGHT = 1.0

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
    """A fitted profile, what it was fitted on, and how well it replays bags of the robot.

    Attributes:
        profile: the fitted noise profile (save it with ``profile.save("robot.json")``).
        replays: the bags it was fitted on, replayed into the fitted profile by the simulator.
        checks: other bags of the robot (``--check``), replayed into the fitted profile.
        driven: the duties the fit saw, as ``(lowest, highest)`` commanded magnitude;
            beyond them the speed curve follows the realistic curve's shape.
        notes: what the bag could not say, and what was done about it.
    """

    profile: NoiseProfile
    replays: Tuple[ReplayReport, ...]
    checks: Tuple[ReplayReport, ...] = ()
    driven: Tuple[float, float] = (0.0, 1.0)
    notes: Tuple[str, ...] = ()

    @property
    def replay(self) -> ReplayReport:
        """The first bag it was fitted on, replayed into the fitted profile."""
        return self.replays[0]

    def figures(self) -> Dict[str, Union[str, int, float]]:
        """The fit as ``name: value`` pairs (what ``duckie calibrate`` prints)."""
        figures: Dict[str, Union[str, int, float]] = {"bag": self.replay.bag}
        curve = self.profile.speed_curve or ()
        curves = {"left": curve, "right": self.profile.right_speed_curve or curve}
        gains = {"left": self.profile.left_gain, "right": self.profile.right_gain}
        figures["calibration_dead_band"] = round(curve[0][0], 4) if curve else 0.0
        figures["calibration_driven_duties"] = f"{self.driven[0]:.2f} to {self.driven[1]:.2f}"
        for wheel in ("left", "right"):
            for duty in (0.3, 0.5, 1.0):
                speed = gains[wheel] * _speed_on(curves[wheel], duty)
                figures[f"calibration_speed_at_{duty:g}_{wheel}"] = round(speed, 3)
        figures["calibration_right_gain"] = self.profile.right_gain
        figures["calibration_turning_scrub"] = self.profile.turning_scrub
        figures["calibration_kinematics_gain"] = self.profile.kinematics_gain
        named = [("calibration", report) for report in self.replays[:1]]
        named += [
            (f"calibration_{index}", report) for index, report in enumerate(self.replays[1:], 2)
        ]
        named += [(f"check_{index}", check) for index, check in enumerate(self.checks, 1)]
        for prefix, report in named:
            if prefix != "calibration":
                figures[f"{prefix}_bag"] = report.bag
            figures[f"{prefix}_travel_ratio_left"] = round(report.left.travel_ratio, 4)
            figures[f"{prefix}_travel_ratio_right"] = round(report.right.travel_ratio, 4)
            figures[f"{prefix}_turn_ratio"] = round(report.turn_ratio, 4)
            figures[f"{prefix}_tick_rate_rms"] = round(report.tick_rate_rms, 3)
            if report.paths is not None:
                paths = report.paths.figures()
                figures[f"{prefix}_heading_ratio"] = paths["heading_ratio"]
                figures[f"{prefix}_final_gap_m"] = paths["final_gap_m"]
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
    """Every command held 1 s or more but stops, with both wheels' speeds over its second half.

    What a bag of held commands says directly; a closed-loop bag (a controller that changes
    its command many times a second) has none, and :func:`calibrate_bag` needs none.
    """
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
    """Each wheel's ``(|duty|, rad/s)`` for every command held 1 s or more.

    The speed is measured over the command's second half, along the command's direction
    (a wheel that turned the other way has a negative speed).
    """
    points: Dict[str, List[Tuple[float, float]]] = {"left": [], "right": []}
    for command in held_commands(bag, command_topic, left_topic, right_topic):
        for wheel, duty, speed in (
            ("left", command.left_duty, command.left_speed),
            ("right", command.right_duty, command.right_speed),
        ):
            if duty != 0:
                points[wheel].append((abs(duty), math.copysign(1.0, duty) * speed))
    return points


@dataclass(frozen=True)
class _Run:
    """One bag, ready to be replayed by :func:`~duckielib.sim.wheels.counted_angles`.

    Times are in seconds from the bag's first command; angles in radians from each wheel's
    first reading.
    """

    name: str
    steps: CommandSteps
    t: Tuple[np.ndarray, np.ndarray]
    angles: Tuple[np.ndarray, np.ndarray]
    edges: np.ndarray

    def duties(self) -> np.ndarray:
        """Every driven step's commanded magnitude, both wheels."""
        both = np.abs(np.concatenate([self.steps.left, self.steps.right]))
        return both[both >= DRIVEN_DUTY]


def _run_of(
    bag: Bag,
    command_topic: Optional[str],
    left_topic: Optional[str],
    right_topic: Optional[str],
) -> Tuple[_Run, Optional[str]]:
    """The bag's commands and readings on one clock (and the note if its clocks differed)."""
    commands = wheel_commands(bag, command_topic)
    streams, skew = aligned_encoders(bag, left_topic, right_topic)
    resolution = encoder_resolution(bag, *streams)
    start, end, kept = compared_readings(bag, commands, streams)
    t = [times - start for times, _ in kept]
    angles = [(ticks - ticks[0]) * math.tau / resolution for _, ticks in kept]
    steps = command_steps(commands.t - start, commands.left, commands.right, end - start)
    first = max(float(t[0][0]), float(t[1][0]))
    last = min(float(t[0][-1]), float(t[1][-1]))
    edges = np.arange(first, last + 1e-9, WINDOW_S)
    if len(edges) < 2:
        edges = np.array([first, last])
    run = _Run(bag.path.name, steps, (t[0], t[1]), (angles[0], angles[1]), edges)
    return run, skew


def _drifts(run: _Run, profile: NoiseProfile) -> Tuple[np.ndarray, np.ndarray]:
    """Each wheel's simulated minus real counted angle at the run's window edges (radians)."""
    counted = counted_angles(run.steps, profile)
    drifts = []
    for t, real, angle in zip(run.t, run.angles, counted):
        simulated = np.interp(t, run.steps.times, angle)
        drifts.append(np.interp(run.edges, t, simulated - simulated[0] - real))
    return drifts[0], drifts[1]


@dataclass(frozen=True)
class _Model:
    """The fitted parameters, as one vector.

    The dead band, the speed at each knot, the right motor's gain on that curve and the
    tyres' scrub (held at the realistic value when nothing in the bags turns the robot).
    """

    knots: Tuple[float, ...]
    ground_seen: bool = True

    def start(self) -> np.ndarray:
        speeds = [max(_speed_on(REALISTIC_SPEED_CURVE, duty), 0.1) for duty in self.knots]
        dead_band = min(_PRIOR_DEAD_BAND[0], self.knots[0] - 0.02)
        return np.array([dead_band, *speeds, 1.0, _PRIOR_SCRUB[0]])

    def bounds(self) -> Tuple[np.ndarray, np.ndarray]:
        count = len(self.knots)
        low = [0.0] + [0.0] * count + [0.5, 0.0]
        high = [max(0.001, self.knots[0] - 0.01)] + [40.0] * count + [1.5, _MOST_SCRUB]
        if not self.ground_seen:  # keep the realistic scrub: nothing in the bag tells it
            low[-1], high[-1] = _PRIOR_SCRUB[0] - 1e-9, _PRIOR_SCRUB[0] + 1e-9
        return np.array(low), np.array(high)

    def curve(self, vector: np.ndarray) -> Curve:
        """The speed curve: the dead band, the knots, then the realistic curve's shape to 1."""
        speeds = vector[1 : 1 + len(self.knots)]
        knots = [(float(vector[0]), 0.0), *zip(self.knots, speeds.tolist())]
        last_duty, last_speed = knots[-1]
        shape = _speed_on(REALISTIC_SPEED_CURVE, last_duty)
        for duty, speed in REALISTIC_SPEED_CURVE:
            if duty > last_duty + 1e-9 and shape > 0:
                knots.append((duty, last_speed * speed / shape))
        if knots[-1][0] < 1.0:
            knots.append((1.0, knots[-1][1]))
        if all(speed <= 0 for _, speed in knots):
            knots[-1] = (knots[-1][0], 1e-3)
        return tuple((round(duty, 5), round(max(speed, 0.0), 5)) for duty, speed in knots)

    def profile(self, vector: np.ndarray, name: str = "calibrated") -> NoiseProfile:
        return NoiseProfile.realistic(
            name=name,
            left_gain=1.0,
            right_gain=round(float(vector[-2]), 4),
            breakaway_pwm=None,
            speed_curve=self.curve(vector),
            turning_scrub=round(float(vector[-1]), 4),
        )

    def prior(self, vector: np.ndarray) -> np.ndarray:
        """How far the parameters are from the realistic ones, in their spreads."""
        realistic = np.array([_speed_on(REALISTIC_SPEED_CURVE, duty) for duty in self.knots])
        spread = np.maximum(_PRIOR_SPEED_SPREAD * realistic, 0.5)
        speeds = vector[1 : 1 + len(self.knots)]
        return np.concatenate(
            [
                [(vector[0] - _PRIOR_DEAD_BAND[0]) / _PRIOR_DEAD_BAND[1]],
                (speeds - realistic) / spread,
                [(vector[-2] - _PRIOR_RIGHT_GAIN[0]) / _PRIOR_RIGHT_GAIN[1]],
                [(vector[-1] - _PRIOR_SCRUB[0]) / _PRIOR_SCRUB[1]],
            ]
        )


def _knots(duties: np.ndarray) -> Tuple[float, ...]:
    """The speed curve's fitted knots: where the bag's commands spent their time (module doc)."""
    knots: List[float] = []
    for share in np.quantile(duties, KNOT_SHARES):
        duty = round(float(min(share, 1.0)), 3)
        if not knots or duty - knots[-1] >= KNOT_GAP:
            knots.append(duty)
    if len(knots) > 1 and knots[0] < 0.03:
        knots = knots[1:]
    return tuple(max(duty, 0.03) for duty in knots)


def _residuals(runs: Sequence[_Run], model: _Model, vector: np.ndarray) -> np.ndarray:
    """What the fit makes small.

    Each window's tick error per wheel, the drift of each wheel and of the turn (each bag
    weighing by its length), and the parameters' distance from the realistic ones.
    """
    profile = model.profile(vector)
    parts = []
    for run in runs:
        left, right = _drifts(run, profile)
        spread = math.sqrt(max(1, len(run.edges) - 1))
        parts += [
            np.diff(left),
            np.diff(right),
            left / spread,
            right / spread,
            _TURN_WEIGHT * (right - left) / spread,
        ]
    parts.append(_PRIOR_WEIGHT * model.prior(vector))
    return np.concatenate(parts)


def _driving_seconds(run: _Run) -> float:
    """How long a wheel was commanded and turned, in seconds."""
    turned = 0.0
    for t, angle in zip(run.t, run.angles):
        rates = np.abs(np.diff(angle)) > 0
        turned = max(turned, float(np.sum(np.diff(t)[rates])))
    commanded = float(
        np.count_nonzero(
            (np.abs(run.steps.left) >= DRIVEN_DUTY) | (np.abs(run.steps.right) >= DRIVEN_DUTY)
        )
        * run.steps.dt
    )
    return min(turned, commanded)


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


def fit_profile(
    bags: Union[Bag, PathLike, Sequence[Union[Bag, PathLike]]],
    name: str = "calibrated",
    command_topic: Optional[str] = None,
    left_topic: Optional[str] = None,
    right_topic: Optional[str] = None,
) -> Tuple[NoiseProfile, Tuple[float, float], Tuple[str, ...]]:
    """The profile that best replays a bag's whole command sequence (module doc).

    Several bags of one robot are fitted together.

    Returns:
        The profile, the duties the fit saw (lowest, highest) and notes on what the bags
        could not say.

    Raises:
        BagError: if a bag lacks the commands or the encoders, or never drives a wheel.
    """
    many: List[Any] = list(bags) if isinstance(bags, (list, tuple)) else [bags]
    runs, notes = [], []
    for item in many:
        bag = item if isinstance(item, Bag) else Bag(item)
        run, skew = _run_of(bag, command_topic, left_topic, right_topic)
        notes += [] if skew is None else [skew]
        driving = _driving_seconds(run)
        if driving < DRIVING_NEEDED_S:
            raise BagError(
                f"{bag.path.name} drives the wheels for {driving:.1f} s only (a wheel commanded "
                "and turning), too little to say how the motors answer their commands: record "
                f"{DRIVING_NEEDED_S:g} s or more of driving (any driving, your mission included) "
                "with the wheel commands and both encoders, and calibrate again."
            )
        runs.append(run)
    duties = np.concatenate([run.duties() for run in runs])
    differs = max(float(np.max(np.abs(run.steps.left - run.steps.right))) for run in runs)
    model = _Model(_knots(duties), ground_seen=differs >= LEVEL_STEP)
    fit = None
    for right_gain in _RIGHT_GAIN_STARTS:  # the fit has a valley for each way the robot pulls
        start = model.start()
        start[-2] = right_gain
        tried = least_squares(
            lambda vector: _residuals(runs, model, vector),
            start,
            bounds=model.bounds(),
            x_scale="jac",
            diff_step=1e-3,
        )
        if fit is None or tried.cost < fit.cost:
            fit = tried
    assert fit is not None  # _RIGHT_GAIN_STARTS is not empty
    driven = (float(np.quantile(duties, 0.02)), float(np.quantile(duties, 0.98)))
    if not model.ground_seen:
        notes.append(
            "The wheels are never driven at different commands, so nothing says how the "
            "ground resists turning: the realistic robot's value is kept."
        )
    profile = model.profile(fit.x, name)
    profile = profile.replace(name=name, kinematics_gain=_kinematics_gain(profile))
    return profile, driven, tuple(notes)


def calibrate_bag(
    bag: Union[Bag, PathLike, Sequence[Union[Bag, PathLike]]],
    name: str = "calibrated",
    command_topic: Optional[str] = None,
    left_topic: Optional[str] = None,
    right_topic: Optional[str] = None,
    check: Sequence[Union[Bag, PathLike]] = (),
    solution: Any = None,
) -> Calibration:
    """Fit the motors and the ground to a bag and replay it, and other bags, into the fit.

    Args:
        bag: a :class:`~duckielib.bags.Bag` or a bag's path, with the wheel commands
            (``wheels_driver_node/wheels_cmd``) and both encoders' ticks; or several bags of
            one robot, fitted together. Any driving will do: a mission, lane following, held
            commands.
        name: the fitted profile's name.
        command_topic: the wheel commands' topic (default: found by type and name).
        left_topic: the left encoder's topic (default: found by name).
        right_topic: the right encoder's topic (default: found by name).
        check: other bags of the same robot, replayed into the fitted profile to see how
            well it predicts runs it was not fitted on.
        solution: what holds the odometry (``delta_phi``, ``estimate_pose``,
            ``WheelPairing``): with it, each replay also compares the headings and paths.

    Raises:
        BagError: if a bag lacks the topics, or the bags to fit never drive the wheels.
    """
    bags: List[Any] = list(bag) if isinstance(bag, (list, tuple)) else [bag]
    opened = [item if isinstance(item, Bag) else Bag(item) for item in bags]
    others = [item if isinstance(item, Bag) else Bag(item) for item in check]  # before the fit
    profile, driven, notes = fit_profile(opened, name, command_topic, left_topic, right_topic)
    replays = tuple(
        replay_bag(item, profile, 0, command_topic, left_topic, right_topic, solution)
        for item in opened
    )
    checks = tuple(replay_bag(other, profile, 0, solution=solution) for other in others)
    return Calibration(profile, replays, checks, driven, notes)


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
#: weaker, and tyres that scrub less (a small difference of the wheels' speeds keeps 30 % of
#: itself, against the realistic 9 %).
CALIBRATION_SAMPLE_ROBOT: Dict[str, Any] = {
    "name": "calibration_sample",
    "speed_curve": ((0.15, 0.0), (0.2, 1.5), (0.3, 3.0), (0.4, 5.2), (0.55, 7.8), (1.0, 13.0)),
    "breakaway_pwm": 89,
    "right_gain": 0.93,
    "turning_scrub": 5.0,
}


def record_calibration_sample(path: PathLike) -> Path:
    """Record the ``calibration_drive`` sample bag's drive, uncompressed, to ``path``."""
    return record_calibration_drive(path, NoiseProfile.realistic(**CALIBRATION_SAMPLE_ROBOT))


def record_other_robot_profile(path: PathLike) -> Path:
    """Write the sample robot's profile (:data:`CALIBRATION_SAMPLE_ROBOT`) to a JSON file.

    ``duckie mission --noise`` with it drives the ``square_then_circle_other_robot`` sample.
    """
    return NoiseProfile.realistic(**CALIBRATION_SAMPLE_ROBOT).save(path)
