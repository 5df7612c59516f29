"""What the robot really did in each moving state of a mission, move by move (instructor only).

The driving score (:mod:`autograder.driving`) checks the robot's motion in every moving state
of the mission on the simulator's ground truth, never on the robot's own odometry: the angle of
each turn on the spot, the length and the end of each straight side, the angle, radius and end
of each arc, and where the way back to the start ends and which way the robot then faces. Each
move is compared with where it would take the robot if done perfectly from the pose at which
the state really began, within the tolerances below; :class:`StateMotion` holds one state's
checks, and the grader's summary lists them under ``"motion"``.

This module works out where a perfect move ends, which is part of what a student writes in
notebook 09's graded ``mission_node``: it belongs to the grader and never to ``duckielib``,
which students get. :func:`duckielib.bags.behaviour.mission_report` gives the states, colours and
stops the checks here start from.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from duckielib.bags.analysis import PoseTrack, pose_tracks
from duckielib.bags.behaviour import (
    CLOSURE_TOLERANCE_M,
    STILL_TOLERANCE_M,
    MissionReport,
    StateRun,
)
from duckielib.bags.reader import Bag, PathLike
from duckielib.missions import (
    Arc,
    Mission,
    Move,
    Pose,
    ReturnToStart,
    Rotate,
    State,
    Straight,
    describe_move,
)

__all__ = [
    "CLOSURE_TOLERANCE_M",
    "LENGTH_TOLERANCE_M",
    "POSITION_TOLERANCE_M",
    "RADIUS_TOLERANCE",
    "TURN_TOLERANCE_RAD",
    "MoveCheck",
    "StateMotion",
    "driving_problems",
    "state_motions",
]

# The way back, and a full circle, must end within CLOSURE_TOLERANCE_M of where they should:
# the same tolerance as the mission report's end near the start.

#: A turn, an arc's angle and the heading after the way back may be off by this, in radians.
TURN_TOLERANCE_RAD = math.radians(10.0)

#: A straight side may be this much longer or shorter than asked, in metres.
LENGTH_TOLERANCE_M = 0.10

#: A side or an arc may end this far from where the perfect move would end, in metres.
POSITION_TOLERANCE_M = 0.20

#: An arc's radius may be off by this share of the radius asked for.
RADIUS_TOLERANCE = 0.25

#: An arc that turns less than this (radians) has no radius worth measuring.
_SHORTEST_ARC_RAD = math.radians(10.0)


# --- What the robot did in each moving state, from the ground truth -------------------------
#
# A moving state's truth track is cut into runs of one kind of motion (standing still, turning
# on the spot to the left or right, driving straight, curving left or right). The mission's moves
# are then matched to consecutive runs so that the length driven and the heading turned of each
# move's runs are as close as possible to the move's own (a small dynamic programme); a run no
# move explains is left out at a cost, so a robot that does something extra is not forced to
# shift every later move. Each move is then measured on its runs and compared with where the
# move, done perfectly, would take the robot from the pose at which the state really began.


@dataclass
class MoveCheck:
    """One check of what the robot did in a moving state.

    Attributes:
        what: what is checked, for people (``"turn 1"``, ``"side 2"``, ``"the circle's radius"``).
        passed: whether the robot did it within tolerance.
        measured: what the robot did (metres or degrees, see ``unit``), NaN when nothing.
        expected: what the mission asks for, in the same unit.
        unit: ``"m"`` or ``"deg"``.
        reason: a sentence saying what went wrong, or None when the check passed.
    """

    what: str
    passed: bool
    measured: float
    expected: float
    unit: str
    reason: Optional[str] = None

    def __post_init__(self) -> None:
        if self.passed:
            self.reason = None

    def as_dict(self) -> Dict[str, Any]:
        """The check as plain data, for the driving score's summary."""
        return {
            "what": self.what,
            "passed": self.passed,
            "measured": None if math.isnan(self.measured) else round(self.measured, 3),
            "expected": round(self.expected, 3),
            "unit": self.unit,
        }


@dataclass
class StateMotion:
    """What the robot did in one moving state of the mission, checked move by move.

    Attributes:
        name: the state's name (``"square"``).
        index: the state's position in the mission, from 0.
        checks: the checks of its moves, in order.
        problems: what went wrong, one sentence each (fewer than the failed checks when one
            sentence says it all, for example that the robot did not move).
    """

    name: str
    index: int
    checks: List[MoveCheck] = field(default_factory=list)
    problems: List[str] = field(default_factory=list)

    @property
    def passed(self) -> int:
        """How many checks passed."""
        return sum(check.passed for check in self.checks)

    @property
    def fraction(self) -> float:
        """The share of checks passed, from 0 to 1."""
        return self.passed / len(self.checks) if self.checks else 0.0

    def as_dict(self) -> Dict[str, Any]:
        """The state's checks as plain data, for the driving score's summary."""
        return {
            "state": self.name,
            "index": self.index,
            "passed": self.passed,
            "checks": [check.as_dict() for check in self.checks],
            "problems": list(self.problems),
        }


#: Below both of these the robot counts as standing still: metres per second, radians per second.
_STILL_SPEED = 0.01
_STILL_TURN_RATE = 0.05
#: A motion turning on a radius below this (metres) turns on the spot; above the next, it is
#: a straight line; in between, an arc.
_SPOT_RADIUS = 0.05
_STRAIGHT_RADIUS = 1.5
#: A run of motion shorter than this many truth samples is noise: it joins the run before it.
_SHORTEST_RUN = 3
#: At most this many runs are matched to moves (beyond, short runs are joined more eagerly).
_MOST_RUNS = 300
#: How many metres of driving one radian of turning weighs when moves are matched to runs.
_METRES_PER_RADIAN = 0.3
#: Motion that no move explains costs this much more than the same motion matched to a move.
_EXTRA_COST = 1.5


def _wrapped(angle: Any) -> Any:
    """Angles (radians) brought into [-pi, pi)."""
    return (angle + math.pi) % (2 * math.pi) - math.pi


def _follow(move: Move, pose: Pose, start: Pose) -> Pose:
    """Where ``move``, done perfectly, takes the robot from ``pose`` (``start``: the mission's)."""
    x, y, theta = pose
    if isinstance(move, Rotate):
        return x, y, theta + move.angle
    if isinstance(move, Straight):
        return x + move.distance * math.cos(theta), y + move.distance * math.sin(theta), theta
    if isinstance(move, Arc):
        # The chord of an arc points half-way between the start and end headings.
        chord = 2 * move.radius * math.sin(abs(move.angle) / 2)
        middle = theta + move.angle / 2
        return x + chord * math.cos(middle), y + chord * math.sin(middle), theta + move.angle
    if isinstance(move, ReturnToStart):
        return start
    return pose


def _planned_length(move: Move, pose: Pose, start: Pose) -> float:
    """How far ``move`` drives from ``pose`` when done perfectly (the way back: straight)."""
    if isinstance(move, Straight):
        return abs(move.distance)
    if isinstance(move, Arc):
        return move.radius * abs(move.angle)
    if isinstance(move, ReturnToStart):
        return math.hypot(start[0] - pose[0], start[1] - pose[1])
    return 0.0


def _move_costs(move: Move, lengths: np.ndarray, turns: np.ndarray) -> np.ndarray:
    """How badly stretches of motion (driven ``lengths`` in m, ``turns`` in rad) match ``move``."""
    weight = _METRES_PER_RADIAN
    if isinstance(move, Rotate):
        return lengths + weight * np.abs(turns - move.angle)
    if isinstance(move, Straight):
        return np.abs(lengths - abs(move.distance)) + weight * np.abs(turns)
    if isinstance(move, Arc):
        return np.abs(lengths - move.radius * abs(move.angle)) + weight * np.abs(turns - move.angle)
    if isinstance(move, ReturnToStart):
        return np.zeros_like(lengths)  # any way back will do: only where it ends is checked
    return lengths + weight * np.abs(turns)  # a stop: no motion at all


def _run_bounds(x: np.ndarray, y: np.ndarray, theta: np.ndarray, t: np.ndarray) -> List[int]:
    """Where the runs of one kind of motion begin (sample indices), and the last sample's index.

    The kinds: standing still, turning on the spot left or right, straight, arc left or right.
    """
    if len(t) < 2:
        return [0]
    steps = np.hypot(np.diff(x), np.diff(y))
    turns = _wrapped(np.diff(theta))
    durations = np.maximum(np.diff(t), 1e-9)
    speed, rate = steps / durations, np.abs(turns) / durations
    kind = np.where(turns < 0, -1, 1) * np.where(
        speed < _SPOT_RADIUS * rate, 1, np.where(speed >= _STRAIGHT_RADIUS * rate, 2, 3)
    )
    kind[np.abs(kind) == 2] = 2
    kind[(speed < _STILL_SPEED) & (rate < _STILL_TURN_RATE)] = 0
    changes = [0] + [int(i) for i in np.flatnonzero(np.diff(kind)) + 1] + [len(kind)]
    shortest = _SHORTEST_RUN
    while True:
        runs: List[List[int]] = []  # [first step, step after the last, kind]
        for begin, end in zip(changes, changes[1:]):
            if runs and (end - begin < shortest or runs[-1][2] == kind[begin]):
                runs[-1][1] = end
            else:
                runs.append([begin, end, int(kind[begin])])
        if len(runs) <= _MOST_RUNS:
            return [run[0] for run in runs] + [runs[-1][1]]
        shortest *= 2


def _match_moves(
    moves: Sequence[Move], bounds: List[int], lengths: np.ndarray, turns: np.ndarray
) -> List[Tuple[int, int]]:
    """The samples each move spans: (first, last) indices, equal when the move did not happen.

    Args:
        moves: the state's moves, in order.
        bounds: where each run of motion begins, and the last sample (:func:`_run_bounds`).
        lengths: the distance driven up to each sample, metres, shape (N,).
        turns: the signed heading turned up to each sample, radians, shape (N,).
    """
    runs = len(bounds) - 1
    at = np.asarray(bounds)
    inf = math.inf
    cost = [[inf] * (runs + 1) for _ in moves] + [[inf] * (runs + 1)]
    came: List[List[Tuple[int, int]]] = [[(-1, -1)] * (runs + 1) for _ in range(len(moves) + 1)]
    cost[0][0] = 0.0
    for k in range(len(moves) + 1):
        for j in range(runs + 1):
            here = cost[k][j]
            if here == inf:
                continue
            if j < runs:  # run j is left out: motion no move explains
                extra = lengths[at[j + 1]] - lengths[at[j]]
                extra += _METRES_PER_RADIAN * abs(turns[at[j + 1]] - turns[at[j]])
                if here + _EXTRA_COST * extra < cost[k][j + 1]:
                    cost[k][j + 1] = here + _EXTRA_COST * extra
                    came[k][j + 1] = (k, j)
            if k < len(moves):  # move k takes runs j to j2 - 1 (none when j2 == j)
                ends = at[j:]
                options = here + _move_costs(
                    moves[k], lengths[ends] - lengths[at[j]], turns[ends] - turns[at[j]]
                )
                for offset, value in enumerate(options):
                    if value < cost[k + 1][j + offset]:
                        cost[k + 1][j + offset] = float(value)
                        came[k + 1][j + offset] = (k, j)
    spans: List[Tuple[int, int]] = []
    k, j = len(moves), runs
    while k > 0 or j > 0:
        previous_k, previous_j = came[k][j]
        if previous_k < k:
            spans.append((int(at[min(previous_j, runs)]), int(at[min(j, runs)])))
        k, j = previous_k, previous_j
    return spans[::-1]


def _turn_words(angle: float) -> str:
    """An angle in radians as people say it: ``"90° clockwise"``."""
    degrees = math.degrees(angle)
    if not math.isfinite(degrees):  # a move of a state that never began
        return "an unknown angle"
    if round(abs(degrees)) == 0:
        return "0°"
    return f"{abs(degrees):.0f}° {'counter-clockwise' if degrees > 0 else 'clockwise'}"


def _move_names(moves: Sequence[Move]) -> List[str]:
    """What each move is called in sentences: ``"turn 1"``, ``"side 2"``, ``"the circle"``."""
    arcs = [move for move in moves if isinstance(move, Arc)]
    counts: Dict[str, int] = {}
    names = []
    for move in moves:
        if isinstance(move, Arc) and len(arcs) == 1:
            full = abs(move.angle) >= 2 * math.pi - 1e-6
            names.append("the circle" if full else "the arc")
            continue
        kind = {Rotate: "turn", Straight: "side", Arc: "arc", ReturnToStart: "the way back"}.get(
            type(move), "stop"
        )
        if isinstance(move, ReturnToStart):
            names.append(kind)
            continue
        counts[kind] = counts.get(kind, 0) + 1
        names.append(f"{kind} {counts[kind]}")
    return names


def _check_move(
    move: Move,
    what: str,
    state: str,
    begin: Pose,
    end: Pose,
    driven: float,
    turned: float,
    expected: Pose,
) -> List[MoveCheck]:
    """The checks of one move: what the robot did against the mission's move.

    Args:
        move: the mission's move.
        what: what the move is called in sentences (``"side 2"``).
        state: the state's name.
        begin: the true pose (x, y, theta) where the move began, metres and radians.
        end: the true pose where it ended.
        driven: the distance the robot drove during the move, metres.
        turned: the heading it turned during the move, radians (counter-clockwise positive).
        expected: where the move, done perfectly from the state's true start, ends.
    """
    off = math.hypot(end[0] - expected[0], end[1] - expected[1])
    where = f"(x = {expected[0]:.2f} m, y = {expected[1]:.2f} m)"
    if isinstance(move, Rotate):
        ok = abs(turned - move.angle) <= TURN_TOLERANCE_RAD
        reason = f"In state {state}, {what} turned {_turn_words(turned)}; it should turn "
        reason += f"{_turn_words(move.angle)}."
        return [MoveCheck(what, ok, math.degrees(turned), math.degrees(move.angle), "deg", reason)]
    if isinstance(move, Straight):
        length = math.hypot(end[0] - begin[0], end[1] - begin[1])
        if abs(length - abs(move.distance)) > LENGTH_TOLERANCE_M:
            reason = f"In state {state}, {what} was {length:.2f} m long; it should be "
            reason += f"{abs(move.distance):.2f} m."
        else:
            reason = f"In state {state}, {what} ended {off:.2f} m from where it should {where}: "
            reason += "the robot drove it in another direction than the mission's."
        ok = abs(length - abs(move.distance)) <= LENGTH_TOLERANCE_M and off <= POSITION_TOLERANCE_M
        return [MoveCheck(what, ok, length, abs(move.distance), "m", reason)]
    if isinstance(move, Arc):
        return _check_arc(move, what, state, driven, turned, off, where)
    if isinstance(move, ReturnToStart):
        return _check_return(what, state, end, expected, off, where)
    return []  # a stop inside a moving state: the stops are checked on their own


def _check_arc(
    move: Arc, what: str, state: str, driven: float, turned: float, off: float, where: str
) -> List[MoveCheck]:
    """An arc's checks: its angle and direction, its radius, and where it ended (``off`` m)."""
    ok = abs(turned - move.angle) <= TURN_TOLERANCE_RAD
    reason = f"In state {state}, {what} turned {_turn_words(turned)}; it should turn "
    reason += f"{_turn_words(move.angle)}."
    checks = [MoveCheck(what, ok, math.degrees(turned), math.degrees(move.angle), "deg", reason)]
    radius = driven / abs(turned) if abs(turned) >= _SHORTEST_ARC_RAD else math.nan
    ok = abs(radius - move.radius) <= RADIUS_TOLERANCE * move.radius
    if math.isnan(radius):
        reason = f"In state {state}, the robot did not drive {what}, so it has no radius; "
    else:
        reason = f"In state {state}, {what} had a radius of {radius:.2f} m; "
    reason += f"it should be {move.radius:.2f} m."
    checks.append(MoveCheck(f"{what}'s radius", ok, radius, move.radius, "m", reason))
    length = move.radius * abs(move.angle)
    if driven < length / 2:
        ok = False
        reason = f"In state {state}, the robot drove {driven:.2f} m of {what}'s {length:.2f} m, "
        reason += "so it did not end where it should."
    else:
        full = abs(move.angle) >= 2 * math.pi - 1e-6  # a circle closes where it began
        ok = off <= (CLOSURE_TOLERANCE_M if full else POSITION_TOLERANCE_M)
        began = " (where it began)" if full else ""
        reason = f"In state {state}, {what} ended {off:.2f} m from where it should{began} "
        reason += f"{where}."
    checks.append(MoveCheck(f"{what}'s end", ok, off, 0.0, "m", reason))
    return checks


def _check_return(
    what: str, state: str, end: Pose, expected: Pose, off: float, where: str
) -> List[MoveCheck]:
    """The way back's checks: how far from the start it ended (``off`` m), and its heading."""
    ok = off <= CLOSURE_TOLERANCE_M
    reason = f"In state {state}, the robot came back to {off:.2f} m from its start {where}; "
    reason += f"it should come within {CLOSURE_TOLERANCE_M:.2f} m."
    checks = [MoveCheck(f"{what}'s end", ok, off, 0.0, "m", reason)]
    heading = float(_wrapped(end[2] - expected[2]))
    ok = abs(heading) <= TURN_TOLERANCE_RAD
    reason = f"In state {state}, the robot came back facing {_turn_words(heading)} off its "
    reason += f"start heading; it should be within {math.degrees(TURN_TOLERANCE_RAD):.0f}°."
    checks.append(MoveCheck(f"{what}'s heading", ok, math.degrees(heading), 0.0, "deg", reason))
    return checks


def _state_motions(
    mission: Mission, runs: Sequence[StateRun], truth: Optional[PoseTrack], t0: float
) -> List[StateMotion]:
    """What the robot did in each moving state of ``mission``, from the truth track.

    Args:
        mission: the mission asked for.
        runs: the states the bag shows, in order (times from ``t0``).
        truth: the ground truth track (record times), or None if the bag has none.
        t0: when the first state was announced (record time), seconds.
    """
    motions: List[StateMotion] = []
    plan = mission.start  # where the perfect robot is at the start of each state
    planned = 0.0  # metres the perfect robot has driven at the start of each state
    if truth is not None:
        theta_all = np.asarray(truth.theta, dtype=float)
        travelled = np.concatenate(([0.0], np.cumsum(np.hypot(np.diff(truth.x), np.diff(truth.y)))))
    for index, state in enumerate(mission.states):
        planned_before = planned
        for move in state.moves:
            planned += _planned_length(move, plan, mission.start)
            plan = _follow(move, plan, mission.start)
        if state.is_stop or not state.moves:
            continue
        motion = StateMotion(state.name, index)
        motions.append(motion)
        run = runs[index] if index < len(runs) and runs[index].name == state.name else None
        names = _move_names(state.moves)
        if truth is None or run is None:
            nowhere = (math.nan, math.nan, math.nan)
            for move, name in zip(state.moves, names):
                motion.checks += _check_move(
                    move, name, state.name, nowhere, nowhere, math.nan, math.nan, nowhere
                )
            if truth is not None:
                motion.problems.append(
                    f"State {index + 1} ({state.name}) never began, so its driving could not "
                    "be checked."
                )
            continue
        first = max(0, int(np.searchsorted(truth.t, t0 + run.start, side="right")) - 1)
        last = max(first + 1, int(np.searchsorted(truth.t, t0 + run.end, side="right")))
        driven = (truth, theta_all, travelled)
        _check_driven(motion, state, names, mission.start, driven, first, last, planned_before)
    return motions


def _check_driven(
    motion: StateMotion,
    state: State,
    names: List[str],
    start: Pose,
    driven: Tuple[PoseTrack, np.ndarray, np.ndarray],
    first: int,
    last: int,
    planned_before: float,
) -> None:
    """Check each move of ``state`` (into ``motion``) on the truth track, ``first`` to ``last``.

    ``driven`` is the whole truth track, its headings as floats (rad) and the metres travelled
    since its start; ``planned_before``, the metres the perfect robot drives before the state.
    """
    truth, theta_all, travelled = driven
    t, x, y = truth.t[first:last], truth.x[first:last], truth.y[first:last]
    theta = theta_all[first:last]
    lengths = travelled[first:last] - travelled[first]
    turns = np.concatenate(([0.0], np.cumsum(_wrapped(np.diff(theta)))))
    spans = _match_moves(state.moves, _run_bounds(x, y, theta, t), lengths, turns)
    expected: Pose = (float(x[0]), float(y[0]), float(theta[0]))
    driven_before = float(travelled[first])
    gated: List[MoveCheck] = []
    for move, name, (a, b) in zip(state.moves, names, spans):
        expected = _follow(move, expected, start)
        checks = _check_move(
            move,
            name,
            state.name,
            (float(x[a]), float(y[a]), float(theta[a])),
            (float(x[b]), float(y[b]), float(theta[b])),
            float(lengths[b] - lengths[a]),
            float(turns[b] - turns[a]),
            expected,
        )
        if isinstance(move, ReturnToStart) and driven_before < planned_before / 2:
            # Already at the start because nothing before drove: the way back is not seen.
            for check in checks:
                check.passed, check.reason = False, None
            gated += checks
        motion.checks += checks
    if gated:
        motion.problems.append(
            f"In state {state.name}, the robot had driven only {driven_before:.2f} m since "
            f"the mission began (the mission drives {planned_before:.2f} m before it), so "
            "there was nothing to come back from."
        )
    failed = [check.reason for check in motion.checks if check.reason is not None]
    still = lengths[-1] <= 2 * STILL_TOLERANCE_M and float(
        np.sum(np.abs(np.diff(turns)))
    ) <= math.radians(5)
    if failed and still:
        moves = ", ".join(describe_move(move) for move in state.moves)
        failed = [f"In state {state.name}, the robot did not move; its moves are: {moves}."]
    motion.problems += [reason for reason in failed if reason is not None]


def state_motions(
    mission: Mission,
    report: MissionReport,
    bag_or_tracks: Union[Bag, PathLike, Sequence[PoseTrack]],
) -> List[StateMotion]:
    """What the robot did in each moving state of ``mission``, checked move by move.

    Args:
        mission: the mission asked for.
        report: what :func:`duckielib.bags.behaviour.mission_report` read from the run's bag.
        bag_or_tracks: the same bag (a :class:`~duckielib.bags.Bag` or a path), or its pose
            tracks with record times (``pose_tracks(bag, "record")``).

    Returns:
        One :class:`StateMotion` per moving state, in the mission's order; a state the bag
        does not show fails all its checks.

    Raises:
        BagError: if the bag cannot be read.
    """
    if isinstance(bag_or_tracks, (Bag, str, os.PathLike)):
        tracks: Sequence[PoseTrack] = pose_tracks(bag_or_tracks, "record")
    else:
        tracks = bag_or_tracks
    truth = next(
        (track for track in tracks if track.label.endswith("ground_truth_pose") and len(track)),
        None,
    )
    return _state_motions(mission, report.states, truth, report.started)


#: What :func:`duckielib.bags.behaviour.mission_report` says about the robot's end: the way back and
#: the circle's end are checked here instead.
_END_PROBLEMS = ("The robot ended ", "The bag has no ground truth")


#: How the mission report's sentence about a wall the robot touched begins.
_WALL_PROBLEM = "The robot touched the mat's wall"


def driving_problems(report: MissionReport, motions: Sequence[StateMotion]) -> List[str]:
    """The report's problems, with its sentence about the end replaced by the moves' own.

    The report checks only that the robot ended near its start; the moves' checks say where
    the way back and the circle ended, and what went wrong before, so they take its place
    (after the states and stops, before the odometry).
    """
    moves = [problem for motion in motions for problem in motion.problems]
    if report.distance_to_start is None:
        moves.insert(
            0,
            "The bag has no ground truth (simulator_node/ground_truth_pose), so what the robot "
            "really did cannot be checked.",
        )
    # A wall the robot touched explains the moves' problems: it comes right after them.
    walls = [problem for problem in report.problems if problem.startswith(_WALL_PROBLEM)]
    moves += walls
    problems: List[str] = []
    placed = False
    for problem in report.problems:
        if problem in walls:
            continue
        is_end = problem.startswith(_END_PROBLEMS)
        if not placed and (is_end or problem.startswith("The bag has no odometry")):
            problems += moves
            placed = True
        if not is_end:
            problems.append(problem)
    return problems if placed else problems + moves
