"""``duckie handin``: notebooks run as Run All runs them, what raised, and the zip to hand in."""

from __future__ import annotations

import shutil
import zipfile

import nbformat
import pytest
from pace import seconds

from autograder.course import ROOT, assignments
from autograder.grade import find_submissions, read_submission
from duckielib.tools.cli import main
from duckielib.tools.handin import (
    CourseCheck,
    HandinError,
    check_course,
    handin,
    run_notebook,
)

pytestmark = pytest.mark.notebook


def graded(cell, grade_id, *, test):
    """Mark a cell as nbgrader marks an exercise or a test cell."""
    cell.metadata["nbgrader"] = {
        "grade_id": grade_id,
        "grade": test,
        "solution": not test,
        "locked": test,
        "points": 1 if test else 0,
        "schema_version": 3,
    }
    return cell


def answer(text, grade_id, points):
    """A markdown cell as nbgrader marks an answer in words, graded by a person."""
    cell = nbformat.v4.new_markdown_cell(text)
    cell.metadata["nbgrader"] = {
        "grade_id": grade_id,
        "grade": True,
        "solution": True,
        "locked": False,
        "points": points,
        "schema_version": 3,
    }
    return cell


def write_notebook(path, cells):
    notebook = nbformat.v4.new_notebook()
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3"}
    notebook.cells = cells
    path.parent.mkdir(parents=True, exist_ok=True)
    nbformat.write(notebook, path)
    return path


def test_a_run_notes_every_cell_that_raised_and_each_tests_result(tmp_path, capfd):
    code = nbformat.v4.new_code_cell
    path = write_notebook(
        tmp_path / "05_odometry" / "05_odometry.ipynb",
        [
            nbformat.v4.new_markdown_cell("# Odometry"),
            code("import math"),
            graded(code("def double(x):\n    raise NotImplementedError()"), "double", test=False),
            graded(
                code("assert double(2) == 4, 'double(2) should be 4'"), "test_double", test=True
            ),
            code("# a demo\nprint(double(3))"),
            graded(code("assert math.pi > 3"), "test_pi", test=True),
            code("print(undefined_name)"),
            answer("YOUR ANSWER HERE", "answer_speed", 2),
            answer("0.2 m/s: faster and the robot overshoots its turns.", "answer_why", 2),
            answer("  \n", "answer_exit", 1),
            nbformat.v4.new_markdown_cell("YOUR ANSWER HERE"),  # not graded: not an answer
        ],
    )
    run = run_notebook(path)
    # The kernel's connection is encrypted: it has no warning to print on the terminal.
    assert "without encryption" not in "".join(capfd.readouterr())
    assert [(cell.number, cell.kind, cell.grade_id) for cell in run.raised] == [
        (4, "test", "test_double"),
        (5, "code", None),
        (7, "code", None),
    ]
    assert run.raised[1].first_line == "print(double(3))"
    assert run.raised[2].error == "NameError: name 'undefined_name' is not defined"
    assert run.stops_at.describe() == "cell 4 (test_double): NotImplementedError"
    assert run.tests == {"test_double": False, "test_pi": True}
    assert run.exercises == {"double": 3}
    assert run.unfinished == ["double"]
    assert not run.clean
    assert run.summary().startswith(
        "05_odometry: 1 of 2 visible tests pass (to do: double); Run All stops at cell 4"
    )
    # The answers in words still as released (or empty), with their points, in order.
    assert run.answers_left == {"answer_speed": 2, "answer_exit": 1}
    assert CourseCheck(tmp_path, [run]).report().splitlines()[-1] == (
        "Written answers left (3 points): 05_odometry answer_speed (2 points), 05_odometry "
        "answer_exit (1 point). Write each in its YOUR ANSWER HERE cell (double-click it), "
        "save, and hand in again."
    )
    # The notebook's file is left as it was: nothing ran in it.
    assert all(c.get("outputs", []) == [] for c in nbformat.read(path, 4).cells if "outputs" in c)


def test_a_figure_shown_as_text_instead_of_a_picture_is_noted(tmp_path):
    # A matplotlib Figure made without pyplot, before pyplot has drawn anything, shows as text.
    path = write_notebook(
        tmp_path / "figures.ipynb",
        [
            nbformat.v4.new_code_cell("from matplotlib.figure import Figure\nFigure()"),
            nbformat.v4.new_code_cell(
                "from duckielib.plots import plot_mission_states\n"
                "from duckielib.missions import SQUARE_THEN_CIRCLE\n"
                "plot_mission_states(SQUARE_THEN_CIRCLE).figure"
            ),
        ],
    )
    assert run_notebook(path).figures_as_text == [1]


def test_a_cell_that_never_ends_is_interrupted_and_the_run_goes_on(tmp_path):
    path = write_notebook(
        tmp_path / "loop.ipynb",
        [
            nbformat.v4.new_code_cell("while True:\n    pass"),
            nbformat.v4.new_code_cell("print('after')"),
        ],
    )
    run = run_notebook(path, cell_seconds=seconds(3))
    assert [cell.error for cell in run.raised] == [
        f"CellTimeoutError: still running after the {seconds(3)} s a cell may take"
    ]
    assert run.stopped is None


def test_a_kernel_that_dies_ends_the_run_with_a_sentence(tmp_path):
    path = write_notebook(
        tmp_path / "crash.ipynb",
        [nbformat.v4.new_code_cell("import os\nos._exit(1)"), nbformat.v4.new_code_cell("1")],
    )
    run = run_notebook(path)
    assert run.stopped.startswith("the kernel died")
    assert not run.clean
    assert "the kernel died" in run.summary()


@pytest.mark.slow
def test_duckie_handin_checks_each_notebook_and_zips_them_for_duckie_grade(tmp_path, capsys):
    course = tmp_path / "course"
    for name in ("01_getting_started", "03_frames"):
        shutil.copytree(ROOT / "solutions" / name, course / name)  # finished: the reference
    shutil.copytree(ROOT / "course" / "04_kinematics", course / "04_kinematics")  # untouched
    (course / "01_getting_started" / "notes.txt").write_text("not handed in")
    assert main(["handin", str(course), "-o", str(tmp_path / "ada.zip")]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == (
        "Running your 3 notebooks from top to bottom as saved, as grading does (about 1 minute)..."
    )
    assert out[1].startswith("01_getting_started: 1 of 1 visible tests pass; Run All runs to")
    assert out[2].startswith("03_frames: 4 of 4 visible tests pass; Run All runs to the end")
    assert out[3].startswith(
        "04_kinematics: 0 of 3 visible tests pass (to do: forward_kinematics, "
        "inverse_kinematics, duty_cycles); Run All stops at cell 10 (test_forward_kinematics)"
    )
    assert out[4].startswith("Unfinished or not running to the end: 04_kinematics.")
    assert out[5] == f"Wrote {tmp_path / 'ada.zip'} (3 notebooks): hand in this file."
    with zipfile.ZipFile(tmp_path / "ada.zip") as archive:
        assert sorted(archive.namelist()) == [
            "01_getting_started/01_getting_started.ipynb",
            "03_frames/03_frames.ipynb",
            "04_kinematics/04_kinematics.ipynb",
        ]
    # The grader takes the zip as one student, named after it, with the three assignments.
    submissions = tmp_path / "submissions"
    submissions.mkdir()
    shutil.copy(tmp_path / "ada.zip", submissions)
    found, skipped = find_submissions(submissions)
    assert skipped == []
    collected = read_submission(found["ada"], assignments(ROOT / "course"))
    assert collected.left_out == []
    assert sorted({name.split("/")[0] for name in collected.files}) == [
        "01_getting_started",
        "03_frames",
        "04_kinematics",
    ]
    assert not list(course.rglob("*.bag")), "the check ran in a copy, not in the course"


def test_duckie_handin_names_the_written_answers_left_and_prints_no_kernel_warning(tmp_path, capfd):
    # Every check can pass while answers in words still read YOUR ANSWER HERE: points lost.
    path = write_notebook(
        tmp_path / "course" / "06_driving" / "06_driving.ipynb",
        [
            nbformat.v4.new_code_cell("speed = 0.2"),
            answer("YOUR ANSWER HERE", "answer_speed", 2),
            answer("The wheels stop: the node sends (0, 0) before it returns.", "answer_exit", 2),
        ],
    )
    assert main(["handin", str(path.parent.parent), "-o", str(tmp_path / "ada.zip")]) == 0
    out, err = capfd.readouterr()  # the kernels' own output too, not only the command's
    lines = out.splitlines()
    assert lines[0].endswith("(about 1 minute)...")
    assert lines[1].startswith("06_driving: no graded test; Run All runs to the end (")
    assert lines[2:] == [
        "Every notebook runs from top to bottom and passes its visible tests.",
        "Written answers left (2 points): 06_driving answer_speed (2 points). Write each in its "
        "YOUR ANSWER HERE cell (double-click it), save, and hand in again.",
        f"Wrote {tmp_path / 'ada.zip'} (1 notebook): hand in this file.",
    ]
    assert "without encryption" not in out + err
    assert err == ""


def test_handin_refuses_what_it_cannot_do_in_one_sentence(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    for argv, text in (
        (["handin", str(tmp_path / "nowhere"), "-o", "ada.zip"], "There is no folder"),
        (["handin", str(tmp_path / "empty"), "-o", "ada.zip"], "holds no course notebook"),
        (["handin", str(tmp_path / "empty"), "-o", "ada.tar"], "must end in .zip"),
        (["handin", str(tmp_path), "-o", str(tmp_path / "no" / "ada.zip")], "There is no folder"),
        (["handin"], "Say where to write the zip with -o NAME.zip"),
        (["handin", "-o", "ada.zip", "--submit", "05_odometry"], "either --submit"),
        (["handin", str(tmp_path), "--submit", "05_odometry"], "fetch the assignment first"),
    ):
        assert main(argv) == 1
        err = capsys.readouterr().err
        assert err.startswith("duckie: ")
        assert text in err
        assert err.count("\n") == 1
    with pytest.raises(HandinError, match="has no notebook 99_extra"):
        check_course(ROOT / "course", names=["99_extra"])
    write_notebook(tmp_path / "c" / "01_x" / "01_x.ipynb", [])
    with pytest.raises(HandinError, match="outside"):
        handin(tmp_path / "c", tmp_path / "c" / "ada.zip")


def test_submitting_off_a_hub_says_so_after_checking_the_notebook(tmp_path, capsys, monkeypatch):
    # No exchange here: nbgrader's own refusal, in a sentence that says where submitting works.
    course = tmp_path / "home"
    shutil.copytree(ROOT / "course" / "01_getting_started", course / "01_getting_started")
    monkeypatch.setenv("JUPYTER_CONFIG_DIR", str(tmp_path / "jupyter"))
    (tmp_path / "jupyter").mkdir()
    (tmp_path / "jupyter" / "nbgrader_config.py").write_text(
        f"c = get_config()\nc.Exchange.root = {str(tmp_path / 'no-exchange')!r}\n"
    )
    assert main(["handin", str(course), "--submit", "01_getting_started"]) == 1
    out, err = capsys.readouterr()
    assert "01_getting_started: " in out  # the check ran first, as grading runs it
    assert err.startswith("duckie: 01_getting_started could not be submitted: ")
    assert "elsewhere, hand in a zip with duckie handin -o NAME.zip" in err
