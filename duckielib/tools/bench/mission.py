"""Benchmark: the whole mission (graph, nodes, odometry, bag) against real time.

The square-then-circle mission on the ideal virtual Duckiebot with the reference solution, as
``duckie mission`` runs it: the drivers, the odometry node running the solution's functions,
the solution's light service and mission nodes, and the bag recorder. The figures leave out the
plots, which are drawn after the run. The headline is the real-time factor (simulated seconds
per wall-clock second of the run), best of three runs; ``summary.json`` reports the same figure
for each run.

The same mission run apart, as the grader runs it (the robot here, the nodes in a process of
their own, one clock over a socket: :mod:`duckielib.tools.apart`), gives two figures:
``mission_apart_wall_s``, the wall-clock seconds of the run with the nodes' process started
and ended (best of three), and ``mission_apart_exchanges``, how many times the clock was
handed to the nodes' side and back.

Two more figures say where the time goes, each from runs of their own:

- ``mission_physics_wall_s``: the part of a run spent in the simulator's physics steps.
- ``mission_wall_s_objects_no_bag``: the same mission with messages handed to subscribers as
  the very objects published (no serializing, no parsing) and nothing recorded; best of three.
  This is not how the graph runs (a subscriber gets its own copy, as from rospy), only a bound:
  what a faster transport could win at most.
"""

from __future__ import annotations

import contextlib
import tempfile
import time
from pathlib import Path
from typing import Any, Callable, Iterator, List, Tuple

from duckielib.messages.message import Message
from duckielib.missions import mission_named
from duckielib.ros.modules import modules_installed
from duckielib.sim.link import RobotLink
from duckielib.sim.simulator import Simulator
from duckielib.solution import MISSION_PARTS, load_solution
from duckielib.tools import runner
from duckielib.tools.apart import run_apart
from duckielib.tools.runner import run_mission

_RUNS = 3


def run() -> List[Tuple[str, str]]:
    """Run the mission three times; return the figures of the fastest run."""
    from duckielib.bags import Bag

    solution = load_solution(required=MISSION_PARTS)
    runs = []
    for _ in range(_RUNS):
        with tempfile.TemporaryDirectory() as folder:
            result = run_mission(solution, out=folder, animation=False)
            runs.append((result, Bag(result.files["bag"]).message_count))
    best, messages = min(runs, key=lambda item: item[0].wall_s)
    apart: List[float] = []
    exchanges: List[float] = []
    for _ in range(_RUNS):
        exchanges.clear()
        with tempfile.TemporaryDirectory() as folder, _timed(RobotLink, "_exchange", exchanges):
            start = time.perf_counter()
            run_apart(out=folder, animation=False, figure=False)
            apart.append(time.perf_counter() - start)
    physics: List[float] = []
    with _timed(Simulator, "_advance", physics):
        _drive(solution)
    with _objects_not_bytes():
        bound = min(_drive(solution) for _ in range(_RUNS))
    return [
        ("mission_simulated_s", f"{best.simulated_s:.1f}"),
        ("mission_wall_s", f"{best.wall_s:.3f}"),
        ("mission_bag_messages", str(messages)),
        ("mission_physics_wall_s", f"{sum(physics):.3f}"),
        ("mission_wall_s_objects_no_bag", f"{bound:.3f}"),
        ("mission_apart_wall_s", f"{min(apart):.3f}"),
        ("mission_apart_exchanges", str(len(exchanges))),
        ("mission_realtime_factor", f"{best.realtime_factor:.0f}"),
    ]


def _drive(solution: Any) -> float:
    """Drive the mission as ``duckie mission`` does, without the report; the wall seconds."""
    with tempfile.TemporaryDirectory() as folder, modules_installed(replace_real=True):
        files = {"bag": Path(folder) / "mission.bag", "log": Path(folder) / "log.txt"}
        chosen = mission_named("square_then_circle")
        return runner.drive_and_record(
            solution, chosen, "ideal", 0, files, runner.DEFAULT_TIME_LIMIT_S
        )[2]


@contextlib.contextmanager
def _timed(owner: type, name: str, spent: List[float]) -> Iterator[None]:
    """Add the wall seconds of each call of ``owner.name`` to ``spent`` while inside."""
    original: Callable[..., Any] = getattr(owner, name)

    def timed(*args: Any, **kwargs: Any) -> Any:
        start = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            spent.append(time.perf_counter() - start)

    setattr(owner, name, timed)
    try:
        yield
    finally:
        setattr(owner, name, original)


@contextlib.contextmanager
def _objects_not_bytes() -> Iterator[None]:
    """Hand messages over as the objects published, and record nothing, while inside.

    Messages "serialize" to themselves and "parse" from themselves, against what their types
    say and on purpose, so the replacements are set by name.
    """
    with _replaced(Message, "to_bytes", lambda self: self), _replaced(
        Message, "from_bytes", classmethod(lambda cls, data: data)
    ), _replaced(runner, "RECORDED", ()):
        yield


@contextlib.contextmanager
def _replaced(owner: object, name: str, value: object) -> Iterator[None]:
    """Set ``owner.name`` to ``value`` while inside; put back what was there (as stored)."""
    original = vars(owner)[name]
    setattr(owner, name, value)
    try:
        yield
    finally:
        setattr(owner, name, original)
