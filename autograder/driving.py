"""The driving score: a student's own exported code drives the missions on the virtual Duckiebot.

The cells the student tagged ``export`` are collected from their notebooks (read as text, never
run here), and that solution drives each mission of :data:`MISSIONS` (square then circle, the
"D", the straight-line task and the rotation task), each a run of its own, scored out of 100
on its own; the driving score is their mean. In each run the robot and the student's nodes
run apart (:mod:`duckielib.tools.apart`): the virtual Duckiebot and the bag recorder run here,
in the grader's process, and the student's nodes in the sandbox, reaching the robot only
through its topics and services (:mod:`duckielib.sim.link`). The grader scores the bag it
recorded itself, with :func:`duckielib.bags.behaviour.mission_report` (states, colours, stops)
and :func:`autograder.motion.state_motions` (the driving):

=================================================  ======
a readable bag with the mission's states               5
the states and LED colours in order, then "done"      20
every stop held for its time, standing still          15
what the robot really did in the moving states        60
=================================================  ======

The 60 points of driving are split evenly over the mission's moving states (square, return and
circle: 20 each; forward and back of the straight task: 30 each), and each state's points evenly
over its checks, measured on the simulator's ground truth from the pose at which the state
really began (see :mod:`autograder.motion` for the tolerances): each turn's angle and direction,
each side's length and where it ends; where the way back ends and the heading it ends with; the
circle's angle and direction, its radius and that it ends where it began. A robot that never
drives earns none of them. Stopping is in the stops' points (after each move the robot must
stand still through the next wait), ending is in the states' (the mission node must announce
"done" and return, as a node that exits properly does).

The feedback page's trajectory figure and animation are drawn from that bag. Nothing the
student's process wrote is read: the nodes cannot move the robot, read where it really is, or
write the truth the bag records. (:func:`score_bag` scores a run folder that ``duckie
mission`` wrote, reading its bag without trusting it: no link followed, no FIFO, device or
file over :data:`BAG_LIMIT`.)

A run that stops early (a node fails, the mission does not announce its end within the
simulated time limit, or the wall-clock limit stops it) is scored from the bag recorded until
then, with the reason first: states it did not finish earn only what they did. A solution that
cannot run at all scores zero, with the reason the student would see from ``duckie mission``.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Sequence

from autograder.sandbox import Limits, started

__all__ = [
    "BAG_LIMIT",
    "MAX_SCORE",
    "MISSIONS",
    "POINTS",
    "Driving",
    "drive",
    "drive_missions",
    "driving_score",
    "not_driven",
    "part_points",
    "score_bag",
]

#: The missions a student's code drives, each scored out of :data:`MAX_SCORE` on its own: the
#: course's task, its "D" variant, and the straight-line and rotation tasks of Part 2.
MISSIONS = ("square_then_circle", "d_shape", "straight", "rotation")

#: Points of each part of the driving score; ``"motion"`` is split over the moving states.
POINTS = {"bag": 5.0, "states": 20.0, "stops": 15.0, "motion": 60.0}
#: The best driving score.
MAX_SCORE = sum(POINTS.values())
#: The robot's name in the run (its namespace).
ROBOT = "duckiebot"
#: Frames of the feedback page's animation of a run (8 a second).
ANIMATION_FRAMES = 64
#: A bag with more messages than this is not played back (the reference's has about 23,000):
#: a student's node that floods a topic must not stretch the grader's drawing.
ANIMATION_MESSAGE_LIMIT = 100_000
#: The missions whose run the feedback page plays back (about 2 s of the grader's time each;
#: the others show their trajectory figure only).
ANIMATED = ("square_then_circle",)
#: The run's bag (or its unfinished recording) may be at most this big (bytes); a larger one
#: is not read. The reference's bag is under 10 MB.
BAG_LIMIT = 200 * 1024**2


@dataclass
class Driving:
    """How a student's code drove the mission.

    Attributes:
        score: the points, out of :data:`MAX_SCORE`.
        parts: the points of each part: ``"bag"``, ``"states"``, ``"stops"``, then one part
            per moving state of the mission, named after it (``"square"``, ``"return"``, ...).
        reasons: why points were lost, one sentence each.
        summary: what the robot did (the mission report as plain data), or None.
        figure: the trajectory figure's PNG bytes, or None.
        animation: the run played back (robot, LEDs, states), GIF bytes drawn by the grader
            from its own copy of the bag (the missions of :data:`ANIMATED`), or None.
        out_of: the most points of each part of ``parts``.
        finished: whether the mission ran to its end.
        timed_out: whether the grader stopped the run at its wall-clock limit.
    """

    score: float = 0.0
    parts: Dict[str, float] = field(default_factory=dict)
    reasons: List[str] = field(default_factory=list)
    summary: Optional[Dict[str, Any]] = None
    figure: Optional[bytes] = None
    animation: Optional[bytes] = None
    out_of: Dict[str, float] = field(default_factory=dict)
    finished: bool = False
    timed_out: bool = False


def part_points(mission: str = "square_then_circle") -> Dict[str, float]:
    """The most points of each part of the driving score of ``mission``.

    The motion's points are split evenly over the mission's moving states, each a part named
    after its state (a name that repeats gets its position: ``"square (state 2)"``).
    """
    from duckielib.missions import mission_named

    moving = [
        (index, state.name)
        for index, state in enumerate(mission_named(mission).states)
        if not state.is_stop and state.moves
    ]
    names = [name for _, name in moving]
    points = {name: POINTS[name] for name in ("bag", "states", "stops")}
    for index, name in moving:
        key = name if names.count(name) == 1 else f"{name} (state {index + 1})"
        points[key] = POINTS["motion"] / len(moving)
    return points


def not_driven(why: str, missions: Sequence[str] = MISSIONS) -> Dict[str, Driving]:
    """Each of ``missions`` scored zero, with the one reason ``why`` none was driven."""
    return {name: Driving(reasons=[why], out_of=part_points(name)) for name in missions}


def driving_score(missions: Dict[str, Driving]) -> float:
    """The driving score of a student: the mean of their missions' scores, out of 100."""
    if not missions:
        return 0.0
    return round(sum(driving.score for driving in missions.values()) / len(missions), 2)


def drive_missions(
    notebooks: Path,
    folder: Path,
    limits: Limits,
    use_sandbox: bool = True,
    missions: Sequence[str] = MISSIONS,
    runs: Optional[Dict[str, Path]] = None,
) -> Dict[str, Driving]:
    """Export the student's notebooks once, then drive and score each mission in a sandbox.

    Each mission runs in a process and a sandbox of its own, in ``folder/MISSION``, with
    ``limits.mission_seconds`` of wall time. When one runs out of time, the missions after it
    are not driven (the same code would most likely hang again): they score zero, saying so.

    Args:
        notebooks: the student's folder of assignment notebooks (a copy of ``course/``), or
            a ``.py`` solution made by ``duckie export``.
        folder: an empty folder the runs may write (owned over to the sandbox's user here).
        limits: the sandbox's limits.
        use_sandbox: whether to run in the sandbox (off only with ``duckie grade --no-sandbox``).
        missions: the missions to drive, in order.
        runs: bags the grader recorded already, by mission, of runs of these nodes on the
            ideal robot with seed 0 and the mission's own colours (the tests of notebook 09
            drive two of the missions so): each is scored rather than driven again, since the
            same nodes on the same simulated robot drive the same run.

    Returns:
        Each mission's driving score with its reasons, in the order of ``missions``.
    """
    from duckielib.errors import DuckielibError
    from duckielib.solution import export_solution

    if notebooks.is_file():  # a module made by duckie export
        text = notebooks.read_text(encoding="utf-8")
    else:
        try:
            text = export_solution(notebooks, strict=False).source
        except DuckielibError as error:
            return not_driven(f"Your notebooks could not be exported: {error}", missions)
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    (folder / "solution.py").write_text(text, encoding="utf-8")
    shutil.chown(folder, limits.uid, limits.uid)
    shutil.chown(folder / "solution.py", limits.uid, limits.uid)
    results: Dict[str, Driving] = {}
    stuck: Optional[str] = None
    for name in missions:
        if stuck is not None:
            results[name] = Driving(
                out_of=part_points(name),
                reasons=[
                    f"Not driven: the {stuck} mission did not end within "
                    f"{limits.mission_seconds} s of wall time, and the same nodes drive this one."
                ],
            )
            continue
        done = (runs or {}).get(name)
        if done is not None and done.is_file():
            results[name] = _score_done(done, name)  # the tests drove it already
            continue
        results[name] = drive(folder, limits, use_sandbox, name)
        if results[name].timed_out:
            stuck = name
    return results


def drive(
    folder: Path, limits: Limits, use_sandbox: bool = True, mission: str = "square_then_circle"
) -> Driving:
    """Drive ``mission`` with the solution ``folder/solution.py`` and score the run's bag.

    The virtual Duckiebot runs here, in the grader's process, and records the bag into a
    folder of the grader's; the solution's nodes run in the sandbox and reach the robot only
    through topics and services (:mod:`duckielib.tools.apart`).

    Args:
        folder: a folder the sandbox's user may write, holding ``solution.py`` (an export).
        limits: the sandbox's limits; the mission has ``limits.mission_seconds`` of wall time.
        use_sandbox: whether to run in the sandbox (off only with ``duckie grade --no-sandbox``).
        mission: the mission to drive; the nodes' process works in ``folder/MISSION/``.

    Returns:
        The driving score with its reasons.
    """
    import contextlib

    from duckielib.missions import mission_named
    from duckielib.tools.apart import OutOfWallTime, drive_apart, nodes_arguments, nodes_command
    from duckielib.tools.runner import DEFAULT_TIME_LIMIT_S

    chosen = mission_named(mission)
    said: List[str] = []

    @contextlib.contextmanager
    def start_nodes(sock: Any) -> Iterator[Any]:
        fd = sock.fileno()
        arguments = nodes_arguments(mission, stall_limit=limits.stall_seconds)
        command = nodes_command(fd, "solution.py", arguments)
        env = {"VEHICLE_NAME": ROBOT}
        with started(command, folder, limits, use_sandbox, env=env, pass_fds=(fd,)) as running:
            yield running
            with contextlib.suppress(subprocess.TimeoutExpired):
                running.process.wait(timeout=5)
            said.append(running.outputs()[1])

    with tempfile.TemporaryDirectory(prefix="driving-") as scratch:
        files = {"bag": Path(scratch) / "mission.bag", "log": Path(scratch) / "log.txt"}
        *_, failure = drive_apart(
            start_nodes,
            chosen,
            "ideal",
            0,
            files,
            DEFAULT_TIME_LIMIT_S,
            wall_limit=limits.mission_seconds,
        )
        if failure is None:
            return _score_copy(files["bag"], mission)
        timed_out = isinstance(failure, OutOfWallTime)
        if timed_out:
            why = f"The mission did not end within {limits.mission_seconds} s of wall time."
        elif "process stopped answering" in str(failure) and said and said[0].strip():
            why = _failure(said[0])  # it died: its last words say more than the broken link
        else:
            why = f"The mission could not run to its end: {_without_paths(str(failure))}"
        driving = _score_stopped(files["bag"], mission, why)
        driving.timed_out = timed_out
        return driving


def _score_done(bag: Path, mission: str) -> Driving:
    """Score a run the grader recorded already, for a test (the same nodes, mission and seed).

    The copy is scored, so that the figures drawn next to it stay in a folder of its own.
    """
    with tempfile.TemporaryDirectory(prefix="driving-") as scratch:
        copy = Path(scratch) / "mission.bag"
        shutil.copyfile(bag, copy)
        return _score_copy(copy, mission)


def _score_unfinished(run: Path, mission: str, why: str) -> Driving:
    """Score what a run that stopped early left: its bag, or what a killed recording kept.

    A recording killed with its process is left as ``mission.bag.active``, without an index;
    it is copied into a folder of the grader's own, and its complete messages into a new bag
    there, which is scored.
    """
    from duckielib.bags.repair import repair_bag
    from duckielib.errors import DuckielibError

    out_of = part_points(mission)
    with tempfile.TemporaryDirectory(prefix="driving-") as scratch:
        try:
            bag = _copy(run, "mission.bag", Path(scratch), "The mission's bag")
        except _Unread as unread:
            if not unread.missing:
                return Driving(out_of=out_of, reasons=[why, unread.reason])
            try:
                active = _copy(run, "mission.bag.active", Path(scratch), "The mission's recording")
            except _Unread as unread_active:
                reasons = [why] if unread_active.missing else [why, unread_active.reason]
                return Driving(out_of=out_of, reasons=reasons)
            bag = Path(scratch) / "mission.bag"
            try:
                repair_bag(active, bag)
            except (DuckielibError, ValueError, OSError):
                return Driving(out_of=out_of, reasons=[why])
        return _score_stopped(bag, mission, why)


def _score_stopped(bag: Path, mission: str, why: str) -> Driving:
    """Score the bag of a run that stopped early (the grader's own file), ``why`` first."""
    out_of = part_points(mission)
    driving = _score_copy(bag, mission) if bag.is_file() else Driving(out_of=out_of)
    if not driving.parts.get("bag"):  # nothing of the mission reached the bag
        return Driving(out_of=out_of, reasons=[why])
    driving.finished = False
    # Ending is part of the states' points: a node that never returned did not end properly.
    driving.parts["states"] = 0.0
    driving.score = round(sum(driving.parts.values()), 2)
    # The report's own sentence about the missing end is said better by the reason.
    driving.reasons = [why, "It is scored from the bag it wrote until then."] + [
        reason for reason in driving.reasons if "never announced" not in reason
    ]
    return driving


class _Unread(Exception):
    """A file of the run the grader does not read, and why (``missing``: it was not written)."""

    def __init__(self, reason: str, missing: bool = False) -> None:
        super().__init__(reason)
        self.reason = reason
        self.missing = missing


def _read(run: Path, name: str, limit: int, what: str) -> bytes:
    """The bytes of the regular file ``name`` in the folder ``run``, read without trusting it.

    Neither ``run`` itself nor ``name`` may be a link: the folder above ``run`` is the
    grader's, and :func:`autograder.files.read_regular` opens each part below it without
    following links, refuses FIFOs, devices and files over ``limit`` bytes.

    Raises:
        _Unread: with a sentence that starts with ``what`` and names no path.
    """
    from autograder.files import UnsafeFile, read_regular

    run = Path(run).absolute()  # not resolved: a link as the run's folder is refused below
    if run.name in ("", ".."):  # the grader's own way to name a folder, not the run's
        run = run.resolve()
    relative = f"{run.name}/{name}"
    try:
        return read_regular(run.parent, relative, limit)
    except UnsafeFile as error:
        said = str(error)
    except OSError:  # the folder above the run cannot be opened
        said = f"{relative}: {run.name} is not a folder."
    if said.startswith(f"{relative}: "):  # the run's folder itself
        if not os.path.lexists(run):
            raise _Unread(f"{what} was not written.", missing=True) from None
        kind = "a symbolic link" if run.is_symlink() else "not a folder"
        raise _Unread(f"{what} was not read: the run's folder is {kind}.") from None
    if said == f"{relative} does not exist.":
        raise _Unread(f"{what} was not written.", missing=True) from None
    raise _Unread(f"{what} was not read: {said.replace(relative, 'it', 1)}") from None


def _copy(run: Path, name: str, scratch: Path, what: str) -> Path:
    """Copy the run's file ``name`` (at most :data:`BAG_LIMIT` bytes) into ``scratch``."""
    target = scratch / name
    target.write_bytes(_read(run, name, BAG_LIMIT, what))
    return target


def _drawn(tracks: List[Any], report: Any, bag: Path) -> Optional[bytes]:
    """The trajectory figure of the grader's copy of the bag, as PNG bytes, or None.

    Drawn here, as the animation is, rather than taken from the run's folder: the page shows
    the run the grader scored, and nothing the student's process wrote.
    """
    from duckielib.errors import DuckielibError
    from duckielib.tools.runner import trajectory_figure

    try:
        return trajectory_figure(tracks, report, bag.with_name("trajectory.png")).read_bytes()
    except (DuckielibError, ValueError, KeyError, IndexError, OSError):
        return None


def _played_back(bag: Path, mission: str) -> Optional[bytes]:
    """The grader's copy of the bag as a GIF for the feedback page, or None if it cannot be.

    Drawn here, from the bag that was scored, rather than taken from the run's folder: the
    page shows what the grader judged.
    """
    from duckielib.bags import Bag
    from duckielib.errors import DuckielibError
    from duckielib.tools.runner import write_animation

    path = bag.with_name("played_back.gif")
    try:
        if Bag(bag).message_count > ANIMATION_MESSAGE_LIMIT:
            return None
        write_animation(bag, f"{mission}: your run, as the grader read it", path, ANIMATION_FRAMES)
        return path.read_bytes()
    except (DuckielibError, ValueError, KeyError, IndexError, OSError):
        return None


def _failure(stderr: str) -> str:
    """The sentence ``duckie mission`` ended with, or the last line it printed, without paths."""
    lines = [line for line in stderr.splitlines() if line.strip()]
    said = [line[len("duckie: ") :] for line in lines if line.startswith("duckie: ")]
    if said:
        return f"The mission could not run to its end: {_without_paths(said[-1])}"
    last = _without_paths(lines[-1][:300]) if lines else "no message"
    return "The mission stopped with an error: " + last


def _without_paths(text: str) -> str:
    """``text`` without the sentences pointing to the run's files, and with files by name only.

    The run's folder and its log stay in the sandbox: a student cannot open them.
    """
    text = re.sub(r"\s*The run's [^.]*? (?:is|are) in \S+?\.?$", "", text.strip())
    text = re.sub(r"[;,]?\s*(?:its|the) traceback is in \S+", "", text)
    return re.sub(r"(?:/[^\s/:;,'\")]+)+/([^\s/:;,'\")]+)", r"\1", text)


def score_bag(run: Path, mission: str = "square_then_circle") -> Driving:
    """Score the run in folder ``run`` from its bag, copied and read by the grader.

    The bag is read without following links (``run`` itself included) and only if it is a
    regular file of at most :data:`BAG_LIMIT` bytes; it is copied into a folder of the
    grader's own, and that copy is scored and drawn (the trajectory figure, the animation).

    Args:
        run: the folder ``duckie mission`` wrote (``mission.bag``).
        mission: the mission that was driven.
    """
    out_of = part_points(mission)
    with tempfile.TemporaryDirectory(prefix="driving-") as scratch:
        try:
            bag = _copy(run, "mission.bag", Path(scratch), "The mission's bag")
        except _Unread as unread:
            why = "The mission wrote no bag." if unread.missing else unread.reason
            return Driving(out_of=out_of, reasons=[why])
        return _score_copy(bag, mission)


def _score_copy(path: Path, mission: str) -> Driving:
    """Score the bag at ``path``, the grader's own copy of a run's bag."""
    from autograder.motion import driving_problems, state_motions
    from duckielib.bags import Bag, pose_tracks
    from duckielib.bags.behaviour import mission_report
    from duckielib.errors import DuckielibError
    from duckielib.missions import mission_named

    out_of = part_points(mission)
    chosen = mission_named(mission)
    try:
        bag = Bag(path)
        tracks = pose_tracks(bag, "record")
        report = mission_report(bag, chosen, f"/{ROBOT}/", tracks=tracks)
        motions = state_motions(chosen, report, tracks)
    except (DuckielibError, ValueError, KeyError, OSError) as error:
        why = f"The mission's bag cannot be read: {_without_paths(str(error))}"
        return Driving(out_of=out_of, reasons=[why])
    summary = report.as_dict()
    problems = summary.pop("problems")
    summary["motion"] = [motion.as_dict() for motion in motions]
    summary["problems"] = problems
    driving = Driving(
        summary=summary,
        reasons=driving_problems(report, motions),
        out_of=out_of,
        finished=report.finished,
    )
    earned = {
        "bag": 1.0 if report.states else 0.0,
        "states": 1.0 if report.states_in_order and report.finished else 0.0,
        "stops": 1.0 if report.stops_held else 0.0,
    }
    moving = [name for name in out_of if name not in earned]
    earned.update(zip(moving, (motion.fraction for motion in motions)))
    driving.parts = {name: round(out_of[name] * earned[name], 2) for name in out_of}
    driving.score = round(sum(driving.parts.values()), 2)
    driving.figure = _drawn(tracks, report, path)
    if mission in ANIMATED:
        driving.animation = _played_back(path, mission)
    return driving
