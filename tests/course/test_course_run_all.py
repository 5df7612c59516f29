"""Gates that run the notebooks as a student does: Run All in a fresh kernel, every cell.

nbgrader's autograde lets a cell raise and still scores the tests after it, so it cannot see a
notebook that breaks for its reader. These gates run each notebook with nbclient, as
JupyterLab's Kernel > Restart Kernel and Run All Cells does, in a copy of the course folder
holding only the notebooks:

- the release filled with the reference answers: no cell may raise (how long each takes is
  measured by ``duckie bench notebooks``, not asserted). The instructors' ``solutions/`` is
  that same code plus the hidden tests, which the class grader runs on the filled release
  (``test_course_autograde.py``: full marks), so it is not run a second time here;
- the untouched release: Run All may stop only at the notebook's first exercise (its cell, its
  test cell, or a cell that says which exercise to finish first). What comes before it
  (explanations, diagrams, listings) must not need later exercises or other notebooks.

The filled and the untouched release are checked through ``duckie handin``, as a student who
finished the course and one who has not started would hand them in.
"""

from __future__ import annotations

import zipfile
from concurrent.futures import ThreadPoolExecutor

import pytest
from claims import CLAIMS, check_claim, markdown_text
from coursetools import (
    COURSE,
    NAMES,
    SOLUTIONS,
    load,
    notebook_path,
    reference_answers,
    student_copy,
    too_early,
)

from autograder import bench_notebooks
from duckielib.tools.handin import handin

pytestmark = [pytest.mark.slow, pytest.mark.notebook, pytest.mark.timeout(1500)]


def runs_of(check):
    return {run.name: run for run in check.runs}


def handed_in(folder, zip_path):
    """``duckie handin``'s check of a whole course, and the notebooks of the zip it wrote."""
    check = handin(folder, zip_path)
    with zipfile.ZipFile(zip_path) as archive:
        assert sorted(archive.namelist()) == [f"{name}/{name}.ipynb" for name in NAMES]
        for name in NAMES:
            data = (folder / name / f"{name}.ipynb").read_bytes()
            assert archive.read(f"{name}/{name}.ipynb") == data
    return runs_of(check)


@pytest.fixture(scope="module")
def hand_ins(tmp_path_factory):
    """Both hand-ins, checked side by side (each notebook's kernel waits on its own much of
    the time): a student who finished the course, and one who has not started and hands in
    the course as it was released."""
    root = tmp_path_factory.mktemp("run_all")
    filled = student_copy(root / "filled", reference_answers())
    with ThreadPoolExecutor(max_workers=2) as pool:
        finished = pool.submit(handed_in, filled, root / "filled.zip")
        not_started = pool.submit(handed_in, COURSE, root / "untouched.zip")
        return finished.result(), not_started.result()


@pytest.fixture(scope="module")
def filled_runs(hand_ins):
    return hand_ins[0]


@pytest.fixture(scope="module")
def untouched_runs(hand_ins):
    return hand_ins[1]


def claims_broken(run, folder, name):
    """Each claim of notebook ``name`` that its text or its run no longer backs, in words."""
    markdown = markdown_text(load(notebook_path(folder, name)))
    printed = "\n".join(run.printed[number] for number in sorted(run.printed))
    found = (check_claim(claim, markdown, printed) for claim in CLAIMS.get(name, []))
    return [problem for problem in found if problem is not None]


def raised(run):
    return "\n".join(cell.describe() for cell in run.raised) or run.stopped


@pytest.mark.parametrize("name", NAMES)
def test_each_filled_release_notebook_runs_clean_under_run_all(filled_runs, name):
    run = filled_runs[name]
    assert run.clean, f"the filled release of {name} raised under Run All:\n{raised(run)}"
    assert all(run.tests.values()), f"{name}: visible tests failing: {run.failed_tests}"
    assert run.figures_as_text == [], f"{name}: cells that show a figure as text, not a picture"


def test_the_notebooks_benchmark_gives_each_notebooks_run_all_and_the_whole(filled_runs):
    figures = dict(bench_notebooks.figures(filled_runs.values()))
    seconds = {name: run.seconds for name, run in filled_runs.items()}
    assert list(figures)[-1] == "run_all_total_s"
    assert {name: float(figures[f"run_all_s_{name}"]) for name in NAMES} == pytest.approx(
        seconds, abs=0.05
    )
    assert float(figures["run_all_max_s"]) == pytest.approx(max(seconds.values()), abs=0.05)
    assert float(figures["run_all_total_s"]) == pytest.approx(sum(seconds.values()), abs=0.1)
    assert figures["all_clean"] == "True"


@pytest.mark.parametrize("name", NAMES)
def test_the_untouched_release_stops_only_at_its_first_exercise(untouched_runs, name):
    run = untouched_runs[name]
    assert too_early(run) is None, too_early(run)


def test_handin_says_what_is_unfinished_in_an_untouched_course(untouched_runs):
    assert untouched_runs["05_odometry"].unfinished == [
        "delta_phi",
        "estimate_pose",
        "WheelPairing",
    ]
    assert (
        untouched_runs["01_getting_started"]
        .summary()
        .startswith(
            "01_getting_started: 0 of 1 visible tests pass (to do: wheel_circumference); "
            "Run All stops at cell 15 (test_wheel_circumference): NotImplementedError"
        )
    )
    assert not any(run.clean for run in untouched_runs.values())


def test_handin_finds_nothing_left_in_a_finished_course(filled_runs):
    assert [run.name for run in filled_runs.values() if run.unfinished or not run.clean] == []


@pytest.mark.parametrize("name", NAMES)
def test_each_notebooks_words_match_what_its_own_runs_print(filled_runs, name):
    # What a figure or a printout is said to show, it shows: in the words of the instructors'
    # notebook and of the release, as a student who finished the course runs it.
    assert claims_broken(filled_runs[name], SOLUTIONS, name) == []
    assert claims_broken(filled_runs[name], COURSE, name) == []
