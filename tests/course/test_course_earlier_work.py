"""A mistake in an earlier notebook is reported where it is made, in the later notebooks too.

The course filled with the reference answers, then ``delta_phi`` (05_odometry) replaced by the
first wrong version of ``wrong_05.py``: the later notebooks' load cells say to fix
``delta_phi`` first, with its visible test's message, and ``duckie handin`` lists
``delta_phi`` as to do and what fails because of it as waiting on it. In-process, from the
course's own notebooks: each notebook's load cell as it is written, and made-up runs (what
Run All gives) for the handin lines.
"""

from __future__ import annotations

import ast
import copy
import json

import pytest
from coursetools import COURSE, load, notebook_path, source, wrong_solutions

from autograder.bench import filled_course
from duckielib.solution import MISSION_PARTS, check_saved, load_solution
from duckielib.tools.handin import NotebookRun, cell_kind, raised_cells, waiting_tests

MISTAKE = ("05_odometry", "delta_phi", "absolute ticks instead of the change")
#: What the wrong delta_phi returns for its visible test's second call: 31340 ticks' angle.
WRONG_ANGLE = "1458.6298335333943"
FIX_FIRST = "Fix notebook 05_odometry first: delta_phi fails its visible test: delta_phi("


@pytest.fixture(scope="module")
def wrong_course(tmp_path_factory):
    folder = filled_course(tmp_path_factory.mktemp("earlier_work") / "course")
    path = notebook_path(folder, "05_odometry")
    notebook = load(path)
    (answer,) = [
        cell
        for cell in notebook["cells"]
        if cell.get("metadata", {}).get("nbgrader", {}).get("grade_id") == "delta_phi"
    ]
    answer["source"] = wrong_solutions()[MISTAKE]
    path.write_text(json.dumps(notebook, indent=1) + "\n", encoding="utf-8")
    return folder


def load_call(name):
    """The statement of a released notebook that first loads the student's earlier work."""
    for cell in load(notebook_path(COURSE, name))["cells"]:
        if cell["cell_type"] != "code":
            continue
        text = source(cell)
        for statement in ast.parse(text).body:
            segment = ast.get_source_segment(text, statement) or ""
            if "load_solution(" in segment and '".."' in segment:
                return segment
    raise AssertionError(f"{name} does not load the student's earlier work")


def sentence_of_load(folder, name, monkeypatch):
    """Run notebook ``name``'s load from its folder in ``folder``: what it raises, or None."""
    monkeypatch.chdir(folder / name)
    namespace = {
        "load_solution": load_solution,
        "MISSION_PARTS": MISSION_PARTS,
        "check_saved": check_saved,
    }
    try:
        exec(load_call(name), namespace)
    except Exception as error:
        return f"{type(error).__name__}: {error}"
    return None


@pytest.mark.parametrize("name", ["06_driving", "07_control", "09_mission"])
def test_a_later_notebook_stops_at_its_load_naming_delta_phi_and_its_test(
    wrong_course, name, monkeypatch
):
    said = sentence_of_load(wrong_course, name, monkeypatch)
    assert said.startswith(f"SolutionError: {FIX_FIRST}"), said
    assert f"not {WRONG_ANGLE}" in said
    assert said.endswith(". Then save it and run this cell again.")


def test_the_filled_course_loads_in_every_later_notebook(tmp_path, monkeypatch):
    folder = filled_course(tmp_path / "course")
    for name in ("06_driving", "07_control", "08_leds", "09_mission"):
        assert sentence_of_load(folder, name, monkeypatch) is None, name


def made_up_run(folder, name, tests, errors):
    """A run of ``folder``'s notebook ``name`` in which the cells ``errors`` raised.

    Args:
        tests: each test's ``grade_id`` and whether it passed.
        errors: cell number -> (exception name, message), as the kernel reported them.
    """
    cells = load(notebook_path(folder, name))["cells"]
    ran = copy.deepcopy(cells)
    for number, (ename, evalue) in errors.items():
        ran[number - 1]["outputs"] = [{"output_type": "error", "ename": ename, "evalue": evalue}]
    run = NotebookRun(name=name, seconds=1.0, tests=tests)
    run.exercises = {
        cell["metadata"]["nbgrader"]["grade_id"]: number
        for number, cell in enumerate(cells, start=1)
        if cell["cell_type"] == "code" and cell_kind(cell) == "exercise"
    }
    run.raised = raised_cells(cells, ran)
    run.waits = waiting_tests(run, folder)
    return run


def test_handin_lists_delta_phi_to_do_and_the_rest_as_waiting_on_it(wrong_course, monkeypatch):
    # 05_odometry: delta_phi fails its test, and WheelPairing's through it (it calls delta_phi).
    odometry = made_up_run(
        wrong_course,
        "05_odometry",
        {"test_delta_phi": False, "test_estimate_pose": True, "test_WheelPairing": False},
        {
            19: ("AssertionError", f"delta_phi(31340, 31329, 135) ... not {WRONG_ANGLE}"),
            29: ("AssertionError", "The left wheel went 100 -> 103 -> 105 (5 ticks in total)"),
        },
    )
    assert odometry.waits == {"test_WheelPairing": ["delta_phi"]}
    assert odometry.unfinished == ["delta_phi"]
    assert odometry.waiting == {"WheelPairing": ["delta_phi"]}
    assert odometry.summary() == (
        "05_odometry: 1 of 3 visible tests pass (to do: delta_phi; WheelPairing waits on it); "
        f"Run All stops at cell 19 (test_delta_phi): AssertionError: delta_phi(31340, 31329, "
        f"135) ... not {WRONG_ANGLE}"
    )
    # 09_mission: both tests stop at their load, which names delta_phi; mission_node is right.
    said = sentence_of_load(wrong_course, "09_mission", monkeypatch).split(": ", 1)[1]
    mission = made_up_run(
        wrong_course,
        "09_mission",
        {"test_mission_node": False, "test_mission_closure": False},
        {18: ("SolutionError", said), 20: ("SolutionError", said)},
    )
    assert mission.waits == {
        "test_mission_node": ["05_odometry: delta_phi"],
        "test_mission_closure": ["05_odometry: delta_phi"],
    }
    assert mission.unfinished == []
    assert mission.summary().startswith(
        "09_mission: 0 of 2 visible tests pass (waits on 05_odometry: delta_phi); Run All stops "
        f"at cell 18 (test_mission_node): SolutionError: {FIX_FIRST}"
    )
    # An earlier function still unwritten holds the mission back the same way.
    unwritten = (
        "Finish notebook 05_odometry: write WheelPairing (their cells still raise "
        "NotImplementedError), save the notebook, and try again."
    )
    mission = made_up_run(
        wrong_course,
        "09_mission",
        {"test_mission_node": False, "test_mission_closure": True},
        {18: ("SolutionError", unwritten)},
    )
    assert mission.summary().startswith(
        "09_mission: 1 of 2 visible tests pass (waits on 05_odometry: WheelPairing); "
    )


def test_an_exercise_not_written_yet_is_to_do_whatever_an_earlier_one_says():
    # The untouched release: 09's load names 05's parts, but mission_node is unwritten too.
    finish = (
        "Finish notebook 05_odometry: write delta_phi, estimate_pose, WheelPairing (their cells "
        "still raise NotImplementedError), save the notebook, and try again."
    )
    mission = made_up_run(
        COURSE,
        "09_mission",
        {"test_mission_node": False, "test_mission_closure": False},
        {18: ("SolutionError", finish), 20: ("SolutionError", finish)},
    )
    assert mission.waits == {}
    assert mission.unfinished == ["mission_node", "test_mission_closure"]
