"""Tests that run a student's nodes on a robot, run in the grader like every other test.

A few tests launch the student's own nodes on a virtual Duckiebot (notebook 08's light service
node) or drive a whole mission with them (notebook 09). In the grader they run as every test
does (:mod:`autograder.calls`), with four names of their notebook's imports taking the grader's
meaning (:func:`robot_names`):

- ``load_solution(...)`` gives a :class:`~duckielib.tools.apart.SavedSolution`: the student's
  solution is never loaded in the grader;
- ``check_saved(...)`` has nothing to check: the notebooks graded are the saved ones;
- ``VirtualDuckiebot(...)`` is an :class:`~duckielib.tools.apart.ApartDuckiebot`: the robot
  and the test's own nodes run here; the student's nodes, launched from the solution, run in
  the sandbox and reach the robot only through topics and services;
- ``run_mission(...)`` runs the mission apart (:func:`~duckielib.tools.apart.run_apart`),
  the student's nodes in the sandbox, the bag recorded here.

The nodes load the student's saved notebooks as the grader repaired them (a folder no
sandbox writes), shown read-only at ``/course``. What the test reads (the robot's LEDs, the
services the graph lists, the bag, the report) is the grader's own.
"""

from __future__ import annotations

import contextlib
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any, Dict, Iterator, List

__all__ = ["COURSE", "sandbox_launcher", "robot_names"]

#: Where the nodes' process sees the student's saved notebooks, read-only.
COURSE = "/course"


def sandbox_launcher(unit: Any) -> Any:
    """Start the nodes' process in the unit's sandbox, with the student's saved notebooks."""
    from autograder.sandbox import started
    from duckielib.tools.apart import nodes_command

    @contextlib.contextmanager
    def start(sock: Any, arguments: List[str]) -> Iterator[Any]:
        fd = sock.fileno()
        folder = Path(tempfile.mkdtemp(prefix="nodes-", dir=unit.student_disk))
        shutil.chown(folder, unit.limits.uid, unit.limits.uid)
        solution = COURSE if unit.use_sandbox else str(unit.export)
        command = nodes_command(fd, solution, arguments)
        try:
            with started(
                command,
                folder,
                unit.limits,
                unit.use_sandbox,
                pass_fds=(fd,),
                shared=(unit.export, COURSE),
            ) as running:
                yield running
                with contextlib.suppress(subprocess.TimeoutExpired):
                    running.process.wait(timeout=5)
        finally:
            shutil.rmtree(folder, ignore_errors=True)

    return start


def _keep_for_driving(unit: Any, run: Any, options: Dict[str, Any]) -> None:
    """Keep a finished run that the driving score would drive again.

    The same mission on the ideal robot, seed 0, the mission's own colours and time limit
    (see :func:`autograder.driving.drive_missions`).
    """
    mission = options.get("mission", "square_then_circle")
    same = (
        isinstance(mission, str)
        and options.get("noise", "ideal") == "ideal"
        and options.get("seed", 0) == 0
        and options.get("stop_color") is None
        and "time_limit" not in options
        and "stall_limit" not in options
    )
    runs = getattr(unit, "runs", None)
    if same and runs is not None and run.report.finished:
        runs.setdefault(mission, run.files["bag"])


def robot_names(unit: Any, space: Dict[str, Any], until: float) -> Dict[str, Any]:
    """The grader's meaning of the names of ``space`` that run a student's nodes.

    Args:
        unit: the student's grading (its sandbox's limits, the repaired notebooks).
        space: the notebook's namespace for its tests (only the names it imports are given).
        until: the ``time.monotonic()`` by which the test must end.
    """
    launcher = sandbox_launcher(unit)

    def left() -> float:
        return max(1.0, until - time.monotonic())

    def load_solution(path: Any = None, required: Any = (), visible_tests: Any = None) -> Any:
        from duckielib.tools.apart import SavedSolution

        return SavedSolution(list(required))

    def check_saved(solution: Any, *defined_here: Any) -> None:
        return None  # the notebooks graded are the saved ones

    def run_mission(solution: Any = None, **options: Any) -> Any:
        from duckielib.errors import DuckielibError
        from duckielib.tools.apart import run_apart

        options.setdefault("out", tempfile.mkdtemp(prefix="mission-", dir=unit.folder))
        try:
            run = run_apart(solution, launcher=launcher, wall_limit=left(), **options)
        except DuckielibError as error:  # the grader's folders mean nothing to the student
            said = re.sub(r"\s*The run's [^.]*? (?:is|are) in \S+?\.?$", "", str(error))
            raise type(error)(said) from None
        _keep_for_driving(unit, run, options)
        return run

    def VirtualDuckiebot(*args: Any, **kwargs: Any) -> Any:  # noqa: N802 - the test's name
        from duckielib.tools.apart import ApartDuckiebot

        return ApartDuckiebot(launcher, *args, wall_limit=left(), **kwargs)

    given = {
        "load_solution": load_solution,
        "check_saved": check_saved,
        "run_mission": run_mission,
        "VirtualDuckiebot": VirtualDuckiebot,
    }
    return {name: value for name, value in given.items() if name in space}
