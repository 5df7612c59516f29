"""Tests that run a student's nodes on a robot, run in the grader: the nodes in the sandbox.

Each test cell runs as the grader runs it (:func:`autograder.calls.run_test` in the namespace of
the notebook's imports, with :func:`autograder.robots.robot_names`), against a copy of the
course whose saved notebooks hold the reference, or the reference with one mistake; the
student's nodes load those notebooks in the sandbox, as in a graded class.
"""

from __future__ import annotations

import copy
import json
import time
import types

import pytest
from adversarial.cases import NEVER_DRIVES
from course.coursetools import NAMES, SOLUTIONS, load_solution_nb, nbgrader, source, wrong_solutions

from autograder.calls import Remote
from autograder.robots import robot_names
from autograder.sandbox import Limits
from autograder.verdict import free_names, prelude, run_test
from duckielib.tools.apart import ApartDuckiebot

pytestmark = pytest.mark.slow

MISTAKES = wrong_solutions()


class NoKernel:
    """The kernel's side of a test that asks it nothing but names it never calls."""

    calls = 0

    def get(self, name):
        return object()


def course_with(folder, name, replacements):
    """The course's reference notebooks in ``folder``, ``name``'s graded cells replaced."""
    for other in NAMES:
        notebook = load_solution_nb(other)
        if other == name:
            notebook = copy.deepcopy(notebook)
            for cell in notebook["cells"]:
                grade_id = nbgrader(cell).get("grade_id")
                if grade_id in replacements:
                    cell["source"] = replacements[grade_id]
        (folder / other).mkdir(parents=True)
        (folder / other / f"{other}.ipynb").write_text(json.dumps(notebook), encoding="utf-8")
    return folder


def graded_test(tmp_path, name, grade_id, replacements=None):
    """Run test ``grade_id`` of notebook ``name`` as the grader does; its outputs."""
    export = course_with(tmp_path / "export", name, replacements or {})
    unit = types.SimpleNamespace(
        folder=tmp_path, student_disk=tmp_path, limits=Limits(), use_sandbox=True, export=export
    )
    cells = load_solution_nb(name)["cells"]
    cells = [{**cell, "source": source(cell)} for cell in cells]
    text = next(cell["source"] for cell in cells if nbgrader(cell).get("grade_id") == grade_id)
    space = prelude(cells)
    given = robot_names(unit, space, time.monotonic() + 120)
    space.update(given)
    return run_test(text, grade_id, space, NoKernel()), given, text


def test_the_robot_tests_take_the_graders_robot_and_never_ask_the_kernel_for_it(
    sandbox, tmp_path, monkeypatch
):
    monkeypatch.setenv("VEHICLE_NAME", "duckiebot")  # a robot sets it: put back afterwards
    outputs, given, text = graded_test(tmp_path, "08_leds", "test_light_service_node")
    assert outputs == []
    # The names notebook 08 imports (it runs no mission: run_mission is not among them).
    assert set(given) == {"load_solution", "check_saved", "VirtualDuckiebot"}
    robot = given["VirtualDuckiebot"](name="grader_check")
    assert isinstance(robot, ApartDuckiebot)
    robot.shutdown()
    # Of the test's names, only the student's own node is the kernel's (check_saved's
    # argument, never called): the robot, the runner and the loader are the grader's.
    space = prelude(
        [{**cell, "source": source(cell)} for cell in load_solution_nb("08_leds")["cells"]]
    )
    space.update(given)
    assert [name for name in free_names(text) if name not in space] == ["light_service_node"]
    assert not isinstance(given["VirtualDuckiebot"], Remote)
    # Notebook 09's mission tests likewise: a run_mission the student defines in the kernel
    # (one that returns a perfect report) is never the test's.
    cells = [{**cell, "source": source(cell)} for cell in load_solution_nb("09_mission")["cells"]]
    space = prelude(cells)
    unit = types.SimpleNamespace(
        folder=tmp_path, student_disk=tmp_path, limits=Limits(), use_sandbox=True, export=None
    )
    space.update(robot_names(unit, space, time.monotonic() + 60))
    for grade_id in ("test_mission_node", "test_mission_closure"):
        text = next(cell["source"] for cell in cells if nbgrader(cell).get("grade_id") == grade_id)
        assert [name for name in free_names(text) if name not in space] == ["mission_node"]


@pytest.mark.parametrize(
    "mistake",
    [
        "ignores the shutdown topic",
        "forwards unknown colours to the emitter without an error",
        "refuses with ValueError instead of rospy.ServiceException",
        "no rospy.spin(): the node ends at once",
        "the handler returns None",
    ],
)
def test_a_light_service_mistake_fails_its_test_in_the_grader(sandbox, tmp_path, mistake):
    wrong = MISTAKES[("08_leds", "light_service_node", mistake)]
    outputs, _, _ = graded_test(
        tmp_path, "08_leds", "test_light_service_node", {"light_service_node": wrong}
    )
    assert [output["output_type"] for output in outputs] == ["error"], mistake
    assert outputs[0]["ename"] == "AssertionError", outputs[0]


def test_the_mission_test_judges_the_robot_the_grader_ran(sandbox, tmp_path):
    outputs, _, _ = graded_test(tmp_path / "reference", "09_mission", "test_mission_node")
    assert outputs == []
    never = (
        "import rospy\nfrom duckietown_msgs.srv import ChangePattern\n"
        "from std_msgs.msg import Empty, String\n\nfrom duckielib.missions import Stop\n\n\n"
        + NEVER_DRIVES
    )
    outputs, _, _ = graded_test(
        tmp_path / "never", "09_mission", "test_mission_node", {"mission_node": never}
    )
    assert [output["output_type"] for output in outputs] == ["error"]
    assert outputs[0]["evalue"].startswith(
        "After the square (a clockwise quarter turn and 1.25 m, then twice a counter-clockwise "
        "quarter turn and 1.25 m) the robot should be at about (0.32, 1.57) m, but it was at "
        "(0.32, 0.32) m"
    ), outputs[0]
    assert "/tmp" not in json.dumps(outputs)
    assert SOLUTIONS.name not in outputs[0]["evalue"]
