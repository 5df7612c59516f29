"""The ``duckie`` command: the course's tools for students and instructors.

Errors the user can fix are printed as one sentence on stderr, without a traceback, and the
command exits with status 1 (2 for a badly formed command line, as argparse does).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import threading
from typing import Any, Callable, Dict, Iterator, List, Optional

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

    print(Bag(args.bag).info())
    return 0


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
            "for a bag of encoder ticks, compute the poses with 'duckie bag odometry'."
        )
    import dataclasses

    from duckielib import plots

    # Times from the bag's first pose: a real robot's clock gives seconds since 1970.
    start = min((float(track.t[0]) for track in tracks if len(track)), default=0.0)
    tracks = [dataclasses.replace(track, t=track.t - start) for track in tracks]
    figure = plots.pose_figure(tracks, title=f"{bag.path.name} (t = 0 at {start:.3f} s)")
    print(f"Wrote {plots.save_figure(figure, args.output)}.")
    return 0


def _bag_odometry(args: argparse.Namespace) -> int:
    import json

    from duckielib.bags import Bag, replay_odometry
    from duckielib.solution import load_solution

    solution = load_solution(args.solution)
    bag = Bag(args.bag)
    track = replay_odometry(
        bag,
        solution,
        start=args.start,
        left_topic=args.left,
        right_topic=args.right,
        time_base=args.time_base,
    )
    x, y, theta = track.final_pose
    if args.json:
        print(json.dumps({"x": x, "y": y, "theta": theta}))
        return 0
    for note in track.notes:
        print(f"note: {note}")
    print(f"{len(track)} poses from {track.t[0]:.3f} s to {track.t[-1]:.3f} s.")
    print(f"final pose: x = {x:.4f} m, y = {y:.4f} m, theta = {theta:.4f} rad")
    return 0


def _bag_repair(args: argparse.Namespace) -> int:
    from duckielib.bags import repair_bag

    print(repair_bag(args.broken, args.output, compression=args.compression))
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


def _handin(args: argparse.Namespace) -> int:
    from duckielib.tools.handin import handin, handin_notebooks

    count = len(handin_notebooks(args.folder, args.output))
    print(
        f"Running your {count} saved notebooks from top to bottom, as grading does "
        "(about a minute)...",
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
    print(f"Wrote {args.output} ({count} notebooks): hand in this file.")
    return 0


def _add_handin(commands: argparse._SubParsersAction) -> None:
    """``duckie handin``: check a student's notebooks as grading runs them, and zip them."""
    hand = commands.add_parser(
        "handin", help="check your notebooks as grading runs them, and zip them to hand in"
    )
    hand.add_argument(
        "folder", nargs="?", default="course", help="your folder of notebooks (default: course)"
    )
    hand.add_argument(
        "-o", "--output", required=True, help="the zip to write, named after you (NAME.zip)"
    )
    hand.set_defaults(handler=_handin)


def _mission(args: argparse.Namespace) -> int:
    from duckielib.tools.runner import run_mission

    if args.solution is None:
        print("Using the reference solution (the export of solutions/).", flush=True)
    run = run_mission(
        solution=args.solution,
        mission=args.mission,
        noise=args.noise,
        seed=args.seed,
        out=args.out,
        stop_color=args.stop_color,
        animation=not args.no_animation,
    )
    print(run.text())
    return 0


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
    mission.add_argument(
        "--noise",
        default="ideal",
        choices=("ideal", "realistic"),
        help="the simulated robot: ideal, or realistic (unequal wheels, slip, dead zone)",
    )
    mission.add_argument("--seed", type=int, default=0, help="the simulator's seed (default 0)")
    mission.add_argument("--stop-color", help="the LED pattern of the stops (default: RED)")
    mission.add_argument("--out", default="runs/latest", help="folder for the bag, plot, summary")
    mission.add_argument(
        "--no-animation", action="store_true", help="skip mission.gif (a few seconds faster)"
    )
    mission.set_defaults(handler=_mission)


def _plugins() -> List[Callable[[argparse._SubParsersAction], None]]:
    """The functions that add more commands: the entry points of the group ``duckie.commands``.

    The instructors' commands (``release``, ``grade``, ``formgrade``, ``feedback``) come this way
    from the ``autograder`` package, so the library students receive never imports it.
    """
    from importlib.metadata import entry_points

    return [entry.load() for entry in sorted(entry_points(group="duckie.commands"), key=str)]


def _parser() -> argparse.ArgumentParser:
    from duckielib.missions import TASK_START

    parser = argparse.ArgumentParser(
        prog="duckie",
        description="Tools of the Duckiebot ROS course.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    _add_mission(commands)

    export = commands.add_parser(
        "export", help="collect the graded functions of your notebooks into one solution module"
    )
    export.add_argument("folder", help="the folder of notebooks (your course/, or solutions/)")
    export.add_argument("-o", "--output", required=True, help="the .py file to write")
    export.set_defaults(handler=_export)

    _add_handin(commands)

    bag = commands.add_parser("bag", help="inspect, plot, replay and repair ROS 1 bags")
    bag_commands = bag.add_subparsers(dest="bag_command", metavar="BAG_COMMAND", required=True)
    info = bag_commands.add_parser("info", help="topics, types, counts and duration of a bag")
    info.add_argument("bag", help="the bag file")
    info.set_defaults(handler=_bag_info)

    time_base: Dict[str, Any] = {
        "choices": ("auto", "header", "record"),
        "default": "auto",
        "help": "times to use: header stamps, record times, or auto (stamps unless all 0)",
    }
    plot = bag_commands.add_parser("plot", help="plot the poses (Pose2DStamped topics) of a bag")
    plot.add_argument("bag", help="the bag file")
    plot.add_argument("-o", "--output", required=True, help="the figure to write (.png/.svg/.pdf)")
    plot.add_argument("--topic", action="append", help="a pose topic to plot (default: all)")
    plot.add_argument("--time-base", **time_base)
    plot.set_defaults(handler=_bag_plot)

    odometry = bag_commands.add_parser(
        "odometry", help="replay wheel odometry from a bag's encoder ticks"
    )
    odometry.add_argument("bag", help="the bag file")
    odometry.add_argument(
        "--start",
        nargs=3,
        type=float,
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
    odometry.add_argument("--time-base", **time_base)
    odometry.add_argument(
        "--json", action="store_true", help='print {"x": .., "y": .., "theta": ..}'
    )
    odometry.set_defaults(handler=_bag_odometry)

    repair = bag_commands.add_parser(
        "repair", help="recover every complete message of a bag whose recording was killed"
    )
    repair.add_argument("broken", help="the damaged bag (for example run.bag.active)")
    repair.add_argument("output", help="the repaired bag to write")
    repair.add_argument("--compression", choices=("none", "bz2"), default="none")
    repair.set_defaults(handler=_bag_repair)

    _add_robot(commands)

    for add_commands in _plugins():
        add_commands(commands)
    bench = commands.add_parser("bench", help="run a benchmark and print its figures")
    bench.add_argument("name", nargs="?", help="benchmark to run; omit to list them")
    bench.set_defaults(handler=_bench)
    return parser


@contextlib.contextmanager
def _noting_ctrl_c(pressed: List[bool]) -> Iterator[None]:
    """Note each Ctrl-C in ``pressed`` while raising KeyboardInterrupt as usual.

    A Ctrl-C that lands inside compiled code (matplotlib drawing a frame) can come out as
    another error; the note lets the command still end as interrupted.
    """
    handler = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or (
        handler is not signal.default_int_handler
    ):
        yield
        return

    def on_ctrl_c(signum: int, frame: object) -> None:
        pressed.append(True)
        raise KeyboardInterrupt

    signal.signal(signal.SIGINT, on_ctrl_c)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, handler)


def main(argv: Optional[List[str]] = None) -> int:
    """Run the ``duckie`` command with ``argv`` (default: the process's arguments)."""
    args = _parser().parse_args(argv)
    pressed: List[bool] = []
    try:
        with _noting_ctrl_c(pressed):
            return args.handler(args)
    except DuckielibError as error:
        print(f"duckie: {error}", file=sys.stderr)
        return 1
    except BrokenPipeError:
        # The reader went away (`duckie bag info run.bag | head`): that is not an error of
        # ours. Point stdout at /dev/null so Python's own flush at exit stays quiet too.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141  # as a shell reports a command ended by SIGPIPE
    except Exception:
        if not pressed:
            raise
        print("duckie: interrupted.", file=sys.stderr)
        return 130
    except KeyboardInterrupt:
        print("duckie: interrupted.", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
