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

MISTAKES = wrong_solutions()


def run_cell(text, label, namespace):
    """Run a cell's text as IPython does, its lines kept where ``inspect.getsource`` finds them."""
    linecache.cache[label] = (len(text), None, text.splitlines(True), label)
    exec(compile(text, label, "exec"), namespace)


def copy_with(folder, name, replacements):
    """The course's notebooks in ``folder``, ``name``'s graded cells replaced: its folder there.

    Tests that load the student's saved notebooks (``load_solution("..")``) then read the
    replaced cells, as they would in a student's folder.
    """
    for other in NAMES:
        (folder / other).mkdir()
        notebook = load_solution_nb(other)
        if other == name:
            notebook = copy.deepcopy(notebook)
            for cell in notebook["cells"]:
                grade_id = nbgrader(cell).get("grade_id")
                if grade_id in replacements:
                    cell["source"] = replacements[grade_id]
        (folder / other / f"{other}.ipynb").write_text(json.dumps(notebook), encoding="utf-8")
    return folder / name


def loads_earlier_work(text):
    """Whether a cell only loads the student's earlier work: assignments, one of them a load."""
    body = ast.parse(text).body
    return "load_solution(" in text and all(isinstance(node, ast.Assign) for node in body)


def failing_checks(name, replacements=None):
    """Run a notebook's graded and test cells; the test cells' grade ids that fail."""
    replacements = replacements or {}
    cells = [cell for cell in load_solution_nb(name)["cells"] if cell["cell_type"] == "code"]
    namespace: dict = {"__name__": "__main__"}
    failing = []
    environment = dict(os.environ)
    folder = Path.cwd()
    scratch = tempfile.TemporaryDirectory(prefix="mistakes-")
    try:
        os.chdir(
            copy_with(Path(scratch.name), name, replacements) if replacements else SOLUTIONS / name
        )
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
    finally:
        os.chdir(folder)
        scratch.cleanup()
        # A notebook may alias rospy and the message packages, or set VEHICLE_NAME: undo both
        # so the tests that follow see the real modules and environment.
        uninstall_modules()
        os.environ.clear()
        os.environ.update(environment)
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
