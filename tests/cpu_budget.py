"""What the suite costs, by test module and by area, in CPU seconds: measured, and held to a budget.

Each test's CPU time is measured in the process that runs it, with every process it started and
waited for (``getrusage`` of the process and of its children: kernels, sandboxes, the grader's
units, Dask's workers, ROS masters, browsers), from its setup to its teardown; a module's shared
setup falls to its first test, its teardown to its last. pytest-xdist's workers hand their
figures to the controller when they end. ``make test`` then prints the modules that cost most
and each area against its budget (:data:`BUDGETS`), in CPU seconds of the reference machine:
the figures measured here are divided by the pace (``tests/pace.py``), so that a slower machine
is not said to be over. Last, how busy the machine's CPUs were over the run (:func:`busy_line`):
browsers and servers the tests did not wait for count there, and not in the modules' figures.
"""

from __future__ import annotations

import resource
from pathlib import Path
from typing import Dict, List, Tuple

__all__ = [
    "AREAS",
    "BUDGETS",
    "Meter",
    "area_of",
    "busy_line",
    "cpu_seconds",
    "machine_ticks",
    "summary",
]

#: The suite's areas, by the folder or module their tests are in (the first that matches).
AREAS: Tuple[Tuple[str, str], ...] = (
    ("tests/adversarial/", "attacks on the grader"),
    ("tests/autograder/test_hub", "the class hub"),
    ("tests/autograder/test_formgrade", "Formgrader"),
    ("tests/autograder/", "grading"),
    ("tests/course/", "the course's notebooks"),
    ("tests/real_ros/", "real ROS"),
    ("tests/foreign/", "other people's projects"),
    ("tests/sim/", "the simulator"),
    ("tests/tools/", "the commands"),
    ("tests/", "the library"),
)

#: Each area's budget, in CPU seconds of the reference machine (pace 1) for the whole suite:
#: what it cost when the budget was set (``make test`` on the 2-core test machine, pace 1.81,
#: 654 s in all), and a quarter more. A new test of a heavy kind (a class graded, the course's
#: notebooks run, a hub, a browser) joins one of the area's shared runs rather than make its own.
BUDGETS: Dict[str, float] = {
    "attacks on the grader": 155,
    "the class hub": 80,
    "Formgrader": 15,
    "grading": 245,
    "the course's notebooks": 180,
    "real ROS": 45,
    "other people's projects": 10,
    "the simulator": 25,
    "the commands": 40,
    "the library": 50,
}


def area_of(module: str) -> str:
    """The area of test module ``module`` (a path as pytest names it)."""
    return next(area for prefix, area in AREAS if module.startswith(prefix))


def cpu_seconds() -> float:
    """CPU seconds (user and system) of this process and of the children it waited for."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def machine_ticks() -> Tuple[int, int]:
    """The machine's CPU time since it started, in clock ticks: (busy, in all), by /proc/stat.

    Every process of the machine counts, the suite's (those it did not wait for too: browsers,
    servers) and any other; idle and waiting for a disk are not busy.
    """
    try:
        first = Path("/proc/stat").read_text(encoding="ascii").split("\n", 1)[0]
    except OSError:
        return 0, 0
    ticks = [int(value) for value in first.split()[1:9]]  # user to steal; guests are in user
    return sum(ticks) - ticks[3] - ticks[4], sum(ticks)


def busy_line(before: Tuple[int, int], after: Tuple[int, int], cpus: int) -> str:
    """How busy the machine's CPUs were between two :func:`machine_ticks`, in one sentence."""
    busy, total = after[0] - before[0], after[1] - before[1]
    if total <= 0:
        return ""
    return (
        f"The machine's {cpus} CPUs were busy {100 * busy / total:.0f}% of the run "
        "(every process on it, the suite's and any other)."
    )


class Meter:
    """CPU seconds by test module, summed over the module's tests."""

    def __init__(self) -> None:
        self.by_module: Dict[str, float] = {}

    def add(self, module: str, seconds: float) -> None:
        """Count ``seconds`` to ``module``."""
        self.by_module[module] = self.by_module.get(module, 0.0) + max(0.0, seconds)

    def merge(self, other: Dict[str, float]) -> None:
        """Add another process's figures (a pytest-xdist worker's)."""
        for module, seconds in other.items():
            self.add(module, float(seconds))


def summary(by_module: Dict[str, float], pace: float, most: int = 12) -> List[str]:
    """The lines ``make test`` ends with: the costliest modules, then each area and its budget."""
    if not by_module:
        return []
    total = sum(by_module.values())
    lines = [
        f"CPU seconds by test module, its tests and what they started (pace {pace:.2f}; "
        f"{total:.0f} s in all, {total / pace:.0f} s at pace 1):"
    ]
    ranked = sorted(by_module.items(), key=lambda pair: -pair[1])
    lines += [f"  {seconds:8.0f}  {module}" for module, seconds in ranked[:most]]
    if len(ranked) > most:
        rest = sum(seconds for _, seconds in ranked[most:])
        lines.append(f"  {rest:8.0f}  the other {len(ranked) - most} modules")
    areas: Dict[str, float] = {}
    for module, seconds in by_module.items():
        area = area_of(module)
        areas[area] = areas.get(area, 0.0) + seconds / pace
    lines.append("CPU seconds by area at pace 1, and its budget:")
    over = []
    for area, budget in BUDGETS.items():
        used = areas.get(area, 0.0)
        flag = "  OVER" if used > budget else ""
        lines.append(f"  {used:8.0f} of {budget:6.0f}  {area}{flag}")
        if used > budget:
            over.append(area)
    lines.append(
        f"Over budget: {', '.join(over)} (README, The suite's budget: a new test of a heavy kind "
        "joins a shared run)."
        if over
        else "Every area is within its budget."
    )
    return lines
