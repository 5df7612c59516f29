"""Missions as data: the exercise's task and its D variant, checked move by move; and the
runner's check that a mission node leaves the wheels at rest once it is done."""

from __future__ import annotations

import math
import re

import pytest

from duckielib.bags.behaviour import STILL_AFTER_DONE_S
from duckielib.errors import ConfigError
from duckielib.missions import (
    D_SHAPE,
    MISSIONS,
    ROTATION,
    SQUARE_THEN_CIRCLE,
    STRAIGHT,
    TASK_START,
    Arc,
    Mission,
    ReturnToStart,
    Rotate,
    State,
    Stop,
    Straight,
    mission_named,
)


def follow(moves, pose):
    """Where ideal moves take a pose (the test's own geometry; ReturnToStart is skipped)."""
    x, y, theta = pose
    for move in moves:
        if isinstance(move, Straight):
            x, y = x + move.distance * math.cos(theta), y + move.distance * math.sin(theta)
        elif isinstance(move, Rotate):
            theta += move.angle
        elif isinstance(move, Arc):
            side = math.copysign(1.0, move.angle)  # +1 centre on the left, -1 on the right
            cx = x - side * move.radius * math.sin(theta)
            cy = y + side * move.radius * math.cos(theta)
            theta += move.angle
            x = cx + side * move.radius * math.sin(theta)
            y = cy - side * move.radius * math.cos(theta)
    return x, y, theta % (2 * math.pi)


def test_the_square_then_circle_task_follows_the_exercise():
    mission = SQUARE_THEN_CIRCLE
    assert mission.start == TASK_START == (0.32, 0.32, math.pi / 2)
    assert [state.name for state in mission.states] == [
        "wait",
        "square",
        "wait",
        "return",
        "wait",
        "circle",
    ]
    assert [state.stop_seconds for state in mission.states if state.is_stop] == [5.0] * 3
    assert mission.colors == ("RED", "GREEN", "RED", "BLUE", "RED", "YELLOW")
    square = mission.states[1].moves
    assert square[0] == Rotate(-math.pi / 2), "the square starts with a clockwise quarter turn"
    x, y, theta = follow(square, mission.start)
    assert (x, y) == (pytest.approx(0.32), pytest.approx(1.57)), "three sides, the last one back"
    assert theta == pytest.approx(math.pi)
    assert mission.states[3].moves == (ReturnToStart(),)
    circle = mission.states[5].moves
    assert follow(circle, mission.start) == pytest.approx(mission.start)
    assert circle[0].angle < 0, "the circle is clockwise"


def test_the_d_closes_where_it_began_and_stays_on_the_mat():
    moves = D_SHAPE.states[1].moves
    assert follow(moves, D_SHAPE.start) == pytest.approx(D_SHAPE.start)
    arcs = [move for move in moves if isinstance(move, Arc)]
    assert [arc.angle for arc in arcs] == [-math.pi / 2] * 2, "two clockwise quarter arcs"
    pose = D_SHAPE.start
    for move in moves:
        pose = follow([move], pose)
        assert 0.1 < pose[0] < 2.24, f"{move} leaves the mat"
        assert 0.1 < pose[1] < 2.24, f"{move} leaves the mat"


def test_the_two_tasks_of_part_2_are_missions_too():
    assert STRAIGHT.colors == ROTATION.colors == ("RED", "GREEN", "RED", "BLUE")
    assert STRAIGHT.states[1].moves == (Straight(1.25),)
    assert STRAIGHT.states[3].moves == (ReturnToStart(),)
    assert ROTATION.states[1].moves == (Rotate(-math.pi / 2),), "clockwise first"
    assert ROTATION.states[3].moves == (Rotate(math.pi / 2),)
    assert follow(ROTATION.states[1].moves + ROTATION.states[3].moves, ROTATION.start) == (
        pytest.approx(ROTATION.start)
    )


def test_missions_by_name_and_the_students_stop_colour():
    assert set(MISSIONS) == {"square_then_circle", "d_shape", "straight", "rotation"}
    assert mission_named("d_shape") is D_SHAPE
    with pytest.raises(
        ConfigError, match="no mission 'square'; choose one of d_shape, rotation, s"
    ):
        mission_named("square")
    purple = SQUARE_THEN_CIRCLE.with_stop_color("BLUE")
    assert purple.colors == ("BLUE", "GREEN", "BLUE", "BLUE", "BLUE", "YELLOW")
    assert purple.states[1] is SQUARE_THEN_CIRCLE.states[1]


def test_states_refuse_unknown_colours_and_moves():
    with pytest.raises(ConfigError, match="'MAUVE' is not an LED pattern"):
        State("wait", "MAUVE", (Stop(5.0),))
    with pytest.raises(ConfigError, match="is not a move"):
        State("wait", "RED", ("stop",))


#: A student's mission node that forgets the zero command: the reference's with its arcs not
#: settling, no stop before 'done' and no shutdown hook, as ``(old, new)`` edits of its export.
FORGETS_THE_ZERO_COMMAND = (
    (
        "    rospy.on_shutdown(lambda: drive(0.0, 0.0))  "
        "# however the node ends, the wheels stop\n",
        "",
    ),
    (
        "ARC_TURN_RATE, omega)))\n            rate.sleep()\n        settle()\n",
        "ARC_TURN_RATE, omega)))\n            rate.sleep()\n",
    ),
    (
        '    drive(0.0, 0.0)\n    announce.publish(String(data="done"))',
        '    announce.publish(String(data="done"))',
    ),
)

#: A short mission that ends on an arc: a wait, then a clockwise quarter circle of 0.2 m.
QUARTER_ARC = Mission(
    "quarter_arc",
    (State("wait", "RED", (Stop(1.0),)), State("arc", "YELLOW", (Arc(0.2, -math.pi / 2),))),
)


@pytest.fixture(scope="module")
def reference_source():
    from autograder.course import ROOT
    from duckielib.solution import export_solution

    return export_solution(ROOT / "solutions").source


def drive_quarter_arc(source, folder):
    """The report of ``source`` (a solution's text) driving :data:`QUARTER_ARC`."""
    from duckielib.solution import MISSION_PARTS, load_solution
    from duckielib.tools.runner import run_mission

    folder.mkdir(exist_ok=True)
    path = folder / "solution.py"
    path.write_text(source, encoding="utf-8")
    solution = load_solution(path, required=MISSION_PARTS)
    out = folder / "run"
    return run_mission(solution, QUARTER_ARC, out=out, animation=False, figure=False).report


def test_wheels_left_turning_after_done_fail_the_mission_with_the_distance(
    reference_source, tmp_path
):
    forgetful = reference_source
    for old, new in FORGETS_THE_ZERO_COMMAND:
        assert forgetful.count(old) == 1, old
        forgetful = forgetful.replace(old, new)
    report = drive_quarter_arc(forgetful, tmp_path)
    assert report.finished
    assert report.states_in_order
    seconds, rolled, turned = report.after_done
    assert seconds == pytest.approx(STILL_AFTER_DONE_S, abs=0.05)
    # The last command of the arc, for 5 s: on the circle, aiming 0.6 rad further round, the
    # robot sees its aim 0.3 rad off its heading, so go_to_point asks for ARC_SPEED 0.15 m/s
    # times cos(0.3), on a curve that stays on the 0.2 m circle.
    assert rolled == pytest.approx(5 * 0.15 * math.cos(0.3), rel=0.05)
    assert turned == pytest.approx(rolled / 0.2, rel=0.1)
    assert not report.still_after_done
    assert not report.stops_held  # the end is a stop: the grader's stop points go too
    assert report.as_dict()["checks"]["still_after_done"] is False
    (said,) = [problem for problem in report.problems if "after 'done'" in problem]
    match = re.fullmatch(
        r"The wheels still turn after 'done': the robot rolled ([\d.]+) cm and turned (\d+)° in "
        r"5 s; send a zero command \(v = 0, omega = 0\) before you finish\.",
        said,
    )
    assert match, said
    assert float(match[1]) == pytest.approx(100 * rolled, abs=0.05)

    reference = drive_quarter_arc(reference_source, tmp_path / "reference")
    _, rolled, turned = reference.after_done
    assert rolled < 1e-4  # the reference stands still: under 0.1 mm, under 0.01 degree
    assert math.degrees(turned) < 0.01
    assert reference.still_after_done
    assert not any("after 'done'" in problem for problem in reference.problems)
