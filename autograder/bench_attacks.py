"""Benchmark: what students who attack the grader cost a well-behaved student graded beside them.

A student with the reference answers of notebook 03 is graded alone (a local cluster of two
workers, as ``duckie grade --jobs 2`` grades), then again in a class of the same size as
:data:`ATTACKS` plus one, each attacker handing in the same notebook with one cell more:

- ``busy``: eight busy loops started in sessions of their own, left running;
- ``fork_bomb``: ``os.fork()`` in an endless loop;
- ``memory``: 20 GB asked for at once;
- ``disk``: a file written until the disk says no;
- ``answer_48mb``: an answer of 48 MB;
- ``sleeps``: three cells of 20 s each.

Figures, in wall-clock seconds of the neighbour's own grading (its unit, from the result's
timings), and in MB of the grader's memory for one student: ``neighbour_alone_s``,
``neighbour_in_class_s``, ``attackers_worst_grader_memory_mb`` (the most the grader's process
for an attacker held), ``neighbour_grader_memory_mb``; the neighbour must keep full marks in
both runs (``neighbour_full_marks``). The headline, last, is ``neighbour_slowdown``: its time
in the class over its time alone (target: 1.3 or less).
"""

from __future__ import annotations

import shutil
import tempfile
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Dict, List, Tuple

import nbformat

from autograder.bench import filled_notebook

if TYPE_CHECKING:
    from autograder.results import StudentResult

#: What ``duckie bench`` lists for this benchmark.
DESCRIPTION = "a well-behaved student graded alone, then beside students who attack the grader"

__all__ = ["ATTACKS", "DESCRIPTION", "run"]

ASSIGNMENT = "03_frames"

#: Each attacker's extra cell, by the attack's name.
ATTACKS: Dict[str, str] = {
    "busy": (
        "import subprocess, sys\n"
        "for _ in range(8):\n"
        "    subprocess.Popen([sys.executable, '-c', 'while 1: pass'], start_new_session=True)\n"
    ),
    "fork_bomb": "import os\nwhile True:\n    os.fork()\n",
    "memory": "hoard = bytearray(20 * 1024**3)\n",
    "disk": (
        "chunk = bytes(1 << 24)\n"
        "with open('disk.bin', 'wb') as out:\n"
        "    while True:\n"
        "        out.write(chunk)\n"
    ),
    "answer_48mb": "wrap_angle = lambda theta: 'x' * 48_000_000\n",
    "sleeps": "import time\ntime.sleep(20)\n",
}


def _hand_in(folder: Path, cell: str = "", repeat: int = 1) -> None:
    """Write the reference notebook into ``folder``, with ``cell`` added ``repeat`` times.

    The cells go right after the answer of ``wrap_angle``: an answer they define is the one
    the test calls.
    """
    notebook = filled_notebook(ASSIGNMENT)
    after = next(
        index
        for index, each in enumerate(notebook.cells)
        if each.get("metadata", {}).get("nbgrader", {}).get("grade_id") == "wrap_angle"
    )
    for _ in range(repeat if cell else 0):
        notebook.cells.insert(after + 1, nbformat.v4.new_code_cell(cell))
    target = folder / ASSIGNMENT
    target.mkdir(parents=True)
    nbformat.write(notebook, target / f"{ASSIGNMENT}.ipynb")


def _grade(submissions: Path, out: Path) -> Dict[str, StudentResult]:
    from autograder.grade import grade_class

    results = grade_class(submissions, out, jobs=2, names=[ASSIGNMENT], driving=False)
    return {result.student: result for result in results}


def run() -> List[Tuple[str, str]]:
    """Grade the neighbour alone, then beside the attackers; return the figures."""
    from sqlalchemy.exc import SAWarning

    with warnings.catch_warnings(), tempfile.TemporaryDirectory(
        prefix="duckie-bench-attacks-"
    ) as scratch:
        warnings.filterwarnings("ignore", category=SAWarning)
        root = Path(scratch)
        _hand_in(root / "alone" / "neighbour")
        alone = _grade(root / "alone", root / "out-alone")["neighbour"]
        shutil.copytree(root / "alone", root / "class")
        for name, cell in ATTACKS.items():
            _hand_in(root / "class" / name, cell, repeat=3 if name == "sleeps" else 1)
        graded = _grade(root / "class", root / "out-class")
    beside = graded["neighbour"]
    alone_s, beside_s = alone.timings["unit"], beside.timings["unit"]
    memory = max(graded[name].timings["grader_memory_mb"] for name in ATTACKS)
    full = all(result.total == result.max_total > 0 for result in (alone, beside))
    return [
        ("neighbour_alone_s", f"{alone_s:.1f}"),
        ("neighbour_in_class_s", f"{beside_s:.1f}"),
        ("neighbour_grader_memory_mb", f"{beside.timings['grader_memory_mb']:.0f}"),
        ("attackers_worst_grader_memory_mb", f"{memory:.0f}"),
        ("neighbour_full_marks", str(full)),
        ("neighbour_slowdown", f"{beside_s / alone_s:.2f}"),
    ]
