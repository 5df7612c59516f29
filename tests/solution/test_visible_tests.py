"""A later notebook's load runs the earlier notebooks' visible tests and names what to fix first.

In-process on a small course of two notebooks written here (05_odometry and 06_driving, the
folder layout of ``course/``), and once in a real kernel, as ``duckie handin`` runs it.
"""

from __future__ import annotations

import os

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_notebook

from duckielib.solution import SolutionError, load_solution
from duckielib.solution import visible_tests as visible
from duckielib.tools.handin import run_notebook

DELTA_PHI = """import math


def delta_phi(ticks, prev_ticks, resolution):
    return 2 * math.pi * (ticks - prev_ticks) / resolution, ticks
"""

#: The first mistake of tests/course/wrong_05.py.
ABSOLUTE_TICKS = """import math


def delta_phi(ticks, prev_ticks, resolution):
    return 2 * math.pi * ticks / resolution, ticks
"""

UNWRITTEN = """def delta_phi(ticks, prev_ticks, resolution):
    # YOUR CODE HERE
    raise NotImplementedError()
"""

PAIRING = """class WheelPairing:
    def __init__(self, resolution=135):
        self.resolution, self.prev, self.change, self.seen = resolution, {}, {}, set()

    def add(self, wheel, ticks):
        if wheel in self.prev:
            change, self.prev[wheel] = delta_phi(ticks, self.prev[wheel], self.resolution)
            self.change[wheel] = self.change.get(wheel, 0.0) + change
        self.prev[wheel] = ticks
        self.seen.add(wheel)
        if len(self.seen) < 2:
            return None
        pair = (self.change.get("left", 0.0), self.change.get("right", 0.0))
        self.change, self.seen = {}, set()
        return pair
"""

ESTIMATE_POSE = """import math


def estimate_pose(R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right):
    d = R * (delta_phi_left + delta_phi_right) / 2
    theta = (theta_prev + R * (delta_phi_right - delta_phi_left) / baseline) % (2 * math.pi)
    return x_prev + d * math.cos(theta_prev), y_prev + d * math.sin(theta_prev), theta
"""

TEST_DELTA_PHI = """print("checking delta_phi")  # a test's output is not the loading cell's
os.environ["VEHICLE_NAME"] = "set_by_a_test"
angle, kept = delta_phi(31340, 31329, 135)
assert math.isclose(angle, ticks_worth(11)), (
    f"delta_phi(31340, 31329, 135) should be 11 ticks' worth, not {angle:.4f}"
)
### BEGIN HIDDEN TESTS
assert False, "a hidden test, which the check never runs"
### END HIDDEN TESTS
"""

TEST_PAIRING = """from duckielib.solution import load_solution

mine = load_solution("..", required=["delta_phi"])  # a test that loads the saved notebooks
pairing = WheelPairing(135)
pairing.add("left", 0)
pairing.add("right", 0)
pairing.add("left", 10)
got = pairing.add("right", 5)
assert np.allclose(got, (ticks_worth(10), ticks_worth(5))), f"expected 10 and 5 ticks, not {got}"
"""

#: A test that needs a variable a cell of its notebook computes: it cannot run alone.
TEST_ESTIMATE_POSE = """assert readings == "never", "this test needs the notebook's own run"
assert estimate_pose(0.0318, 0.1, 0, 0, 0, 0, 0) == (0.0, 0.0, 0.0)
"""

DISTANCE_ALONG = """import math


def distance_along(start, pose):
    return (pose[0] - start[0]) * math.cos(start[2]) + (pose[1] - start[1]) * math.sin(start[2])
"""

#: What notebook 06_driving's load cell does.
LOAD_06 = 'mine = load_solution("..", required=["delta_phi", "estimate_pose", "WheelPairing"])'


def cell(source, grade_id=None, test=False, export=False):
    made = new_code_cell(source)
    if grade_id is not None:
        made.metadata["nbgrader"] = {
            "grade_id": grade_id,
            "grade": test,
            "solution": not test,
            "locked": test,
            "points": 1 if test else 0,
            "schema_version": 3,
        }
    if export:
        made.metadata["tags"] = ["export"]
    return made


def answer(source, grade_id):
    return cell(source, grade_id, export=True)


def write(path, cells):
    path.parent.mkdir(parents=True, exist_ok=True)
    notebook = new_notebook(cells=cells)
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3"}
    nbformat.write(notebook, path)


def small_course(folder, delta=DELTA_PHI, test_pairing=TEST_PAIRING):
    """05_odometry with three exercises and their tests, 06_driving loading them."""
    write(
        folder / "05_odometry" / "05_odometry.ipynb",
        [
            cell("import math\nimport os\n\nimport numpy as np"),
            cell(
                "TICK = 2 * math.pi / 135\nreadings = sorted([3, 1, 2])\n\n\n"
                "def ticks_worth(n):\n    return n * TICK"
            ),
            answer(delta, "delta_phi"),
            cell(TEST_DELTA_PHI, "test_delta_phi", test=True),
            answer(PAIRING, "WheelPairing"),
            cell(test_pairing, "test_WheelPairing", test=True),
            answer(ESTIMATE_POSE, "estimate_pose"),
            cell(TEST_ESTIMATE_POSE, "test_estimate_pose", test=True),
        ],
    )
    write(
        folder / "06_driving" / "06_driving.ipynb",
        [
            cell("from duckielib.solution import load_solution"),
            cell(LOAD_06),
            answer(DISTANCE_ALONG, "distance_along"),
            cell(
                'mine = load_solution("..", required=["WheelPairing"])\n'
                "assert distance_along((0, 0, 0), (1, 0.5, 0)) == 1",
                "test_distance_along",
                test=True,
            ),
        ],
    )
    return folder


FIX_DELTA_PHI = (
    "Fix notebook 05_odometry first: delta_phi fails its visible test: delta_phi(31340, 31329, "
    "135) should be 11 ticks' worth, not 1458.6298. Then save it and run this cell again."
)


def test_a_later_notebook_names_the_earlier_function_that_fails_its_visible_test(
    tmp_path, monkeypatch, capsys
):
    course = small_course(tmp_path / "course", delta=ABSOLUTE_TICKS)
    monkeypatch.chdir(course / "06_driving")
    environment = dict(os.environ)
    with pytest.raises(SolutionError) as raised:
        load_solution("..", required=["delta_phi", "estimate_pose", "WheelPairing"])
    # delta_phi's test runs first: WheelPairing's fails too, but only because of delta_phi.
    assert str(raised.value) == FIX_DELTA_PHI
    with pytest.raises(SolutionError, match=r"^Fix notebook 05_odometry first: delta_phi fails"):
        load_solution("..", required=["WheelPairing"])  # a part it builds on
    assert capsys.readouterr() == ("", "")  # what the tests printed stays in the check
    assert dict(os.environ) == environment  # what they set in the environment too
    # Not asked, not checked: outside the course's notebook folders, and at the caller's wish.
    assert load_solution("..", required=["delta_phi"], visible_tests=False).delta_phi
    monkeypatch.chdir(tmp_path)
    assert load_solution(course, required=["delta_phi"]).delta_phi
    with pytest.raises(SolutionError, match=r"^Fix notebook 05_odometry first: delta_phi"):
        load_solution(course, required=["delta_phi"], visible_tests=True)


def test_a_right_solution_loads_after_the_tests_it_can_run(tmp_path, monkeypatch):
    # The hidden test fails if it runs, test_estimate_pose if the notebook's own run does, and
    # test_WheelPairing loads the solution again (no check inside a check).
    course = small_course(tmp_path / "course")
    monkeypatch.chdir(course / "06_driving")
    mine = load_solution("..", required=["delta_phi", "estimate_pose", "WheelPairing"])
    assert mine.WheelPairing(135).add("left", 0) is None
    assert not visible.checking()


def test_a_passed_check_is_not_run_again_until_a_notebook_changes(tmp_path, monkeypatch):
    # Notebook 09 loads the same solution three times: the tests run once, until 05 is saved.
    course = small_course(tmp_path / "course")
    monkeypatch.chdir(course / "06_driving")
    ran = []
    monkeypatch.setattr(visible, "_run_notebook", lambda *args: ran.append(args[0].name))
    load_solution("..", required=["delta_phi"])
    load_solution("..", required=["delta_phi"])
    assert ran == ["05_odometry.ipynb"]
    monkeypatch.undo()
    monkeypatch.chdir(course / "06_driving")
    small_course(course, delta=ABSOLUTE_TICKS)  # the student saves a mistake into 05
    with pytest.raises(SolutionError, match=r"^Fix notebook 05_odometry first: delta_phi"):
        load_solution("..", required=["delta_phi"])


@pytest.mark.timeout(60)
def test_a_fifo_among_the_notebooks_is_never_read(tmp_path, monkeypatch):
    # A student's cell once made a FIFO named like a notebook: reading it blocks for ever.
    course = small_course(tmp_path / "course", delta=ABSOLUTE_TICKS)
    os.mkfifo(course / "05_odometry" / "zz_scratch.ipynb")
    (course / "03_frames").mkdir()
    os.mkfifo(course / "03_frames" / "03_frames.ipynb")
    monkeypatch.chdir(course / "06_driving")
    with pytest.raises(SolutionError, match=r"^Fix notebook 05_odometry first: delta_phi"):
        load_solution("..", required=["delta_phi"])


def test_the_notebook_that_loads_tests_its_own_parts_itself(tmp_path, monkeypatch):
    course = small_course(tmp_path / "course", delta=ABSOLUTE_TICKS)
    monkeypatch.chdir(course / "05_odometry")
    assert load_solution("..", required=["delta_phi"]).delta_phi(10, 0, 135)[1] == 10


def test_an_unwritten_function_it_builds_on_is_named_to_finish(tmp_path, monkeypatch):
    course = small_course(tmp_path / "course", delta=UNWRITTEN)
    monkeypatch.chdir(course / "06_driving")
    with pytest.raises(SolutionError) as raised:
        load_solution("..", required=["WheelPairing"])
    assert str(raised.value) == (
        "Finish notebook 05_odometry first: delta_phi is not written yet (its visible test "
        "stops at NotImplementedError). Write it, save the notebook, and run this cell again."
    )


def test_a_test_that_runs_too_long_is_passed_over(tmp_path, monkeypatch):
    endless = "while True:\n    pass\n"
    course = small_course(tmp_path / "course", delta=ABSOLUTE_TICKS, test_pairing=endless)
    monkeypatch.chdir(course / "06_driving")
    monkeypatch.setattr(visible, "TEST_SECONDS", 0.2)
    # delta_phi's test still fails; with it unchecked, WheelPairing's endless one is passed over.
    with pytest.raises(SolutionError, match="delta_phi fails its visible test"):
        load_solution("..", required=["WheelPairing"])
    fixed = small_course(tmp_path / "fixed", test_pairing=endless)
    monkeypatch.chdir(fixed / "06_driving")
    assert load_solution("..", required=["WheelPairing"]).WheelPairing


@pytest.mark.notebook
def test_run_all_stops_at_the_load_and_handin_says_what_waits_on_what(tmp_path):
    course = small_course(tmp_path / "course", delta=ABSOLUTE_TICKS)
    run = run_notebook(course / "06_driving" / "06_driving.ipynb")
    assert [(cell.number, cell.grade_id) for cell in run.raised] == [
        (2, None),
        (4, "test_distance_along"),
    ]
    assert all(cell.error.startswith(f"SolutionError: {FIX_DELTA_PHI[:60]}") for cell in run.raised)
    assert run.waits == {"test_distance_along": ["05_odometry: delta_phi"]}
    assert run.unfinished == []
    assert run.summary().startswith(
        "06_driving: 0 of 1 visible tests pass (waits on 05_odometry: delta_phi); "
        f"Run All stops at cell 2 ({LOAD_06[:49]}…): SolutionError: Fix notebook 05_odometry"
    )
