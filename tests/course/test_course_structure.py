"""Gates on the course's files: a fresh release, no leaks, well-formed grade cells, the contract."""

from __future__ import annotations

import ast
import re

import pytest
from coursetools import (
    COURSE,
    HIDDEN_REGION,
    NAMES,
    SOLUTION_REGION,
    SOLUTIONS,
    answer_cells,
    checking_cells,
    graded_cells,
    load,
    load_solution_nb,
    nbgrader,
    notebook_path,
    source,
)

from autograder.course import compare_release
from duckielib.solution import CONTRACT, EXPORT_TAG, export_solution, load_solution

EXPECTED = ["01_getting_started", "02_ros_concepts", "03_frames", "04_kinematics", "05_odometry"]


def test_the_course_has_its_notebooks_in_order():
    assert NAMES[: len(EXPECTED)] == EXPECTED


def test_course_is_byte_identical_to_a_fresh_release():
    assert compare_release() == [], "run 'duckie release' and commit course/"


def test_course_holds_only_the_student_notebooks():
    files = sorted(p.relative_to(COURSE).as_posix() for p in COURSE.rglob("*") if p.is_file())
    assert files == [f"{name}/{name}.ipynb" for name in NAMES]


def test_no_solution_line_or_hidden_test_reaches_the_course():
    released = "\n".join(
        path.read_text(encoding="utf-8") for path in COURSE.rglob("*") if path.is_file()
    )
    released_lines = {
        line.strip()
        for path in COURSE.rglob("*.ipynb")
        for cell in load(path)["cells"]
        for line in source(cell).splitlines()
    }
    public, secret = set(), {}
    for name in NAMES:
        for cell in load_solution_nb(name)["cells"]:
            text = source(cell)
            regions = SOLUTION_REGION.findall(text) + HIDDEN_REGION.findall(text)
            for region in regions:
                for line in region.splitlines():
                    secret.setdefault(line.strip(), name)
            outside = SOLUTION_REGION.sub("", HIDDEN_REGION.sub("", text))
            public |= {line.strip() for line in outside.splitlines()}
    # Lines the course shows anyway, and bare syntax ("pass", "]", "else:"), give nothing away.
    leaks = [
        f"{name}: {line}"
        for line, name in sorted(secret.items())
        if line not in public and len(line.replace(" ", "")) >= 8 and line in released_lines
    ]
    assert not leaks, "solution or hidden-test lines in course/:\n" + "\n".join(leaks)
    assert "BEGIN HIDDEN TESTS" not in released
    assert "BEGIN SOLUTION" not in released


@pytest.mark.parametrize("name", NAMES)
def test_source_notebooks_are_clean(name):
    notebook = load_solution_nb(name)
    assert notebook["metadata"]["kernelspec"]["name"] == "python3"
    for cell in notebook["cells"]:
        if cell["cell_type"] == "code":
            assert cell["outputs"] == [], f"{name}: outputs must be stripped"
            assert cell["execution_count"] is None
            assert "sys.path" not in source(cell)


@pytest.mark.parametrize("name", NAMES)
def test_grade_cells_have_points_ids_and_tests(name):
    notebook = load_solution_nb(name)
    ids = [nbgrader(cell)["grade_id"] for cell in notebook["cells"] if nbgrader(cell)]
    assert len(ids) == len(set(ids)), f"{name}: duplicate grade ids"
    tests = checking_cells(notebook)
    for grade_id, cell in tests.items():
        assert nbgrader(cell)["points"] > 0, f"{name}: {grade_id} has no points"
        assert nbgrader(cell)["locked"], f"{name}: {grade_id} must be locked"
    for grade_id, cell in graded_cells(notebook).items():
        assert f"test_{grade_id}" in tests, f"{name}: {grade_id} has no test cell"
        text = source(cell)
        assert SOLUTION_REGION.search(text), f"{name}: {grade_id} has no solution region"
        assert HIDDEN_REGION.search(source(tests[f"test_{grade_id}"])), (
            f"{name}: test_{grade_id} has no hidden tests"
        )


#: Every question of the exercise (spec: "Questions every student must be able to answer", and
#: the bag analysis) and the answer cell that collects it, graded by a person.
EXERCISE_ANSWERS = {
    "which topic moves the robot, and how did you find it": (
        "02_ros_concepts",
        "answer_find_topic",
    ),
    "how did you track the angle travelled": ("06_driving", "answer_angle"),
    "which speed, and what happens when you raise or lower it": ("06_driving", "answer_speed"),
    "why do the actual and the desired location differ": ("06_driving", "answer_differ"),
    "does the program exit properly when done": ("06_driving", "answer_exit"),
    "the task's time, and the final pose by odometry against the truth": (
        "09_mission",
        "answer_final_pose",
    ),
    "the final location per odometry, and how close to the real one": (
        "10_bag_analysis",
        "answer_bag_final",
    ),
    "theta over time: where does it wrap at 2 pi, and why": (
        "10_bag_analysis",
        "answer_theta_wrap",
    ),
}
RUBRIC = re.compile(r"^\*\*Rubric \((\d+(?:\.\d+)?) points?\)\.\*\* \S")


def test_every_question_of_the_exercise_has_an_answer_cell():
    for question, (name, grade_id) in EXERCISE_ANSWERS.items():
        assert grade_id in answer_cells(load_solution_nb(name)), (
            f"{name} has no answer cell {grade_id} for the question: {question}"
        )


@pytest.mark.parametrize("name", NAMES)
def test_answer_cells_hold_a_rubric_that_never_reaches_the_course(name):
    released = load(notebook_path(COURSE, name))["cells"]
    by_id = {nbgrader(cell).get("grade_id"): cell for cell in released if nbgrader(cell)}
    cells = load_solution_nb(name)["cells"]
    for index, cell in enumerate(cells):
        if cell not in answer_cells(load_solution_nb(name)).values():
            continue
        grade_id, points = nbgrader(cell)["grade_id"], nbgrader(cell)["points"]
        assert cell["cell_type"] == "markdown", f"{name}: {grade_id} must be a markdown cell"
        assert not nbgrader(cell)["locked"], f"{name}: students must be able to write {grade_id}"
        region = SOLUTION_REGION.fullmatch(source(cell).strip())
        assert region, f"{name}: {grade_id} must hold only its rubric, in a solution region"
        rubric = RUBRIC.match(region.group(1))
        assert rubric, f"{name}: {grade_id}'s rubric must start **Rubric (N points).**"
        assert float(rubric.group(1)) == points, f"{name}: {grade_id} gives {points} points"
        assert cells[index - 1]["cell_type"] == "markdown", f"{name}: ask before {grade_id}"
        assert source(by_id[grade_id]) == "YOUR ANSWER HERE", f"{name}: {grade_id} in course/"


def test_all_grade_ids_are_unique_across_the_course():
    ids = [
        nbgrader(cell)["grade_id"]
        for name in NAMES
        for cell in load_solution_nb(name)["cells"]
        if nbgrader(cell)
    ]
    assert len(ids) == len(set(ids))


def test_every_contract_part_is_an_exported_graded_cell_of_its_notebook():
    for part in CONTRACT.values():
        if part.notebook not in NAMES:
            continue
        cells = graded_cells(load_solution_nb(part.notebook))
        assert part.name in cells, f"{part.notebook} grades no cell {part.name}"
        assert EXPORT_TAG in cells[part.name]["metadata"].get("tags", []), part.name
        tree = ast.parse(source(cells[part.name]))
        defined = [node.name for node in tree.body if hasattr(node, "name")]
        assert part.name in defined


def test_exported_cells_import_only_what_the_robot_has():
    allowed = re.compile(
        r"^(import (math|os|rospy)|import numpy as np|from typing import .*"
        r"|from (duckietown_msgs\.(msg|srv)|std_msgs\.msg|duckielib\.missions) import .*)$"
    )
    for name in NAMES:
        for cell in load_solution_nb(name)["cells"]:
            if EXPORT_TAG not in cell["metadata"].get("tags", []):
                continue
            for line in source(cell).splitlines():
                if line.startswith(("import ", "from ")):
                    assert allowed.match(line), f"{name}: exported cell imports {line!r}"


def test_the_reference_solution_is_complete_and_the_release_is_not():
    reference = export_solution(SOLUTIONS)
    assert reference.complete, reference.report()
    module = load_solution(required=list(CONTRACT))
    assert module.wrap_angle(-0.5) == pytest.approx(2 * 3.141592653589793 - 0.5)
    released = export_solution(COURSE)
    assert released.missing == [p for p in CONTRACT if CONTRACT[p].notebook not in NAMES]
    assert released.unfinished == [p for p in CONTRACT if CONTRACT[p].notebook in NAMES]
    assert (
        "Finish notebook 05_odometry: write delta_phi, estimate_pose, WheelPairing."
        in released.report()
    )


def test_released_graded_cells_keep_signature_and_docstring():
    for name in NAMES:
        solution_cells = graded_cells(load_solution_nb(name))
        released = graded_cells(load(notebook_path(COURSE, name)))
        assert set(released) == set(solution_cells)
        for grade_id, cell in released.items():
            text = source(cell)
            assert "raise NotImplementedError()" in text, f"{name}: {grade_id}"
            before = SOLUTION_REGION.split(source(solution_cells[grade_id]))[0]
            assert text.startswith(before), f"{name}: {grade_id} lost its signature"


def test_a_stale_release_is_named_file_by_file(tmp_path):
    import shutil

    stale = tmp_path / "course"
    shutil.copytree(COURSE, stale)
    first = notebook_path(stale, NAMES[0])
    first.write_text(first.read_text(encoding="utf-8").replace("Duckiebot", "Duckybot", 1))
    (stale / "notes.txt").write_text("mine")
    shutil.rmtree(stale / NAMES[-1])
    differences = compare_release(stale)
    assert differences == [
        f"{NAMES[0]}/{NAMES[0]}.ipynb differs from a fresh release.",
        f"{NAMES[-1]}/{NAMES[-1]}.ipynb is missing from course/.",
        "notes.txt is in course/ but not in a fresh release.",
    ]


def test_duckie_release_check_passes_on_the_committed_course():
    import subprocess
    import sys

    result = subprocess.run(
        [sys.executable, "-m", "duckielib.tools.cli", "release", "--check"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "identical to a fresh release" in result.stdout


THINK = "**Think about it** (nothing to write, not graded):"
QUESTION = re.compile(r"^\*\*Question:\*\*", re.M)
SECTION = re.compile(r"^#{1,3} ", re.M)


@pytest.mark.parametrize("name", NAMES)
def test_every_question_has_an_answer_cell_or_says_it_is_for_thinking_only(name):
    # A student must never wonder where, or whether, to write an answer: a **Question:** has its
    # answer cell before the next question or section; a prompt with none says so.
    cells = load_solution_nb(name)["cells"]
    answers = list(answer_cells(load_solution_nb(name)).values())
    for index, cell in enumerate(cells):
        text = source(cell)
        if cell["cell_type"] != "markdown" or cell in answers:
            continue
        if QUESTION.search(text):
            after = []
            for later in cells[index + 1 :]:
                ends = QUESTION.search(source(later)) or SECTION.search(source(later))
                if ends and later["cell_type"] == "markdown" and later not in answers:
                    break
                after.append(later)
            assert any(later in answers for later in after), (
                f"{name}, cell {index + 1}: a **Question:** with no answer cell under it; give it "
                f"one, or make it a prompt to think about: {THINK}"
            )
        assert "**Think about it**" not in text or THINK in text, (
            f"{name}, cell {index + 1}: a prompt to think about starts: {THINK}"
        )
        assert "in a markdown cell below" not in text, f"{name}, cell {index + 1}: which cell?"


@pytest.mark.parametrize("folder", [SOLUTIONS, COURSE], ids=["solutions", "course"])
def test_no_given_code_cell_is_longer_than_the_limit(folder):
    # Given code shows the experiment; its plumbing belongs in the library, behind a name.
    from notebook_sizes import CELL_LINES, sizes

    found = sizes(folder)
    assert [size.name for size in found] == NAMES
    over = [f"{size.name}, cell {number}: {count} lines" for size in found
            for number, count in size.over()]  # fmt: skip
    assert over == [], f"given code cells over {CELL_LINES} lines:\n" + "\n".join(over)
