"""The driving score: a student's exported code drives the mission in the sandbox.

Each adversarial solution below is the reference's export with one part changed, run for real:
a robot that only pretends to drive, missions that never end, a square turned the wrong way.
"""

from __future__ import annotations

import io
import os
import re
import struct
import subprocess

import pytest
from adversarial.cases import FORGES_THE_DRIVE, NEVER_DRIVES
from pace import seconds

from autograder.course import ROOT
from autograder.driving import (
    BAG_LIMIT,
    MAX_SCORE,
    MISSIONS,
    POINTS,
    _score_unfinished,
    drive_missions,
    part_points,
    score_bag,
)
from autograder.sandbox import Limits
from duckielib.bags import Bag
from duckielib.solution import export_solution
from duckielib.tools.runner import MissionError, run_mission

pytestmark = pytest.mark.slow


_DONE = 'announce.publish(String(data="done"))'


@pytest.fixture(scope="module")
def reference():
    return export_solution(ROOT / "solutions").source


def drive(solution, folder, limits, mission="square_then_circle"):
    """How ``solution`` (notebooks or an export) drives one mission in the sandbox."""
    return drive_missions(solution, folder, limits, missions=[mission])[mission]


def changed(reference, old, new, path):
    """The reference solution with ``old`` replaced by ``new``, written to ``path``."""
    assert reference.count(old) == 1, old
    path.write_text(reference.replace(old, new), encoding="utf-8")
    return path


def test_the_points_split_the_driving_over_the_moving_states():
    assert POINTS == {"bag": 5, "states": 20, "stops": 15, "motion": 60}
    assert MAX_SCORE == 100
    assert part_points() == {
        "bag": 5, "states": 20, "stops": 15, "square": 20, "return": 20, "circle": 20,
    }  # fmt: skip
    assert part_points("d_shape")["d"] == 20


@pytest.fixture(scope="module")
def reference_drives(graded_course):
    """The reference's notebooks driving every graded mission in the sandbox: its drives in
    the class graded once per run (tests/shared_runs.py)."""
    _, results, _ = graded_course
    return results["reference"].missions


def test_the_reference_drives_every_graded_mission_for_full_marks(reference_drives):
    missions = reference_drives
    assert (
        list(missions)
        == list(MISSIONS)
        == ["square_then_circle", "d_shape", "straight", "rotation"]
    )
    assert {name: driving.score for name, driving in missions.items()} == dict.fromkeys(
        MISSIONS, 100
    )
    assert missions["straight"].parts == {
        "bag": 5, "states": 20, "stops": 15, "forward": 30, "back": 30,
    }  # fmt: skip
    assert missions["rotation"].parts == {
        "bag": 5, "states": 20, "stops": 15, "clockwise": 30, "back": 30,
    }  # fmt: skip
    assert [(m["state"], m["passed"]) for m in missions["rotation"].summary["motion"]] == [
        ("clockwise", 1), ("back", 1),
    ]  # fmt: skip
    assert all(driving.figure.startswith(b"\x89PNG") for driving in missions.values())


def test_the_nodes_process_leaves_nothing_the_grader_reads(sandbox, tmp_path):
    # The robot's side, in the grader, records the bag, and the grader draws each figure
    # from it: the nodes' process writes nothing into the folder the grader reads.
    box = tmp_path / "box"
    (driving,) = drive_missions(ROOT / "solutions", box, Limits(), missions=["rotation"]).values()
    assert driving.score == 100
    assert sorted(path.name for path in box.iterdir()) == ["solution.py"]


def test_a_figure_left_in_a_run_folder_never_reaches_the_page(reference_drives, tmp_path):
    # A run folder of duckie mission may hold any trajectory.png next to its bag: the page
    # shows the grader's drawing of the bag it scored.
    missions = reference_drives
    run_mission(mission="rotation", out=tmp_path / "rotation", animation=False)
    forged = b"\x89PNG\r\n\x1a\n" + b"not the run" * 100
    (tmp_path / "rotation" / "trajectory.png").write_bytes(forged)
    driving = score_bag(tmp_path / "rotation", "rotation")
    assert driving.score == 100
    assert driving.figure.startswith(b"\x89PNG")
    assert driving.figure != forged
    assert driving.figure == missions["rotation"].figure


def test_a_forged_drive_scores_what_the_robot_really_did(sandbox, tmp_path, reference):
    # The node never drives: it moves the simulator's robot body itself, publishes ideal poses
    # as the ground truth, and looks for the true pose to steer on. In one process with the
    # simulator the forgery works (the recorded truth follows the ideal path) ...
    forged = tmp_path / "forged.py"
    forged.write_text(reference + "\n\n" + FORGES_THE_DRIVE, encoding="utf-8")
    run_mission(forged, mission="straight", out=tmp_path / "run", animation=False)
    fooled = score_bag(tmp_path / "run", "straight")
    assert fooled.parts["forward"] == fooled.parts["back"] == 30
    assert "the true pose is offered" in (tmp_path / "run" / "log.txt").read_text()
    # ... but graded, the nodes run apart from the robot: the robot never moved.
    driving = drive(forged, tmp_path / "box", Limits(), mission="straight")
    assert driving.parts == {
        "bag": 5, "states": 20, "stops": 15, "forward": 0, "back": 0,
    }  # fmt: skip
    assert driving.reasons[0] == (
        "In state forward, the robot did not move; its moves are: straight 1.25 m."
    )


def test_a_node_that_never_ends_loses_the_states_points_with_a_sentence(
    sandbox, tmp_path, reference
):
    # Everything done, "done" announced, and then the node spins for ever: it never exits.
    spins = changed(reference, "shutdown.publish(Empty())", "rospy.spin()", tmp_path / "s.py")
    driving = drive(spins, tmp_path / "box", Limits(), mission="rotation")
    assert driving.parts == {
        "bag": 5, "states": 0, "stops": 15, "clockwise": 30, "back": 30,
    }  # fmt: skip
    assert driving.reasons[0] == (
        "The mission could not run to its end: The mission node announced 'done' but did not "
        "end within 240 simulated seconds: a node must return once its work is done (a loop "
        "that never stops, or rospy.spin(), keeps it alive)."
    )


def test_a_mission_that_runs_out_of_wall_time_leaves_the_next_ones_undriven(sandbox, tmp_path):
    source = export_solution(ROOT / "solutions").source
    solution = tmp_path / "solution.py"
    # It calls rospy, so the graph does not stop it, but each step costs real time: the
    # simulation crawls, and only the wall clock ends it.
    slow = (
        "\n\ndef mission_node(mission):\n    from duckielib.ros import rospy\n"
        "    rospy.init_node('mission_node')\n"
        "    while True:\n        sum(range(200000))\n        rospy.get_time()\n"
    )
    solution.write_text(source + slow)
    missions = drive_missions(solution, tmp_path / "box", Limits(mission_seconds=seconds(5)))
    assert missions["square_then_circle"].timed_out
    assert {name: driving.score for name, driving in missions.items()} == dict.fromkeys(MISSIONS, 0)
    assert missions["rotation"].reasons == [
        "Not driven: the square_then_circle mission did not end within "
        f"{seconds(5)} s of wall time, and the same nodes drive this one."
    ]


def test_the_reference_drives_the_mission_for_full_marks(reference_drives):
    driving = reference_drives["square_then_circle"]
    assert driving.score == MAX_SCORE == 100
    assert driving.parts == part_points()
    assert driving.reasons == []
    assert driving.finished
    assert [state["name"] for state in driving.summary["states"]] == [
        "wait", "square", "wait", "return", "wait", "circle",
    ]  # fmt: skip
    assert [(m["state"], m["passed"], len(m["checks"])) for m in driving.summary["motion"]] == [
        ("square", 6, 6), ("return", 2, 2), ("circle", 3, 3),
    ]  # fmt: skip
    assert driving.summary["distance_to_start"] < 0.05
    assert driving.figure.startswith(b"\x89PNG")
    # The feedback page's animation, drawn by the grader from its copy of the bag.
    from PIL import Image

    with Image.open(io.BytesIO(driving.animation)) as gif:
        assert gif.format == "GIF"
        assert gif.size[0] >= 800
        assert gif.n_frames == 64


def test_the_realistic_robot_is_judged_by_where_it_really_went(tmp_path):
    # On the realistic robot odometry drifts as on a real DB21 (smaller wheels, wider track
    # than nominal): the reference's turns believe they turned 90 degrees and really turn
    # less, and the judge, measuring the ground truth, says so. The course grades the ideal
    # robot; this run shows what a student would meet on a real one.
    run_mission(out=tmp_path / "run", noise="realistic", seed=0, animation=False)
    driving = score_bag(tmp_path / "run")
    assert driving.finished
    assert driving.parts["states"] == 20
    assert driving.parts["stops"] == 15
    assert driving.score < 60
    first = next(reason for reason in driving.reasons if reason.startswith("In state"))
    turned = int(re.match(r"In state square, turn 1 turned (\d+)° clockwise", first).group(1))
    assert 70 <= turned <= 85, first
    # On the open floor nothing holds the drifting robot: it ends as far from its start as real
    # robots did (62 to 64 cm), and no wall is blamed.
    assert 0.5 < driving.summary["distance_to_start"] < 0.9
    assert not any(reason.startswith("The robot touched") for reason in driving.reasons)


def test_a_robot_that_never_drives_loses_every_driving_point(tmp_path, reference):
    solution = tmp_path / "solution.py"
    solution.write_text(reference + "\n\n" + NEVER_DRIVES, encoding="utf-8")
    run_mission(solution, out=tmp_path / "run", animation=False)
    driving = score_bag(tmp_path / "run")
    assert driving.parts == {
        "bag": 5, "states": 20, "stops": 15, "square": 0, "return": 0, "circle": 0,
    }  # fmt: skip
    assert driving.score == 40
    assert driving.summary["distance_to_start"] < 0.01, "it never left home"
    assert (
        "In state square, the robot did not move; its moves are: rotate -90°, straight 1.25 m, "
        "rotate +90°, straight 1.25 m, rotate +90°, straight 1.25 m."
    ) in driving.reasons
    assert (
        "In state return, the robot had driven only 0.00 m since the mission began (the "
        "mission drives 3.75 m before it), so there was nothing to come back from."
    ) in driving.reasons
    assert any(
        reason.startswith("In state circle, the robot did not move") for reason in driving.reasons
    )


def test_a_square_turned_the_wrong_way_loses_the_square_but_not_the_circle(tmp_path, reference):
    # Every turn of the square goes the other way: the first one faces the robot west, and it
    # drives its square mirrored, off the mat's edge onto the open floor (the missions' mat has
    # no walls, as a real one has none). It comes back home from there and drives its circle:
    # only the square is lost.
    wrong = changed(
        reference,
        "goal = (x, y, (theta + move.angle) % (2 * math.pi))",
        "goal = (x, y, (theta - move.angle) % (2 * math.pi))",
        tmp_path / "solution.py",
    )
    run_mission(wrong, out=tmp_path / "run", animation=False)
    driving = score_bag(tmp_path / "run")
    assert driving.parts["square"] <= 20 / 6
    assert driving.parts == {
        "bag": 5, "states": 20, "stops": 15, "square": 3.33, "return": 20, "circle": 20,
    }  # fmt: skip
    assert driving.reasons[0] == "In state square, turn 1 turned 0°; it should turn 90° clockwise."
    assert (
        "side 1 ended 2.50 m from where it should (x = 1.57 m, y = 0.32 m)" in (driving.reasons[1])
    )
    assert not [reason for reason in driving.reasons if not reason.startswith("In state square")]


def test_a_mission_past_the_simulated_time_limit_is_scored_from_its_bag(tmp_path, reference):
    # The node drives every state, then waits for ever instead of announcing "done".
    endless = changed(reference, _DONE, "while True:\n        rospy.sleep(1.0)", tmp_path / "s.py")
    with pytest.raises(MissionError, match="did not announce 'done' within 240 simulated s"):
        run_mission(endless, out=tmp_path / "run", animation=False)
    assert (tmp_path / "run" / "summary.json").is_file(), "the summary is written before it fails"
    driving = score_bag(tmp_path / "run")
    assert driving.parts == {
        "bag": 5, "states": 0, "stops": 15, "square": 20, "return": 20, "circle": 20,
    }  # fmt: skip
    assert not driving.finished


def test_a_mission_that_never_ends_is_scored_from_its_bag_in_the_sandbox(
    sandbox, tmp_path, reference
):
    endless = changed(reference, _DONE, "while True:\n        rospy.sleep(1.0)", tmp_path / "s.py")
    driving = drive(endless, tmp_path / "box", Limits(mission_seconds=seconds(120)))
    assert driving.reasons[:2] == [
        "The mission could not run to its end: The mission did not announce 'done' within 240 "
        "simulated seconds (last log: state circle (YELLOW)).",
        "It is scored from the bag it wrote until then.",
    ]
    assert driving.score == 80, driving.reasons
    assert not any("/" in reason or "log.txt" in reason for reason in driving.reasons)


def test_a_mission_that_never_ends_is_stopped_by_the_wall_clock_and_scored(
    sandbox, tmp_path, reference
):
    # A busy loop after the circle: the simulation cannot go on, so the graph stops the node
    # after the stall limit's real seconds, saying why.
    busy = changed(reference, _DONE, "while True:\n        pass", tmp_path / "s.py")
    driving = drive(
        busy, tmp_path / "box", Limits(mission_seconds=seconds(20), stall_seconds=seconds(3))
    )
    assert driving.reasons[:2] == [STALLED, "It is scored from the bag it wrote until then."]
    assert driving.parts == {
        "bag": 5, "states": 0, "stops": 15, "square": 20, "return": 20, "circle": 20,
    }  # fmt: skip


#: Why the graph stops a mission node whose code never waits (with a stall limit of 3 s).
STALLED = (
    "The mission could not run to its end: The mission node stopped: its code ran for "
    f"{seconds(3)} s of "
    "real time without calling rospy, and simulated time cannot move while a node's code runs: "
    "a loop that waits for a callback or another thread never sees it happen. Wait inside the "
    "loop with rospy.sleep() or rate.sleep()."
)


def test_a_busy_node_from_the_start_scores_zero_saying_why_it_was_stopped(sandbox, tmp_path):
    source = export_solution(ROOT / "solutions").source
    solution = tmp_path / "solution.py"
    solution.write_text(source + "\n\ndef mission_node(mission):\n    while True:\n        pass\n")
    driving = drive(
        solution, tmp_path / "box", Limits(mission_seconds=seconds(15), stall_seconds=seconds(3))
    )
    assert driving.score == 0
    assert driving.reasons == [STALLED]


def test_an_unfinished_course_scores_zero_with_the_students_reason(sandbox, tmp_path):
    driving = drive(ROOT / "course", tmp_path / "box", Limits())
    assert driving.score == 0
    (reason,) = driving.reasons
    assert reason.startswith("The mission could not run to its end: Finish notebook")
    assert "log.txt" not in reason
    assert "/" not in reason


def test_wrong_colours_lose_the_states_and_stops_but_keep_the_driving(tmp_path):
    run_mission(out=tmp_path / "run", stop_color="GREEN", animation=False)
    driving = score_bag(tmp_path / "run")
    assert driving.parts == {
        "bag": 5, "states": 0, "stops": 0, "square": 20, "return": 20, "circle": 20,
    }  # fmt: skip
    assert driving.score == 65
    assert driving.reasons[0] == ("State 1 should be wait in RED, but the bag shows wait in GREEN.")


def test_a_flooded_bag_is_scored_but_not_played_back(tmp_path, monkeypatch):
    import autograder.driving

    run = run_mission(None, out=tmp_path / "run", animation=False)  # the reference
    played = score_bag(tmp_path / "run")
    assert played.animation[:6] == b"GIF89a"
    count = Bag(run.files["bag"]).message_count
    monkeypatch.setattr(autograder.driving, "ANIMATION_MESSAGE_LIMIT", count - 1)
    flooded = score_bag(tmp_path / "run")
    assert flooded.animation is None
    assert flooded.score == played.score == 100


def test_a_missing_or_broken_bag_scores_zero(tmp_path):
    assert score_bag(tmp_path).reasons == ["The mission wrote no bag."]
    (tmp_path / "mission.bag").write_bytes(b"#ROSBAG V2.0\n" + struct.pack("<i", 99) + b"junk")
    broken = score_bag(tmp_path)
    assert broken.score == 0
    assert broken.reasons[0].startswith("The mission's bag cannot be read:")
    assert str(tmp_path) not in broken.reasons[0]


def test_the_moves_geometry_is_the_graders_not_the_librarys():
    from duckielib.bags import behaviour

    assert not hasattr(behaviour, "_follow")
    assert not hasattr(behaviour, "StateMotion")
    assert "motion" not in behaviour.MissionReport.__dataclass_fields__


def _plain(reason):
    return "/" not in reason.replace("/ground_truth_pose", "")


def test_a_run_folder_that_is_a_link_is_not_followed(tmp_path):
    # The link points to a folder with a bag the grader would otherwise read (and reject as
    # broken): the reason shows it never got that far.
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "mission.bag").write_bytes(b"#ROSBAG V2.0\n" + struct.pack("<i", 99) + b"junk")
    (elsewhere / "trajectory.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    (tmp_path / "run").symlink_to(elsewhere)
    driving = score_bag(tmp_path / "run")
    assert driving.score == 0
    assert driving.reasons == [
        "The mission's bag was not read: the run's folder is a symbolic link."
    ]
    assert driving.figure is None
    assert all(_plain(reason) for reason in driving.reasons)


@pytest.mark.timeout(30)
def test_a_fifo_for_a_bag_is_refused_without_blocking(tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    os.mkfifo(run / "mission.bag")
    os.mkfifo(run / "trajectory.png")
    driving = score_bag(run)
    assert driving.score == 0
    assert driving.reasons == ["The mission's bag was not read: it is a FIFO, not a file."]
    assert driving.figure is None
    # A run that stopped early, whose killed recording is a FIFO, is not read either.
    (run / "mission.bag").unlink()
    os.mkfifo(run / "mission.bag.active")
    unfinished = _score_unfinished(run, "square_then_circle", "The mission stopped.")
    assert unfinished.score == 0
    assert unfinished.reasons == [
        "The mission stopped.",
        "The mission's recording was not read: it is a FIFO, not a file.",
    ]


def test_a_bag_over_the_bound_is_not_read(tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    size = 300 * 1024**2
    assert size > BAG_LIMIT
    subprocess.run(["truncate", "-s", str(size), str(run / "mission.bag")], check=True)
    driving = score_bag(run)
    assert driving.score == 0
    assert driving.reasons == [
        "The mission's bag was not read: it is 300.0 MB; at most 200.0 MB is read."
    ]
    assert all(_plain(reason) for reason in driving.reasons)


def test_a_mission_stuck_in_its_square_is_scored_state_by_state(tmp_path, reference):
    # A one-line odometry bug: the counts themselves for their change. The square never ends.
    solution = changed(
        reference, "ticks_turned = ticks - prev_ticks", "ticks_turned = ticks", tmp_path / "s.py"
    )
    # The whole mission takes 62 simulated seconds: in 150, this square has long been stuck.
    with pytest.raises(MissionError, match="within 150 simulated s"):
        run_mission(solution=solution, out=tmp_path / "run", animation=False, time_limit=150)
    driving = score_bag(tmp_path / "run")
    assert driving.parts["return"] == driving.parts["circle"] == 0
    assert driving.parts["bag"] == POINTS["bag"]
    assert "State 4 (return) never began, so its driving could not be checked." in driving.reasons
