"""Gates that run the notebooks as a student does: Run All in a fresh kernel, every cell.

nbgrader's autograde lets a cell raise and still scores the tests after it, so it cannot see a
notebook that breaks for its reader. These gates run each notebook with nbclient, as
JupyterLab's Kernel > Restart Kernel and Run All Cells does, in a copy of the course folder
holding only the notebooks:

- the instructors' ``solutions/`` and the release filled with the reference answers: no cell
  may raise, and each notebook runs in under 60 s;
- the untouched release: Run All may stop only at the notebook's first exercise (its cell, its
  test cell, or a cell that says which exercise to finish first). What comes before it
  (explanations, diagrams, listings) must not need later exercises or other notebooks.
"""

from __future__ import annotations

import pytest
from coursetools import COURSE, NAMES, SOLUTIONS, reference_answers, student_copy, too_early

from duckielib.handin import check_course

pytestmark = [pytest.mark.slow, pytest.mark.notebook, pytest.mark.timeout(1500)]


def runs_of(folder):
    return {run.name: run for run in check_course(folder).runs}


@pytest.fixture(scope="module")
def source_runs():
    return runs_of(SOLUTIONS)


@pytest.fixture(scope="module")
def filled_runs(tmp_path_factory):
    return runs_of(student_copy(tmp_path_factory.mktemp("run_all") / "filled", reference_answers()))


@pytest.fixture(scope="module")
def untouched_runs():
    return runs_of(COURSE)


def raised(run):
    return "\n".join(cell.describe() for cell in run.raised) or run.stopped


@pytest.mark.parametrize("name", NAMES)
def test_each_source_notebook_runs_clean_under_run_all(source_runs, name):
    run = source_runs[name]
    assert run.clean, f"solutions/{name} raised under Run All:\n{raised(run)}"
    assert run.figures_as_text == [], f"{name}: cells that show a figure as text, not a picture"
    assert run.seconds < 60, f"solutions/{name} took {run.seconds:.0f} s"


@pytest.mark.parametrize("name", NAMES)
def test_each_filled_release_notebook_runs_clean_under_run_all(filled_runs, name):
    run = filled_runs[name]
    assert run.clean, f"the filled release of {name} raised under Run All:\n{raised(run)}"
    assert all(run.tests.values()), f"{name}: visible tests failing: {run.failed_tests}"
    assert run.figures_as_text == [], f"{name}: cells that show a figure as text, not a picture"
    assert run.seconds < 60, f"the filled release of {name} took {run.seconds:.0f} s"


@pytest.mark.parametrize("name", NAMES)
def test_the_untouched_release_stops_only_at_its_first_exercise(untouched_runs, name):
    run = untouched_runs[name]
    assert too_early(run) is None, too_early(run)
