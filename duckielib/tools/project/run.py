"""A project's nodes run on the virtual Duckiebot, and what the run did.

Laptop side; never deployed.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import sys
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Tuple, Union

from duckielib.tools.project.image import ImageEnvironment, image_environment
from duckielib.tools.project.launch import NodeSpec, launched_nodes
from duckielib.tools.project.workspace import PathLike, Workspace
from duckielib.tools.robot_env import node_clocks, robot_data, robot_hostname, windows_saved

__all__ = ["ProjectRun", "run_project"]

#: Topics a run does not record: the camera's images (about 30 large messages a second).
_NOT_RECORDED = r".*/camera_node/image/compressed"


def _run_files(folder: Path) -> Dict[str, Path]:
    """A run's files in its folder, by kind."""
    return {
        "bag": folder / "run.bag",
        "log": folder / "log.txt",
        "summary": folder / "summary.json",
    }


@dataclass
class ProjectRun:
    """What a run of a project did.

    Attributes:
        folder: the run's folder (``run.bag``, ``log.txt``, ``summary.json``).
        nodes: each node's name and how it ended (``"running"`` when the run ended first).
        topics: messages recorded, by topic.
        notes: what the launch files held that the run left out.
        simulated: simulated seconds.
        wall: wall-clock seconds.
        wheels: the wheels' duty cycles (left, right) once the run had stopped the robot.
        interrupted: whether Ctrl-C (or SIGTERM) ended the run.
        failures: each node that failed, in a sentence with the project's file and line, in
            the order they failed (the others ran on, as roslaunch lets them).
    """

    folder: Path
    nodes: Dict[str, str]
    topics: Dict[str, int]
    notes: List[str]
    simulated: float
    wall: float
    wheels: Tuple[float, float] = (0.0, 0.0)
    interrupted: bool = False
    failures: List[str] = field(default_factory=list)

    @property
    def files(self) -> Dict[str, Path]:
        """The run's files, by kind."""
        return _run_files(self.folder)

    def text(self) -> str:
        """What ``duckie run`` prints: the nodes, the topics they published, the files."""
        ended = ", stopped by Ctrl-C" if self.interrupted else ""
        lines = [f"ran {len(self.nodes)} node(s) for {self.simulated:.1f} s (simulated){ended}:"]
        width = max(len(name) for name in self.nodes)
        lines += [f"  {name:<{width}}  {how}" for name, how in self.nodes.items()]
        lines += [f"failed: {failure}" for failure in self.failures]
        lines.append("recorded:")
        width = max((len(topic) for topic in self.topics), default=0)
        lines += [f"  {topic:<{width}}  {count}" for topic, count in self.topics.items()]
        lines += [f"note: {note}" for note in self.notes]
        data = sorted(path for path in (self.folder / "data").rglob("*") if path.is_file())
        if data:
            lines.append(
                f"the nodes wrote {len(data)} file(s) to the robot's /data: they are in "
                f"{self.folder / 'data'}"
            )
        left, right = self.wheels
        lines.append(f"the wheels were stopped: duty cycles {left:g}, {right:g} at the end")
        lines.append(f"wrote run.bag, log.txt, summary.json in {self.folder}")
        return "\n".join(lines)

    def summary(self) -> Dict[str, Any]:
        """The run as JSON-ready data."""
        return {
            "nodes": self.nodes,
            "topics": self.topics,
            "notes": self.notes,
            "simulated_s": round(self.simulated, 3),
            "wall_s": round(self.wall, 3),
            "wheels_at_end": list(self.wheels),
            "interrupted": self.interrupted,
            "failures": self.failures,
        }


def _node_main(spec: NodeSpec, run: Any, ended: Dict[str, str]) -> Any:
    """A node's main code that notes in ``ended`` whether it ended or failed."""

    def node_main() -> None:
        try:
            run()
            ended[spec.label] = "ended"
        except KeyboardInterrupt:
            raise  # Ctrl-C landed in the node's code: the run stops, the node did not fail
        except BaseException:
            ended[spec.label] = "failed"
            raise

    node_main.__name__ = run.__name__
    return node_main


def _how_it_ended(
    how: Optional[str], spec: NodeSpec, simulated: float, seconds: float, interrupted: bool
) -> str:
    if how == "ended":
        return "ended" + (" (required: the run ended with it)" if spec.required else "")
    if how == "failed":
        return "failed (its traceback is in log.txt)"
    if how is not None and how.startswith("waiting"):
        return f"still {how}, stopped"
    if interrupted:
        return "running, stopped by Ctrl-C"
    if simulated >= seconds - 1e-6:
        return f"still running after {seconds:g} s, stopped"
    return "running, stopped when the run ended"


def _recording_new_topics(recorder: Any) -> Callable[[Any, bool], None]:
    """A graph's topic watcher that has ``recorder`` record a new topic from its first message.

    ``rosbag record -a`` finds new topics by asking the master now and then, and misses
    their first messages; a run's bag has every message a node published.
    """

    def watch(handle: Any, publishes: bool) -> None:
        if publishes and not re.fullmatch(_NOT_RECORDED, handle.name):
            recorder.add(handle.name)

    return watch


def _window_publisher(graph: Any) -> Callable[[str, bytes], None]:
    """``publish(topic, jpeg)`` for ``cv2`` windows: a node ``cv2_windows`` publishes the frames."""
    from duckielib.messages import CompressedImage
    from duckielib.ros import rospy
    from duckielib.ros.context import node_context

    publishers: Dict[str, Any] = {}

    def publish(topic: str, jpeg: bytes) -> None:
        if topic not in publishers:
            node = graph.nodes.get("/cv2_windows") or graph.host_node("cv2_windows")
            with node_context(node):
                publishers[topic] = rospy.Publisher(topic, CompressedImage, queue_size=1)
        message: Any = CompressedImage(format="jpeg", data=jpeg)
        message.header.stamp = rospy.Time.from_sec(graph.time)
        publishers[topic].publish(message)

    return publish


@contextlib.contextmanager
def _exported(variables: Dict[str, str]) -> Iterator[None]:
    """Set what the launcher exports for its nodes, then put the environment back."""
    before = {name: os.environ.get(name) for name in variables}
    os.environ.update(variables)
    try:
        yield
    finally:
        for name, value in before.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


@contextlib.contextmanager
def _as_on_the_robot(
    workspace: Workspace,
    image: ImageEnvironment,
    exported: Dict[str, str],
    folder: Path,
    graph: Any,
    notes: List[str],
) -> Iterator[None]:
    """What node code finds as on the robot: packages, image, rospy, /data, clocks, windows."""
    from duckielib.ros.modules import modules_installed

    clock: Callable[[], float] = lambda: graph.time  # noqa: E731
    publish = _window_publisher(graph)

    with contextlib.ExitStack() as robot:
        robot.enter_context(workspace.importable())
        robot.enter_context(image.applied())
        robot.enter_context(_exported(exported))
        robot.enter_context(modules_installed(replace_real=True))
        robot.enter_context(robot_data(folder / "data"))
        robot.enter_context(node_clocks(workspace.root, clock))
        robot.enter_context(robot_hostname(workspace.root, os.environ["VEHICLE_NAME"]))
        robot.enter_context(windows_saved(folder / "windows", notes, publish))
        # A node's relative paths land in the run's folder, as in the robot's container.
        robot.enter_context(contextlib.chdir(folder))
        yield


def run_project(
    path: PathLike,
    launcher: Union[str, Sequence[str]] = "default",
    noise: Any = "ideal",
    seed: int = 0,
    seconds: float = 30.0,
    out: PathLike = "runs/project",
    live: Optional[Callable[[Any], Any]] = None,
) -> ProjectRun:
    """Run a Duckietown project's nodes on the virtual Duckiebot for ``seconds``.

    The run's bag (every topic but the camera's images), ``log.txt`` and ``summary.json`` are
    written in ``out``; what the nodes write to the robot's ``/data`` lands in ``out/data``,
    and the frames they show with ``cv2.imshow`` in ``out/windows`` (:mod:`.robot_env`). It
    ends after ``seconds`` of simulated time, or when a ``required`` node ends, or when every
    node has ended; the wheels are stopped in every case.

    A node that fails (raises, or exits with a status other than 0) is said in the run's
    ``failures``, with the project's file and line, and the others run on, as roslaunch lets
    them; a ``required`` node's failure ends the run.

    ``live``, to watch the run as it goes, is given the virtual Duckiebot before the nodes
    start; what it returns is closed at the end (``lambda bot: bot.live()`` serves the run to
    Foxglove or Lichtblick, the camera and the ``cv2`` windows included).

    Raises:
        ProjectError: for a project, launcher or launch file that cannot be run (the file and
            line said).
        KeyboardInterrupt: Ctrl-C, once the run's files are written (the run is its ``run``).
    """
    from duckielib.bags import BagRecorder
    from duckielib.ros import Graph
    from duckielib.sim import VirtualDuckiebot
    from duckielib.sim.world import OPEN_MAT

    os.environ.setdefault("VEHICLE_NAME", "duckiebot")
    workspace, launched = launched_nodes(path, launcher)
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    files = _run_files(folder.resolve())  # the run works in its folder (see _as_on_the_robot)
    for each in files.values():
        each.unlink(missing_ok=True)
    graph = Graph(echo_logs=False)
    bot = VirtualDuckiebot(seed=seed, noise=noise, graph=graph, world=OPEN_MAT)
    for name, value in launched.params.items():
        graph.set_param(name, value)
    ended: Dict[str, str] = {}
    wall = time.perf_counter()
    path_before = list(sys.path)  # node scripts put their folders first, as on the robot
    image = image_environment(workspace.root)
    notes = [*launched.notes, *image.notes]
    with _as_on_the_robot(workspace, image, launched.environment, folder.resolve(), graph, notes):
        stages = _Stages(bot, launched.nodes, ended)
        recorder = BagRecorder(files["bag"], graph=graph, exclude=_NOT_RECORDED)
        graph.topic_watchers.append(_recording_new_topics(recorder))
        at_end, failures, interrupt = _drive_to_the_end(
            bot, stages, recorder, workspace, files, live, seconds, path_before
        )
    run = ProjectRun(
        folder=folder,
        nodes={
            spec.label: _how_it_ended(
                at_end.get(spec.label), spec, bot.time, seconds, interrupt is not None
            )
            for spec in launched.nodes
        },
        topics=dict(sorted(recorder.counts.items())),
        notes=notes,
        simulated=bot.time,
        wall=time.perf_counter() - wall,
        wheels=bot.sim.wheel_duties,
        interrupted=interrupt is not None,
        failures=failures,
    )
    files["summary"].write_text(json.dumps(run.summary(), indent=2) + "\n")
    if interrupt is not None:
        interrupt.run = run  # type: ignore[attr-defined]  # what ran, for the command to print
        raise interrupt
    return run


def _drive_to_the_end(
    bot: Any,
    stages: _Stages,
    recorder: Any,
    workspace: Workspace,
    files: Dict[str, Path],
    live: Optional[Callable[[Any], Any]],
    seconds: float,
    path_before: List[str],
) -> Tuple[Dict[str, str], List[str], Optional[KeyboardInterrupt]]:
    """Drive the started nodes until the run is over; then stop everything, however it ends.

    The robot is shut down, the live view and the bag closed, the log written and
    ``sys.path`` put back.

    Returns:
        How each node stood at the end (:func:`_waiting`, by label), the failures said, and
        the Ctrl-C that ended the run if one did.
    """
    graph = bot.graph
    failures: List[str] = []
    interrupt: Optional[KeyboardInterrupt] = None
    view = None
    try:
        view = None if live is None else live(bot)
        _drive(bot, stages, seconds, lambda error: failures.append(_crash_said(error, workspace)))
    except KeyboardInterrupt as error:  # Ctrl-C: stop as at the end, then say so
        interrupt = error
    finally:
        at_end = {**_waiting(graph), **stages.ended}
        bot.shutdown()
        if view is not None:
            view.close()
        recorder.close()
        files["log"].write_text(
            "\n".join(repr(record) for record in graph.log) + "\n", encoding="utf-8"
        )
        sys.path[:] = path_before
    return at_end, failures, interrupt


class _Stages:
    """A launcher's nodes, started as bash runs its lines.

    The nodes of ``dt-exec`` and ``&`` lines start at once; a line that runs in the
    foreground holds back the lines after it until its nodes have ended (stage by stage, see
    :attr:`NodeSpec.stage`).
    """

    def __init__(self, bot: Any, specs: List[NodeSpec], ended: Dict[str, str]) -> None:
        self.bot = bot
        self.specs = specs
        self.ended = ended
        self.later = sorted((s for s in specs if s.stage > 0), key=lambda s: (s.launcher, s.stage))
        self.required = [spec.label for spec in specs if spec.required]
        self._start([spec for spec in specs if spec.stage == 0])

    def _start(self, specs: List[NodeSpec]) -> None:
        from duckielib.ros import node_script

        for spec in specs:
            self.bot.launch(
                _node_main(spec, node_script(spec.script, *spec.args), self.ended),
                name=spec.name,
                namespace=spec.namespace,
                remap=spec.remap or None,
                params=spec.params or None,
            )

    def over(self) -> bool:
        """Whether the run is over: a required node ended, or every node has."""
        if any(label in self.ended for label in self.required):
            return True
        return not self.later and len(self.ended) == len(self.specs)

    def _ready(self) -> List[NodeSpec]:
        """The next stage of each launcher whose foreground line before it has ended."""
        ready: List[NodeSpec] = []
        for launcher in dict.fromkeys(spec.launcher for spec in self.later):
            stage = min(spec.stage for spec in self.later if spec.launcher == launcher)
            if all(
                spec.label in self.ended
                for spec in self.specs
                if spec.launcher == launcher and spec.stage == stage - 1 and spec.foreground
            ):
                ready += [s for s in self.later if s.launcher == launcher and s.stage == stage]
        return ready

    def next_ready(self) -> bool:
        """Whether a launcher's next line may start."""
        return bool(self._ready())

    def start_next(self) -> None:
        """Start what may start now."""
        starting = self._ready()
        self.later = [spec for spec in self.later if spec not in starting]
        self._start(starting)


def _waiting(graph: Any) -> Dict[str, str]:
    """What the nodes still running wait for, by node name: ``waiting for service /x ...``."""
    return {
        node.name: f"waiting for {node.waiting_for[0]} since {node.waiting_for[1]:.1f} s"
        for node in graph.nodes.values()
        if node.waiting_for is not None
    }


def _drive(bot: Any, stages: _Stages, seconds: float, failed: Callable[[Exception], None]) -> None:
    """Run until the run is over or ``seconds``; each node's failure goes to ``failed``.

    As roslaunch: a node that fails is said, and the others run on (a required node's
    failure ends the run, as its end does).
    """
    from duckielib.ros.graph import NodeCrashed

    while bot.time < seconds:
        try:
            bot.run_until(lambda: stages.over() or stages.next_ready(), seconds - bot.time)
        except NodeCrashed as error:
            failed(error)
            continue
        if stages.over() or not stages.next_ready():
            return
        stages.start_next()


def _crash_said(crash: BaseException, workspace: Workspace) -> str:
    """A node's crash in a sentence, at the project's own line that raised."""
    cause = crash.__cause__ or crash
    node = str(getattr(crash, "node", "")).rsplit("/", 1)[-1] or "a node"
    frames = [
        frame
        for frame in traceback.extract_tb(cause.__traceback__)
        if workspace.root in Path(frame.filename).resolve().parents
    ]
    at = ""
    if frames:
        frame = frames[-1]
        at = f" at {Path(frame.filename).relative_to(workspace.root)}, line {frame.lineno}"
    if isinstance(cause, SystemExit):
        said = f"The node {node} exited with status {cause.code}{at} (it said why above)."
    else:
        said = f"The node {node} stopped with {type(cause).__name__}{at}: {cause}."
    if isinstance(cause, ModuleNotFoundError) and cause.name:
        said += " " + _install_hint(cause.name.partition(".")[0], workspace)
    return said


def _install_hint(module: str, workspace: Workspace) -> str:
    """How to get a module a node imports: from the project's ``dependencies-py3.txt``."""
    listed = workspace.root / "dependencies-py3.txt"
    wanted = re.sub(r"[-_.]+", "_", module).lower()
    if listed.is_file():
        for line in listed.read_text(encoding="utf-8", errors="replace").splitlines():
            requirement = line.split("#", 1)[0].strip()
            name = re.split(r"[\s<>=!~;\[]", requirement, maxsplit=1)[0]
            if name and re.sub(r"[-_.]+", "_", name).lower() == wanted:
                return (
                    f"The project lists {requirement} in dependencies-py3.txt, which dts devel "
                    f"build installs on the robot: install it here too, with "
                    f"'.venv/bin/pip install {requirement}'."
                )
    apt = workspace.root / "dependencies-apt.txt"
    if apt.is_file():
        ros_name = "-" + module.replace("_", "-").lower()
        for line in apt.read_text(encoding="utf-8", errors="replace").splitlines():
            package = line.split("#", 1)[0].strip()
            if package.startswith("ros-") and package.endswith(ros_name):
                return (
                    f"The project installs it on the robot from dependencies-apt.txt "
                    f"({package}), a ROS package the virtual Duckiebot does not serve: copy "
                    "what the node needs of it into the project, or run this node on the robot."
                )
    return (
        f"If {module} is a library your robot's image installs, install it here too "
        "(.venv/bin/pip install ...)."
    )
