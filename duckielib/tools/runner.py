"""Run a mission on the virtual Duckiebot with a solution: the course's main job.

:func:`run_mission` starts the virtual Duckiebot, launches three nodes written with rospy
(the library's odometry node running the solution's odometry functions, and the solution's own
light service node and mission node), records a ROS 1 bag, and when the mission is over writes
what happened to a folder::

    mission.bag       poses (odometry and truth), encoder ticks, commands, LEDs, states,
                      when the robot touched a wall
    trajectory.png    the path on the mat and x, y, theta over time, odometry against truth
    mission.gif       the same path, animated
    summary.json      the states with their LED colours and times, the final poses, the
                      distance to the start, the real-time factor
                      (see :mod:`duckielib.bags.behaviour`)
    log.txt           every node's log

``duckie mission`` and ``make run`` call it with the reference solution (the export of
``solutions/``) unless given a student's. A solution that is missing a part or fails gives the
contract's one-sentence error naming the notebook to finish. A run that stops early (a node
fails, or the mission does not end in time) still writes its bag, figure and summary first,
with the error in the summary, so what the robot did until then can be looked at and scored.
"""

# Over 600 lines: a mission run from launching its nodes to its bag, figure, animation and summary,
# whose steps share the run's folder and the way a failure is said and still written.

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import json
import math
import os
import re
import tempfile
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Mapping, Optional, Tuple, Union

from duckielib.errors import ConfigError, DuckielibError
from duckielib.missions import Mission, mission_named
from duckielib.solution import (
    CONTRACT,
    MISSION_PARTS,
    SolutionError,
    check_part,
    load_solution,
)

if TYPE_CHECKING:  # the bag's analysis is imported where a run is read, not by the nodes
    from duckielib.bags.behaviour import MissionReport
    from duckielib.sim.noise import NoiseProfile

__all__ = [
    "MissionError",
    "MissionRun",
    "OUTPUTS",
    "RECORDED",
    "chosen_mission",
    "drive_and_record",
    "finish_run",
    "logged_error",
    "node_crash",
    "run_files",
    "run_mission",
    "trajectory_figure",
    "write_animation",
]


def noise_name(noise: Union[str, NoiseProfile]) -> str:
    """The name a run's summary and title give its noise profile."""
    return noise if isinstance(noise, str) else noise.name


#: The files a run writes in its folder.
OUTPUTS = ("mission.bag", "trajectory.png", "mission.gif", "summary.json", "log.txt")

#: The topics recorded, relative to the robot's namespace.
RECORDED = (
    "odometry_node/pose",
    "simulator_node/ground_truth_pose",
    "simulator_node/wall_contact",
    "left_wheel_encoder_node/tick",
    "right_wheel_encoder_node/tick",
    "car_cmd_switch_node/cmd",
    "wheels_driver_node/wheels_cmd_executed",
    "led_emitter_node/led_pattern",
    "mission_node/state",
)

#: Simulated seconds a mission may take before it is stopped: four times the longest mission
#: with the reference solution (square then circle, about 62 s). A run still going then is
#: stuck, and saying so after 240 simulated seconds keeps the wait short.
DEFAULT_TIME_LIMIT_S = 240.0

#: The student's nodes, whose errors stop the run with their message.
_STUDENT_NODES = ("odometry_node", "light_service_node", "mission_node")


class MissionError(DuckielibError):
    """The mission could not run to its end (the message says why and what to do)."""


@dataclass
class MissionRun:
    """A finished run.

    Attributes:
        report: what the robot did, from the bag (:class:`~duckielib.bags.behaviour.MissionReport`).
        summary: the content of ``summary.json``.
        folder: where the files are.
        files: the files written, by name (``"bag"``, ``"trajectory"``, ...).
        simulated_s: simulated seconds run.
        wall_s: wall-clock seconds the simulation took (graph, nodes, odometry, bag).
    """

    report: MissionReport
    summary: Dict[str, Any]
    folder: Path
    files: Dict[str, Path]
    simulated_s: float
    wall_s: float

    @property
    def realtime_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        return self.simulated_s / self.wall_s if self.wall_s > 0 else math.inf

    def text(self) -> str:
        """A short summary for people."""
        report = self.report
        lines = [
            f"{report.mission.name} on the {self.summary['noise']} robot "
            f"(seed {self.summary['seed']}), {self.summary['solution']} solution:"
        ]
        for run in report.states:
            lines.append(f"  {run.name:<9} {run.color:<7} {run.start:6.1f} s to {run.end:6.1f} s")
        lines.append(
            f"total time {report.total_time:.1f} s (simulated), run in {self.wall_s:.2f} s: "
            f"{self.realtime_factor:.0f}x real time"
        )
        for label, pose in (
            ("final pose by odometry", report.final_pose_odometry),
            ("true final pose       ", report.final_pose_truth),
        ):
            if pose is not None:
                x, y, theta = pose
                lines.append(
                    f"{label}: x = {x:.3f} m, y = {y:.3f} m, theta = {theta:.3f} rad "
                    f"({math.degrees(theta):.1f} deg)"
                )
        error = report.odometry_error
        if error is not None and report.distance_to_start is not None:
            lines.append(
                f"odometry is {100 * error[0]:.1f} cm and {math.degrees(error[1]):.1f} deg from "
                f"the truth; the robot ended {100 * report.distance_to_start:.1f} cm from the start"
            )
        for start, end in report.wall_contacts:
            lines.append(f"the robot touched a wall from {start:.1f} s to {end:.1f} s")
        lines += [f"problem: {problem}" for problem in report.problems]
        if not report.problems:
            lines.append("every check passed: states and colours in order, stops held, back home")
        written = ", ".join(path.name for path in self.files.values())
        lines.append(f"wrote {written} in {self.folder}")
        return "\n".join(lines)


def _solution(solution: Any) -> Any:
    """The solution as something with the parts as attributes or keys, checked."""
    if solution is None or isinstance(solution, (str, os.PathLike)):
        return load_solution(solution, required=MISSION_PARTS)
    for name in MISSION_PARTS:
        check_part(solution, name)
    return solution


def _part(solution: Any, name: str) -> Any:
    return solution[name] if isinstance(solution, Mapping) else getattr(solution, name)


def _unwritten_part(error: BaseException) -> Optional[str]:
    """The contract part whose unfinished body raised ``error`` (a NotImplementedError)."""
    for frame, _ in reversed(list(traceback.walk_tb(error.__traceback__))):
        name = frame.f_code.co_name
        if name in CONTRACT:
            return name
        owner = type(frame.f_locals.get("self")).__name__
        if owner in CONTRACT:
            return owner
    return None


def _crash_message(node: str, error: BaseException) -> Tuple[type, str]:
    """What stopped the ``node``: the error class to raise, and its sentence.

    A :class:`SolutionError` when a part of the solution is unfinished, a
    :class:`MissionError` for any other failure.
    """
    if isinstance(error, SolutionError):
        return SolutionError, str(error)
    if isinstance(error, NotImplementedError):
        name = _unwritten_part(error)
        if name is not None:
            part = CONTRACT[name]
            return SolutionError, (
                f"Finish notebook {part.notebook}: {part.name} is not written yet "
                f"(the {node} needs it)."
            )
        return MissionError, (
            f"The {node} called a function that is not written yet (NotImplementedError)."
        )
    last = traceback.extract_tb(error.__traceback__)[-1:] or None
    where = f" (line {last[0].lineno} of {last[0].name})" if last else ""
    said = " ".join(str(error).split()).rstrip(".")
    return MissionError, f"The {node} stopped with {type(error).__name__}: {said}{where}."


def _prepare_folder(folder: Path) -> None:
    """Make ``folder`` ready for a run's files: created, writable, an earlier run's removed.

    A bag still being recorded is ``mission.bag.active``; one left there was cut off (its
    process was killed, or the disk filled up). It is kept under a new name, and a line says
    where, since its messages can still be recovered.

    Raises:
        MissionError: if ``folder`` is a file or cannot be created or written to.
    """
    if folder.exists() and not folder.is_dir():
        raise MissionError(
            f"{folder} is a file, not a folder: choose a folder for the run's files (it is "
            "created if it does not exist)."
        )
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise MissionError(
            f"Cannot create the folder {folder} for the run's files ({error.strerror or error}): "
            "choose a folder you can write to."
        ) from None
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass  # writing there works
        cut_off = folder / "mission.bag.active"
        if cut_off.exists():
            kept = _unused_name(folder, "unfinished-{}.bag.active")
            cut_off.replace(kept)
            print(
                f"note: {cut_off} is a recording that was cut off before it finished; it is "
                f"kept as {kept}, and 'duckie bag repair {kept} {kept.with_suffix('')}' "
                "recovers its messages.",
                flush=True,
            )
        for name in OUTPUTS:
            for path in (folder / name, folder / (name + ".active")):
                if path.exists():
                    path.unlink()
    except OSError as error:
        raise MissionError(
            f"Cannot write the run's files into the folder {folder} ({error.strerror or error}): "
            "choose a folder you can write to."
        ) from None


def _unused_name(folder: Path, pattern: str) -> Path:
    """The first ``folder / pattern.format(n)``, n = 1, 2, ..., that does not exist."""
    return next(
        path
        for path in (folder / pattern.format(number) for number in itertools.count(1))
        if not path.exists()
    )


def run_mission(
    solution: Any = None,
    mission: Union[str, Mission] = "square_then_circle",
    noise: Union[str, NoiseProfile] = "ideal",
    seed: int = 0,
    out: Union[str, os.PathLike] = "runs/latest",
    stop_color: Optional[str] = None,
    animation: bool = True,
    time_limit: float = DEFAULT_TIME_LIMIT_S,
    figure: bool = True,
    stall_limit: Optional[float] = None,
    live: Optional[Callable[[Any], Any]] = None,
) -> MissionRun:
    """Run ``mission`` on the virtual Duckiebot with ``solution`` and write its files to ``out``.

    Args:
        solution: the solution: None for the reference (the export of ``solutions/``), a
            folder of notebooks or a ``.py`` made by ``duckie export``, a loaded module, or a
            notebook's ``globals()``.
        mission: a :class:`~duckielib.missions.Mission` or its name (``"square_then_circle"``,
            ``"d_shape"``).
        noise: the simulator's noise profile: ``"ideal"``, ``"realistic"``, a profile file
            (``duckie calibrate`` writes one) or a :class:`~duckielib.sim.NoiseProfile`.
        seed: the simulator's seed (same seed and solution, same run).
        out: the folder to write the files to (created if needed; earlier files replaced,
            but a recording cut off by a killed run is kept as ``unfinished-N.bag.active``,
            with a line saying so).
        stop_color: the LED pattern of the stop states, if not the mission's (``"RED"``).
        animation: whether to write ``mission.gif`` (it takes a few seconds).
        time_limit: simulated seconds after which an unfinished mission is stopped.
        figure: whether to draw ``trajectory.png`` (the grader draws its own, from the bag).
        stall_limit: real seconds a node's code may run without calling rospy before the
            mission stops it (simulated time cannot move meanwhile); None: the graph's 10 s.
        live: to watch the run as it goes, a function given the virtual Duckiebot before the
            mission starts; what it returns is closed at the end (``lambda bot: bot.live()``
            serves the run to Foxglove or Lichtblick).

    Returns:
        The run: its report, summary and files.

    Raises:
        SolutionError: if the solution lacks a part or a part fails (naming the notebook).
        MissionError: if the mission cannot run to its end, or ``out`` cannot be written.
        ConfigError: if the mission, noise profile or colour is unknown, or the seed negative.
    """
    from duckielib.ros.modules import modules_installed

    chosen = chosen_mission(mission, seed, stop_color)
    label = "the reference" if solution is None else "your"
    # The nodes import rospy: the in-process graph's, even where a real ROS is installed.
    with modules_installed(replace_real=True):
        parts = _solution(solution)
    files = run_files(Path(out))
    with modules_installed(replace_real=True):
        namespace, simulated, wall, failure = drive_and_record(
            parts, chosen, noise, seed, files, time_limit, stall_limit, live
        )
    run = (chosen, namespace, noise, seed, label, files, simulated, wall)
    return finish_run(run, failure, animation, figure)


def chosen_mission(
    mission: Union[str, Mission], seed: int, stop_color: Optional[str] = None
) -> Mission:
    """The mission to drive, with its stops' colour; the seed checked.

    Raises:
        ConfigError: if the mission or colour is unknown, or the seed is not 0 or more.
    """
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ConfigError(f"The simulator's seed must be a whole number 0 or more, not {seed!r}.")
    chosen = mission_named(mission) if isinstance(mission, str) else mission
    return chosen if stop_color is None else chosen.with_stop_color(stop_color)


def run_files(folder: Path) -> Dict[str, Path]:
    """The run's folder made ready (see :func:`run_mission`), and its bag's and log's paths."""
    _prepare_folder(folder)
    return {"bag": folder / "mission.bag", "log": folder / "log.txt"}


def finish_run(
    run: Tuple[Mission, str, Union[str, NoiseProfile], int, str, Dict[str, Path], float, float],
    failure: Optional[DuckielibError],
    animation: bool = True,
    figure: bool = True,
) -> MissionRun:
    """Write a driven run's figure, animation and summary; raise ``failure`` if it stopped.

    Args:
        run: the mission, namespace, noise, seed, solution's label, files, simulated and
            wall-clock seconds of the run.
        failure: why the run stopped early, or None.
        animation: whether to write ``mission.gif``.
        figure: whether to draw ``trajectory.png``.
    """
    chosen, namespace, noise, seed, label, files, simulated, wall = run
    if failure is None:
        return _write_run(
            chosen, namespace, noise, seed, label, files, simulated, wall, animation, figure=figure
        )
    if files["bag"].is_file():
        # What the robot did until the run stopped is worth keeping: the summary says why.
        with contextlib.suppress(DuckielibError, ValueError, KeyError, IndexError, OSError):
            # A bag too short to summarise: the failure below says what went wrong.
            _write_run(
                chosen, namespace, noise, seed, label, files, simulated, wall, False, failure,
                figure=figure,
            )  # fmt: skip
    raise failure


def _write_run(
    chosen: Mission,
    namespace: str,
    noise: Union[str, NoiseProfile],
    seed: int,
    label: str,
    files: Dict[str, Path],
    simulated: float,
    wall: float,
    animation: bool,
    failure: Optional[DuckielibError] = None,
    figure: bool = True,
) -> MissionRun:
    """Read the run's bag and write its figure, animation and summary next to it."""
    from duckielib.bags import pose_tracks

    folder = files["bag"].parent
    tracks = pose_tracks(files["bag"], "record")
    from duckielib.bags.behaviour import mission_report

    report = mission_report(files["bag"], chosen, namespace, tracks=tracks)
    summary: Dict[str, Any] = report.as_dict()
    summary.update(
        {
            "robot": namespace.strip("/"),
            "noise": noise_name(noise),
            "seed": seed,
            "solution": label.replace("the ", ""),
            "simulated_s": round(simulated, 3),
            "wall_s": round(wall, 3),
            "realtime_factor": round(simulated / wall, 1) if wall > 0 else None,
            "error": None if failure is None else str(failure),
        }
    )
    if figure:
        files["trajectory"] = trajectory_figure(tracks, report, folder / "trajectory.png")
    if animation:
        files["animation"] = _animation(files["bag"], chosen, label, noise, folder / "mission.gif")
    files["summary"] = folder / "summary.json"
    partial = folder / "summary.json.partial"
    partial.write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    partial.replace(files["summary"])
    return MissionRun(report, summary, folder, files, simulated, wall)


def drive_and_record(
    parts: Any,
    chosen: Mission,
    noise: Union[str, NoiseProfile],
    seed: int,
    files: Dict[str, Path],
    time_limit: float,
    stall_limit: Optional[float] = None,
    live: Optional[Callable[[Any], Any]] = None,
) -> Tuple[str, float, float, Optional[DuckielibError]]:
    """Run the mission's nodes on a new virtual Duckiebot, recording the bag and the log.

    :func:`run_mission` without the figures and the summary (``duckie bench mission`` times it).

    Returns:
        The robot's namespace, the simulated seconds, the wall-clock seconds, and the error
        that stopped the mission early (None when it ended).
    """
    import rospy  # the in-process graph's, served by install_modules

    from duckielib.bags import BagRecorder
    from duckielib.bags.behaviour import AFTER_DONE_S
    from duckielib.nodes import odometry_node
    from duckielib.ros.graph import STALL_LIMIT_S, Graph, NodeCrashed
    from duckielib.sim import VirtualDuckiebot
    from duckielib.sim.world import OPEN_MAT

    graph = Graph(echo_logs=False, stall_limit=stall_limit or STALL_LIMIT_S)
    bot = VirtualDuckiebot(
        seed=seed, noise=noise, graph=graph, world=OPEN_MAT, start_pose=chosen.start
    )
    finished: List[bool] = []

    def mission_main() -> None:
        try:
            _part(parts, "mission_node")(chosen)
        finally:
            finished.append(True)

    bot.launch(odometry_node, rospy, parts, chosen.start)
    bot.launch(_part(parts, "light_service_node"))
    bot.launch(mission_main, name="mission_node")
    topics = [bot.namespace + name for name in RECORDED]
    recorder = BagRecorder(files["bag"], topics, graph=graph)
    crash: Optional[Tuple[type, str]] = None
    wall = time.perf_counter()
    view = None
    try:
        view = None if live is None else live(bot)
        ended = bot.run_until(lambda: bool(finished), time_limit)
        # Once the node has returned, watch the robot a while: wheels it left turning show in
        # the bag (the report checks that the robot stands still after 'done').
        bot.run(AFTER_DONE_S if ended else 0.2)  # and the last messages arrive
        crash = None if ended else logged_error(graph)
    except NodeCrashed as error:
        crash, ended = node_crash(error), False
    finally:
        bot.shutdown()  # what the robot does on the way out is still served
        if view is not None:
            view.close()
        recorder.close()
        wall = time.perf_counter() - wall
        simulated = bot.time
        log = "\n".join(repr(record) for record in graph.log) + "\n"
        files["log"].write_text(log, encoding="utf-8")
    if crash is None and recorder.error is not None:
        crash = (
            MissionError,
            f"Recording the bag failed ({recorder.error}); what reached the disk is in "
            f"{recorder.active_path.name}, which duckie bag repair recovers.",
        )
    return (
        bot.namespace,
        simulated,
        wall,
        _failure(crash, ended, files, bot.namespace, time_limit, graph),
    )


def logged_error(graph: Any) -> Optional[Tuple[type, str]]:
    """The first error a student's node logged, as what stopped the run; None if none did."""
    from duckielib.ros.log import ERROR

    errors = [
        record
        for record in graph.log
        if record.level >= ERROR and record.node.rsplit("/", 1)[-1] in _STUDENT_NODES
    ]
    if not errors:
        return None
    # The last line of the first traceback, its error's class without its module.
    said = re.sub(r"^(?:\w+\.)+(?=\w+: )", "", errors[0].text.splitlines()[-1])
    return (MissionError, f"The {errors[0].node} logged an error: {said.rstrip('.')}.")


def node_crash(error: Any) -> Tuple[type, str]:
    """What stopped a run whose node crashed (a :class:`~duckielib.ros.graph.NodeCrashed`)."""
    node = error.node.rsplit("/", 1)[-1]
    if error.__cause__ is None:  # stopped by the graph itself (code that never waits)
        said = str(error).split(": ", 1)[-1]
        return (MissionError, f"The {node.replace('_', ' ')} stopped: {said}")
    return _crash_message(node.replace("_", " "), error.__cause__)


def _failure(
    crash: Optional[Tuple[type, str]],
    ended: bool,
    files: Dict[str, Path],
    namespace: str,
    time_limit: float,
    graph: Any,
) -> Optional[DuckielibError]:
    """Why the run stopped early, as the error to raise; None when it ended."""
    from duckielib.bags.behaviour import DONE

    failure: Optional[DuckielibError] = None
    if crash is not None:
        kind, said = crash
        failure = kind(f"{said.rstrip('.')}. The run's log is in {files['log']}.")
    elif not ended and _announced_done(files["bag"], namespace):
        failure = MissionError(
            f"The mission node announced '{DONE}' but did not end within {time_limit:.0f} "
            "simulated seconds: a node must return once its work is done (a loop that never "
            "stops, or rospy.spin(), keeps it alive). The run's bag and log are in "
            f"{files['log'].parent}."
        )
    elif not ended:
        last = [record.text for record in graph.log if "state" in record.text][-1:]
        failure = MissionError(
            f"The mission did not announce '{DONE}' within {time_limit:.0f} simulated seconds"
            + (f" (last log: {last[0]})" if last else "")
            + f". The run's bag and log are in {files['log'].parent}."
        )
    return failure


def _announced_done(bag: Path, namespace: str) -> bool:
    """Whether the mission node's last state in the run's bag is ``done``."""
    from duckielib.bags import Bag
    from duckielib.bags.behaviour import DONE

    try:
        names = [item.message.data for item in Bag(bag).read(namespace + "mission_node/state")]
    except (DuckielibError, KeyError, ValueError, OSError, AttributeError):
        return False
    return bool(names) and names[-1] == DONE


def _named_tracks(tracks: List[Any]) -> List[Any]:
    """The odometry and truth tracks, labelled for people, times from the first pose."""
    named = []
    for track in tracks:
        if track.label.endswith("odometry_node/pose"):
            label = "odometry"
        elif track.label.endswith("ground_truth_pose"):
            label = "truth"
        else:
            continue
        named.append(dataclasses.replace(track, label=label))
    start = min(float(track.t[0]) for track in named)
    return [dataclasses.replace(track, t=track.t - start) for track in sorted(named, key=_label)]


def _label(track: Any) -> str:
    return track.label


def trajectory_figure(tracks: List[Any], report: MissionReport, path: Path) -> Path:
    """Draw a run's ``trajectory.png``: odometry against the truth on the mat, and over time.

    Args:
        tracks: the run's pose tracks, as ``pose_tracks(bag, "record")`` reads them.
        report: the run's mission report (the title and the start pose).
        path: the PNG to write.

    Returns:
        The path written.
    """
    from duckielib import plots

    figure = plots.pose_figure(
        _named_tracks(tracks),
        title=f"{report.mission.name}: odometry and truth",
        reference=report.mission.start,
    )
    return plots.save_figure(figure, path)


def _animation(
    bag: Path, chosen: Mission, label: str, noise: Union[str, NoiseProfile], path: Path
) -> Path:
    """``mission.gif``: the run played back in about 12 s."""
    title = f"{chosen.name}: {label.replace('the ', '')} solution, {noise_name(noise)} robot"
    return write_animation(bag, title, path)


def write_animation(bag: Path, title: str, path: Path, frames: int = 100) -> Path:
    """Write a mission's bag as an animation: the robot with its LEDs and states, in 12 s.

    Args:
        bag: the run's bag.
        title: what the run is, shown beside the mat.
        path: the GIF (or MP4) to write.
        frames: how many frames (8 a second).

    Raises:
        BagError: if the bag cannot be read.
        DuckielibError: if it holds nothing to play, or the file cannot be written.
    """
    from duckielib.plots import Recording, RunPlayer
    from duckielib.sim.world import OPEN_MAT

    recording = Recording.from_bag(bag, world=OPEN_MAT, title=title)
    return RunPlayer.lasting(recording, max_frames=frames).save(path)
