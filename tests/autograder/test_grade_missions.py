"""Each task is graded by how the student's own code drives it, in a column of its own.

A class of five, each handing in the whole course with one mistake in their mission node
(notebook 09), graded with the driving score. The grader drives each student's export on the
four missions (square then circle, the "D", the straight-line task and the rotation task) and
``grades.csv`` has one column per mission, so each mistake shows where it belongs:

- ``reference``: every mission 100.
- ``short_sides``: every straight move is 20 % short: the straight task, the square and the D
  lose points; the rotation task keeps all of them.
- ``wrong_turns``: every turn on the spot goes the other way: the rotation task, the square
  and the D lose points; the straight task keeps all of them.
- ``left_arcs``: arcs curve left instead of right: the circle and the D's bowl lose points;
  the straight and rotation tasks keep all of them.
- ``never_ends``: announces "done" and then spins for ever: the node never exits, and every
  mission loses the points for its states, and only those.
"""

from __future__ import annotations

import csv
import shutil

import nbformat
import pytest

from autograder.bench import filled_course
from autograder.driving import MISSIONS
from autograder.grade import grade_class
from autograder.sandbox import Limits

pytestmark = [pytest.mark.slow, pytest.mark.timeout(900)]

MISTAKES = {
    "short_sides": [
        ("x + move.distance * math.cos(theta)", "x + 0.8 * move.distance * math.cos(theta)"),
        ("y + move.distance * math.sin(theta)", "y + 0.8 * move.distance * math.sin(theta)"),
    ],
    "wrong_turns": [
        (
            "goal = (x, y, (theta + move.angle) % (2 * math.pi))",
            "goal = (x, y, (theta - move.angle) % (2 * math.pi))",
        )
    ],
    "left_arcs": [
        (
            "sign = 1.0 if angle > 0 else -1.0  # +1",
            "sign = -1.0 if angle > 0 else 1.0  # +1",
        )
    ],
    "never_ends": [("shutdown.publish(Empty())", "rospy.spin()")],
}


def _mistake(folder, edits):
    """Make the student's mission node in ``folder`` carry ``edits`` (each found once)."""
    path = folder / "09_mission" / "09_mission.ipynb"
    notebook = nbformat.read(path, as_version=4)
    (cell,) = [
        cell
        for cell in notebook.cells
        if cell.metadata.get("nbgrader", {}).get("grade_id") == "mission_node"
    ]
    for old, new in edits:
        assert cell.source.count(old) == 1, old
        cell.source = cell.source.replace(old, new)
    nbformat.write(notebook, path)


@pytest.fixture(scope="module")
def graded(sandbox, tmp_path_factory):
    root = tmp_path_factory.mktemp("missions")
    filled = filled_course(root / "filled")
    submissions, out = root / "submissions", root / "out"
    shutil.copytree(filled, submissions / "reference")
    for student, edits in MISTAKES.items():
        shutil.copytree(filled, submissions / student)
        _mistake(submissions / student, edits)
    results = grade_class(submissions, out, jobs=2, names=["03_frames"], limits=Limits())
    with (out / "grades.csv").open() as handle:
        rows = {row["student"]: row for row in csv.DictReader(handle)}
    return {result.student: result for result in results}, rows


def _scores(rows, student):
    return {name: float(rows[student][f"driving:{name}"]) for name in MISSIONS}


def test_grades_csv_has_a_column_per_mission_and_their_mean(graded):
    results, rows = graded
    header = list(rows["reference"])
    columns = ["driving_score"] + [f"driving:{name}" for name in MISSIONS]
    assert header[4:9] == columns
    assert _scores(rows, "reference") == dict.fromkeys(MISSIONS, 100.0)
    for student, row in rows.items():
        mean = sum(_scores(rows, student).values()) / len(MISSIONS)
        assert float(row["driving_score"]) == pytest.approx(mean, abs=0.01)
        assert results[student].problems == []


#: Each mistake: the missions that keep every point, and those that lose some.
KEPT_AND_LOST = {
    "short_sides": ({"rotation"}, {"straight", "square_then_circle", "d_shape"}),
    "wrong_turns": ({"straight"}, {"rotation", "square_then_circle", "d_shape"}),
    "left_arcs": ({"straight", "rotation"}, {"square_then_circle", "d_shape"}),
}


@pytest.mark.parametrize("student", list(KEPT_AND_LOST))
def test_each_mistake_loses_points_only_in_the_missions_it_spoils(graded, student):
    _, rows = graded
    kept, lost = KEPT_AND_LOST[student]
    scores = _scores(rows, student)
    assert {name for name, score in scores.items() if score == 100} == kept, scores
    assert {name for name, score in scores.items() if score < 100} == lost, scores


def test_each_mistake_is_measured_where_it_happens(graded):
    results, _ = graded
    forward = results["short_sides"].missions["straight"]
    assert forward.parts["forward"] == 0, forward.parts
    (check,) = forward.summary["motion"][0]["checks"]
    assert check["measured"] == pytest.approx(1.0, abs=0.03), check
    rotation = results["wrong_turns"].missions["rotation"]
    assert rotation.parts["clockwise"] == 0, rotation.parts
    assert any("clockwise" in reason for reason in rotation.reasons), rotation.reasons
    arcs = results["left_arcs"].missions
    assert arcs["square_then_circle"].parts["circle"] < 20
    assert arcs["square_then_circle"].parts["square"] == 20
    assert arcs["d_shape"].parts["d"] < 20


def test_a_node_that_never_ends_loses_only_the_states_points_of_every_mission(graded):
    results, rows = graded
    assert _scores(rows, "never_ends") == dict.fromkeys(MISSIONS, 80.0)
    for driving in results["never_ends"].missions.values():
        assert driving.parts["states"] == 0
        assert "did not end" in driving.reasons[0]
        assert "keeps it alive" in driving.reasons[0]
    assert (
        "rotation: The mission could not run to its end" in rows["never_ends"]["driving_problems"]
    )
