"""Benchmark: how long each notebook of a finished course takes under Run All.

The released ``course/`` with every graded answer cell filled with the reference code (see
:func:`autograder.bench.filled_course`), each notebook run top to bottom in a fresh kernel as
JupyterLab's Run All runs it (:func:`duckielib.tools.handin.check_course`, kernel start
included). The course's target is under 60 s for each notebook and under 3 minutes for all.
Figures:

- ``run_all_s_NAME``: each notebook's Run All.
- ``run_all_max_s``: the slowest notebook.
- ``run_all_total_s``, the headline: the whole course.

Each notebook must run clean (``all_clean``), since timing a broken run means nothing.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Iterable, List, Tuple

from autograder.bench import filled_course

#: What ``duckie bench`` lists for this benchmark.
DESCRIPTION = "seconds of Run All for each notebook of a finished course (target: under 60 s)"

__all__ = ["DESCRIPTION", "figures", "run"]


def figures(runs: Iterable) -> List[Tuple[str, str]]:
    """The benchmark's figures from the notebooks' runs (``NotebookRun``), headline last."""
    runs = list(runs)
    pairs = [(f"run_all_s_{run.name}", f"{run.seconds:.1f}") for run in runs]
    pairs.append(("all_clean", str(all(run.clean for run in runs))))
    pairs.append(("run_all_max_s", f"{max(run.seconds for run in runs):.1f}"))
    pairs.append(("run_all_total_s", f"{sum(run.seconds for run in runs):.1f}"))
    return pairs


def run() -> List[Tuple[str, str]]:
    """Fill a copy of the course, Run All each notebook, and return the figures."""
    from duckielib.tools.handin import check_course

    with tempfile.TemporaryDirectory(prefix="duckie-bench-notebooks-") as scratch:
        course = filled_course(Path(scratch) / "course")
        return figures(check_course(course).runs)
