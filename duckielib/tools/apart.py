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
import functools
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import (
    Any,
    Callable,
    ContextManager,
    Dict,
    Iterator,
    List,
    Optional,
    Sequence,
    Tuple,
    Union,
)

from duckielib.errors import ConfigError, DuckielibError
from duckielib.missions import Mission, mission_named
from duckielib.tools.runner import (
    DEFAULT_TIME_LIMIT_S,
    RECORDED,
    MissionError,
    _failure,
    _part,
    chosen_mission,
    finish_run,
    logged_error,
    node_crash,
    run_files,
)

__all__ = [
    "OutOfWallTime",
    "drive_apart",
    "ApartDuckiebot",
    "Launcher",
    "NODE_PARTS",
    "SavedSolution",
    "SolutionPart",
    "local_launcher",
    "nodes_arguments",
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


#: The solution's parts that are a node's main code without arguments, which the robot's side
#: may launch on the nodes' side (:meth:`ApartDuckiebot.launch`).
NODE_PARTS = ("light_service_node",)

#: How a run apart starts the nodes' process: given the nodes' end of the socket and the
#: process's arguments (:func:`nodes_arguments`), start it (it inherits the socket) and return a
#: context that ends it when left. :func:`local_launcher` starts it here; the grader starts it
#: in its sandbox.
Launcher = Callable[[socket.socket, List[str]], ContextManager[Any]]


def nodes_arguments(
    mission: Optional[str] = None,
    stop_color: Optional[str] = None,
    stall_limit: Optional[float] = None,
    required: Optional[Sequence[str]] = None,
) -> List[str]:
    """The nodes' process's arguments.

    ``mission``: the mission to drive (its three nodes are launched at once), or None (the
    robot's side launches parts); ``required``: the parts the solution must have.
    """
    arguments: List[str] = []
    if mission is not None:
        arguments += ["--mission", mission]
    if stop_color is not None:
        arguments += ["--stop-color", stop_color]
    if stall_limit is not None:
        arguments += ["--stall-limit", repr(float(stall_limit))]
    if required is not None:
        arguments += ["--required", ",".join(required)]
    return arguments


def nodes_command(fd: int, solution: Optional[str], arguments: Sequence[str]) -> List[str]:
    """The command line of the nodes' process, given the socket's file descriptor ``fd``."""
    command = [sys.executable, "-m", "duckielib.tools.apart", "--link-fd", str(fd)]
    if solution is not None:
        command += ["--solution", str(solution)]
    return command + list(arguments)


def local_launcher(solution: Optional[Union[str, os.PathLike]]) -> Launcher:
    """Start the nodes' process here, with the user's rights (``duckie mission --apart``).

    ``solution``: a folder of notebooks or a ``.py`` file; None: the reference.
    """
    given = None if solution is None else os.fspath(solution)

    @contextlib.contextmanager
    def start(sock: socket.socket, arguments: List[str]) -> Iterator[Any]:
        fd = sock.fileno()
        command = nodes_command(fd, given, arguments)
        # A group of its own: what a node forked (a busy loop in a child) ends with the run.
        process = subprocess.Popen(
            command, pass_fds=(fd,), stdout=subprocess.DEVNULL, start_new_session=True
        )
        try:
            yield process
        finally:
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(process.pid, signal.SIGKILL)

    return start


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
    launcher: Optional[Launcher] = None,
    wall_limit: Optional[float] = None,
    live: Optional[Callable[[Any], Any]] = None,
) -> Any:
    """:func:`~duckielib.tools.runner.run_mission` with the nodes in a process of their own.

    The solution is a folder of notebooks or a ``.py`` file made by ``duckie export`` (None:
    the reference); ``launcher`` starts the nodes' process (default: here, with that
    solution); ``wall_limit`` stops a run that takes longer, in wall-clock seconds. The other
    arguments, what it returns and raises are run_mission's.
    """
    chosen = chosen_mission(mission, seed, stop_color)
    if launcher is None:
        if solution is not None and not isinstance(solution, (str, os.PathLike)):
            raise ConfigError("A mission run apart takes its solution as a folder or a .py file.")
        launcher = local_launcher(solution)
    label = "the reference" if solution is None else "your"
    files = run_files(Path(out))
    arguments = nodes_arguments(chosen.name, stop_color, stall_limit)
    start = functools.partial(_with_arguments, launcher, arguments)
    namespace, simulated, wall, failure = drive_apart(
        start, chosen, noise, seed, files, time_limit, wall_limit, live
    )
    run = (chosen, namespace, noise, seed, label, files, simulated, wall)
    return finish_run(run, failure, animation, figure)


class SavedSolution:
    """A solution that stays on the nodes' side: its node parts can be launched apart.

    What :func:`duckielib.solution.load_solution` stands for where the solution must not be
    loaded (the grader): ``solution.light_service_node`` names the part, and an
    :class:`ApartDuckiebot` launches it in the nodes' process.

    Args:
        required: the parts the solution must have (checked when the nodes' process loads it).
    """

    def __init__(self, required: Sequence[str] = ()) -> None:
        self.required = tuple(required)

    def __getattr__(self, name: str) -> SolutionPart:
        from duckielib.solution import CONTRACT

        if name.startswith("_") or name not in CONTRACT:
            raise AttributeError(name)
        return SolutionPart(self, name)

    def __repr__(self) -> str:
        return f"<solution on the nodes' side: {', '.join(self.required) or 'no parts named'}>"


class SolutionPart:
    """A part of a :class:`SavedSolution`, by name."""

    def __init__(self, solution: SavedSolution, name: str) -> None:
        self.solution = solution
        self.name = name
        self.__name__ = name

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        """Refused: the part runs on the nodes' side only."""
        raise ConfigError(f"{self.name} runs on the nodes' side: launch it on an ApartDuckiebot.")

    def __repr__(self) -> str:
        return f"<{self.name} of the solution on the nodes' side>"


class ApartDuckiebot:
    """A virtual Duckiebot whose solution nodes run in a process of their own.

    As :class:`~duckielib.sim.VirtualDuckiebot` (same arguments, attributes and methods),
    except that launching a :class:`SolutionPart` starts it in the nodes' process, started by
    ``launcher`` on the first such launch; nodes given as functions run here, on the robot's
    graph, as on a VirtualDuckiebot. The robot's graph lists the nodes' side's nodes and
    services as its own, and a service call reaches them; topics cross as in a run apart.

    Args:
        launcher: starts the nodes' process (:data:`Launcher`).
        *args: :class:`~duckielib.sim.VirtualDuckiebot`'s.
        wall_limit: wall-clock seconds the robot may run with the nodes' process.
        **kwargs: :class:`~duckielib.sim.VirtualDuckiebot`'s.
    """

    def __init__(
        self, launcher: Launcher, *args: Any, wall_limit: Optional[float] = None, **kwargs: Any
    ) -> None:
        from duckielib.sim import VirtualDuckiebot

        self._bot = VirtualDuckiebot(*args, **kwargs)
        self._launcher = launcher
        self._deadline = None if wall_limit is None else time.monotonic() + wall_limit
        self._link: Any = None
        self._process: Optional[ContextManager[Any]] = None

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self._bot, name)

    def launch(self, target: Any, *args: Any, **kwargs: Any) -> None:
        """Launch ``target``: a :class:`SolutionPart` on the nodes' side, a function here."""
        if isinstance(target, SolutionPart):
            self._linked(target.solution.required).launch(target.name)
        else:
            self._bot.launch(target, *args, **kwargs)

    def _linked(self, required: Sequence[str]) -> Any:
        from duckielib.sim.link import RobotLink

        if self._link is None:
            robot_end, nodes_end = socket.socketpair()
            arguments = nodes_arguments(required=list(required) or list(NODE_PARTS))
            self._process = self._launcher(nodes_end, arguments)
            self._process.__enter__()
            nodes_end.close()
            self._link = RobotLink(robot_end, self._bot, REPLY_TIMEOUT_S, self._deadline)
            self._link.start()
        return self._link

    def run(self, duration: float) -> None:
        """Advance the robot and every node, here and apart, by ``duration`` simulated s."""
        if self._link is None:
            self._bot.run(duration)
            return
        from duckielib.rostime import NS_PER_S

        self._link.advance(self._bot.graph.now_ns + round(duration * NS_PER_S))

    def run_until(self, condition: Callable[[], bool], timeout: float) -> bool:
        """Advance until ``condition()`` is true (checked every 10 ms) or ``timeout`` s pass."""
        if self._link is None:
            return bool(self._bot.run_until(condition, timeout))
        end = self._bot.time + timeout
        while not condition():
            if self._bot.time >= end:
                return False
            self.run(min(0.01, end - self._bot.time))
        return True

    def shutdown(self) -> None:
        """Stop every node, apart and here, and the nodes' process."""
        from duckielib.sim.link import LinkError

        try:
            if self._link is not None:
                with contextlib.suppress(LinkError):
                    self._link.end(True)
                self._link.sock.close()
        finally:
            if self._process is not None:
                process, self._process = self._process, None
                process.__exit__(None, None, None)
            self._bot.shutdown()

    def __repr__(self) -> str:
        return repr(self._bot).replace("VirtualDuckiebot", "ApartDuckiebot", 1)


def _with_arguments(launcher: Launcher, arguments: List[str], sock: socket.socket) -> Any:
    return launcher(sock, arguments)


def drive_apart(
    start_nodes: Callable[[socket.socket], ContextManager[Any]],
    chosen: Mission,
    noise: str,
    seed: int,
    files: Dict[str, Path],
    time_limit: float,
    wall_limit: Optional[float] = None,
    live: Optional[Callable[[Any], Any]] = None,
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
        live: as :func:`duckielib.tools.runner.run_mission`'s: given the robot before the
            mission starts; what it returns is closed at the end.

    Returns:
        As :func:`duckielib.tools.runner.drive_and_record`: the robot's namespace, the
        simulated and the wall-clock seconds, and the error that stopped the mission early.
    """
    from duckielib.bags import BagRecorder
    from duckielib.ros.graph import Graph
    from duckielib.sim import VirtualDuckiebot
    from duckielib.sim import link as wire
    from duckielib.sim.world import OPEN_MAT

    robot_end, nodes_end = socket.socketpair()
    wall = time.perf_counter()
    deadline = None if wall_limit is None else time.monotonic() + wall_limit
    graph = Graph(echo_logs=False)
    bot = VirtualDuckiebot(
        seed=seed, noise=noise, graph=graph, world=OPEN_MAT, start_pose=chosen.start
    )
    link = wire.RobotLink(robot_end, bot, REPLY_TIMEOUT_S, deadline)
    recorder = BagRecorder(files["bag"], [bot.namespace + name for name in RECORDED], graph=graph)
    view = None
    try:
        view = None if live is None else live(bot)
        with start_nodes(nodes_end):
            nodes_end.close()
            ended, crash, unloaded = _follow(link, time_limit, wall_limit)
    finally:
        bot.shutdown()  # what the robot does on the way out is still served
        if view is not None:
            view.close()
        recorder.close()
        robot_end.close()
        wall = time.perf_counter() - wall
        simulated = bot.time
        files["log"].write_text("".join(f"{record!r}\n" for record in graph.log), encoding="utf-8")
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
    except wire.LinkError as error:  # a hang while the solution loads, too
        return False, _why_stopped(error, wall_limit), None
    try:
        ended = link.advance(graph.now_ns + round(time_limit * NS_PER_S), until_finished=True)
        after = AFTER_DONE_S if ended else 0.2
        link.advance(graph.now_ns + round(after * NS_PER_S))
        last = link.end(ended)
    except (wire.NodesStopped, wire.LinkError) as error:
        return False, _why_stopped(error, wall_limit), None
    return ended, (_said(last) if last is not None and not ended else None), None


def _why_stopped(error: BaseException, wall_limit: Optional[float]) -> Tuple[type, str]:
    """What stopped a run apart early, as an error class and its sentence."""
    from duckielib.sim import link as wire

    if isinstance(error, wire.NodesStopped):
        return _said(error)
    if isinstance(error, wire.OutOfWallTime):
        return OutOfWallTime, f"The mission did not end within {wall_limit} s of wall time."
    return MissionError, f"The nodes' process stopped answering: {error}."


def _said(stopped: Any) -> Tuple[type, str]:
    from duckielib.solution import SolutionError

    return (SolutionError if stopped.kind == "solution" else MissionError), stopped.why


class _Logged:
    """The nodes' log where :func:`_failure` reads a graph's (its ``log``)."""

    def __init__(self, log: List[Any]) -> None:
        self.log = log


def serve_nodes(
    parts: Any,
    chosen: Optional[Mission],
    sock: socket.socket,
    stall_limit: Optional[float] = None,
) -> Tuple[Optional[Tuple[str, str]], List[Any], bool]:
    """Run nodes on a graph of their own, following the robot at ``sock``.

    With ``chosen``, the mission's three nodes run from the start; the robot's side may also
    launch any node part of the solution (``light_service_node``) at any time.

    Returns:
        What stopped the nodes (``("solution" | "mission", sentence)``), or None when the
        robot ended the run, the nodes' log (:class:`~duckielib.ros.log.LogRecord`), and
        whether the robot's side was told (what stopped them is then its to say).
    """
    import rospy  # the in-process graph's, served by install_modules

    from duckielib.nodes import odometry_node
    from duckielib.ros.graph import STALL_LIMIT_S, Graph, NodeCrashed
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

    def launch_part(name: str) -> None:
        node = getattr(parts, name, None) if name in NODE_PARTS else None
        if node is None:
            raise SolutionError(f"The solution has no node {name[:80]!r} to launch.")
        graph.launch(node, namespace=namespace)

    link.launcher = launch_part
    if chosen is not None:
        graph.launch(odometry_node, rospy, parts, chosen.start, namespace=namespace)
        graph.launch(_part(parts, "light_service_node"), namespace=namespace)
        graph.launch(mission_main, name="mission_node", namespace=namespace)
    link.ready()
    crash: Optional[Tuple[type, str]] = None
    try:
        ended = link.serve(lambda: bool(finished))
        crash = None if ended else logged_error(graph)
    except NodeCrashed as error:
        crash = node_crash(error)
    except SolutionError as error:
        crash = (SolutionError, str(error))
    except LinkError:
        return None, list(graph.log), False  # the robot has gone: nobody to tell
    graph.shutdown("the run ended")
    log = list(graph.log)
    stopped: Optional[Tuple[str, str]] = None
    if crash is not None:
        stopped = ("solution" if crash[0] is SolutionError else "mission", crash[1])
    try:
        link.bye(stopped)
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
    parser.add_argument("--mission")
    parser.add_argument("--required", help="the solution's parts it must have, by comma")
    parser.add_argument("--stop-color")
    parser.add_argument("--stall-limit", type=float)
    parser.add_argument("--log")
    return parser.parse_args(argv)


def main(argv: Optional[List[str]] = None) -> int:
    """The nodes' process: load the solution, then serve the mission's nodes."""
    from duckielib.ros.modules import modules_installed
    from duckielib.sim.link import LinkError, receive, send
    from duckielib.solution import MISSION_PARTS, SolutionError, load_solution

    args = _arguments(argv)
    sock = socket.socket(fileno=args.link_fd)
    chosen = None if args.mission is None else mission_named(args.mission)
    if chosen is not None and args.stop_color:
        chosen = chosen.with_stop_color(args.stop_color)
    required = MISSION_PARTS if args.required is None else args.required.split(",")
    with modules_installed(replace_real=True):
        try:
            # The saved notebooks, as duckie mission loads them; their visible tests are
            # graded on their own.
            parts = load_solution(args.solution, required=required, visible_tests=False)
        except (SolutionError, DuckielibError, KeyError) as error:
            kind = "solution" if isinstance(error, (SolutionError, KeyError)) else "mission"
            try:
                receive(sock, 30.0)  # the robot's hello
                send(sock, {"k": "bye", "crash": [kind, str(error)]})
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
