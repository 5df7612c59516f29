"""The grading benchmark: a filled course, the full-marks check, and a small run of the bench."""

from __future__ import annotations

import json
import re

import pytest

from autograder.bench import check_full_marks, filled_course, reference_answers, run
from autograder.course import ROOT, CourseError

FIGURES = [
    "submissions",
    "notebooks_per_submission",
    "nbgrader_sequential_s_per_submission",
    "grade_jobs1_s_per_submission",
    "jobs1_unit_s_per_submission",
    "jobs1_notebooks_s_per_submission",
    "jobs1_cells_s_per_submission",
    "jobs1_nbgrader_s_per_submission",
    "grade_jobs2_s_per_submission",
    "grade_cluster2_s_per_submission",
    "all_full_marks",
    "grade_cluster2_speedup_vs_nbgrader",
    "grade_speedup_vs_nbgrader",
]


def _answer_cells(path):
    """The cells of a notebook that carry a grade_id: ``grade_id -> source``."""
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    return {
        cell["metadata"]["nbgrader"]["grade_id"]: "".join(cell["source"])
        for cell in cells
        if cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")
    }


def test_a_filled_course_holds_the_reference_code_without_markers(tmp_path):
    folder = filled_course(tmp_path / "student")
    answers = reference_answers()
    filled = _answer_cells(folder / "03_frames" / "03_frames.ipynb")
    released = _answer_cells(ROOT / "course" / "03_frames" / "03_frames.ipynb")
    assert "raise NotImplementedError()" in released["wrap_angle"]
    assert "def wrap_angle(theta):" in filled["wrap_angle"]
    assert "NotImplementedError" not in filled["wrap_angle"]
    assert "### BEGIN SOLUTION" not in filled["wrap_angle"]
    ours = {grade_id: text for (name, grade_id), text in answers.items() if name == "03_frames"}
    assert ours
    assert {grade_id: filled[grade_id] for grade_id in ours} == ours
    assert {grade_id for grade_id in filled if grade_id.startswith("test_")} == {
        grade_id for grade_id in released if grade_id.startswith("test_")
    }
    assert sorted(path.name for path in folder.iterdir()) == sorted(
        path.name for path in (ROOT / "course").iterdir()
    )


def test_the_full_marks_check_names_the_student_and_the_cell():
    expected = {("03_frames", "test_wrap_angle"), ("03_frames", "test_rotation_matrix")}
    full = dict.fromkeys(expected, (2.0, 2.0))
    check_full_marks("nbgrader", "student_1", full, expected)
    short = {**full, ("03_frames", "test_wrap_angle"): (0.0, 2.0)}
    with pytest.raises(CourseError, match="nbgrader gave student_1 0 of 2 in 03_frames test_wrap"):
        check_full_marks("nbgrader", "student_1", short, expected)
    both = dict.fromkeys(expected, (1.0, 2.0))
    with pytest.raises(CourseError, match=r"1 of 2 in 03_frames test_rotation_matrix \(and 1 more"):
        check_full_marks("nbgrader", "student_1", both, expected)
    missing = {("03_frames", "test_rotation_matrix"): (2.0, 2.0)}
    with pytest.raises(CourseError, match=r"no score for 03_frames test_wrap_angle, where every"):
        check_full_marks("grade_class with 2 jobs", "student_2", missing, expected)
    with pytest.raises(CourseError, match="problems grading student_3: 03_frames: stopped"):
        check_full_marks("grade", "student_3", full, expected, ["03_frames: stopped after 600 s"])


@pytest.mark.slow
@pytest.mark.notebook
@pytest.mark.timeout(600)
def test_the_bench_grades_one_copy_of_one_assignment_four_ways(sandbox):
    figures = run(names=["03_frames"], copies=1)
    assert [name for name, _ in figures] == FIGURES
    values = dict(figures)
    assert values["submissions"] == "1"
    assert values["notebooks_per_submission"] == "1"
    assert values["all_full_marks"] == "yes"
    timed = [name for name in FIGURES if name.endswith(("_s_per_submission", "_vs_nbgrader"))]
    for name in timed:
        assert re.fullmatch(r"\d+\.\d+", values[name]), (name, values[name])
        assert float(values[name]) > 0, name
    # The unit's parts fit in the unit; its cells run inside its notebooks' runs.
    unit, notebooks, cells, nbgrader = (
        float(values[f"jobs1_{part}_s_per_submission"])
        for part in ("unit", "notebooks", "cells", "nbgrader")
    )
    assert cells <= notebooks <= unit
    assert notebooks + nbgrader <= unit + 0.2
    assert figures[-1][0] == "grade_speedup_vs_nbgrader"
