"""Every deliberately wrong solution fails the test cell of its function, hidden tests included.

Fast and in-process: a notebook's import cell, the cells that load the student's earlier work
(``load_solution("..")``), then its graded and test cells in order (the reference code, with
one cell replaced by a wrong one), as nbgrader runs them. They run from the notebook's folder in
a copy of the course whose notebook holds the wrong cell, so a test that loads the student's
saved notebooks loads the wrong cell too. The real nbgrader run of the first mistake of each
cell is in ``test_course_autograde.py``.
"""

from __future__ import annotations

import ast
import contextlib
import copy
import io
import json
import linecache
import os
import tempfile
from pathlib import Path

import pytest
from coursetools import NAMES, SOLUTIONS, load_solution_nb, nbgrader, source, wrong_solutions

from duckielib.ros import uninstall_modules
from duckielib.solution import SolutionError

MISTAKES = wrong_solutions()


def run_cell(text, label, namespace):
    """Run a cell's text as IPython does, its lines kept where ``inspect.getsource`` finds them."""
    linecache.cache[label] = (len(text), None, text.splitlines(True), label)
    exec(compile(text, label, "exec"), namespace)


def copy_with(folder, name, replacements, others=None):
    """The course's notebooks in ``folder``, ``name``'s graded cells replaced: its folder there.

    Tests that load the student's saved notebooks (``load_solution("..")``) then read the
    replaced cells, as they would in a student's folder. ``others`` replaces graded cells of the
    other notebooks too: ``{(notebook, grade_id): source}``.
    """
    others = others or {}
    for other in NAMES:
        (folder / other).mkdir()
        notebook = load_solution_nb(other)
        swaps = dict(replacements) if other == name else {}
        swaps.update(
            {grade_id: text for (owner, grade_id), text in others.items() if owner == other}
        )
        if swaps:
            notebook = copy.deepcopy(notebook)
            for cell in notebook["cells"]:
                grade_id = nbgrader(cell).get("grade_id")
                if grade_id in swaps:
                    cell["source"] = swaps[grade_id]
        (folder / other / f"{other}.ipynb").write_text(json.dumps(notebook), encoding="utf-8")
    return folder / name


def loads_earlier_work(text):
    """Whether a cell only loads the student's earlier work: assignments, one of them a load."""
    body = ast.parse(text).body
    return "load_solution(" in text and all(isinstance(node, ast.Assign) for node in body)


@contextlib.contextmanager
def scratch_folder(prefix):
    """A scratch folder; after it, the working folder, the environment and the modules as before.

    A notebook may alias rospy and the message packages, or set VEHICLE_NAME: both are undone
    so the tests that follow see the real modules and environment.
    """
    environment = dict(os.environ)
    folder = Path.cwd()
    scratch = tempfile.TemporaryDirectory(prefix=prefix)
    try:
        yield Path(scratch.name)
    finally:
        os.chdir(folder)
        scratch.cleanup()
        uninstall_modules()
        os.environ.clear()
        os.environ.update(environment)


def failing_checks(name, replacements=None):
    """Run a notebook's graded and test cells; the test cells' grade ids that fail."""
    replacements = replacements or {}
    cells = [cell for cell in load_solution_nb(name)["cells"] if cell["cell_type"] == "code"]
    namespace: dict = {"__name__": "__main__"}
    failing = []
    with scratch_folder("mistakes-") as scratch:
        os.chdir(copy_with(scratch, name, replacements) if replacements else SOLUTIONS / name)
        with contextlib.redirect_stdout(io.StringIO()):
            run_cell(source(cells[0]), f"<{name}[imports]>", namespace)
            for cell in cells[1:]:
                meta = nbgrader(cell)
                if not meta:
                    if loads_earlier_work(source(cell)):
                        run_cell(source(cell), f"<{name}[earlier work]>", namespace)
                    continue
                text = replacements.get(meta["grade_id"], source(cell))
                try:
                    run_cell(text, f"<{name}[{meta['grade_id']}]>", namespace)
                except Exception:
                    failing.append(meta["grade_id"])
    return failing


@pytest.mark.parametrize("name", NAMES)
def test_the_reference_passes_every_check_in_process(name):
    assert failing_checks(name) == []


@pytest.mark.parametrize(
    ("name", "grade_id", "mistake"), sorted(MISTAKES), ids=["-".join(k) for k in sorted(MISTAKES)]
)
def test_the_mistake_fails_its_check(name, grade_id, mistake):
    failing = failing_checks(name, {grade_id: MISTAKES[(name, grade_id, mistake)]})
    assert f"test_{grade_id}" in failing, f"{mistake!r} passes test_{grade_id}"


@contextlib.contextmanager
def given_cells(name, wanted, others=None):
    """A notebook's namespace after its imports, earlier work, graded cells and given ``wanted``.

    The given cells ``wanted`` (cell ids) run with the first cell, the cells that load earlier
    work and the graded cells, in the notebook's order, from its folder in a copy of the course
    (``others`` as for :func:`copy_with`); test cells and the other given cells do not run.
    """
    namespace: dict = {"__name__": "__main__"}
    with scratch_folder("given-") as scratch:
        os.chdir(copy_with(scratch, name, {}, others))
        cells = [cell for cell in load_solution_nb(name)["cells"] if cell["cell_type"] == "code"]
        with contextlib.redirect_stdout(io.StringIO()):
            for index, cell in enumerate(cells):
                text, meta = source(cell), nbgrader(cell)
                graded = meta.get("solution") and not meta.get("grade")
                if index == 0 or graded or cell["id"] in wanted or loads_earlier_work(text):
                    run_cell(text, f"<{name}[{cell['id']}]>", namespace)
        yield namespace


#: The given cells of 06_driving that define its runs: the constants, the driver, run_task with
#: its checks and report, and the exit test.
DRIVING = ("5c0a9138", "856af4fb", "52d1b742", "795d0c52")


def test_driving_says_in_words_what_a_run_is_missing():
    # A run the driver did not finish, a node gone before it is killed: a sentence for the
    # student, never a bare KeyError or IndexError from a given cell.
    out = io.StringIO()
    with given_cells("06_driving", DRIVING) as notebook, contextlib.redirect_stdout(out):
        run = notebook["run_task"](notebook["STRAIGHT"], limit=0.5)  # too short for a move
        notebook["report"](run)
        with pytest.raises(SolutionError, match=r"never finished move 1 of 2 \(straight \+1\.25"):
            notebook["moves_done"](run)

        def quick_driver(distance):
            notebook["rospy"].init_node("quick_driver")  # and returns at once

        how, *_ = notebook["exit_test"](quick_driver, "quick_driver", kill_after=0.8)
    assert "The driver finished 0 of the 2 moves" in out.getvalue()
    assert how == "returned"


def test_driving_says_when_the_odometry_is_absurdly_far_from_the_truth():
    # A WheelPairing that passes its visible tests but keeps its state in the class: the second
    # robot's odometry starts from the first one's counts, metres away.
    mistake = ("05_odometry", "WheelPairing", "state kept in the class, shared by every pairing")
    others = {mistake[:2]: MISTAKES[mistake]}
    out = io.StringIO()
    with given_cells("06_driving", DRIVING, others) as notebook, contextlib.redirect_stdout(out):
        for _ in range(2):
            notebook["run_task"]([("straight", 0.1)])
    assert "Your odometry ended" in out.getvalue()
    assert "fix notebook 05 first" in out.getvalue()
