"""A mission with the robot and the nodes in two processes, as the grader runs it.

``duckie mission --apart`` and the grader run a mission this way: this process runs the
virtual Duckiebot (simulator, drivers) and records the bag, and the solution's nodes run in a
process of their own, started by :func:`drive_apart`'s caller (the grader starts it in its
sandbox), that reaches the robot only through topics and services (see
:mod:`duckielib.sim.link`). The nodes cannot move the robot, read where it really is, or write
the bag: what the bag records as the truth is what their commands really did.

The nodes' process is ``python -m duckielib.tools.apart --link-fd FD ...``
(:func:`main`): it loads the solution, launches the mission's three nodes on a graph of its
own, and follows the robot's clock until the robot ends the run.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Callable, ContextManager, Dict, Iterator, List, Optional, Tuple, Union

from duckielib.errors import ConfigError, DuckielibError
from duckielib.missions import Mission, mission_named
from duckielib.tools.runner import (
    _STUDENT_NODES,
    DEFAULT_TIME_LIMIT_S,
    RECORDED,
    MissionError,
    _crash_message,
    _failure,
    _part,
    chosen_mission,
    finish_run,
    run_files,
)

__all__ = [
    "OutOfWallTime",
    "drive_apart",
    "local_nodes",
    "main",
    "nodes_command",
    "run_apart",
    "serve_nodes",
]

#: Wall-clock seconds the nodes' side may take to answer one step (a node that computes
#: without calling rospy is stopped by its own graph well before: see ``stall_limit``).
REPLY_TIMEOUT_S = 60.0


class OutOfWallTime(MissionError):
    """The run was stopped at its wall-clock limit (the grader's, for a run apart)."""


def nodes_command(
    fd: int,
    solution: Optional[str],
    mission: str,
    stop_color: Optional[str] = None,
    stall_limit: Optional[float] = None,
    log: Optional[str] = None,
) -> List[str]:
    """The command line of the nodes' process, given the socket's file descriptor ``fd``."""
    command = [sys.executable, "-m", "duckielib.tools.apart", "--link-fd", str(fd)]
    if solution is not None:
        command += ["--solution", str(solution)]
    command += ["--mission", mission]
    if stop_color is not None:
        command += ["--stop-color", stop_color]
    if stall_limit is not None:
        command += ["--stall-limit", repr(float(stall_limit))]
    if log is not None:
        command += ["--log", log]
    return command


def run_apart(
    solution: Optional[Union[str, os.PathLike]] = None,
    mission: Union[str, Mission] = "square_then_circle",
    noise: str = "ideal",
    seed: int = 0,
    out: Union[str, os.PathLike] = "runs/latest",
    stop_color: Optional[str] = None,
    animation: bool = True,
    time_limit: float = DEFAULT_TIME_LIMIT_S,
    figure: bool = True,
    stall_limit: Optional[float] = None,
) -> Any:
    """:func:`~duckielib.tools.runner.run_mission` with the nodes in a process of their own.

    The solution is a folder of notebooks or a ``.py`` file made by ``duckie export`` (None:
    the reference); the other arguments, what it returns and raises are run_mission's.
    """
    chosen = chosen_mission(mission, seed, stop_color)
    if solution is not None and not isinstance(solution, (str, os.PathLike)):
        raise ConfigError("A mission run apart takes its solution as a folder or a .py file.")
    label = "the reference" if solution is None else "your"
    files = run_files(Path(out))
    start = local_nodes(solution, chosen, stop_color, stall_limit)
    namespace, simulated, wall, failure = drive_apart(start, chosen, noise, seed, files, time_limit)
    run = (chosen, namespace, noise, seed, label, files, simulated, wall)
    return finish_run(run, failure, animation, figure)


def local_nodes(
    solution: Any,
    chosen: Mission,
    stop_color: Optional[str] = None,
    stall_limit: Optional[float] = None,
) -> Callable[[socket.socket], ContextManager[Any]]:
    """How ``duckie mission --apart`` starts the nodes' process: here, with the user's rights.

    Returns:
        What :func:`drive_apart` takes as ``start_nodes``.
    """

    @contextlib.contextmanager
    def start(sock: socket.socket) -> Iterator[Any]:
        fd = sock.fileno()
        given = None if solution is None else os.fspath(solution)
        command = nodes_command(fd, given, chosen.name, stop_color, stall_limit)
        process = subprocess.Popen(command, pass_fds=(fd,), stdout=subprocess.DEVNULL)
        try:
            yield process
        finally:
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()

    return start


def drive_apart(
    start_nodes: Callable[[socket.socket], ContextManager[Any]],
    chosen: Mission,
    noise: str,
    seed: int,
    files: Dict[str, Path],
    time_limit: float,
    wall_limit: Optional[float] = None,
) -> Tuple[str, float, float, Optional[DuckielibError]]:
    """Drive ``chosen`` on a virtual Duckiebot here, with the nodes in another process.

    Args:
        start_nodes: given the nodes' end of the socket, starts the nodes' process (which
            inherits it) and returns a context that ends it when left.
        chosen: the mission (its start pose is the robot's).
        noise: the simulator's noise profile.
        seed: the simulator's seed.
        files: where to write the bag (``"bag"``) and the log (``"log"``).
        time_limit: simulated seconds after which an unfinished mission is stopped.
        wall_limit: wall-clock seconds after which the run is stopped (None: no limit).

    Returns:
        As :func:`duckielib.tools.runner.drive_and_record`: the robot's namespace, the
        simulated and the wall-clock seconds, and the error that stopped the mission early.
    """
    from duckielib.bags import BagRecorder
    from duckielib.ros.graph import Graph
    from duckielib.sim import VirtualDuckiebot
    from duckielib.sim import link as wire

    robot_end, nodes_end = socket.socketpair()
    wall = time.perf_counter()
    deadline = None if wall_limit is None else time.monotonic() + wall_limit
    graph = Graph(echo_logs=False)
    bot = VirtualDuckiebot(seed=seed, noise=noise, graph=graph, start_pose=chosen.start)
    link = wire.RobotLink(robot_end, bot, REPLY_TIMEOUT_S, deadline)
    recorder = BagRecorder(files["bag"], [bot.namespace + name for name in RECORDED], graph=graph)
    try:
        with start_nodes(nodes_end):
            nodes_end.close()
            ended, crash, unloaded = _follow(link, time_limit, wall_limit)
    finally:
        bot.shutdown()
        recorder.close()
        robot_end.close()
        wall = time.perf_counter() - wall
        simulated = bot.time
        log = sorted(graph.log + link.nodes_log, key=lambda record: record.time)
        files["log"].write_text("".join(f"{record!r}\n" for record in log), encoding="utf-8")
    if unloaded is not None:
        return bot.namespace, simulated, wall, unloaded
    if crash is None and recorder.error is not None:
        crash = (MissionError, f"Recording the bag failed ({recorder.error}).")
    failure = _failure(crash, ended, files, bot.namespace, time_limit, _Logged(link.nodes_log))
    return bot.namespace, simulated, wall, failure


def _follow(
    link: Any, time_limit: float, wall_limit: Optional[float]
) -> Tuple[bool, Optional[Tuple[type, str]], Optional[DuckielibError]]:
    """Start the nodes, run the mission with them, and end it.

    Returns:
        Whether the mission ended, what stopped it early (an error class and its sentence),
        and the error of a solution that could not even be loaded.
    """
    from duckielib.bags.behaviour import AFTER_DONE_S
    from duckielib.rostime import NS_PER_S
    from duckielib.sim import link as wire

    graph = link.graph
    try:
        link.start()
    except wire.NodesStopped as stopped:
        kind, why = _said(stopped)
        return False, (kind, why), kind(why)
    except wire.LinkError as error:
        return False, (MissionError, f"The nodes' process stopped answering: {error}."), None
    try:
        ended = link.advance(graph.now_ns + round(time_limit * NS_PER_S), until_finished=True)
        after = AFTER_DONE_S if ended else 0.2
        link.advance(graph.now_ns + round(after * NS_PER_S))
        last = link.end(ended)
    except wire.NodesStopped as error:
        return False, _said(error), None
    except wire.OutOfWallTime:
        return (
            False,
            (OutOfWallTime, f"The mission did not end within {wall_limit} s of wall time."),
            None,
        )
    except wire.LinkError as error:
        return False, (MissionError, f"The nodes' process stopped answering: {error}."), None
    return ended, (_said(last) if last is not None and not ended else None), None


def _said(stopped: Any) -> Tuple[type, str]:
    from duckielib.solution import SolutionError

    return (SolutionError if stopped.kind == "solution" else MissionError), stopped.why


class _Logged:
    """The nodes' log where :func:`_failure` reads a graph's (its ``log``)."""

    def __init__(self, log: List[Any]) -> None:
        self.log = log


def serve_nodes(
    parts: Any,
    chosen: Mission,
    sock: socket.socket,
    stall_limit: Optional[float] = None,
) -> Tuple[Optional[Tuple[str, str]], List[Any], bool]:
    """Run the mission's nodes on a graph of their own, following the robot at ``sock``.

    Returns:
        What stopped the nodes (``("solution" | "mission", sentence)``), or None when the
        robot ended the run, the nodes' log (:class:`~duckielib.ros.log.LogRecord`), and
        whether the robot's side was told (what stopped them is then its to say).
    """
    import rospy  # the in-process graph's, served by install_modules

    from duckielib.nodes import odometry_node
    from duckielib.ros.graph import STALL_LIMIT_S, Graph, NodeCrashed
    from duckielib.ros.log import ERROR
    from duckielib.sim.link import LinkError, NodesLink
    from duckielib.solution import SolutionError

    graph = Graph(echo_logs=False, stall_limit=stall_limit or STALL_LIMIT_S)
    link = NodesLink(sock, graph)
    finished: List[bool] = []

    def mission_main() -> None:
        try:
            _part(parts, "mission_node")(chosen)
        finally:
            finished.append(True)

    namespace = link.namespace
    graph.launch(odometry_node, rospy, parts, chosen.start, namespace=namespace)
    graph.launch(_part(parts, "light_service_node"), namespace=namespace)
    graph.launch(mission_main, name="mission_node", namespace=namespace)
    link.ready()
    crash: Optional[Tuple[type, str]] = None
    try:
        ended = link.serve(lambda: bool(finished))
        errors = [
            record
            for record in graph.log
            if record.level >= ERROR and record.node.rsplit("/", 1)[-1] in _STUDENT_NODES
        ]
        if errors and not ended:
            said = re.sub(r"^(?:\w+\.)+(?=\w+: )", "", errors[0].text.splitlines()[-1])
            crash = (MissionError, f"The {errors[0].node} logged an error: {said.rstrip('.')}.")
    except NodeCrashed as error:
        node = error.node.rsplit("/", 1)[-1]
        if error.__cause__ is None:  # stopped by the graph itself (code that never waits)
            said = str(error).split(": ", 1)[-1]
            crash = (MissionError, f"The {node.replace('_', ' ')} stopped: {said}")
        else:
            crash = _crash_message(node.replace("_", " "), error.__cause__)
    except LinkError:
        return None, list(graph.log), False  # the robot has gone: nobody to tell
    graph.shutdown("the run ended")
    log = list(graph.log)
    stopped: Optional[Tuple[str, str]] = None
    if crash is not None:
        stopped = ("solution" if crash[0] is SolutionError else "mission", crash[1])
    try:
        link.bye(stopped, log)
    except (LinkError, OSError):
        return stopped, log, False
    return stopped, log, True


def _arguments(argv: Optional[List[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="python -m duckielib.tools.apart",
        description="The nodes' process of a mission run apart (started by duckie mission "
        "--apart and by the grader, not by hand).",
    )
    parser.add_argument("--link-fd", type=int, required=True)
    parser.add_argument("--solution")
    parser.add_argument("--mission", required=True)
    parser.add_argument("--stop-color")
    parser.add_argument("--stall-limit", type=float)
    parser.add_argument("--log")
    return parser.parse_args(argv)


def main(argv: Optional[List[str]] = None) -> int:
    """The nodes' process: load the solution, then serve the mission's nodes."""
    from duckielib.ros.modules import modules_installed
    from duckielib.sim.link import LinkError, receive, send
    from duckielib.solution import SolutionError
    from duckielib.tools.runner import _solution

    args = _arguments(argv)
    sock = socket.socket(fileno=args.link_fd)
    chosen = mission_named(args.mission)
    if args.stop_color:
        chosen = chosen.with_stop_color(args.stop_color)
    with modules_installed(replace_real=True):
        try:
            parts = _solution(args.solution)
        except (SolutionError, DuckielibError) as error:
            kind = "solution" if isinstance(error, SolutionError) else "mission"
            try:
                receive(sock, 30.0)  # the robot's hello
                send(sock, {"k": "bye", "crash": [kind, str(error)], "log": []})
            except (LinkError, OSError):
                print(f"duckie: {error}", file=sys.stderr)  # nobody else will say it
            return 1
        crash, log, told = serve_nodes(parts, chosen, sock, args.stall_limit)
    if args.log:
        Path(args.log).write_text("".join(f"{record!r}\n" for record in log), encoding="utf-8")
    if crash is not None:
        if not told:
            print(f"duckie: {crash[1]}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":  # pragma: no cover - run as a process
    with contextlib.suppress(KeyboardInterrupt):
        sys.exit(main())
    os._exit(130)
