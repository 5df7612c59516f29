"""The ``duckie`` command: the course's tools for students and instructors.

Errors the user can fix are printed as one sentence on stderr, without a traceback, and the
command exits with status 1 (2 for a badly formed command line, as argparse does). Ctrl-C and
SIGTERM end a command as cleanly as its own end would (a mission's bag is closed whole and
its wheels stopped), with a sentence and status 130 or 143.
"""

# Over 600 lines: the whole `duckie` command line, each command's options beside the thin handler
# that runs it; the bag commands (about 300 lines with their parsers) are the seam to split along.

from __future__ import annotations

import argparse
import contextlib
import math
import os
import re
import signal
import sys
import threading
from typing import Any, Callable, Dict, Iterator, List, Optional, Tuple

from duckielib.errors import DuckielibError

__all__ = ["main"]


def _bench(args: argparse.Namespace) -> int:
    from duckielib.tools.bench import benchmarks, run_benchmark

    if args.name is None:
        for name, (_, description) in sorted(benchmarks().items()):
            print(f"{name}: {description}")
        return 0
    for figure, value in run_benchmark(args.name):
        print(f"{figure}: {value}", flush=True)
    return 0


def _bag_info(args: argparse.Namespace) -> int:
    from duckielib.bags import Bag

    bag = Bag(args.bag)
    print(bag.info(check=args.check))
    # A damaged bag is said on the damage line, and in the exit status for scripts.
    return 1 if args.check and bag.check() else 0


def _bag_plot(args: argparse.Namespace) -> int:
    from duckielib.bags import Bag, pose_tracks
    from duckielib.errors import BagError

    bag = Bag(args.bag)
    tracks = pose_tracks(bag, args.time_base)
    if args.topic:
        tracks = [track for track in tracks if track.label in args.topic]
        for topic in args.topic:
            bag.topic(topic)
    if not tracks:
        raise BagError(
            f"{bag.path.name} has no topic of type duckietown_msgs/Pose2DStamped to plot; "
            "for a bag of encoder ticks, draw the path odometry computes from them with "
            f"'duckie bag odometry {args.bag} --plot {args.output}'."
        )
    print(f"Wrote {_pose_figure(tracks, bag.path.name, args.output)}.")
    return 0


def _bag_animate(args: argparse.Namespace) -> int:
    from duckielib.plots import Recording, RunPlayer

    recording = Recording.from_bag(args.bag, camera_topic=args.camera)
    player = RunPlayer.lasting(recording, args.seconds, max_frames=200)
    print(f"Wrote {player.save(args.output)} ({len(player)} frames).")
    return 0


def _pose_figure(tracks: List[Any], title: str, path: str) -> Any:
    """Draw pose ``tracks`` to the figure file ``path``, times from the first pose; the path."""
    import dataclasses

    from duckielib import plots

    # Times from the bag's first pose: a real robot's clock gives seconds since 1970.
    start = min((float(track.t[0]) for track in tracks if len(track)), default=0.0)
    tracks = [dataclasses.replace(track, t=track.t - start) for track in tracks]
    figure = plots.pose_figure(tracks, title=f"{title} (t = 0 at {start:.3f} s)")
    return plots.save_figure(figure, path)


def _bag_odometry(args: argparse.Namespace) -> int:
    import json

    from duckielib.bags import Bag, replay_odometry
    from duckielib.solution import load_solution

    solution = load_solution(args.solution)
    bag = Bag(args.bag)
    left, right = _encoder_pair(bag, args.left, args.right)
    track = replay_odometry(
        bag,
        solution,
        start=args.start,
        left_topic=left,
        right_topic=right,
        time_base=args.time_base,
        label=f"odometry ({'your' if args.solution else 'reference'} solution)",
    )
    x, y, theta = track.final_pose
    title = f"{bag.path.name}: odometry from the encoder ticks"
    wrote = _pose_figure([track], title, args.plot) if args.plot else None
    if args.json:
        print(json.dumps({"x": x, "y": y, "theta": theta}))
        return 0
    for note in track.notes:
        print(f"note: {note}")
    print(f"{len(track)} poses from {track.t[0]:.3f} s to {track.t[-1]:.3f} s.")
    print(f"final pose: x = {x:.4f} m, y = {y:.4f} m, theta = {theta:.4f} rad")
    if wrote is not None:
        print(f"Wrote {wrote}.")
    return 0


#: The message type of the wheels' encoder topics.
_ENCODER_TYPE = "duckietown_msgs/WheelEncoderStamped"


def _encoder_pair(bag: Any, left: Optional[str], right: Optional[str]) -> Tuple[Any, Any]:
    """The encoder topics ``--left`` and ``--right`` ask for; with one given, the other's match.

    The other wheel's topic is the given one's twin (``left_wheel_encoder`` for
    ``right_wheel_encoder``, same namespace), or else the bag's only topic of that wheel.

    Returns:
        The two topics, or None for what ``replay_odometry`` is to find by name.

    Raises:
        DuckielibError: if both are the same topic, or which topic to use is not clear.
    """
    if left is not None and left == right:
        raise DuckielibError(
            f"--left and --right are both {left}: give each wheel its own encoder topic."
        )
    encoders = bag.topics_of_type(_ENCODER_TYPE)
    if left is None and right is None:
        for side in ("left", "right"):
            found = [name for name in encoders if f"{side}_wheel_encoder" in name]
            if len(found) > 1:
                raise DuckielibError(
                    f"{bag.path.name} has {len(found)} {side} encoder topics "
                    f"({', '.join(found)}): choose one with --{side}."
                )
        return None, None  # one of each, or the library says what is missing
    if left is not None and right is not None:
        return left, right
    if left is not None:
        given, side, other = left, "left", "right"
    else:
        given, side, other = str(right), "right", "left"
    bag.topic(given)  # a sentence if the bag has no such topic
    twin = given.replace(f"{side}_wheel_encoder", f"{other}_wheel_encoder")
    found = [name for name in encoders if f"{other}_wheel_encoder" in name]
    if twin != given and twin in found:
        chosen = twin
    elif len(found) == 1 and found[0] != given:
        chosen = found[0]
    elif len(found) > 1:
        raise DuckielibError(
            f"{bag.path.name} has {len(found)} {other} encoder topics ({', '.join(found)}): "
            f"choose the one that pairs with {given} with --{other}."
        )
    else:
        raise DuckielibError(
            f"{bag.path.name} has no {other} encoder topic to pair with {given}: give one "
            f"with --{other}."
        )
    return (given, chosen) if side == "left" else (chosen, given)


def _bag_repair(args: argparse.Namespace) -> int:
    from duckielib.bags import repair_bag

    print(repair_bag(args.broken, args.output, compression=args.compression))
    return 0


def _bag_convert(args: argparse.Namespace) -> int:
    from duckielib.bags.convert import bag_kind, convert_bag

    target = convert_bag(
        args.source, args.target, schema=args.schema, storage=args.storage, poses_3d=args.poses_3d
    )
    kind = bag_kind(target)
    said = {
        "ros1": "a ROS 1 bag",
        "mcap": f"an MCAP file with ROS {args.schema[-1]} schemas",
        "ros2": f"a ROS 2 bag folder ({args.storage})",
    }[kind]
    print(f"Wrote {target}: {said}.")
    if args.poses_3d:
        print("Each 2D pose is also a frame on /tf and a PoseStamped on TOPIC_3d, for 3D panels.")
    if kind == "mcap":
        print("Open it in Foxglove, Lichtblick or PlotJuggler 4 (File > Open).")
    return 0


def _export(args: argparse.Namespace) -> int:
    from pathlib import Path

    from duckielib.solution import export_solution

    export = export_solution(args.folder)
    output = Path(args.output)
    if output.suffix != ".py":
        raise DuckielibError(f"{output} must end in .py: a solution is a Python module.")
    if not output.parent.is_dir():
        raise DuckielibError(f"There is no folder {output.parent} to write {output.name} into.")
    partial = output.with_name(output.name + ".partial")
    partial.write_text(export.source, encoding="utf-8")
    partial.replace(output)
    print(export.report())
    print(f"Wrote {output}.")
    return 0


def _submit(args: argparse.Namespace) -> int:
    from duckielib.tools.handin import submit

    folder = args.folder or "."
    print(
        f"Running {args.submit} from top to bottom as saved, as grading does, then submitting "
        "it...",
        flush=True,
    )
    check = submit(folder, args.submit, progress=lambda run: print(run.summary(), flush=True))
    if any(not run.clean for run in check.runs):
        print(
            "It does not run to the end yet or fails a visible test: fix it if you can, then "
            "submit again (your instructor collects the latest submission)."
        )
    answers = check.answers_left()
    if answers:
        print(answers)
    print(f"Submitted {args.submit}: it shows under Submitted assignments in the Assignment List.")
    return 0


def _handin(args: argparse.Namespace) -> int:
    from duckielib.tools.handin import check_minutes, handin, handin_notebooks

    if args.submit:
        if args.output:
            raise DuckielibError("Give either --submit ASSIGNMENT or -o NAME.zip, not both.")
        return _submit(args)
    if not args.output:
        raise DuckielibError(
            "Say where to write the zip with -o NAME.zip (on a class hub: --submit ASSIGNMENT)."
        )
    args.folder = args.folder or "course"
    count = len(handin_notebooks(args.folder, args.output))
    notebooks = f"{count} notebook" + ("" if count == 1 else "s")
    minutes = check_minutes(count)
    print(
        f"Running your {notebooks} from top to bottom as saved, as grading does "
        f"(about {minutes} minute{'' if minutes == 1 else 's'})...",
        flush=True,
    )
    check = handin(args.folder, args.output, progress=lambda run: print(run.summary(), flush=True))
    todo = [run.name for run in check.runs if not run.clean]
    if todo:
        print(
            f"Unfinished or not running to the end: {', '.join(todo)}. Fix them if you can, "
            "then hand in again; cells that raise are shown to your instructor."
        )
    else:
        print("Every notebook runs from top to bottom and passes its visible tests.")
    answers = check.answers_left()
    if answers:
        print(answers)
    print(f"Wrote {args.output} ({notebooks}): hand in this file.")
    return 0


def _add_handin(commands: argparse._SubParsersAction) -> None:
    """``duckie handin``: check a student's notebooks as grading runs them, and zip them."""
    hand = commands.add_parser(
        "handin", help="check your notebooks as grading runs them, and zip them to hand in"
    )
    hand.add_argument(
        "folder",
        nargs="?",
        help="your folder of notebooks (default: course; with --submit, this folder)",
    )
    hand.add_argument("-o", "--output", help="the zip to write, named after you (NAME.zip)")
    hand.add_argument(
        "--submit",
        metavar="ASSIGNMENT",
        help="on a class hub: check ASSIGNMENT, then submit it as the Assignment List does",
    )
    hand.set_defaults(handler=_handin)


def _mission(args: argparse.Namespace) -> int:
    from duckielib.tools.apart import run_apart
    from duckielib.tools.runner import run_mission

    if args.solution is None:
        from duckielib.solution import reference_solution_dir

        reference_solution_dir()  # a sentence where this copy of the course has none
        print("Using the reference solution (the export of solutions/).", flush=True)
    run = (run_apart if args.apart else run_mission)(
        solution=args.solution,
        mission=args.mission,
        noise=args.noise,
        seed=args.seed,
        out=args.out,
        stop_color=args.stop_color,
        animation=not args.no_animation,
        figure=not args.no_figure,
        stall_limit=args.stall_limit,
        live=_live_view(args.port, args.rate, "mission starts") if args.live else None,
    )
    print(run.text())
    if args.mcap:
        from pathlib import Path

        from duckielib.bags.convert import convert_bag

        bag = Path(run.files["bag"])
        mcap = bag.with_suffix(".mcap")
        mcap.unlink(missing_ok=True)  # a previous run's, in the same folder
        convert_bag(bag, mcap, poses_3d=True)
        print(
            f"wrote {mcap}: the same run as MCAP, its poses also as frames of a 3D panel, for "
            "Foxglove, Lichtblick or PlotJuggler 4"
        )
    return 0


def _live_view(port: int, rate: float, starts: str) -> Any:
    """What ``--live`` gives a run: serve the robot, then wait for a viewer to start."""

    def serve(bot: Any) -> Any:
        view = bot.live(port=port, rate=rate)
        print(f"The {starts} when a viewer subscribes to a topic (Ctrl-C to stop).", flush=True)
        view.wait_for_viewer()
        print(f"A viewer is watching: driving at {rate:g} x the wall clock's pace.", flush=True)
        return view

    return serve


def _run(args: argparse.Namespace) -> int:
    from duckielib.tools.project import run_project

    try:
        run = run_project(
            args.path,
            launcher=args.launcher or "default",
            noise=args.noise,
            seed=args.seed,
            seconds=args.seconds,
            out=args.out,
            live=_live_view(args.port, args.rate, "nodes start") if args.live else None,
        )
    except KeyboardInterrupt as stopped:  # the run's files are written: say what ran
        interrupted = getattr(stopped, "run", None)
        if interrupted is not None:
            print(interrupted.text())
        raise
    print(run.text())
    if run.failures:
        print(f"duckie: {run.failures[0]}", file=sys.stderr)
        return 1
    return 0


def _add_run(commands: argparse._SubParsersAction) -> None:
    """``duckie run``: a Duckietown project's nodes on the virtual Duckiebot."""
    run = commands.add_parser(
        "run",
        help="run a Duckietown project (its launcher, launch files and nodes, unchanged) on the "
        "virtual Duckiebot, as dts devel run runs it on the robot",
    )
    run.add_argument(
        "path", help="the project's folder (the one with packages/), a launch file or a node script"
    )
    run.add_argument(
        "-L",
        "--launcher",
        action="append",
        help="the launcher to run, launchers/NAME.sh (default: default); give -L again to run "
        "several together, as several dts devel run containers on one robot",
    )
    _add_robot_options(run)
    run.add_argument(
        "--seconds",
        type=_seconds,
        default=30.0,
        help="simulated seconds to run at most (default 30)",
    )
    run.add_argument("--out", default="runs/project", help="folder for the bag, log, summary")
    _add_live_options(run)
    run.set_defaults(handler=_run)


def _add_live_options(command: argparse.ArgumentParser) -> None:
    """``--live``, ``--port`` and ``--rate``: watch a run in Foxglove or Lichtblick."""
    command.add_argument(
        "--live",
        action="store_true",
        help="serve the run to Foxglove or Lichtblick as it goes (every topic, the camera, "
        "the poses as frames of a 3D panel), at the wall clock's pace; it starts when a "
        "viewer subscribes",
    )
    command.add_argument(
        "--port",
        type=_port,
        default=8765,
        help="with --live: the port to serve on, on this computer only (default 8765)",
    )
    command.add_argument(
        "--rate",
        type=_rate,
        default=1.0,
        help="with --live: simulated seconds per wall-clock second (default 1)",
    )


def _robot_prepare(args: argparse.Namespace) -> int:
    from duckielib.tools.deploy import prepare

    prepare(solution=args.solution, project=args.project)
    return 0


def _add_robot(commands: argparse._SubParsersAction) -> None:
    """``duckie robot ...``: from the notebooks to a real Duckiebot."""
    robot = commands.add_parser("robot", help="get your solution ready for a real Duckiebot")
    robot_commands = robot.add_subparsers(
        dest="robot_command", metavar="ROBOT_COMMAND", required=True
    )
    robot_prepare = robot_commands.add_parser(
        "prepare",
        help="write the course library and your solution into robot_nodes/deploy/",
    )
    robot_prepare.add_argument(
        "--solution",
        help="your notebooks' folder or a file made by duckie export (default: the reference)",
    )
    robot_prepare.add_argument(
        "--project",
        help="the Duckietown project to prepare (default: the course's robot_nodes/)",
    )
    robot_prepare.set_defaults(handler=_robot_prepare)


def _add_mission(commands: argparse._SubParsersAction) -> None:
    """``duckie mission``: drive a mission on the virtual Duckiebot."""
    from duckielib.missions import MISSIONS

    mission = commands.add_parser(
        "mission",
        help="drive a mission (square then circle, the D, the straight or the rotation task) on "
        "the virtual Duckiebot",
    )
    mission.add_argument(
        "--solution",
        help="your notebooks' folder or a file made by duckie export (default: the reference)",
    )
    mission.add_argument(
        "--mission",
        default="square_then_circle",
        choices=sorted(MISSIONS),
        help="which mission to drive (default: square_then_circle)",
    )
    _add_robot_options(mission)
    mission.add_argument(
        "--stop-color", type=_pattern, help="the LED pattern of the stops (default: RED)"
    )
    mission.add_argument("--out", default="runs/latest", help="folder for the bag, plot, summary")
    mission.add_argument(
        "--no-animation", action="store_true", help="skip mission.gif (a few seconds faster)"
    )
    mission.add_argument(
        "--no-figure", action="store_true", help="skip trajectory.png (the grader draws its own)"
    )
    mission.add_argument(
        "--mcap",
        action="store_true",
        help="also write the run as mission.mcap (ROS 1 schemas, every message), which "
        "Foxglove, Lichtblick and PlotJuggler 4 open",
    )
    _add_live_options(mission)
    mission.add_argument(
        "--stall-limit",
        type=_seconds,
        metavar="SECONDS",
        help="real seconds a node's code may run without calling rospy before the mission "
        "stops it (default 10)",
    )
    mission.add_argument(
        "--apart",
        action="store_true",
        help="run your nodes in a process of their own that reaches the robot only through "
        "topics and services, as the grader does",
    )
    mission.set_defaults(handler=_mission)


def _add_robot_options(parser: argparse.ArgumentParser) -> None:
    """``--noise`` and ``--seed``: which virtual Duckiebot a command drives."""
    parser.add_argument(
        "--noise",
        default="ideal",
        type=_noise,
        help="the simulated robot: ideal (default), realistic (motors, wheels and drift as "
        "measured on real DB21s), or a profile file duckie calibrate wrote",
    )
    parser.add_argument(
        "--seed", type=_seed, default=0, help="the simulator's seed, 0 or more (default 0)"
    )


def _noise(text: str) -> str:
    """A noise profile from the command line: ``ideal``, ``realistic`` or a profile file."""
    if text in ("ideal", "realistic") or text.endswith(".json"):
        return text
    raise argparse.ArgumentTypeError(
        f"give ideal, realistic or a profile file (robot.json), not {text!r}"
    )


def _add_simulator(commands: argparse._SubParsersAction) -> None:
    """``duckie calibrate`` and ``duckie sim replay``: the simulator against a real robot."""
    calibrate = commands.add_parser(
        "calibrate",
        help="fit the simulated motors to your robot, from a bag of its wheel commands and ticks",
    )
    calibrate.add_argument(
        "bag",
        nargs="+",
        help="a bag with wheels_driver_node/wheels_cmd and both encoders' ticks (any driving: "
        "your mission, lane following, held commands); several bags of one robot fit together",
    )
    calibrate.add_argument("-o", "--out", help="write the fitted profile to this file (.json)")
    calibrate.add_argument("--name", help="the profile's name (default: the file's name)")
    calibrate.add_argument(
        "--check",
        nargs="+",
        default=[],
        metavar="OTHER",
        help="other bags of the same robot: replay them into the fitted profile to see how "
        "well it predicts runs it was not fitted on",
    )
    calibrate.add_argument(
        "--solution",
        help="the odometry that turns ticks into headings and paths, to compare them too: "
        "your notebooks' folder (course) or a file made by duckie export (default: the "
        "reference, where there is one)",
    )
    _add_replay_topics(calibrate)
    calibrate.add_argument("--json", action="store_true", help="print the figures as JSON")
    calibrate.set_defaults(handler=_calibrate)

    sim = commands.add_parser("sim", help="the simulator against a real robot's bag")
    sim_commands = sim.add_subparsers(dest="sim_command", metavar="SIM_COMMAND", required=True)
    replay = sim_commands.add_parser(
        "replay",
        help="replay a bag's wheel commands into the simulator and compare the ticks",
    )
    replay.add_argument(
        "bag", help="a bag with wheels_driver_node/wheels_cmd and both encoders' ticks"
    )
    replay.add_argument(
        "--noise",
        default="realistic",
        type=_noise,
        help="the simulated robot: ideal, realistic (default) or a profile file (.json)",
    )
    replay.add_argument("--seed", type=_seed, default=0, help="the simulator's seed (default 0)")
    replay.add_argument(
        "--solution",
        help="the odometry that turns ticks into headings and paths: your notebooks' folder "
        "(course) or a file made by duckie export (default: the reference, where there is one)",
    )
    replay.add_argument("--plot", help="draw both paths and headings to this file (.png)")
    _add_replay_topics(replay)
    replay.add_argument("--json", action="store_true", help="print the figures as JSON")
    replay.set_defaults(handler=_sim_replay)
    motors = sim_commands.add_parser(
        "motors",
        help="the simulated wheels' steady speeds for the commands real DB21s were measured with",
    )
    motors.add_argument(
        "--noise",
        default="realistic",
        type=_noise,
        help="the simulated robot: ideal, realistic (default) or a profile file (.json)",
    )
    motors.set_defaults(handler=_sim_motors)


def _add_replay_topics(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--commands", help="the wheel commands' topic (default: found by type and name)"
    )
    parser.add_argument("--left", help="the left encoder's topic (default: found by name)")
    parser.add_argument("--right", help="the right encoder's topic (default: found by name)")


def _print_figures(figures: Dict[str, Any], as_json: bool) -> None:
    if as_json:
        import json

        # A figure that says nothing (NaN) is JSON's null: NaN is not JSON.
        clean = {
            name: None if isinstance(value, float) and math.isnan(value) else value
            for name, value in figures.items()
        }
        print(json.dumps(clean, indent=2, allow_nan=False))
    else:
        for name, value in figures.items():
            print(f"{name}: {value}")


def _calibrate(args: argparse.Namespace) -> int:
    from pathlib import Path

    from duckielib.sim.calibrate import calibrate_bag

    name = args.name or (Path(args.out).stem if args.out else "calibrated")
    solution = _odometry_solution(args.solution)
    calibration = calibrate_bag(
        args.bag, name, args.commands, args.left, args.right, args.check, solution
    )
    _print_figures(calibration.figures(), args.json)
    for note in calibration.notes:
        print(f"note: {note}", file=sys.stderr)
    if args.out:
        path = calibration.profile.save(args.out)
        if not args.json:
            print(f"wrote {path}: use it with duckie mission --noise {path}")
    elif not args.json:
        print("(write the profile to a file with -o robot.json)")
    return 0


def _sim_replay(args: argparse.Namespace) -> int:
    from duckielib.plots.replay import replay_figure
    from duckielib.sim.replay import replay_bag

    solution = _odometry_solution(args.solution)
    report = replay_bag(
        args.bag, args.noise, args.seed, args.commands, args.left, args.right, solution
    )
    _print_figures(report.figures(), args.json)
    for note in report.notes:
        print(f"note: {note}", file=sys.stderr)
    if report.paths is None:
        print(
            "note: headings and paths were not compared (the travel alone does not say where "
            "the robot went): give --solution course to compare them with your odometry "
            "(notebook 05).",
            file=sys.stderr,
        )
        if args.plot:
            raise DuckielibError("--plot draws the paths: give --solution course as well.")
    elif args.plot:
        print(f"wrote {replay_figure(report, args.plot)}", file=sys.stderr)
    return 0


def _odometry_solution(given: Optional[str]) -> Any:
    """The solution whose odometry a replay uses: ``given``, or the reference if it is there."""
    from duckielib.solution import ODOMETRY_PARTS, load_solution, reference_solution_dir

    if given is None:
        try:
            reference_solution_dir()
        except DuckielibError:  # a student's copy of the course: no reference
            return None
    return load_solution(given, required=ODOMETRY_PARTS)


def _sim_motors(args: argparse.Namespace) -> int:
    from duckielib.sim.motors import motor_table

    print(f"{'command':<30} {'duties':>14} {'simulated rad/s':>17} {'real DB21 rad/s':>21}")
    for row in motor_table(args.noise):
        duties = f"{row.duties[0]:+.3f} {row.duties[1]:+.3f}"
        simulated = f"{row.simulated[0]:.1f} {row.simulated[1]:.1f}"
        real = " ".join(f"{low:.1f}-{high:.1f}" for low, high in row.real)
        print(f"{row.what:<30} {duties:>14} {simulated:>17} {real:>21}")
    return 0


def _pattern(text: str) -> str:
    """An LED pattern's name from the command line (``RED``, ``GREEN``...)."""
    from duckielib.leds import PATTERNS

    if text not in PATTERNS:
        raise argparse.ArgumentTypeError(
            f"give an LED pattern's name ({', '.join(PATTERNS)}), not {text!r}"
        )
    return text


def _seed(text: str) -> int:
    """A seed from the command line: a whole number 0 or more."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"give a whole number 0 or more, not {text!r}")
    return value


def _above_zero(text: str, what: str) -> float:
    """A finite number above 0 from the command line, or a sentence saying ``what`` it is."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not value > 0 or math.isinf(value):
        raise argparse.ArgumentTypeError(f"give {what}, not {text!r}")
    return value


def _seconds(text: str) -> float:
    """A duration from the command line: a number of seconds above 0."""
    return _above_zero(text, "a number of seconds above 0")


def _rate(text: str) -> float:
    """A pace from the command line: simulated seconds per wall second, above 0."""
    return _above_zero(text, "simulated seconds per wall-clock second, a number above 0")


def _port(text: str) -> int:
    """A TCP port from the command line: 1 to 65535, or 0 for any free one."""
    if not text.isdigit() or int(text) > 65535:
        raise argparse.ArgumentTypeError(
            f"give a port from 1 to 65535 (0: any free one), not {text!r}"
        )
    return int(text)


def _finite(text: str) -> float:
    """A number from the command line, refused if it is not finite (nan, inf)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"give a number, not {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"give a finite number, not {text!r}")
    return value


def _plugins() -> List[Callable[[argparse._SubParsersAction], None]]:
    """The functions that add more commands: the entry points of the group ``duckie.commands``.

    The instructors' commands (``release``, ``grade``, ``formgrade``, ``feedback``) come this way
    from the ``autograder`` package, so the library students receive never imports it.
    """
    from importlib.metadata import entry_points

    found = []
    for entry in sorted(entry_points(group="duckie.commands"), key=str):
        try:
            found.append(entry.load())
        except ModuleNotFoundError as error:
            # The student edition has no autograder/, even where the environment was made for
            # the whole repository: then its commands are simply not there.
            if not error.name or not (entry.module + ".").startswith(error.name + "."):
                raise
    return found


def _add_bag_writers(bag_commands: argparse._SubParsersAction) -> None:
    """The ``duckie bag`` commands that write a new bag: ``repair`` and ``convert``."""
    repair = bag_commands.add_parser(
        "repair", help="recover every complete message of a bag whose recording was killed"
    )
    repair.add_argument("broken", help="the damaged bag (for example run.bag.active)")
    repair.add_argument("output", help="the repaired bag to write")
    repair.add_argument("--compression", choices=("none", "bz2"), default="none")
    repair.set_defaults(handler=_bag_repair)

    convert = bag_commands.add_parser(
        "convert",
        help="write a bag as MCAP (for Foxglove, Lichtblick, PlotJuggler 4), as a ROS 2 bag or "
        "as a ROS 1 bag",
    )
    convert.add_argument("source", help="a ROS 1 bag, an MCAP file or a ROS 2 bag folder")
    convert.add_argument(
        "target", help="run.mcap (MCAP), run.bag (ROS 1) or run (a ROS 2 bag folder)"
    )
    convert.add_argument(
        "--schema",
        choices=("ros1", "ros2"),
        default="ros1",
        help="an MCAP target's messages: ROS 1 bytes and definitions, nothing lost (default), "
        "or ROS 2's CDR as rosbag2 writes it (a Header's seq dropped)",
    )
    convert.add_argument(
        "--storage",
        choices=("mcap", "sqlite3"),
        default="mcap",
        help="a ROS 2 bag folder's storage (default mcap)",
    )
    convert.add_argument(
        "--poses-3d",
        action="store_true",
        help="also write each 2D pose (duckietown_msgs/Pose2DStamped) as a frame on /tf and a "
        "geometry_msgs/PoseStamped on TOPIC_3d, which 3D panels draw",
    )
    convert.set_defaults(handler=_bag_convert)


#: The ``--time-base`` option of the ``duckie bag`` commands that read poses or ticks.
_TIME_BASE: Dict[str, Any] = {
    "choices": ("auto", "header", "record"),
    "default": "auto",
    "help": "times to use: header stamps, record times, or auto (stamps unless all 0)",
}


def _add_export(commands: argparse._SubParsersAction) -> None:
    export = commands.add_parser(
        "export", help="collect the graded functions of your notebooks into one solution module"
    )
    export.add_argument("folder", help="the folder of notebooks (your course/, or solutions/)")
    export.add_argument("-o", "--output", required=True, help="the .py file to write")
    export.set_defaults(handler=_export)


def _add_bag(commands: argparse._SubParsersAction) -> None:
    bag = commands.add_parser("bag", help="inspect, plot, replay and repair ROS 1 bags")
    bag_commands = bag.add_subparsers(dest="bag_command", metavar="BAG_COMMAND", required=True)
    _add_bag_readers(bag_commands)
    _add_bag_odometry(bag_commands)
    _add_bag_writers(bag_commands)


def _add_bag_readers(bag_commands: argparse._SubParsersAction) -> None:
    """The ``duckie bag`` commands that show a bag: ``info``, ``plot`` and ``animate``."""
    info = bag_commands.add_parser("info", help="topics, types, counts and duration of a bag")
    info.add_argument("bag", help="the bag file")
    info.add_argument(
        "--no-check",
        dest="check",
        action="store_false",
        help="read only the index, not every record (faster on big compressed bags; damage "
        "in the middle goes unnoticed)",
    )
    info.set_defaults(handler=_bag_info)

    plot = bag_commands.add_parser("plot", help="plot the poses (Pose2DStamped topics) of a bag")
    plot.add_argument("bag", help="the bag file")
    plot.add_argument("-o", "--output", required=True, help="the figure to write (.png/.svg/.pdf)")
    plot.add_argument("--topic", action="append", help="a pose topic to plot (default: all)")
    plot.add_argument("--time-base", **_TIME_BASE)
    plot.set_defaults(handler=_bag_plot)

    animate = bag_commands.add_parser(
        "animate",
        help="play a bag back as a GIF or MP4: the robot, its LEDs, its paths, state and camera",
    )
    animate.add_argument(
        "bag", help="the bag file (poses, and LEDs, states, camera if it has them)"
    )
    animate.add_argument("-o", "--output", required=True, help="the animation to write (.gif/.mp4)")
    animate.add_argument(
        "--camera", metavar="TOPIC", help="the CompressedImage topic to show (default: the first)"
    )
    animate.add_argument(
        "--seconds", type=float, default=12.0, help="how long the animation lasts (default 12)"
    )
    animate.set_defaults(handler=_bag_animate)


def _add_bag_odometry(bag_commands: argparse._SubParsersAction) -> None:
    from duckielib.missions import TASK_START

    odometry = bag_commands.add_parser(
        "odometry", help="replay wheel odometry from a bag's encoder ticks"
    )
    odometry.add_argument("bag", help="the bag file")
    odometry.add_argument(
        "--start",
        nargs=3,
        type=_finite,
        metavar=("X", "Y", "THETA"),
        default=TASK_START,
        help="the starting pose, in metres and radians (default: 0.32 0.32 pi/2)",
    )
    odometry.add_argument(
        "--solution",
        help="your notebooks' folder or a file made by duckie export (default: the reference)",
    )
    odometry.add_argument("--left", help="the left encoder topic (default: found by name)")
    odometry.add_argument("--right", help="the right encoder topic (default: found by name)")
    odometry.add_argument("--time-base", **_TIME_BASE)
    odometry.add_argument(
        "--json", action="store_true", help='print {"x": .., "y": .., "theta": ..}'
    )
    odometry.add_argument(
        "--plot",
        metavar="FIGURE",
        help="also draw the path and x, y, theta over time to this figure (.png/.svg/.pdf)",
    )
    odometry.set_defaults(handler=_bag_odometry)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="duckie",
        description="Tools of the Duckiebot ROS course.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    _add_mission(commands)
    _add_run(commands)
    _add_export(commands)
    _add_handin(commands)
    _add_bag(commands)
    _add_robot(commands)
    _add_simulator(commands)

    for add_commands in _plugins():
        add_commands(commands)
    bench = commands.add_parser("bench", help="run a benchmark and print its figures")
    bench.add_argument("name", nargs="?", help="benchmark to run; omit to list them")
    bench.set_defaults(handler=_bench)
    return parser


class _Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, a scheduler ending a job), raised as Ctrl-C is, to end as it does."""


@contextlib.contextmanager
def _noting_signals(received: List[int]) -> Iterator[None]:
    """Note each Ctrl-C (SIGINT) and SIGTERM in ``received``; raise KeyboardInterrupt for both.

    Both end a command the same way: what is under way closes in ``finally`` blocks (a
    mission's bag is closed whole, its wheels stopped). A Ctrl-C that lands inside compiled
    code (matplotlib drawing a frame) can come out as another error; the note lets the
    command still end as interrupted. Only signals left to Python's defaults are taken.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    defaults = {signal.SIGINT: signal.default_int_handler, signal.SIGTERM: signal.SIG_DFL}
    previous = {signum: signal.getsignal(signum) for signum in defaults}

    def on_signal(signum: int, frame: object) -> None:
        received.append(signum)
        raise _Terminated if signum == signal.SIGTERM else KeyboardInterrupt

    for signum, default in defaults.items():
        if previous[signum] is default:
            signal.signal(signum, on_signal)
    try:
        yield
    finally:
        for signum, handler in previous.items():
            if handler is not None:
                signal.signal(signum, handler)


def _stopped(received: List[int]) -> int:
    """Say that a signal ended the command; the exit status a shell expects for it."""
    if signal.SIGTERM in received:
        print("duckie: stopped by SIGTERM (a request to end).", file=sys.stderr)
        return 128 + signal.SIGTERM
    print("duckie: interrupted.", file=sys.stderr)
    return 130


#: The library's parameters that are options of ``duckie``, to name in messages.
_OPTIONS = {"time_base": "--time-base"}


def _said(error: BaseException) -> str:
    """An error's sentence as ``duckie`` prints it: in the command's own words, one full stop.

    The library speaks of its parameters (``time_base='record'``); the command line has
    options (``--time-base record``). A message that ends with another's sentence may repeat
    its full stop.
    """
    text = re.sub(
        r"\b(" + "|".join(_OPTIONS) + r")=(['\"]?)([^\s'\"]+)\2",
        lambda match: f"{_OPTIONS[match[1]]} {match[3].rstrip('.')}",
        str(error),
    )
    return re.sub(r"(?<![./])\.\.(?=\s|$)", ".", text)


def main(argv: Optional[List[str]] = None) -> int:
    """Run the ``duckie`` command with ``argv`` (default: the process's arguments)."""
    args = _parser().parse_args(argv)
    received: List[int] = []
    try:
        with _noting_signals(received):
            return args.handler(args)
    except DuckielibError as error:
        print(f"duckie: {_said(error)}", file=sys.stderr)
        return 1
    except BrokenPipeError:
        # The reader went away (`duckie bag info run.bag | head`): that is not an error of
        # ours. Point stdout at /dev/null so Python's own flush at exit stays quiet too.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141  # as a shell reports a command ended by SIGPIPE
    except Exception:
        if not received:
            raise
        return _stopped(received)
    except KeyboardInterrupt:
        return _stopped(received)


if __name__ == "__main__":
    sys.exit(main())
