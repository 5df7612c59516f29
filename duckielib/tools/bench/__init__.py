"""Benchmarks, run as ``duckie bench NAME``.

Each benchmark is a module here with a ``run()`` function that returns its figures as
``(name, value)`` pairs, the headline figure last; ``duckie bench`` prints them one per line as
``name: value``. Figures are measured, never asserted: tests check that a benchmark runs and
prints well-formed figures, not how fast this machine is.
"""

from __future__ import annotations

import importlib
from typing import Dict, List, Tuple

from duckielib.errors import DuckielibError

__all__ = ["BENCHMARKS", "benchmarks", "run_benchmark"]

#: Benchmark name -> (module, one-line description): the library's own. :func:`benchmarks`
#: adds those other packages register (the grader's ``grade``).
BENCHMARKS: Dict[str, Tuple[str, str]] = {
    "messages": (
        "duckielib.tools.bench.messages",
        "build, serialize and read back the course's messages",
    ),
    "graph": (
        "duckielib.tools.bench.graph",
        "real-time factor of the virtual Duckiebot with a controller and a listener node",
    ),
    "camera": (
        "duckielib.tools.bench.camera",
        "real-time factor of the virtual Duckiebot with a node subscribed to its camera",
    ),
    "sim": (
        "duckielib.tools.bench.sim",
        "real-time factor of the simulator alone (60 s drive, encoders and LEDs on)",
    ),
    "mission": (
        "duckielib.tools.bench.mission",
        "real-time factor of the whole square-then-circle mission (nodes, odometry, bag)",
    ),
    "kernel": (
        "duckielib.tools.bench.kernel",
        "seconds from starting a notebook's kernel to its first cell's result, per notebook",
    ),
    "bags": (
        "duckielib.tools.bench.bags",
        "odometry replayed from a 100,000-message encoder bag, and Debian's rosbag reading it",
    ),
}

Figure = Tuple[str, str]


def benchmarks() -> Dict[str, Tuple[str, str]]:
    """Every benchmark: the library's, and those of the entry point group ``duckie.benchmarks``.

    A registered benchmark names its module; its one-line description is the module's
    ``DESCRIPTION``.
    """
    from importlib.metadata import entry_points

    found = dict(BENCHMARKS)
    for entry in entry_points(group="duckie.benchmarks"):
        try:
            module = importlib.import_module(entry.value)
        except ModuleNotFoundError as error:
            # The student edition has no autograder/, even where the environment was made for
            # the whole repository: then its benchmark is simply not there.
            if not error.name or not (entry.value + ".").startswith(error.name + "."):
                raise
            continue
        found[entry.name] = (entry.value, str(getattr(module, "DESCRIPTION", "")))
    return found


def run_benchmark(name: str) -> List[Figure]:
    """Run one benchmark and return its figures, headline last.

    Raises:
        DuckielibError: if there is no benchmark of that name.
    """
    known = BENCHMARKS if name in BENCHMARKS else benchmarks()
    if name not in known:
        choices = ", ".join(sorted(known))
        raise DuckielibError(f"There is no benchmark called {name!r}; choose one of: {choices}.")
    module = importlib.import_module(known[name][0])
    return module.run()
