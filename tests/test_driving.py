"""The driving score: a student's exported code drives the mission in the sandbox."""

from __future__ import annotations

import shutil
import struct

import pytest

from autograder.course import ROOT
from autograder.driving import MAX_SCORE, POINTS, drive, score_bag
from autograder.sandbox import Limits, check_sandbox
from duckielib.runner import run_mission
from duckielib.solution import export_solution

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def sandbox():
    if shutil.which("bwrap") is None:
        pytest.skip("bubblewrap is not installed; run `make ros`.")
    check_sandbox()


def test_the_reference_drives_the_mission_for_full_marks(sandbox, tmp_path):
    driving = drive(ROOT / "solutions", tmp_path / "box", Limits())
    assert driving.score == MAX_SCORE == 100
    assert driving.parts == POINTS
    assert driving.reasons == []
    assert [state["name"] for state in driving.summary["states"]] == [
        "wait", "square", "wait", "return", "wait", "circle",
    ]  # fmt: skip
    assert driving.summary["distance_to_start"] < 0.05
    assert driving.figure.startswith(b"\x89PNG")


def test_an_unfinished_course_scores_zero_with_the_students_reason(sandbox, tmp_path):
    driving = drive(ROOT / "course", tmp_path / "box", Limits())
    assert driving.score == 0
    (reason,) = driving.reasons
    assert reason.startswith("The mission could not run: Finish notebook")
    assert "log.txt" not in reason


def test_a_mission_that_never_ends_is_stopped_by_the_wall_clock(sandbox, tmp_path):
    source = export_solution(ROOT / "solutions").source
    solution = tmp_path / "solution.py"
    solution.write_text(source + "\n\ndef mission_node(mission):\n    while True:\n        pass\n")
    driving = drive(solution, tmp_path / "box", Limits(mission_seconds=15))
    assert driving.score == 0
    assert driving.reasons == ["The mission did not end within 15 s of wall time."]


def test_wrong_colours_lose_the_states_and_stops_but_keep_the_bag_and_closure(tmp_path):
    run_mission(out=tmp_path / "run", stop_color="GREEN", animation=False)
    driving = score_bag(tmp_path / "run")
    assert driving.parts == {"bag": 10.0, "states": 0.0, "stops": 0.0, "closure": 25.0}
    assert driving.score == 35
    assert driving.reasons[0] == ("State 1 should be wait in RED, but the bag shows wait in GREEN.")


def test_a_missing_or_broken_bag_scores_zero(tmp_path):
    assert score_bag(tmp_path).reasons == ["The mission wrote no bag."]
    (tmp_path / "mission.bag").write_bytes(b"#ROSBAG V2.0\n" + struct.pack("<i", 99) + b"junk")
    broken = score_bag(tmp_path)
    assert broken.score == 0
    assert broken.reasons[0].startswith("The mission's bag cannot be read:")
