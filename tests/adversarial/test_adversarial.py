"""Adversarial submissions graded in one class, in parallel, next to a well-behaved student.

For each case of ``cases.py``: the outcome an instructor wants (the points it should keep or
lose, the problem reported), every other student graded normally, and the gradebook intact.
"""

from __future__ import annotations

import csv
import html
import json
import shutil
import sqlite3
from pathlib import Path

import nbformat
import pytest
from cases import ASSIGNMENT, CASES, FULL_MARKS, expected_loss
from pace import seconds

from autograder.bench import filled_notebook
from autograder.course import ROOT
from autograder.grade import grade_class
from autograder.sandbox import Limits

pytestmark = [pytest.mark.slow, pytest.mark.timeout(600)]


def _grade_id(cell) -> str:
    return cell.get("metadata", {}).get("nbgrader", {}).get("grade_id", "")


def build(folder, name, case, paths):
    """Write student ``name``'s submission of ``case`` into ``folder/name``."""
    target = folder / name / ASSIGNMENT
    if case.empty:
        (folder / name).mkdir(parents=True)
        return
    shutil.copytree(ROOT / "course" / ASSIGNMENT, target, ignore=shutil.ignore_patterns("*.ipynb"))
    path = target / f"{ASSIGNMENT}.ipynb"
    for file_name, text in case.files.items():
        (target / file_name).write_text(text, encoding="utf-8")
    if case.link is not None:
        (target / case.link).symlink_to(paths[0])
    if case.raw is not None:
        path.write_text(case.raw, encoding="utf-8")
        return
    if case.blank:
        notebook = nbformat.read(ROOT / "course" / ASSIGNMENT / f"{ASSIGNMENT}.ipynb", 4)
    else:
        notebook = filled_notebook(ASSIGNMENT)
    for cell in notebook.cells:
        if _grade_id(cell) in case.answers:
            cell.source = case.answers[_grade_id(cell)]
    if case.cell is not None:
        code = case.cell.replace("{paths}", repr(paths))
        if case.after is None:
            index = next(i for i, cell in enumerate(notebook.cells) if cell.cell_type == "code")
        else:
            index = next(
                i for i, cell in enumerate(notebook.cells) if _grade_id(cell) == case.after
            )
        notebook.cells.insert(index + 1, nbformat.v4.new_code_cell(code))
    nbformat.write(notebook, path)


@pytest.fixture(scope="module")
def graded(sandbox, tmp_path_factory):
    root = tmp_path_factory.mktemp("adversarial")
    submissions, out = root / "submissions", root / "out"
    # What a submission must not reach: the gradebook and the grader's work, the course
    # source with the hidden tests, another student's submission and sandbox.
    # (The environment is there read-only: /etc, and the library under the repository's path.)
    paths = [
        str(out / "work" / "gradebook.db"),
        str(out / "work"),
        str(ROOT / "solutions"),
        str(ROOT / "course"),
        str(submissions / "reference"),
        str(out / "work" / "sandboxes" / "reference" / ASSIGNMENT),
    ]
    for name, case in CASES.items():
        build(submissions, name, case, paths)
    results = grade_class(
        submissions,
        out,
        jobs=2,
        limits=Limits(cell_seconds=seconds(15), submission_seconds=seconds(90), processes=64),
        names=[ASSIGNMENT],
        driving=False,
    )
    # By folder name as written (a folder nbgrader cannot take as an id is graded under another).
    return {result.shown: result for result in results}, out, paths


def _scores(result):
    return {grade_id: score for (_, grade_id), (score, _) in result.cells.items()}


def _outputs(out, student):
    path = out / "work" / "autograded" / student / ASSIGNMENT / f"{ASSIGNMENT}.ipynb"
    notebook = nbformat.read(path, 4)
    return [
        output
        for cell in notebook.cells
        if cell.cell_type == "code"
        for output in cell.get("outputs", [])
    ]


@pytest.mark.parametrize("name", sorted(CASES))
def test_each_case_keeps_what_it_earned_and_loses_what_it_did_not(graded, name):
    results, _, _ = graded
    result = results[name]
    assert result.max_total == FULL_MARKS, f"{name}: every student is graded out of the same"
    lost = expected_loss(name)
    scores = _scores(result)
    assert set(scores) == set(_scores(results["reference"]))
    for grade_id, score in scores.items():
        wanted_zero = lost == ("*",) or grade_id in lost
        assert (score == 0) if wanted_zero else (score > 0), (name, grade_id, score)


def test_a_well_behaved_student_in_the_same_class_gets_full_marks(graded):
    results, _, _ = graded
    assert results["reference"].total == FULL_MARKS
    assert results["reference"].problems == []


def test_a_folder_name_nbgrader_cannot_take_is_graded_under_an_id_and_shown_as_written(graded):
    results, out, _ = graded
    with (out / "grades.csv").open(newline="") as handle:
        rows = {row["student"]: row for row in csv.DictReader(handle)}
    for name in ("st[1] with\na new line ", "l" * 250):
        result = results[name]
        assert (result.total, result.problems) == (FULL_MARKS, [])
        assert result.student != name
        assert rows[name]["total"] == f"{FULL_MARKS:g}"
        page = (out / "feedback" / f"{result.student}.html").read_text()
        assert f"Feedback for {html.escape(name)}" in page


@pytest.mark.parametrize(
    ("name", "words"),
    [
        ("os_exit", "the kernel died"),
        ("kernel_crash", "the kernel died"),
        ("monkey_patch", "math.isclose"),
        ("malformed", "not a readable notebook"),
        ("empty", "no 03_frames.ipynb"),
        ("sys_exit", "SystemExit"),
        (
            "infinite_loop",
            f"CellTimeoutError: still running after the {seconds(15)} s a cell may take",
        ),
        ("raises_outside_tests", "NameError"),
        ("write_outside", "03_frames: the notebook tried to write outside the student's folders: "),
    ],
)
def test_the_instructor_is_told_what_happened(graded, name, words):
    results, _, _ = graded
    assert any(words in problem for problem in results[name].problems), results[name].problems


def test_a_cell_outside_the_tests_that_raised_is_named_with_its_error(graded):
    results, out, _ = graded
    path = out / "work" / "autograded" / "raises_outside_tests" / ASSIGNMENT / f"{ASSIGNMENT}.ipynb"
    cells = nbformat.read(path, 4).cells
    (stray,) = [i for i, cell in enumerate(cells, 1) if cell.source == "print(undefined_name)\n"]
    (failed,) = [cell for cell in cells if _grade_id(cell) == "test_wrap_angle"]
    assert [o["ename"] for o in failed.outputs if o.output_type == "error"] == ["AssertionError"]
    # One sentence, naming the cell by position and first line, and the error; the failing
    # test cell (which raised too) is a failed test, not this problem.
    wanted = (
        f"{ASSIGNMENT}: 1 cell outside the tests raised: cell {stray} (print(undefined_name)): "
        "NameError: name 'undefined_name' is not defined"
    )
    assert [p for p in results["raises_outside_tests"].problems if "raised" in p] == [wanted]
    with (out / "grades.csv").open() as handle:
        rows = {row["student"]: row for row in csv.DictReader(handle)}
    assert rows["raises_outside_tests"]["problems"] == wanted
    page = (out / "feedback" / "raises_outside_tests.html").read_text()
    assert html.escape(wanted) in page
    # Cells the dead kernel never ran are not reported again as raising.
    for name in ("os_exit", "kernel_crash"):
        assert not [p for p in results[name].problems if "outside the tests" in p], name
    assert rows["reference"]["problems"] == ""
    assert "outside the tests" not in (out / "feedback" / "reference.html").read_text()


def test_the_monkey_patches_were_undone_before_the_tests(graded):
    results, _, _ = graded
    (problem,) = [p for p in results["monkey_patch"].problems if "replaced" in p]
    for name in ("math.isclose", "numpy.allclose", "numpy.testing.assert_allclose", "the name np"):
        assert name in problem
    assert "IPython custom exception handler" in problem


def test_nothing_outside_the_sandbox_can_be_read_or_written(graded):
    _, out, paths = graded
    printed = "".join(
        output.get("text", "")
        for case in ("read_outside", "write_outside", "symlink_out")
        for output in _outputs(out, case)
        if output.get("output_type") == "stream"
    )
    assert printed.count("readable: []") == 2
    assert "written: []" in printed
    for path in [*paths, ROOT, "/etc"]:
        assert not (Path(path) / "pwned.txt").exists(), path


def test_the_network_is_unreachable_and_stderr_is_harmless(graded):
    results, out, _ = graded
    errors = [o for o in _outputs(out, "network") if o.get("output_type") == "error"]
    assert [error["ename"] for error in errors][:1] in (["gaierror"], ["OSError"])
    assert results["stderr"].total == FULL_MARKS
    assert any(o.get("name") == "stderr" for o in _outputs(out, "stderr"))


def test_the_gradebook_is_intact_and_holds_every_grade(graded):
    results, out, _ = graded
    database = out / "work" / "gradebook.db"
    with sqlite3.connect(database) as connection:
        assert connection.execute("PRAGMA integrity_check").fetchone() == ("ok",)
    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{database}") as gradebook:
        graded_students = {
            submission.student.id for submission in gradebook.assignment_submissions(ASSIGNMENT)
        }
        by_id = {result.student: result for result in results.values()}
        for name in graded_students:
            submission = gradebook.find_submission(ASSIGNMENT, name)
            assert submission.score == by_id[name].total, name
    assert graded_students >= {results[name].student for name in CASES if name != "empty"}
    # A problem may span lines (a quoted field): count the CSV's records, not its lines.
    with (out / "grades.csv").open(newline="") as handle:
        students = [row["student"] for row in csv.DictReader(handle)]
    assert sorted(students) == sorted(CASES)
    assert json.loads((out / "skipped.json").read_text()) == []


def test_a_fork_bomb_costs_only_its_own_cell(graded):
    # The bomb's copies of the kernel are killed once its cell is over: the cells after it run
    # in a kernel alone again, with room for their threads. The bomb's own cell ends at the
    # process limit, or at the cell's time limit on a busy machine.
    results, _, _ = graded
    (problem,) = results["fork_bomb"].problems
    alone = "03_frames: 1 cell outside the tests raised: cell 3 (import os): "
    assert problem.startswith(alone)
    assert problem[len(alone) :].startswith(("BlockingIOError: ", "CellTimeoutError: ")), problem


def test_code_that_turns_the_tests_off_in_its_kernel_changes_nothing(graded):
    # AST and input transformers, a startup file, a forged reply: the tests do not run in the
    # kernel, and the server's pipes and memory are out of the kernel's reach.
    results, out, _ = graded
    assert results["tests_turned_off"].total == 0
    printed = "".join(o.get("text", "") for o in _outputs(out, "tests_turned_off"))
    assert "opened: []" in printed


def test_no_hidden_test_reaches_the_student_or_the_problems(graded):
    results, out, _ = graded
    source = nbformat.read(ROOT / "solutions" / ASSIGNMENT / f"{ASSIGNMENT}.ipynb", 4)
    hidden = [
        line.strip()
        for cell in source.cells
        if _grade_id(cell).startswith("test_") and "### BEGIN HIDDEN TESTS" in cell.source
        for line in cell.source.split("### BEGIN HIDDEN TESTS")[1].splitlines()
        if len(line.strip()) > 25
    ]
    assert len(hidden) > 20
    said = [
        " ".join(results[name].problems)
        + " ".join(results[name].messages.values())
        + (out / "feedback" / f"{name}.html").read_text()
        for name in ("reads_history", "peeking", "tests_turned_off")
    ]
    said.append((out / "grades.csv").read_text())
    leaked = [line for line in hidden for text in said if line in text or html.escape(line) in text]
    assert not leaked
    # The history the student's code could read held no test.
    assert any("RuntimeError" in problem for problem in results["reads_history"].problems)
    assert results["reads_history"].total == FULL_MARKS


def test_busy_loops_left_running_are_stopped_and_said(graded):
    results, _, _ = graded
    result = results["busy_loops"]
    assert result.total == FULL_MARKS
    assert result.problems == [
        "03_frames: the notebook left 8 processes running after its last cell; the grader "
        "stopped them"
    ]
