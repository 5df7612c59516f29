"""A class with students who attack the grader itself, graded with the driving score.

Each student hands in the whole course. What each does, and what an instructor wants:

- ``reference``: the reference answers: every point, a driving score of 100, no problem, as
  when graded alone.
- ``link_farm``: the untouched release, plus a cell that links the reference solutions into
  its working folder, where the grader once exported from: nothing of them is read, so no test
  point and no driving point.
- ``fifo``: a FIFO named like a notebook in the submission, and one made by a cell: the run
  never blocks, the FIFO is left out and said.
- ``sparse``: a sparse 100 GB file named like a notebook: left out and said; the student
  keeps every point.
- ``forges_the_drive``: a mission node that announces every state and colour but never
  drives: it moves the simulator's robot body itself (found through the garbage collector),
  publishes ideal poses as the ground truth and looks for the true pose. The robot runs in the
  grader, apart from the nodes: the driving points for the moves are lost.
- ``hangs_on_import``: an exported constant whose value takes for ever: the driving run is
  stopped by its wall clock, said in ``problems``; the tests keep their points.
- ``prints_20mb``: a cell that prints 20 MB: the stored notebook keeps 2 MB, said.
- ``nests_a_frame``: a mission node that writes, on the nodes' end of the link to the robot, a
  frame whose header nests 200,000 lists deep: the robot refuses it without recursing, the
  missions stop with a sentence, and the student is graded as usual.
"""

from __future__ import annotations

import os
import shutil

import nbformat
import pytest
from cases import FORGES_THE_DRIVE
from pace import seconds

from autograder.bench import filled_course
from autograder.course import ROOT
from autograder.grade import grade_class
from autograder.sandbox import Limits
from duckielib.tools.apart import REPLY_TIMEOUT_S

pytestmark = [pytest.mark.slow, pytest.mark.timeout(900)]

#: The class is graded on the notebook the attacks are in; the driving exports every notebook.
GRADED = ["03_frames"]
#: The limits a cell and a mission have here: tight, so that a hang costs little waiting. A
#: mission's stays below the minute the robot waits for the nodes to answer (REPLY_TIMEOUT_S),
#: so that its wall clock, not that silence, is what stops a run that hangs.
CELL, MISSION = seconds(15), min(seconds(20), int(REPLY_TIMEOUT_S) - 5)


LINK_FARM = """\
import os
for name in ("05_odometry", "06_driving", "07_control", "08_leds", "09_mission"):
    os.symlink(f"{solutions}/{{name}}/{{name}}.ipynb", f"zz_{{name}}.ipynb")
print(sorted(os.listdir(".")))
"""


NESTS_A_FRAME = """\
def mission_node(mission):
    import os
    import socket
    import struct
    import sys

    rospy.init_node("mission_node")
    link = socket.socket(fileno=os.dup(int(sys.argv[sys.argv.index("--link-fd") + 1])))
    head = b"[" * 200_000
    link.sendall(struct.pack("!II", len(head), 0) + head)
    rospy.sleep(1.0)
"""


def _append(folder, name, source, export=False):
    """Add a code cell at the end of the student's notebook ``name``."""
    path = folder / name / f"{name}.ipynb"
    notebook = nbformat.read(path, as_version=4)
    cell = nbformat.v4.new_code_cell(source)
    if export:
        cell.metadata["tags"] = ["export"]
    notebook.cells.append(cell)
    nbformat.write(notebook, path)


@pytest.fixture(scope="module")
def graded(sandbox, tmp_path_factory):
    root = tmp_path_factory.mktemp("class")
    submissions, out = root / "submissions", root / "out"
    filled = filled_course(root / "filled")
    for student in (
        "reference",
        "fifo",
        "sparse",
        "forges_the_drive",
        "hangs_on_import",
        "prints_20mb",
        "nests_a_frame",
    ):
        shutil.copytree(filled, submissions / student)
    shutil.copytree(ROOT / "course", submissions / "link_farm")
    _append(
        submissions / "link_farm",
        "03_frames",
        LINK_FARM.format(solutions=ROOT / "solutions"),
    )
    os.mkfifo(submissions / "fifo" / "03_frames" / "zz_pipe.ipynb")
    _append(submissions / "fifo", "03_frames", "import os\n\nos.mkfifo('zz_scratch.ipynb')\n")
    with (submissions / "sparse" / "03_frames" / "zz_big.ipynb").open("wb") as handle:
        handle.truncate(100 * 1024**3)
    _append(submissions / "forges_the_drive", "09_mission", FORGES_THE_DRIVE, export=True)
    _append(
        submissions / "hangs_on_import",
        "05_odometry",
        "SETTLING_TIME = __import__('time').sleep(10**6)\n",
        export=True,
    )
    _append(submissions / "prints_20mb", "03_frames", "print('x' * 20_000_000)\n")
    _append(submissions / "nests_a_frame", "09_mission", NESTS_A_FRAME, export=True)
    results = grade_class(
        submissions,
        out,
        jobs=2,
        names=GRADED,
        limits=Limits(cell_seconds=CELL, submission_seconds=seconds(300), mission_seconds=MISSION),
    )
    return {result.student: result for result in results}, out


def _reasons(result):
    return {name: driving.reasons for name, driving in result.missions.items()}


def _lost(result):
    return sorted(grade_id for (_, grade_id), (score, most) in result.cells.items() if score < most)


def test_the_reference_student_is_graded_as_if_alone(graded):
    results, _ = graded
    reference = results["reference"]
    assert reference.problems == []
    assert reference.total == reference.max_total > 0
    assert reference.driving_score == 100, _reasons(reference)
    assert len(results) == 8


def test_links_to_the_solutions_made_during_the_run_are_never_read(graded):
    results, _ = graded
    farm = results["link_farm"]
    assert farm.total == 0
    assert farm.driving_score == 0
    for driving in farm.missions.values():
        assert driving.reasons[0].startswith("The mission could not run"), driving.reasons
        assert "Finish notebook" in driving.reasons[0]


def test_a_fifo_neither_hangs_the_grader_nor_costs_a_point(graded):
    results, _ = graded
    fifo = results["fifo"]
    assert _lost(fifo) == []
    assert fifo.driving_score == 100
    assert fifo.problems == ["03_frames: zz_pipe.ipynb is a FIFO; it was left out."]


def test_a_sparse_file_is_left_out_and_said(graded):
    results, _ = graded
    sparse = results["sparse"]
    assert _lost(sparse) == []
    assert sparse.problems == [
        "03_frames: zz_big.ipynb is 102400.0 MB; at most 50.0 MB is read. It was left out."
    ]


def test_a_forged_drive_keeps_its_tests_but_loses_the_moves(graded):
    results, _ = graded
    idle = results["forges_the_drive"]
    assert _lost(idle) == []
    for driving in idle.missions.values():
        assert driving.score == 40, driving.parts
        assert any("did not move" in reason for reason in driving.reasons)


def test_code_that_hangs_on_import_is_stopped_and_reported(graded):
    results, _ = graded
    stuck = results["hangs_on_import"]
    assert _lost(stuck) == []
    assert stuck.driving_score == 0
    first, *others = stuck.missions.values()
    assert first.reasons == [f"The mission did not end within {MISSION} s of wall time."]
    assert [driving.reasons for driving in others] == [
        [
            "Not driven: the square_then_circle mission did not end within "
            f"{MISSION} s of wall time, and the same nodes drive this one."
        ]
    ] * 3
    # A notebook's cells that import the solution would run out of their time as any endless
    # cell does (test_adversarial.py, infinite_loop); 03_frames imports none of it.
    assert stuck.problems == [
        f"Driving: the square_then_circle mission did not end within {MISSION} s of wall time."
    ]


def test_a_huge_print_is_cut_in_the_stored_notebook_and_said(graded):
    results, out = graded
    loud = results["prints_20mb"]
    assert _lost(loud) == []
    (problem,) = loud.problems
    assert problem.startswith("03_frames: cell ")
    assert problem.endswith(" showed 20.0 MB of output; the stored notebook keeps the first 2.0 MB")
    stored = out / "work" / "autograded" / "prints_20mb" / "03_frames" / "03_frames.ipynb"
    assert stored.stat().st_size < 3_000_000


def test_a_frame_that_nests_too_deeply_stops_the_missions_not_the_grading(graded):
    results, _ = graded
    nested = results["nests_a_frame"]
    assert nested.complete
    assert _lost(nested) == []
    assert not [problem for problem in nested.problems if problem.startswith("Not graded")]
    for driving in nested.missions.values():
        assert any("nests more than 32 levels deep" in reason for reason in driving.reasons), (
            driving.reasons
        )
