"""What a mission's bag shows the robot did: its states, LED colours, stops and where it ended.

A mission node announces each state by publishing the state's name on ``~state``
(``std_msgs/String``) when the state starts, and ``"done"`` when the mission is over. The bag
of the run holds those announcements, the LED emitter's ``led_pattern``, the odometry's pose
and the simulator's ground truth; :func:`mission_report` reads them and compares them with the
:class:`~duckielib.missions.Mission` that was asked for. ``duckie mission`` writes the report to
``summary.json``; notebook 09 and the class grader score a student's mission with it.

The checks are about behaviour, never about how the code is written: the states and colours in
order, each stop standing still for its time, the robot standing still after ``"done"`` (the
runner watches it for a few seconds more), and the true end near the start.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Set, Tuple, Union

import numpy as np

from duckielib.bags.analysis import PoseTrack, pose_tracks
from duckielib.bags.reader import Bag, PathLike
from duckielib.leds import named_pattern
from duckielib.missions import Mission, Pose
from duckielib.rostime import NS_PER_S

__all__ = [
    "AFTER_DONE_S",
    "CLOSURE_TOLERANCE_M",
    "COAST_S",
    "DONE",
    "STILL_AFTER_DONE_S",
    "STILL_TOLERANCE_M",
    "STILL_TURN_TOLERANCE",
    "STOP_TOLERANCE_S",
    "MissionReport",
    "StateRun",
    "led_messages",
    "mission_report",
]

#: What the mission node publishes on ``~state`` when the mission is over.
DONE = "done"

#: A stop may last this much longer or shorter than asked, in seconds.
STOP_TOLERANCE_S = 0.5

#: During a stop the robot may move this far (truth), in metres.
STILL_TOLERANCE_M = 0.01

#: The true end must be this close to the start, in metres.
CLOSURE_TOLERANCE_M = 0.10
#: Touches of a wall less than this apart (seconds) are said as one.
CONTACT_GAP_S = 1.0

#: After ``done`` the wheels have this long to come to rest (the motors lag), in seconds.
COAST_S = 0.5

#: Then the robot must stand still this long (within :data:`STILL_TOLERANCE_M`, and turning
#: less than :data:`STILL_TURN_TOLERANCE`), in seconds: a node that ends without a zero
#: command leaves the wheels turning.
STILL_AFTER_DONE_S = 5.0

#: How long the runner watches the robot after the mission node returns, in seconds.
AFTER_DONE_S = COAST_S + STILL_AFTER_DONE_S

#: While it stands still after ``done`` the robot may turn this much on the spot, in radians.
STILL_TURN_TOLERANCE = math.radians(2.0)


@dataclass
class StateRun:
    """One state as the bag shows it.

    Attributes:
        name: the name the mission node announced.
        color: the LED pattern shown during the state (``"RED"``; ``"custom"`` or
            ``"unknown"`` when no named pattern matches).
        start: when it was announced, in seconds from the mission's start.
        end: when the next state (or the end) was announced, in seconds.
        moved: how far the robot really moved during the state, in metres.
    """

    name: str
    color: str
    start: float
    end: float
    moved: float

    @property
    def duration(self) -> float:
        """How long the state lasted, in seconds."""
        return self.end - self.start

    def as_dict(self) -> Dict[str, Any]:
        """The state for ``summary.json``."""
        return {
            "name": self.name,
            "color": self.color,
            "start": round(self.start, 3),
            "end": round(self.end, 3),
            "moved": round(self.moved, 4),
        }


@dataclass
class MissionReport:
    """What a mission's run did, and how it compares with the mission asked for.

    Attributes:
        mission: the mission asked for.
        states: the states the bag shows, in order.
        finished: whether the mission node announced the end.
        total_time: from the first state's start to the end (or the last message), seconds.
        started: the record time of the first announcement, in seconds: the zero of the
            states' ``start`` and ``end`` (0 when the bag has none).
        final_pose_odometry: the last pose of the odometry, (x, y, theta), or None.
        final_pose_truth: where the robot really was at the end, (x, y, theta), or None.
        distance_to_start: true end to the mission's start, in metres, or None.
        after_done: how the robot really moved once ``done`` was announced and the wheels had
            :data:`COAST_S` to come to rest: (seconds watched, at most
            :data:`STILL_AFTER_DONE_S`; metres rolled; radians turned), or None when the bag
            shows no ``done`` or no truth after it.
        wall_contacts: when the robot touched one of the mat's walls, as (start, end) in
            seconds from ``started`` (the simulator's ``simulator_node/wall_contact``; empty
            when it never did, or the bag cannot tell).
        problems: what differs from the mission, one sentence each (empty when all is well).
    """

    mission: Mission
    states: List[StateRun] = field(default_factory=list)
    finished: bool = False
    total_time: float = 0.0
    started: float = 0.0
    final_pose_odometry: Optional[Pose] = None
    final_pose_truth: Optional[Pose] = None
    distance_to_start: Optional[float] = None
    after_done: Optional[Tuple[float, float, float]] = None
    wall_contacts: List[Tuple[float, float]] = field(default_factory=list)
    problems: List[str] = field(default_factory=list)

    @property
    def states_in_order(self) -> bool:
        """Whether the states' names and colours are the mission's, in order."""
        expected = [(state.name, state.color) for state in self.mission.states]
        return [(run.name, run.color) for run in self.states] == expected

    @property
    def still_after_done(self) -> bool:
        """Whether the robot stood still after ``done`` (True when the bag cannot tell)."""
        if self.after_done is None:
            return True
        _, rolled, turned = self.after_done
        return rolled <= STILL_TOLERANCE_M and turned <= STILL_TURN_TOLERANCE

    @property
    def stops_held(self) -> bool:
        """Whether every stop held its time and stood still, and so did the end (``done``).

        Each stop state must last its time (within tolerance) standing still, and after
        ``done`` the robot must stand still too (:attr:`still_after_done`).
        """
        if not self.states_in_order or not self.still_after_done:
            return False
        return all(
            _stop_problem(state, run) is None
            for state, run in zip(self.mission.states, self.states)
            if state.is_stop
        )

    @property
    def closed(self) -> bool:
        """Whether the true end is within :data:`CLOSURE_TOLERANCE_M` of the start."""
        return self.distance_to_start is not None and (
            self.distance_to_start <= CLOSURE_TOLERANCE_M
        )

    @property
    def odometry_error(self) -> Optional[Tuple[float, float]]:
        """(distance in metres, |heading difference| in radians) from odometry to truth."""
        if self.final_pose_odometry is None or self.final_pose_truth is None:
            return None
        (xo, yo, to), (xt, yt, tt) = self.final_pose_odometry, self.final_pose_truth
        turn = abs((to - tt + math.pi) % (2 * math.pi) - math.pi)
        return math.hypot(xo - xt, yo - yt), turn

    def as_dict(self) -> Dict[str, Any]:
        """The report as plain data for ``summary.json``."""
        error = self.odometry_error
        return {
            "mission": self.mission.name,
            "finished": self.finished,
            "states": [run.as_dict() for run in self.states],
            "total_time": round(self.total_time, 3),
            "final_pose_odometry": _rounded(self.final_pose_odometry),
            "final_pose_truth": _rounded(self.final_pose_truth),
            "distance_to_start": _round(self.distance_to_start),
            "after_done": None
            if self.after_done is None
            else {
                key: round(value, 4)
                for key, value in zip(("seconds", "rolled", "turned"), self.after_done)
            },
            "odometry_error": None
            if error is None
            else {"distance": round(error[0], 4), "heading": round(error[1], 4)},
            "wall_contacts": [
                [round(start, 3), round(end, 3)] for start, end in self.wall_contacts
            ],
            "checks": {
                "states_in_order": self.states_in_order,
                "stops_held": self.stops_held,
                "still_after_done": self.still_after_done,
                "closed": self.closed,
            },
            "problems": list(self.problems),
        }


def _round(value: Optional[float], digits: int = 4) -> Optional[float]:
    return None if value is None else round(value, digits)


def _rounded(pose: Optional[Pose]) -> Optional[List[float]]:
    return None if pose is None else [round(value, 4) for value in pose]


def _pattern_name(message: Any) -> str:
    """The named pattern whose colours and blinking an ``LEDPattern`` message shows."""
    named = named_pattern(message.color_list, message.frequency)
    if named is not None:
        return named.name
    return "custom" if "custom" in message.color_list else "unknown"


def led_messages(bag: Bag, topic: str) -> List[Tuple[float, Any]]:
    """The LED emitter's ``LEDPattern`` messages on ``topic``, with when each was shown.

    The emitter stamps each pattern when it shows it. A recorder in another process may
    connect to the latched topic late and receive the pattern later (its record time), so
    the stamps are used unless every one is 0 (an emitter that does not stamp).

    Returns:
        (time in seconds, message) pairs, in time order.
    """
    records = [
        (item.time, item.message.header.stamp.to_nsec() / NS_PER_S, item.message)
        for item in bag.read(topic)
    ]
    stamped = any(stamp for _, stamp, _ in records)
    shown = [(stamp if stamped else t, message) for t, stamp, message in records]
    return sorted(shown, key=lambda pair: pair[0])


def _led_changes(bag: Bag, topic: str) -> List[Tuple[float, str]]:
    """When each LED pattern was shown, in time order, and its name."""
    return [(t, _pattern_name(message)) for t, message in led_messages(bag, topic)]


def _track(tracks: Sequence[PoseTrack], suffix: str) -> Optional[PoseTrack]:
    for track in tracks:
        if track.label.endswith(suffix) and len(track):
            return track
    return None


def _pose_at(track: PoseTrack, t: float) -> Pose:
    index = max(0, int(np.searchsorted(track.t, t, side="right")) - 1)
    return float(track.x[index]), float(track.y[index]), float(track.theta[index])


def _moved(track: Optional[PoseTrack], start: float, end: float) -> float:
    """The largest distance from the pose at ``start`` reached until ``end`` (truth)."""
    if track is None:
        return float("nan")
    inside = (track.t >= start) & (track.t <= end)
    x0, y0, _ = _pose_at(track, start)
    if not inside.any():
        return 0.0
    return float(np.max(np.hypot(track.x[inside] - x0, track.y[inside] - y0)))


def _after_done(track: PoseTrack, done: float) -> Optional[Tuple[float, float, float]]:
    """(seconds watched, metres rolled, radians turned) after ``done`` and the coast (truth)."""
    start = done + COAST_S
    inside = (track.t > start) & (track.t <= start + STILL_AFTER_DONE_S)
    if not inside.any():
        return None
    x0, y0, theta0 = _pose_at(track, start)
    x = np.concatenate(([x0], track.x[inside]))
    y = np.concatenate(([y0], track.y[inside]))
    theta = np.unwrap(np.concatenate(([theta0], track.theta[inside])))
    rolled = float(np.sum(np.hypot(np.diff(x), np.diff(y))))
    turned = float(np.max(np.abs(theta - theta[0])))
    return float(track.t[inside][-1]) - start, rolled, turned


def _after_done_problem(report: MissionReport) -> str:
    """The sentence for wheels that still turn after ``done``."""
    assert report.after_done is not None
    seconds, rolled, turned = report.after_done
    moved = []
    if rolled > STILL_TOLERANCE_M:
        moved.append(f"rolled {100 * rolled:.1f} cm")
    if turned > STILL_TURN_TOLERANCE:
        moved.append(f"turned {math.degrees(turned):.0f}°")
    return (
        f"The wheels still turn after '{DONE}': the robot {' and '.join(moved)} in "
        f"{round(seconds, 1):g} s; send a zero command (v = 0, omega = 0) before you finish."
    )


def _stop_problem(state: Any, run: StateRun) -> Optional[str]:
    wanted = state.stop_seconds
    if abs(run.duration - wanted) > STOP_TOLERANCE_S:
        return (
            f"The stop '{run.name}' at {run.start:.1f} s lasted {run.duration:.1f} s instead of "
            f"{wanted:.1f} s."
        )
    if not run.moved <= STILL_TOLERANCE_M:
        return (
            f"The robot moved {100 * run.moved:.1f} cm during the stop '{run.name}' at "
            f"{run.start:.1f} s; the wheels must stand still."
        )
    return None


def mission_report(
    bag: Union[Bag, PathLike],
    mission: Mission,
    namespace: str = "/duckiebot/",
    state_topic: Optional[str] = None,
    tracks: Optional[Sequence[PoseTrack]] = None,
) -> MissionReport:
    """Read a mission's bag and say what the robot did compared with ``mission``.

    Args:
        bag: the bag of the run (a :class:`~duckielib.bags.Bag` or a path). It should hold
            ``mission_node/state``, ``led_emitter_node/led_pattern``, ``odometry_node/pose``
            and ``simulator_node/ground_truth_pose`` under ``namespace``.
        mission: the mission that was asked for.
        namespace: the robot's namespace, ``/VEH/``.
        state_topic: where the states were announced (default ``/VEH/mission_node/state``).
        tracks: the bag's pose tracks with record times, if already read
            (``pose_tracks(bag, "record")``).

    Returns:
        The report; its ``problems`` say, one sentence each, what differs from the mission.

    Raises:
        BagError: if the bag cannot be read.
    """
    bag = bag if isinstance(bag, Bag) else Bag(bag)
    namespace = "/" + namespace.strip("/") + "/"
    state_topic = state_topic or namespace + "mission_node/state"
    report = MissionReport(mission)
    topics = set(bag.topics)
    announcements = _announcements(bag, state_topic, topics, report)
    led_topic = namespace + "led_emitter_node/led_pattern"
    leds = _led_changes(bag, led_topic) if led_topic in topics else []
    tracks = pose_tracks(bag, "record") if tracks is None else tracks
    truth = _track(tracks, "ground_truth_pose")
    odometry = _track(tracks, "odometry_node/pose")

    t0 = announcements[0][0] if announcements else 0.0
    report.started = t0
    done = [t for t, name in announcements if name == DONE]
    report.finished = bool(done)
    states = [(t, name) for t, name in announcements if name != DONE]
    last_time = max(
        [t for t, _ in announcements]
        + [float(track.t[-1]) for track in (truth, odometry) if track is not None]
        + [0.0]
    )
    end_time = done[0] if done else last_time
    report.states += _state_runs(states, end_time, leds, truth, t0)
    report.total_time = (end_time - t0) if announcements else 0.0
    if done and truth is not None:
        report.after_done = _after_done(truth, done[0])
    contact_topic = namespace + "simulator_node/wall_contact"
    if contact_topic in topics:
        changes = [(item.time, bool(item.message.data)) for item in bag.read(contact_topic)]
        report.wall_contacts = [
            (start - t0, end - t0) for start, end in _intervals(changes, last_time)
        ]
    if odometry is not None:
        report.final_pose_odometry = _pose_at(odometry, last_time)
    if truth is not None:
        report.final_pose_truth = _pose_at(truth, last_time)
        x, y, _ = report.final_pose_truth
        report.distance_to_start = math.hypot(x - mission.start[0], y - mission.start[1])
    report.problems += _problems(report)
    return report


def _announcements(
    bag: Bag, state_topic: str, topics: Set[str], report: MissionReport
) -> List[Tuple[float, str]]:
    """The states announced on ``state_topic``: (record time, name), in order.

    A bag without the topic (not in ``topics``, the bag's) has none, and ``report`` says so
    in its problems.
    """
    if state_topic not in topics:
        report.problems.append(
            f"The bag has no {state_topic}: the mission node must publish each state's name "
            "there (std_msgs/String) when the state starts."
        )
        return []
    return [(item.time, item.message.data) for item in bag.read(state_topic)]


def _state_runs(
    states: List[Tuple[float, str]],
    end_time: float,
    leds: List[Tuple[float, str]],
    truth: Optional[PoseTrack],
    t0: float,
) -> List[StateRun]:
    """Each announced state as it ran: its colour, its times from ``t0`` and how far it moved.

    A state ends where the next begins, the last at ``end_time`` (record times, seconds).
    """
    runs = []
    for index, (start, name) in enumerate(states):
        end = states[index + 1][0] if index + 1 < len(states) else end_time
        # The colour shown once the state has begun: half a second in (or half-way through
        # a shorter state), so the order of the LED call and the announcement does not matter.
        seen_at = min(start + 0.5, (start + end) / 2)
        shown = [color for t, color in leds if t <= seen_at]
        runs.append(
            StateRun(
                name=name,
                color=shown[-1] if shown else "unknown",
                start=start - t0,
                end=end - t0,
                moved=_moved(truth, start, end),
            )
        )
    return runs


def _intervals(changes: List[Tuple[float, bool]], end: float) -> List[Tuple[float, float]]:
    """The (start, end) times during which a flag that changes at ``changes`` was true.

    Intervals less than :data:`CONTACT_GAP_S` apart are one (a robot pushing along a wall
    touches and leaves it many times a second).
    """
    intervals: List[Tuple[float, float]] = []
    since: Optional[float] = None
    for t, on in changes:
        if on and since is None:
            since = t
        elif not on and since is not None:
            if intervals and since - intervals[-1][1] < CONTACT_GAP_S:
                since = intervals.pop()[0]
            intervals.append((since, t))
            since = None
    if since is not None:
        if intervals and since - intervals[-1][1] < CONTACT_GAP_S:
            since = intervals.pop()[0]
        intervals.append((since, max(since, end)))
    return intervals


def _wall_problem(report: MissionReport) -> str:
    """The sentence for a robot that touched a wall: where, and for how long."""
    spans = ", ".join(f"{start:.1f} s to {end:.1f} s" for start, end in report.wall_contacts)
    total = sum(end - start for start, end in report.wall_contacts)
    return (
        f"The robot touched the mat's wall ({spans}; {total:.1f} s in all): there the wall "
        "held it, whatever its wheels did, so the path after it is not the mission node's alone."
    )


def _closure_problem(report: MissionReport) -> str:
    """The sentence for a robot that ended too far from the start, with odometry's belief."""
    assert report.distance_to_start is not None
    problem = (
        f"The robot ended {100 * report.distance_to_start:.1f} cm from the start; "
        f"it should end within {100 * CLOSURE_TOLERANCE_M:.0f} cm."
    )
    believed = report.final_pose_odometry
    start = report.mission.start
    if believed is not None:
        away = math.hypot(believed[0] - start[0], believed[1] - start[1])
        if away <= CLOSURE_TOLERANCE_M:
            cause = (
                "the wall it touched and odometry's drift"
                if report.wall_contacts
                else "odometry's drift (wheels, track and slip unlike the nominal ones)"
            )
            problem += (
                f" Its odometry believed it was {100 * away:.1f} cm from the start: the "
                f"difference is {cause}, not the mission node's."
            )
    return problem


def _problems(report: MissionReport) -> List[str]:
    problems: List[str] = []
    if not report.finished:
        problems.append(f"The mission node never announced '{DONE}' on its state topic.")
    problems += _state_problems(report)
    if not report.still_after_done:
        problems.append(_after_done_problem(report))
    if report.wall_contacts:
        problems.append(_wall_problem(report))
    if report.distance_to_start is None:
        problems.append("The bag has no ground truth, so the end cannot be checked.")
    elif not report.closed:
        problems.append(_closure_problem(report))
    if report.final_pose_odometry is None:
        problems.append("The bag has no odometry pose (odometry_node/pose).")
    return problems


def _state_problems(report: MissionReport) -> List[str]:
    """The first state out of order, or else each stop that did not hold."""
    problems: List[str] = []
    mission = report.mission
    expected = [(state.name, state.color) for state in mission.states]
    seen = [(run.name, run.color) for run in report.states]
    if seen != expected:
        for index, wanted in enumerate(expected):
            got = seen[index] if index < len(seen) else None
            if got != wanted:
                shown = "nothing" if got is None else f"{got[0]} in {got[1]}"
                problems.append(
                    f"State {index + 1} should be {wanted[0]} in {wanted[1]}, but the bag "
                    f"shows {shown}."
                )
                break
        if len(seen) > len(expected):
            problems.append(f"The bag shows {len(seen)} states; the mission has {len(expected)}.")
    else:
        for state, run in zip(mission.states, report.states):
            if state.is_stop:
                problem = _stop_problem(state, run)
                if problem:
                    problems.append(problem)
    return problems
