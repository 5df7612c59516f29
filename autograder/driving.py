"""The driving score: a student's own exported code drives the mission on the virtual Duckiebot.

The cells the student tagged ``export`` are collected from their notebooks (read as text, never
run here), and ``duckie mission`` runs that solution on the square-then-circle mission inside
the same sandbox as their notebooks. The grader then reads the run's bag itself and scores what
the robot did, with :func:`duckielib.behaviour.mission_report`:

=========================================  ======
a readable bag with the mission's states     10
the states and LED colours in order          40
every stop held for its time, standing still 25
the true end within 10 cm of the start       25
=========================================  ======

A solution that is incomplete or fails scores zero, with the reason the student would see from
``duckie mission``. The student's code runs in the simulator's process, so the bag is evidence
of behaviour, not a proof against forgery: a submission that writes a fake bag is a matter for
the instructor, like any other cheating.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional

from autograder.sandbox import NOBODY, Limits, run

__all__ = ["MAX_SCORE", "POINTS", "Driving", "drive"]

#: Points of each part of the driving score.
POINTS = {"bag": 10.0, "states": 40.0, "stops": 25.0, "closure": 25.0}
#: The best driving score.
MAX_SCORE = sum(POINTS.values())
#: The robot's name in the run (its namespace).
ROBOT = "duckiebot"
#: The trajectory figure may be at most this big (bytes); a larger file is left out.
FIGURE_LIMIT = 2_000_000
_PNG = b"\x89PNG\r\n\x1a\n"


@dataclass
class Driving:
    """How a student's code drove the mission.

    Attributes:
        score: the points, out of :data:`MAX_SCORE`.
        parts: the points of each part of :data:`POINTS`.
        reasons: why points were lost, one sentence each.
        summary: what the robot did (the mission report as plain data), or None.
        figure: the trajectory figure's PNG bytes, or None.
    """

    score: float = 0.0
    parts: Dict[str, float] = field(default_factory=dict)
    reasons: List[str] = field(default_factory=list)
    summary: Optional[Dict[str, Any]] = None
    figure: Optional[bytes] = None


def drive(
    notebooks: Path,
    folder: Path,
    limits: Limits,
    use_sandbox: bool = True,
    mission: str = "square_then_circle",
) -> Driving:
    """Export the student's notebooks, run the mission in a sandbox on ``folder``, score it.

    Args:
        notebooks: the student's folder of assignment notebooks (a copy of ``course/``), or
            a ``.py`` solution made by ``duckie export``.
        folder: an empty folder the run may write (owned over to the sandbox's user here).
        limits: the sandbox's limits; the mission has ``limits.mission_seconds`` of wall time.
        use_sandbox: whether to run in the sandbox (off only with ``duckie grade --no-sandbox``).
        mission: the mission to drive.

    Returns:
        The driving score with its reasons.
    """
    from duckielib.errors import DuckielibError
    from duckielib.solution import export_solution

    if notebooks.is_file():  # a module made by duckie export
        text = notebooks.read_text(encoding="utf-8")
    else:
        try:
            text = export_solution(notebooks, strict=False).source
        except DuckielibError as error:
            return Driving(reasons=[f"Your notebooks could not be exported: {error}"])
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    (folder / "solution.py").write_text(text, encoding="utf-8")
    for path in [folder, *folder.rglob("*")]:
        shutil.chown(path, NOBODY, NOBODY)
    command = [sys.executable, "-m", "duckielib.cli", "mission", "--solution", "solution.py"]
    command += ["--mission", mission, "--out", "run", "--no-animation"]
    try:
        result = run(
            command,
            folder,
            limits,
            limits.mission_seconds,
            use_sandbox=use_sandbox,
            env={"VEHICLE_NAME": ROBOT},
        )
    except subprocess.TimeoutExpired:
        return Driving(
            reasons=[f"The mission did not end within {limits.mission_seconds} s of wall time."]
        )
    if result.returncode != 0:
        return Driving(reasons=[_failure(result.stderr)])
    return score_bag(folder / "run", mission)


def _failure(stderr: str) -> str:
    """The sentence ``duckie mission`` ended with, or the last line it printed."""
    lines = [line for line in stderr.splitlines() if line.strip()]
    said = [line[len("duckie: ") :] for line in lines if line.startswith("duckie: ")]
    if said:
        # The run's log stays in the sandbox: the sentence pointing to it is left out.
        reason = re.sub(r"\s*The run's log is in \S+$", "", said[-1])
        return f"The mission could not run: {reason}"
    return "The mission stopped with an error: " + (lines[-1][:300] if lines else "no message")


def score_bag(run: Path, mission: str = "square_then_circle") -> Driving:
    """Score the run in folder ``run`` from its bag, read by the grader.

    Args:
        run: the folder ``duckie mission`` wrote (``mission.bag``, ``trajectory.png``).
        mission: the mission that was driven.
    """
    from duckielib.behaviour import mission_report
    from duckielib.errors import DuckielibError
    from duckielib.missions import mission_named

    bag = run / "mission.bag"
    if not bag.is_file() or bag.is_symlink():
        return Driving(reasons=["The mission wrote no bag."])
    try:
        report = mission_report(bag, mission_named(mission), f"/{ROBOT}/")
    except (DuckielibError, ValueError, KeyError, OSError) as error:
        return Driving(reasons=[f"The mission's bag cannot be read: {error}"])
    driving = Driving(summary=report.as_dict(), reasons=list(report.problems))
    earned = {
        "bag": bool(report.states),
        "states": report.states_in_order,
        "stops": report.stops_held,
        "closure": report.closed,
    }
    driving.parts = {name: POINTS[name] if ok else 0.0 for name, ok in earned.items()}
    driving.score = sum(driving.parts.values())
    figure = run / "trajectory.png"
    if figure.is_file() and not figure.is_symlink() and figure.stat().st_size <= FIGURE_LIMIT:
        data = figure.read_bytes()
        driving.figure = data if data.startswith(_PNG) else None
    return driving
