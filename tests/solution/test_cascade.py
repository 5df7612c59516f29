"""Cascades: which graded functions each test builds on, and the sentence that says so first."""

from __future__ import annotations

import inspect
import json
import os
from pathlib import Path
from typing import List, Optional, Tuple

import pytest

from autograder.course import ROOT
from duckielib.solution import MISSION_PARTS, ODOMETRY_PARTS, load_solution
from duckielib.solution.cascade import Dependencies, Function

DELTA_PHI = Function("05_odometry", "delta_phi")
WHEEL_PAIRING = Function("05_odometry", "WheelPairing")
ANGLE_ERROR = Function("06_driving", "angle_error")
ANGLE_TRACKER = Function("06_driving", "AngleTracker")
MISSION_NODE = Function("09_mission", "mission_node")

TEST_DELTA_PHI = ("05_odometry", "test_delta_phi")
TEST_WHEEL_PAIRING = ("05_odometry", "test_WheelPairing")
TEST_ANGLE_ERROR = ("06_driving", "test_angle_error")
TEST_ANGLE_TRACKER = ("06_driving", "test_AngleTracker")
TEST_ERROR_PARTS = ("06_driving", "test_error_parts")
TEST_MISSION_NODE = ("09_mission", "test_mission_node")
TEST_MISSION_CLOSURE = ("09_mission", "test_mission_closure")

#: What notebook 09's mission tests build on besides mission_node: the mission's parts.
MISSION_FUNCTIONS = {
    Function("05_odometry", "delta_phi"),
    Function("05_odometry", "estimate_pose"),
    Function("05_odometry", "WheelPairing"),
    Function("06_driving", "distance_along"),
    Function("06_driving", "angle_error"),
    Function("06_driving", "AngleTracker"),
    Function("07_control", "PID"),
    Function("07_control", "go_to_point"),
    Function("08_leds", "light_service_node"),
}

DELTA_PHI_FIRST = (
    "This test builds on delta_phi (05_odometry), which fails its own test test_delta_phi: "
    "fix that first."
)


@pytest.fixture(scope="module")
def course() -> Dependencies:
    return Dependencies.from_source(ROOT / "solutions")


# --- The real course's dependencies -------------------------------------------------------


def test_every_graded_function_of_the_course_has_its_own_test(course):
    assert len(course.functions) == 29  # 26, move_topic (02), error_parts (06), plot_theta (10)
    assert set(course.functions) == set(course.own_tests)
    assert course.own_tests[DELTA_PHI] == (TEST_DELTA_PHI,)
    assert course.own_tests[WHEEL_PAIRING] == (TEST_WHEEL_PAIRING,)
    assert course.own_tests[MISSION_NODE] == (TEST_MISSION_NODE, TEST_MISSION_CLOSURE)
    assert course.problems == ()


def test_answer_code_builds_on_the_functions_it_calls_across_notebooks(course):
    assert course.functions[WHEEL_PAIRING] == {DELTA_PHI}
    assert course.functions[ANGLE_TRACKER] == {ANGLE_ERROR}
    assert course.functions[MISSION_NODE] == {
        ANGLE_ERROR,
        ANGLE_TRACKER,
        Function("07_control", "PID"),
        Function("07_control", "go_to_point"),
    }
    assert course.functions[DELTA_PHI] == frozenset()


def test_wheel_pairing_s_test_builds_on_delta_phi(course):
    assert course.tests[TEST_WHEEL_PAIRING] == {WHEEL_PAIRING, DELTA_PHI}
    assert course.own_functions(TEST_WHEEL_PAIRING) == {WHEEL_PAIRING}
    assert course.builds_on(TEST_WHEEL_PAIRING) == {DELTA_PHI}
    assert course.builds_on(TEST_ANGLE_TRACKER) == {ANGLE_ERROR}
    assert course.builds_on(TEST_ERROR_PARTS) == {Function("06_driving", "distance_along")}


def test_the_mission_tests_build_on_every_part_the_mission_loads(course):
    # Not visible by name: they call load_solution("..", required=MISSION_PARTS), then a run.
    for test in (TEST_MISSION_NODE, TEST_MISSION_CLOSURE):
        assert course.own_functions(test) == {MISSION_NODE}
        assert course.builds_on(test) == MISSION_FUNCTIONS
    assert course.mission == MISSION_FUNCTIONS | {MISSION_NODE}
    assert {function.name for function in course.mission} == set(MISSION_PARTS)


def test_the_other_tests_of_05_to_08_build_on_nothing_else(course):
    lonely = [
        test
        for test in course.tests
        if "05" <= test[0] < "09"
        and test not in (TEST_WHEEL_PAIRING, TEST_ANGLE_TRACKER, TEST_ERROR_PARTS)
    ]
    assert len(lonely) == 8
    assert all(course.builds_on(test) == frozenset() for test in lonely)


def test_the_map_is_worked_out_once_per_source(course):
    assert Dependencies.from_source(ROOT / "solutions") is course


# --- The messages -------------------------------------------------------------------------


def test_a_one_line_bug_in_delta_phi_is_named_first_in_the_tests_it_cascades_into(course):
    failed = {
        TEST_DELTA_PHI: "delta_phi(10, 0, 135) should be 10/135 of a turn",
        TEST_WHEEL_PAIRING: "The left wheel went 100 -> 103 -> 105",
        TEST_MISSION_NODE: "After the square the robot should be at about (0.32, 1.57) m",
        TEST_MISSION_CLOSURE: "At the end of the mission the robot should really be within 10 cm",
    }
    explained = course.explain(failed)
    assert explained == {
        TEST_DELTA_PHI: "delta_phi(10, 0, 135) should be 10/135 of a turn",
        TEST_WHEEL_PAIRING: f"{DELTA_PHI_FIRST} The left wheel went 100 -> 103 -> 105",
        TEST_MISSION_NODE: (
            f"{DELTA_PHI_FIRST} After the square the robot should be at about (0.32, 1.57) m"
        ),
        TEST_MISSION_CLOSURE: (
            f"{DELTA_PHI_FIRST} At the end of the mission the robot should really be within 10 cm"
        ),
    }
    # WheelPairing and mission_node fail too, but only through delta_phi: not named.
    assert course.causes(TEST_MISSION_NODE, failed) == [DELTA_PHI]
    assert course.driving_note(failed) == (
        "The mission uses delta_phi (05_odometry), which fails its own test test_delta_phi: "
        "fix that first."
    )


def test_a_test_whose_own_function_is_wrong_gets_no_cascade_sentence(course):
    failed = {TEST_WHEEL_PAIRING: "a WheelPairing mistake"}
    assert course.explain(failed) == failed
    failed = {TEST_MISSION_NODE: "one", TEST_MISSION_CLOSURE: "two"}
    assert course.explain(failed) == failed  # a test never blames its own function
    assert course.driving_note(failed) == (
        "The mission uses mission_node (09_mission), which fails its own tests "
        "test_mission_node and test_mission_closure: fix that first."
    )
    assert course.driving_note({("10_bag_analysis", "test_pose_error"): "off"}) is None
    assert course.driving_note([]) is None


def test_two_deep_mistakes_are_named_in_course_order(course):
    tests = (TEST_ANGLE_ERROR, TEST_ANGLE_TRACKER, TEST_DELTA_PHI, TEST_WHEEL_PAIRING)
    failed = dict.fromkeys((*tests, TEST_MISSION_NODE), "message")
    explained = course.explain(failed)
    assert explained[TEST_MISSION_NODE] == (
        "This test builds on functions that fail their own tests: delta_phi (05_odometry, "
        "test_delta_phi) and angle_error (06_driving, test_angle_error); fix those first. message"
    )
    assert explained[TEST_ANGLE_TRACKER] == (
        "This test builds on angle_error (06_driving), which fails its own test "
        "test_angle_error: fix that first. message"
    )
    assert course.driving_note(failed).startswith(
        "The mission uses functions that fail their own tests: delta_phi (05_odometry, "
        "test_delta_phi) and angle_error (06_driving, test_angle_error); fix those first."
    )


# --- Any course source, however its notebooks are written ---------------------------------

Cell = Tuple[str, Optional[str], str]  # (kind, grade_id, source)


def write_notebook(folder: Path, name: str, cells: List[Cell], tags=("export",)) -> Path:
    """Write an nbgrader source notebook ``folder/name/name.ipynb``."""
    json_cells = []
    for kind, grade_id, source in cells:
        metadata = {}
        if kind == "answer":
            metadata = {
                "nbgrader": {"solution": True, "grade": False, "grade_id": grade_id},
                "tags": list(tags),
            }
        elif kind == "test":
            metadata = {
                "nbgrader": {"solution": False, "grade": True, "grade_id": grade_id, "points": 1}
            }
        json_cells.append(
            {"cell_type": "code", "metadata": metadata, "source": source, "outputs": []}
        )
    path = folder / name / f"{name}.ipynb"
    path.parent.mkdir(parents=True)
    path.write_text(json.dumps({"cells": json_cells, "metadata": {}, "nbformat": 4}))
    return path


def test_magics_syntax_errors_and_unreadable_notebooks_do_not_stop_the_map(tmp_path):
    write_notebook(
        tmp_path,
        "01_first",
        [
            ("other", None, "%matplotlib inline\nimport math"),
            ("answer", "half", "%load_ext autoreload\ndef half(x):\n    return x / 2\n"),
            ("test", "test_half", "files = !ls\nassert half(2) == 1\nhalf?"),
            ("answer", "quarter", "def quarter(x):\n    return half(half(x))\n"),
            ("test", "test_quarter", "%%time\nassert quarter(4) == 1\n"),
        ],
    )
    write_notebook(
        tmp_path,
        "02_second",
        [
            ("answer", "broken", "def broken(x:\n    return quarter(x)\n"),
            ("test", "test_broken", "assert broken(8) == 2 +"),
        ],
    )
    (tmp_path / "03_unreadable").mkdir()
    (tmp_path / "03_unreadable" / "03_unreadable.ipynb").write_text("{not json")

    course = Dependencies.from_source(tmp_path)
    half, quarter, broken = (
        Function("01_first", "half"),
        Function("01_first", "quarter"),
        Function("02_second", "broken"),
    )
    assert course.functions == {half: set(), quarter: {half}, broken: {half, quarter}}
    assert course.tests[("01_first", "test_half")] == {half}
    assert course.builds_on(("01_first", "test_quarter")) == {half}
    assert course.builds_on(("02_second", "test_broken")) == {half, quarter}
    assert course.own_functions(("02_second", "test_broken")) == {broken}
    assert len(course.problems) == 1
    assert course.problems[0].startswith("The source notebook 03_unreadable/03_unreadable.ipynb")
    failed = {("01_first", "test_half"): "a", ("02_second", "test_broken"): "b"}
    assert course.explain(failed)[("02_second", "test_broken")] == (
        "This test builds on half (01_first), which fails its own test test_half: fix that first. b"
    )


def test_a_loaded_solution_counts_and_a_changed_notebook_is_read_again(tmp_path):
    write_notebook(
        tmp_path,
        "01_first",
        [
            ("answer", "delta_phi", "def delta_phi(ticks, prev_ticks, resolution):\n    pass\n"),
            ("test", "test_delta_phi", "delta_phi(1, 0, 135)"),
            ("answer", "angle_error", "def angle_error(target, theta):\n    pass\n"),
            ("test", "test_angle_error", "angle_error(1, 0)"),
        ],
    )
    path = write_notebook(
        tmp_path,
        "02_second",
        [
            ("other", None, "from duckielib.solution import load_solution"),
            ("other", None, 'mine = load_solution("..", required=["angle_error"])'),
            ("test", "test_with_a_variable", "mine.angle_error(1, 0)"),
            ("test", "test_by_default", 'load_solution("..")'),
            ("test", "test_unknown_parts", 'load_solution("..", required=PARTS)'),
        ],
    )
    delta_phi, angle_error = Function("01_first", "delta_phi"), Function("01_first", "angle_error")
    course = Dependencies.from_source(tmp_path)
    assert course.builds_on(("02_second", "test_with_a_variable")) == {angle_error}
    assert course.builds_on(("02_second", "test_by_default")) == {delta_phi}  # ODOMETRY_PARTS
    assert inspect.signature(load_solution).parameters["required"].default == ODOMETRY_PARTS
    assert course.builds_on(("02_second", "test_unknown_parts")) == {delta_phi, angle_error}
    assert course.mission == {delta_phi, angle_error}

    path.write_text(path.read_text().replace("mine.angle_error(1, 0)", "None"))
    os.utime(path, ns=(path.stat().st_mtime_ns + 10**9,) * 2)
    again = Dependencies.from_source(tmp_path)
    assert again is not course
    assert again.builds_on(("02_second", "test_with_a_variable")) == frozenset()


def test_a_folder_without_notebooks_explains_nothing(tmp_path):
    course = Dependencies.from_source(tmp_path / "missing")
    assert course.tests == {}
    assert "holds no source notebook" in course.problems[0]
    assert course.explain({TEST_WHEEL_PAIRING: "message"}) == {TEST_WHEEL_PAIRING: "message"}
    assert course.driving_note([TEST_DELTA_PHI]) is None
