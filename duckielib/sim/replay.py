"""Replay a bag's wheel commands into the simulator and compare its ticks with the bag's.

A bag recorded on a robot (or in the simulator) that holds the wheel commands
(``wheels_driver_node/wheels_cmd``, duckietown_msgs/WheelsCmdStamped) and both encoders' ticks
says how far each command really turned each wheel. :func:`replay_bag` sends the same commands,
at the same times from the bag's first command, to a simulated robot with a noise profile, and
reads its encoders at the times the bag's encoders were read. The comparison, per wheel:

- ``travel``: how many ticks the wheel turned in all (forward and back both count);
- ``travel_ratio``: simulated over real travel (1 when the profile is right);
- ``tick_rate_rms``: the root mean square, over consecutive 1 s windows, of the difference
  between the simulated and the real tick rate, in ticks per second.

``duckie sim replay BAG`` prints them; ``duckie calibrate`` fits a profile that brings them
close to 1 and 0.

Laptop side; never deployed.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np

from duckielib.bags import Bag, read_encoders, read_topic
from duckielib.bags.analysis import (
    EncoderStream,
    PoseTrack,
    encoder_resolution,
    odometry_of_streams,
)
from duckielib.errors import BagError
from duckielib.sim.encoders import EncoderReading
from duckielib.sim.noise import NoiseProfile, noise_profile
from duckielib.sim.simulator import Simulator
from duckielib.sim.world import World

__all__ = [
    "Commands",
    "Paths",
    "ReplayReport",
    "WheelReplay",
    "aligned_encoders",
    "compared_readings",
    "replay_bag",
    "wheel_commands",
]

#: The wheel commands' type, and the topics that carry them (the first found is used).
COMMAND_TYPE = "duckietown_msgs/WheelsCmdStamped"
_COMMAND_TOPICS = ("wheels_driver_node/wheels_cmd", "wheels_driver_node/wheels_cmd_executed")
#: A mat large enough that a replayed run never meets a wall.
_OPEN_FLOOR = World(tiles_x=60, tiles_y=60)
#: How long after the last command the wheels are still compared (they coast to a stop).
COAST_S = 1.0
#: The length of the windows whose tick rates are compared, in seconds.
WINDOW_S = 1.0
#: The least net turn, as a share of the wheels' travel, for which ``turn_ratio`` is given.
TURN_SHARE = 0.05
#: A robot's clock this far from the recorder's (seconds) is said, and the times aligned.
SKEW_LIMIT_S = 0.5

PathLike = Union[str, "os.PathLike[str]"]


@dataclass(frozen=True)
class Commands:
    """A bag's wheel commands, in order.

    Attributes:
        topic: the topic they came from.
        t: their record times (when the driver received them), in seconds.
        left: the left wheel's duty cycles.
        right: the right wheel's duty cycles.
    """

    topic: str
    t: np.ndarray
    left: np.ndarray
    right: np.ndarray


@dataclass(frozen=True)
class WheelReplay:
    """One wheel, real against simulated.

    Attributes:
        wheel: ``"left"`` or ``"right"``.
        real_travel: the ticks the real wheel turned, in all.
        sim_travel: the ticks the simulated wheel turned, in all.
        travel_ratio: ``sim_travel / real_travel`` (NaN if the real wheel never turned).
        tick_rate_rms: the 1 s tick-rate error, in ticks per second.
    """

    wheel: str
    real_travel: int
    sim_travel: int
    travel_ratio: float
    tick_rate_rms: float


@dataclass(frozen=True)
class Paths:
    """Where odometry puts the robot, from the bag's ticks and from the simulated ones.

    All three start at (0, 0, 0) when the first command is sent.

    Attributes:
        real: odometry from the bag's ticks (the real robot, as its odometry saw it).
        sim: odometry from the simulated ticks, read at the same times.
        truth: the simulated robot's true path.
    """

    real: PoseTrack
    sim: PoseTrack
    truth: PoseTrack

    @staticmethod
    def heading_change(track: PoseTrack) -> float:
        """How far a track turned in all, counter-clockwise positive, in radians."""
        if len(track.theta) < 2:
            return 0.0
        unwrapped = np.unwrap(track.theta)
        return float(unwrapped[-1] - unwrapped[0])

    def figures(self) -> Dict[str, float]:
        """The headings and final poses, and their gaps (what ``duckie sim replay`` prints)."""
        figures: Dict[str, float] = {}
        for name, track in (("real", self.real), ("sim", self.sim), ("sim_truth", self.truth)):
            figures[f"heading_change_{name}_rad"] = round(self.heading_change(track), 4)
        for name, track in (("real", self.real), ("sim", self.sim), ("sim_truth", self.truth)):
            figures[f"final_x_{name}_m"] = round(float(track.x[-1]), 4)
            figures[f"final_y_{name}_m"] = round(float(track.y[-1]), 4)
        real, sim = self.heading_change(self.real), self.heading_change(self.sim)
        figures["heading_ratio"] = round(sim / real, 4) if abs(real) > 1e-9 else math.nan
        figures["heading_gap_rad"] = round(sim - real, 4)
        gap = math.hypot(
            float(self.sim.x[-1] - self.real.x[-1]), float(self.sim.y[-1] - self.real.y[-1])
        )
        figures["final_gap_m"] = round(gap, 4)
        return figures


@dataclass(frozen=True)
class ReplayReport:
    """What a replay found, wheel by wheel, and the whole run's figures.

    Attributes:
        bag: the bag's file name.
        noise: the noise profile's name.
        commands: how many commands were replayed, and from which topic.
        duration: the seconds compared, from the first command.
        left, right: each wheel's comparison.
        tick_rate_rms: the 1 s tick-rate error over both wheels, in ticks per second.
        real_ticks, sim_ticks: each wheel's counts at the compared times, from 0 (for plots).
        t: each wheel's compared times (its real encoder's readings), in seconds from the
            first command.
    """

    bag: str
    noise: str
    commands: int
    command_topic: str
    duration: float
    left: WheelReplay
    right: WheelReplay
    tick_rate_rms: float
    t: Tuple[np.ndarray, np.ndarray]
    real_ticks: Tuple[np.ndarray, np.ndarray]
    sim_ticks: Tuple[np.ndarray, np.ndarray]
    paths: Optional[Paths] = None
    notes: Tuple[str, ...] = ()

    def turn(self, which: str) -> int:
        """How far the robot turned in ticks: the right wheel's net ticks minus the left's.

        Odometry's heading change is proportional to it, so ``turn_ratio`` is the simulated
        heading change over the real one, whatever odometry computes it.
        ``which``: ``"real"`` or ``"sim"``.
        """
        left, right = self.real_ticks if which == "real" else self.sim_ticks
        return int(right[-1] - right[0]) - int(left[-1] - left[0])

    @property
    def turn_ratio(self) -> float:
        """The simulated turn over the real one.

        NaN when the real robot's net turn is under :data:`TURN_SHARE` of its wheels' mean
        travel (a run that comes back to its heading): a ratio of two small numbers says
        nothing there, and the turns in ticks and the paths do.
        """
        real = self.turn("real")
        travel = 0.5 * (self.left.real_travel + self.right.real_travel)
        return self.turn("sim") / real if real and abs(real) >= TURN_SHARE * travel else math.nan

    def figures(self) -> Dict[str, Union[str, int, float]]:
        """The report as ``name: value`` pairs (what ``duckie sim replay`` prints)."""
        figures: Dict[str, Union[str, int, float]] = {
            "bag": self.bag,
            "noise": self.noise,
            "commands": self.commands,
            "command_topic": self.command_topic,
            "duration_s": round(self.duration, 3),
        }
        for side in (self.left, self.right):
            figures[f"real_travel_{side.wheel}"] = side.real_travel
            figures[f"sim_travel_{side.wheel}"] = side.sim_travel
            figures[f"travel_ratio_{side.wheel}"] = round(side.travel_ratio, 4)
            figures[f"tick_rate_rms_{side.wheel}"] = round(side.tick_rate_rms, 3)
        figures["tick_rate_rms"] = round(self.tick_rate_rms, 3)
        figures["turn_ticks_real"] = self.turn("real")
        figures["turn_ticks_sim"] = self.turn("sim")
        figures["turn_ratio"] = round(self.turn_ratio, 4)
        if self.paths is not None:
            figures.update(self.paths.figures())
        return figures


def wheel_commands(bag: Union[Bag, PathLike], topic: Optional[str] = None) -> Commands:
    """The wheel commands a bag holds (``wheels_driver_node/wheels_cmd`` by preference).

    Raises:
        BagError: if the bag holds no wheel commands, or ``topic`` is not a topic of them.
    """
    bag = bag if isinstance(bag, Bag) else Bag(bag)
    found = bag.topics_of_type(COMMAND_TYPE)
    if topic is None:
        for ending in _COMMAND_TOPICS:
            topic = next((name for name in found if name.endswith(ending)), None)
            if topic is not None:
                break
        else:
            topic = found[0] if found else None
    if topic is None or topic not in found:
        what = f"{topic} is not a topic of them" if topic else "it has none"
        raise BagError(
            f"{bag.path.name} needs the wheel commands ({COMMAND_TYPE} on "
            f"wheels_driver_node/wheels_cmd) to be replayed, but {what}. Record that topic "
            "together with both wheels' encoder ticks."
        )
    arrays = read_topic(bag, topic, time_base="record")  # when the driver got each one
    if len(arrays) == 0:
        raise BagError(f"{topic} in {bag.path.name} holds no command to replay.")
    return Commands(topic, arrays.t, arrays["vel_left"], arrays["vel_right"])


def _travel(ticks: np.ndarray) -> int:
    return int(np.abs(np.diff(ticks)).sum()) if len(ticks) > 1 else 0


def _rate_error(t: np.ndarray, real: np.ndarray, sim: np.ndarray) -> np.ndarray:
    """Simulated minus real tick rate in each whole 1 s window, in ticks per second."""
    if len(t) < 2 or t[-1] - t[0] < WINDOW_S:
        return np.array([])
    edges = np.arange(t[0], t[-1] + 1e-9, WINDOW_S)
    real_at = np.interp(edges, t, real)
    sim_at = np.interp(edges, t, sim)
    return (np.diff(sim_at) - np.diff(real_at)) / WINDOW_S


def _rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(values**2))) if len(values) else 0.0


def replay_bag(
    bag: Union[Bag, PathLike],
    noise: Union[str, NoiseProfile] = "realistic",
    seed: int = 0,
    command_topic: Optional[str] = None,
    left_topic: Optional[str] = None,
    right_topic: Optional[str] = None,
    solution: Any = None,
) -> ReplayReport:
    """Replay a bag's wheel commands into the simulator and compare the ticks (module doc).

    Args:
        bag: a :class:`~duckielib.bags.Bag` or a bag's path.
        noise: the simulated robot's noise profile: a name, a profile file or a profile.
        seed: the simulator's seed.
        command_topic: the wheel commands' topic (default: found by type and name).
        left_topic: the left encoder's topic (default: found by name).
        right_topic: the right encoder's topic (default: found by name).
        solution: what holds the odometry (``delta_phi``, ``estimate_pose``,
            ``WheelPairing``): with it, the report also says where odometry puts the robot
            from the bag's ticks and from the simulated ones, and where the simulated robot
            really went (:class:`Paths`). None: travel and tick rates only.

    Raises:
        BagError: if the bag lacks the commands or the encoders, or they do not overlap.
        SolutionError: if the solution's odometry is missing, unfinished or fails.
    """
    bag = bag if isinstance(bag, Bag) else Bag(bag)
    profile = noise_profile(noise)
    commands = wheel_commands(bag, command_topic)
    streams, skew = aligned_encoders(bag, left_topic, right_topic)
    notes = [] if skew is None else [skew]
    start, end, kept = compared_readings(bag, commands, streams)
    # The simulated robot is switched on when the bag starts, and stands still until the
    # first command: a bag of the simulator replays on its own clock, reading for reading.
    # (To the millisecond: a bag written here starts at 1 ns, ROS's smallest valid time.)
    origin = min(start, math.floor(bag.start_ns / 1e6) / 1e3)
    sim = Simulator(
        seed=seed,
        noise=profile,
        world=_OPEN_FLOOR,
        start_pose=(_OPEN_FLOOR.width / 2, _OPEN_FLOOR.height / 2, 0.0),
        trace_rate_hz=0 if solution is None else 50.0,
    )
    readings = _replayed(sim, commands, origin, end)
    sampled = _sampled(readings, kept, origin)
    sides, errors = _compared(kept, sampled)
    paths = None
    if solution is not None:
        resolution = encoder_resolution(bag, *streams)
        paths = _paths(solution, resolution, kept, sampled, sim, (start, origin))
    return ReplayReport(
        bag=bag.path.name,
        noise=profile.name,
        commands=len(commands.t),
        command_topic=commands.topic,
        duration=end - start,
        left=sides[0],
        right=sides[1],
        tick_rate_rms=_rms(np.concatenate(errors)),
        t=(kept[0][0] - start, kept[1][0] - start),
        real_ticks=(kept[0][1] - kept[0][1][0], kept[1][1] - kept[1][1][0]),
        sim_ticks=(sampled[0] - sampled[0][0], sampled[1] - sampled[1][0]),
        paths=paths,
        notes=tuple(notes),
    )


def _replayed(
    sim: Simulator, commands: Commands, origin: float, end: float
) -> List[EncoderReading]:
    """The simulated encoders' readings as ``sim`` follows ``commands`` until ``end``.

    ``origin`` is the bag's time at the simulator's 0 s; times in seconds.
    """
    readings: List[EncoderReading] = []
    for when, left, right in zip(commands.t - origin, commands.left, commands.right):
        sim.run_until(when)
        sim.set_wheel_duties(float(left), float(right))
        readings += sim.pop_encoder_readings()
    sim.run_until(end - origin)
    readings += sim.pop_encoder_readings()
    return readings


def _sampled(
    readings: List[EncoderReading], kept: List[Tuple[np.ndarray, np.ndarray]], origin: float
) -> List[np.ndarray]:
    """The simulated counts of each wheel (left, right) at the bag's reading times.

    The simulated encoders' own readings, each read at the bag's reading times (the last one
    at or before each): with the bag's own seed and profile, the very same counts.
    """
    sampled = []
    for wheel, (t, _) in zip(("left", "right"), kept):
        own = [(r.time, r.ticks) for r in readings if r.wheel == wheel]
        own_t = np.array([0.0] + [time for time, _ in own])
        own_ticks = np.array([own[0][1] if own else 0] + [ticks for _, ticks in own], np.int64)
        at = np.searchsorted(own_t, t - origin + 1e-9, side="right") - 1
        sampled.append(own_ticks[np.clip(at, 0, len(own_ticks) - 1)])
    return sampled


def _compared(
    kept: List[Tuple[np.ndarray, np.ndarray]], sampled: List[np.ndarray]
) -> Tuple[List[WheelReplay], List[np.ndarray]]:
    """Each wheel's travel, real and simulated, and its tick rate errors over time."""
    sides = []
    errors = []
    for wheel, (t, real_counts), sim_counts in zip(("left", "right"), kept, sampled):
        real = real_counts - real_counts[0]
        simulated = sim_counts - sim_counts[0]
        error = _rate_error(t, real.astype(float), simulated.astype(float))
        errors.append(error)
        real_travel, sim_travel = _travel(real), _travel(simulated)
        ratio = sim_travel / real_travel if real_travel else math.nan
        sides.append(WheelReplay(wheel, real_travel, sim_travel, ratio, _rms(error)))
    return sides, errors


def compared_readings(
    bag: Bag, commands: Commands, streams: Tuple[EncoderStream, EncoderStream]
) -> Tuple[float, float, List[Tuple[np.ndarray, np.ndarray]]]:
    """The span where commands and readings are compared, and each wheel's readings there.

    It runs from the first command to the last one's coast (or the readings' end); the
    readings are (times, ticks).

    Raises:
        BagError: if a wheel has fewer than two readings there.
    """
    start = float(commands.t[0])
    end = min(float(commands.t[-1]) + COAST_S, *(float(s.t[-1]) for s in streams))
    kept = [_within(stream, start, end) for stream in streams]
    if any(len(t) < 2 for t, _ in kept):
        raise BagError(
            f"{bag.path.name} has fewer than two encoder readings of a wheel while its wheel "
            "commands run: record the encoders and the commands at the same time."
        )
    return start, end, kept


def aligned_encoders(
    bag: Bag, left_topic: Optional[str] = None, right_topic: Optional[str] = None
) -> Tuple[Tuple[EncoderStream, EncoderStream], Optional[str]]:
    """Both encoders' readings on the recorder's clock, the one the wheel commands are read on.

    A robot's clock may be far from the recorder's (a robot whose clock was never set: in
    some real bags it runs a minute ahead). The readings are timed by their header stamps,
    which the robot wrote, and those are moved by the clocks' gap, measured as the median
    difference between each reading's stamp and the time it was recorded: their spacing
    stays the robot's own.

    Returns:
        The two streams, and a sentence saying what was moved, or None when nothing was.
    """
    streams = read_encoders(bag, left_topic, right_topic)
    if streams[0].time_base != "header":
        return streams, None
    recorded = read_encoders(bag, left_topic, right_topic, time_base="record")
    stamped = np.concatenate([np.sort(stream.t) for stream in streams])
    written = np.concatenate([np.sort(stream.t) for stream in recorded])
    skew = float(np.median(stamped - written)) if len(stamped) == len(written) else 0.0
    if abs(skew) <= SKEW_LIMIT_S:
        return streams, None
    moved = tuple(dataclasses.replace(stream, t=stream.t - skew) for stream in streams)
    side = "ahead of" if skew > 0 else "behind"
    note = (
        f"The robot's clock ran {abs(skew):.2f} s {side} the recorder's (the encoders' "
        "header stamps against the times they were recorded): the encoders' times were moved "
        "onto the recorder's clock, on which the wheel commands are read."
    )
    return (moved[0], moved[1]), note


def _paths(
    solution: Any,
    resolution: int,
    kept: List[Tuple[np.ndarray, np.ndarray]],
    sampled: List[np.ndarray],
    sim: Simulator,
    clocks: Tuple[float, float],
) -> Paths:
    """Odometry from the bag's and the simulated ticks, and the simulated truth, from (0, 0, 0).

    ``clocks`` is (the first command's time, the simulator's zero), both on the bag's clock;
    the tracks' times are seconds from the first command.
    """
    start, origin = clocks
    tracks = []
    for label, counts in (
        ("real ticks", [ticks for _, ticks in kept]),
        ("simulated ticks", sampled),
    ):
        left, right = (
            EncoderStream(
                wheel,
                t - start,
                np.asarray(ticks, np.int64),
                np.full(len(t), resolution),
                "record",
            )
            for wheel, (t, _), ticks in zip(("left", "right"), kept, counts)
        )
        tracks.append(
            odometry_of_streams(left, right, solution, resolution, (0.0, 0.0, 0.0), label=label)
        )
    trace = sim.trace
    times = np.asarray(trace.times)
    keep = times >= start - origin - 1e-9
    poses = trace.poses()[keep]
    x0, y0, theta0 = poses[0]
    dx, dy = poses[:, 0] - x0, poses[:, 1] - y0
    cos, sin = math.cos(-theta0), math.sin(-theta0)
    truth = PoseTrack(
        times[keep] - (start - origin),
        cos * dx - sin * dy,
        sin * dx + cos * dy,
        np.unwrap(poses[:, 2]) - theta0,
        "simulated truth",
    )
    real, simulated = tracks
    return Paths(real, simulated, truth)


def _within(stream: EncoderStream, start: float, end: float) -> Tuple[np.ndarray, np.ndarray]:
    """A wheel's readings from ``start`` to ``end`` (seconds)."""
    keep = (stream.t >= start) & (stream.t <= end)
    return stream.t[keep], stream.ticks[keep].astype(np.int64)
