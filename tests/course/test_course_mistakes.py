"""Every deliberately wrong solution fails the test cell of its function, hidden tests included.

Fast and in-process: a notebook's import cell, the cells that load the student's earlier work
(``load_solution("..")``, run from the notebook's folder, so they load the reference), then
its graded and test cells in order (the reference code, with one cell replaced by a wrong one),
as nbgrader runs them. The real
nbgrader run of the first mistake of each cell is in ``test_course_autograde.py``.
"""

from __future__ import annotations

import contextlib
import io
import os
from pathlib import Path

import pytest
from coursetools import NAMES, SOLUTIONS, load_solution_nb, nbgrader, source, wrong_solutions

from duckielib.ros import uninstall_modules

MISTAKES = wrong_solutions()


def failing_checks(name, replacements=None):
    """Run a notebook's graded and test cells; the test cells' grade ids that fail."""
    replacements = replacements or {}
    cells = [cell for cell in load_solution_nb(name)["cells"] if cell["cell_type"] == "code"]
    namespace: dict = {"__name__": "__main__"}
    failing = []
    environment = dict(os.environ)
    folder = Path.cwd()
    try:
        os.chdir(SOLUTIONS / name)
        with contextlib.redirect_stdout(io.StringIO()):
            exec(compile(source(cells[0]), f"{name}[imports]", "exec"), namespace)
            for cell in cells[1:]:
                meta = nbgrader(cell)
                if not meta:
                    if "load_solution(" in source(cell):
                        exec(compile(source(cell), f"{name}[earlier work]", "exec"), namespace)
                    continue
                text = replacements.get(meta["grade_id"], source(cell))
                try:
                    exec(compile(text, f"{name}[{meta['grade_id']}]", "exec"), namespace)
                except Exception:
                    failing.append(meta["grade_id"])
    finally:
        os.chdir(folder)
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
