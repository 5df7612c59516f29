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
    (folder / name).mkdir(parents=True)
    for file_name, text in case.top_files.items():
        (folder / name / file_name).write_text(text, encoding="utf-8")
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
        # The grader's process for a student: its course (the hidden tests), its gradebook, its
        # result, as that process sees them.
        "/unit/course/source",
        "/unit/course/gradebook.db",
        "/unit/nbgrader/gradebook.db",
        "/unit/out",
        "/unit/task.json",
    ]
    for name, case in CASES.items():
        build(submissions, name, case, paths)
    limits = Limits(
        cell_seconds=seconds(15),
        submission_seconds=seconds(90),
        processes=64,
        disk_bytes=256 * 1024**2,
        slow_cell_seconds=8,
    )
    # Started beside submissions/, as the README's command is.
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(root)
        results = grade_class(
            submissions, out, jobs=3, limits=limits, names=[ASSIGNMENT], driving=False
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
    message = results["monkey_patch"].messages[(ASSIGNMENT, "test_world_from_robot")]
    assert "uses get_ipython(): the grader cannot read what that defines" in message
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
    # The bomb's cell may also be named as slow (it ends at the process limit, or its time).
    (problem,) = [p for p in results["fork_bomb"].problems if "took over" not in p]
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


def test_no_line_of_the_submission_runs_in_the_grader(graded):
    # The grader built the tests' namespace from the course alone: the module beside the
    # notebooks, imported by a cell, ran only in the sandbox (where it is not even there).
    results, out, _ = graded
    result = results["imports_beside"]
    assert result.total == 0
    assert not list(out.parent.rglob("TAKEN_OVER"))
    (raised,) = [problem for problem in result.problems if "outside the tests raised" in problem]
    assert "ModuleNotFoundError: No module named 'take_over'" in raised


def test_names_the_tests_read_stay_the_graders(graded):
    # math and abs rebound in the kernel change nothing of the tests' own math and abs: the
    # junk answers fail (test_each_case_... holds which), the others keep their points.
    results, _, _ = graded
    result = results["rebinds_names"]
    assert result.total == FULL_MARKS - 4
    # The kernel's own math is put back before the hidden tests call the student's code.
    assert any("replaced the name math" in problem for problem in result.problems)


def test_a_student_who_fills_the_disk_fills_only_their_own(graded):
    results, out, _ = graded
    result = results["fills_the_disk"]
    assert result.total == FULL_MARKS
    assert result.complete
    printed = "".join(o.get("text", "") for o in _outputs(out, "fills_the_disk"))
    assert printed.count("No space left on device") == 2, printed
    assert "The notebooks filled the 268 MB the grader gives a student's files" in " ".join(
        result.problems
    )
    assert results["reference"].problems == []


def test_an_answer_too_long_fails_its_test_and_leaves_the_graders_memory_alone(graded):
    results, _, _ = graded
    result = results["answers_48mb"]
    message = result.messages[(ASSIGNMENT, "test_wrap_angle")]
    assert "48.0 MB of data" in message, message
    assert "at most 4.2 MB" in message, message
    assert result.complete
    # Its other tests keep their points (the notebook's own cells that use the answer may fail).
    assert result.total == FULL_MARKS - 2
    grown = result.timings["grader_memory_mb"] - results["reference"].timings["grader_memory_mb"]
    assert grown < 100, grown


def test_a_hidden_input_never_comes_back_in_a_later_cell(graded):
    # The student's wrap_angle keeps every angle it is given; the last cell raises with them,
    # and the answer tried to leave each one in a path the grader notes. The hidden tests ran
    # after that cell: only the visible tests' inputs could come back.
    results, out, _ = graded
    result = results["records_its_inputs"]
    assert result.total == FULL_MARKS
    said = " ".join(result.problems)
    for visible in ("0.5", "3.0", "-1.0", "7.283185307179586"):
        assert visible in said, said
    assert "/etc/seen-0.5" in said
    page = (out / "feedback" / "records_its_inputs.html").read_text()
    table = (out / "grades.csv").read_text()
    for hidden in ("100.0", "1000000.0", "44.23318530717959", "1e-300", "-1e-17", "6282.18"):
        for text in (said, page, table):
            assert hidden not in text, hidden


def test_slow_cells_are_named(graded):
    results, _, _ = graded
    (slow,) = [p for p in results["sleeps"].problems if "took over" in p]
    assert slow.startswith("03_frames: 1 cell took over 8 s: cell ")
    assert "(import time): 9 s." in slow
    assert results["sleeps"].total == FULL_MARKS


def test_an_answer_a_library_call_does_fails_with_the_notebooks_rule(graded):
    results, out, _ = graded
    result = results["library_answers"]
    messages = result.messages
    assert messages[(ASSIGNMENT, "test_rotation_matrix")] == (
        "rotation_matrix uses tf.transformations.euler_matrix, which would do this exercise for "
        "you: build the matrix with math.cos and math.sin (notebook 03 says so above the "
        "exercise)."
    )
    assert (
        "matplotlib.transforms.Affine2D (through _moved)"
        in messages[(ASSIGNMENT, "test_world_from_robot")]
    )
    page = (out / "feedback" / "library_answers.html").read_text()
    assert "tf.transformations.euler_matrix" in page


def test_the_graders_process_for_a_student_is_out_of_the_students_reach(graded):
    # A forged result is written nowhere the grader reads; the code kills what it can (its
    # own sandbox's processes, not the grader's: the student is graded and said); no user
    # namespace can be made in the sandbox.
    results, out, _ = graded
    forged = results["forges_a_result"]
    printed = "".join(o.get("text", "") for o in _outputs(out, "forges_a_result"))
    assert "written: [" in printed
    assert "/unit/out" not in printed.split("written:")[1]
    assert forged.total == 0
    assert forged.complete
    killed = results["kills_everything"]
    assert killed.complete
    assert killed.total == 0
    assert not [p for p in killed.problems if p.startswith("Not graded")]
    assert any("03_frames: the notebook" in p for p in killed.problems), killed.problems
    printed = "".join(o.get("text", "") for o in _outputs(out, "makes_a_namespace"))
    assert "unshare: -1" in printed, printed
    assert results["makes_a_namespace"].total == FULL_MARKS
    assert results["reference"].total == FULL_MARKS


def test_a_kernel_that_dies_after_the_last_test_keeps_every_point(graded):
    # The visible parts ran where the notebook reached them; the hidden parts, after its last
    # cell, ran whole in a new kernel that ran the cells before the one the kernel died in.
    results, _, _ = graded
    result = results["dies_at_the_end"]
    assert result.total == FULL_MARKS
    assert any("the kernel died" in problem for problem in result.problems)
