"""The main job: a mission on the virtual Duckiebot with a solution, its bag and its report."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from duckielib.bags import Bag, BagWriter
from duckielib.bags.behaviour import mission_report
from duckielib.errors import ConfigError
from duckielib.missions import D_SHAPE, SQUARE_THEN_CIRCLE
from duckielib.solution import (
    MISSION_PARTS,
    SolutionError,
    export_solution,
    load_solution,
    reference_solution_dir,
)
from duckielib.tools.runner import RECORDED, MissionError, run_mission


@pytest.fixture(scope="module")
def reference():
    return load_solution(required=MISSION_PARTS)


@pytest.fixture(scope="module")
def square(reference, tmp_path_factory):
    return run_mission(reference, out=tmp_path_factory.mktemp("square"), animation=False)


def test_the_reference_drives_the_square_then_circle_as_asked(square):
    report = square.report
    assert [(run.name, run.color) for run in report.states] == [
        (state.name, state.color) for state in SQUARE_THEN_CIRCLE.states
    ]
    assert report.finished
    assert report.states_in_order
    assert report.stops_held
    for run in report.states:
        if run.name == "wait":
            assert run.duration == pytest.approx(5.0, abs=0.2)
            assert run.moved < 0.005
    square_leg = report.states[1]
    assert square_leg.moved > 1.7  # the far corner is 1.25 * sqrt(2) m away
    assert report.problems == []


def test_on_the_ideal_robot_odometry_and_truth_agree_and_the_robot_comes_home(square):
    distance, heading = square.report.odometry_error
    assert distance < 0.05
    assert math.degrees(heading) < 5.0
    assert square.report.distance_to_start < 0.10
    assert square.report.closed


def test_summary_json_holds_the_figures_the_issue_names(square):
    summary = json.loads(square.files["summary"].read_text())
    for key in (
        "states",
        "total_time",
        "final_pose_odometry",
        "final_pose_truth",
        "distance_to_start",
        "realtime_factor",
    ):
        assert key in summary, key
    assert [state["name"] for state in summary["states"]] == [
        state.name for state in SQUARE_THEN_CIRCLE.states
    ]
    assert all({"name", "color", "start", "end"} <= set(state) for state in summary["states"])
    assert summary["states"][0]["start"] == 0.0
    assert summary["total_time"] == pytest.approx(summary["states"][-1]["end"])
    assert len(summary["final_pose_truth"]) == 3
    assert len(summary["final_pose_odometry"]) == 3
    assert summary["realtime_factor"] > 1
    assert summary["noise"] == "ideal"
    assert summary["solution"] == "your"


def test_the_bag_holds_every_recorded_topic_and_reads_back_to_the_same_report(square):
    bag = Bag(square.files["bag"])
    for name in RECORDED:
        assert bag.topic("/duckiebot/" + name).count > 0, name
    again = mission_report(bag, SQUARE_THEN_CIRCLE)
    assert again.as_dict() == square.report.as_dict()
    assert square.files["trajectory"].stat().st_size > 10_000
    assert "mission_node" in square.files["log"].read_text()


def test_lights_recorded_late_count_from_when_the_emitter_showed_them(square, tmp_path):
    # A recorder in another process (rosbag record) may connect to the latched LED topic a
    # second after the first state began and only then receive the pattern shown.
    bag = Bag(square.files["bag"])
    led_topic = "/duckiebot/led_emitter_node/led_pattern"
    late = tmp_path / "late.bag"
    with BagWriter(late) as writer:
        for topic, recorded_ns, data in bag.raw_messages(bag.topics):
            info = bag.topic(topic)
            late_ns = max(recorded_ns, 1_500_000_000) if topic == led_topic else recorded_ns
            writer.write_raw(topic, info.type, info.md5sum, info.message_definition, late_ns, data)
    first_led = Bag(late).read(led_topic)[1]
    assert first_led.time == 1.5
    assert first_led.message.header.stamp.to_sec() < 1.0
    report = mission_report(late, SQUARE_THEN_CIRCLE)
    assert [run.color for run in report.states] == [run.color for run in square.report.states]
    assert report.states_in_order, report.problems


def test_a_run_is_deterministic_for_a_seed(reference, square, tmp_path):
    again = run_mission(reference, out=tmp_path, animation=False)
    assert again.report.as_dict() == square.report.as_dict()


def test_nodes_in_threads_drive_the_same_mission_as_greenlets(
    reference, square, tmp_path, monkeypatch
):
    from duckielib.ros import graph as graph_module

    monkeypatch.setattr(graph_module, "_greenlet", None)  # as without the greenlet package
    again = run_mission(reference, out=tmp_path, animation=False)
    assert again.report.as_dict() == square.report.as_dict()


def test_the_d_variant_is_the_same_node_with_other_data(reference, tmp_path):
    run = run_mission(reference, mission="d_shape", out=tmp_path, animation=False)
    assert run.report.states_in_order
    assert run.report.stops_held
    assert run.report.states[1].name == "d"
    assert [run.name for run in run.report.states] == [state.name for state in D_SHAPE.states]
    assert run.report.closed, run.report.problems


def test_the_realistic_robot_reports_its_figures(reference, tmp_path):
    run = run_mission(
        reference, noise="realistic", seed=3, stop_color="WHITE", out=tmp_path, animation=True
    )
    assert [run.color for run in run.report.states if run.name == "wait"] == ["WHITE"] * 3
    assert run.summary["noise"] == "realistic"
    assert run.summary["odometry_error"]["distance"] >= 0
    assert run.files["animation"].read_bytes()[:6] == b"GIF89a"
    assert "realistic robot (seed 3)" in run.text()


def strip_colors(frame, colors, tolerance=24, least=1500):
    """The names of ``colors`` ({name: rgb}) that fill the LED strip beside the mat in ``frame``."""
    panel = frame[:, int(0.6 * frame.shape[1]) :].astype(int)
    return [
        name
        for name, rgb in colors.items()
        if np.all(np.abs(panel - rgb) <= tolerance, axis=2).sum() >= least
    ]


def test_the_mission_animation_shows_each_states_lights_in_order(reference, tmp_path):
    from PIL import Image, ImageSequence

    from duckielib.leds import pattern_colors, pattern_named

    run = run_mission(reference, out=tmp_path, animation=True)
    wanted = [state.color for state in run.report.states]
    colors = {
        name: np.round(np.asarray(pattern_colors(pattern_named(name))[0]) * 255)
        for name in set(wanted)
    }
    seen = []
    with Image.open(run.files["animation"]) as gif:
        assert gif.size[0] >= 800
        assert gif.n_frames >= 60
        for frame in ImageSequence.Iterator(gif):
            shown = strip_colors(np.asarray(frame.convert("RGB")), colors)
            assert len(shown) <= 1
            if shown and (not seen or seen[-1] != shown[0]):
                seen.append(shown[0])
    # Every state's colour shows, in the states' order (states in a row with one colour
    # show as one).
    in_order = [
        name for index, name in enumerate(wanted) if index == 0 or wanted[index - 1] != name
    ]
    assert seen == in_order


def test_an_unwritten_part_names_the_notebook_to_finish(tmp_path):
    unwritten_pid = """

class PID:
    def __init__(self, kp, ki, kd, limit):
        pass

    def update(self, error, dt):
        raise NotImplementedError()

    def reset(self):
        pass
"""
    module = tmp_path / "mine.py"
    module.write_text(export_solution(reference_solution_dir()).source + unwritten_pid)
    out = tmp_path / "run"
    # As for a folder of notebooks: the run stops before it starts, naming what to write.
    with pytest.raises(SolutionError, match=r"^Finish notebook 07_control: write PID \("):
        run_mission(str(module), out=out, animation=False)
    assert not out.exists()


def test_a_mission_that_never_ends_is_stopped_with_a_sentence(reference, tmp_path):
    def mission_node(mission):
        import rospy

        rospy.init_node("mission_node")
        rospy.spin()

    parts = {**vars(reference), "mission_node": mission_node}
    with pytest.raises(MissionError, match="did not announce 'done' within 30 simulated"):
        run_mission(parts, out=tmp_path, animation=False, time_limit=30)


def test_wrong_colours_are_reported_as_problems(reference, tmp_path):
    def light_service_node():
        import rospy
        from duckietown_msgs.srv import ChangePattern, ChangePatternResponse

        rospy.init_node("light_service_node")
        rospy.Service("~set_color", ChangePattern, lambda request: ChangePatternResponse())
        rospy.spin()

    parts = {**vars(reference), "light_service_node": light_service_node}
    run = run_mission(parts, out=tmp_path, animation=False)
    assert not run.report.states_in_order
    assert run.report.problems[0] == (
        "State 1 should be wait in RED, but the bag shows wait in WHITE."
    )


def test_unknown_choices_are_refused_before_anything_runs(reference, tmp_path):
    with pytest.raises(ConfigError, match="no mission 'circle'"):
        run_mission(reference, mission="circle", out=tmp_path)
    with pytest.raises(ConfigError, match="not an LED pattern"):
        run_mission(reference, stop_color="PINK", out=tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_the_command_line_runs_the_mission_and_refuses_an_unfinished_course(tmp_path):
    root = Path(__file__).resolve().parents[2]
    done = subprocess.run(
        [sys.executable, "-m", "duckielib.tools.cli", "mission", "--out", str(tmp_path / "run")],
        capture_output=True,
        text=True,
        check=False,
        cwd=root,
    )
    assert done.returncode == 0, done.stderr
    assert "every check passed" in done.stdout
    assert {path.name for path in (tmp_path / "run").iterdir()} >= {
        "mission.bag",
        "trajectory.png",
        "mission.gif",
        "summary.json",
        "log.txt",
    }
    refused = subprocess.run(
        [
            sys.executable,
            "-m",
            "duckielib.tools.cli",
            "mission",
            "--solution",
            "course",
            "--out",
            "x",
        ],
        capture_output=True,
        text=True,
        check=False,
        cwd=root,
    )
    assert refused.returncode == 1
    assert refused.stderr.startswith("duckie: Finish notebook 05_odometry: write ")
    assert "Traceback" not in refused.stderr


def _failing_after(reference, x_limit, failure):
    """The reference with an estimate_pose that fails (``failure(pose)``) once x passes a limit."""

    def estimate_pose(R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right):  # noqa: N803
        pose = reference.estimate_pose(
            R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right
        )
        return failure(pose) if pose[0] > x_limit else pose

    return {**vars(reference), "estimate_pose": estimate_pose}


def _nan_heading(pose):
    return pose[0], pose[1], math.nan


def _divided_by_zero(pose):
    return pose[0] / 0.0


@pytest.mark.parametrize(
    ("failure", "said"),
    [
        (_nan_heading, r"returned \(0\.8\d+, 0\.3\d+, nan\): every number it returns must be"),
        (_divided_by_zero, r"raised ZeroDivisionError in _divided_by_zero: float division by "),
    ],
    ids=["nan", "exception"],
)
def test_the_first_failure_of_the_odometry_ends_the_run_at_once(reference, tmp_path, failure, said):
    # Half-way along the square's first side (it starts about 7 s in), the solution fails.
    parts = _failing_after(reference, 0.8, failure)
    pattern = r"^estimate_pose\(0\.0318, 0\.1, 0\.7\d+, 0\.3\d+, [\d.e-]+, [\d.]+, [\d.]+\), from "
    with pytest.raises(SolutionError, match=pattern + r"notebook 05_odometry, ") as caught:
        run_mission(parts, out=tmp_path, animation=False)
    message = str(caught.value)
    assert re.search(said, message), message
    assert message.endswith(f"The run's log is in {tmp_path / 'log.txt'}.")
    assert "\n" not in message
    # The robot stopped there and then, its bag whole, its wheels at zero.
    bag = Bag(tmp_path / "mission.bag")
    executed = bag.read("/duckiebot/wheels_driver_node/wheels_cmd_executed")
    assert executed[-1].time < 10.0, "the run ended when the odometry failed"
    assert (executed[-1].message.vel_left, executed[-1].message.vel_right) == (0.0, 0.0)
    assert not (tmp_path / "mission.bag.active").exists()
    # One error in the log, with one traceback, not one per encoder reading.
    log = (tmp_path / "log.txt").read_text()
    assert log.count("[ERROR]") == 1
    # A solution's exception comes with its own traceback (and then the node's).
    tracebacks = 1 if failure is _nan_heading else 2
    assert log.count("Traceback (most recent call last)") == tracebacks
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["error"] == message


def test_bad_places_for_the_files_and_bad_seeds_are_refused_with_a_sentence(reference, tmp_path):
    with pytest.raises(ConfigError, match=r"^The simulator's seed must be a whole number 0 or"):
        run_mission(reference, seed=-1, out=tmp_path)
    a_file = tmp_path / "notes.txt"
    a_file.write_text("mine")
    with pytest.raises(MissionError, match=r"notes\.txt is a file, not a folder: choose a folder"):
        run_mission(reference, out=a_file)
    assert a_file.read_text() == "mine"
    with pytest.raises(MissionError, match=r"^Cannot create the folder .*notes\.txt/run for the"):
        run_mission(reference, out=a_file / "run")


def test_an_error_a_node_only_logged_is_said_as_one_sentence(reference, tmp_path):
    def light_service_node():
        import rospy
        from duckietown_msgs.msg import WheelEncoderStamped

        def on_tick(reading):
            raise ValueError("no light for this tick")

        rospy.Subscriber("left_wheel_encoder_node/tick", WheelEncoderStamped, on_tick)
        reference.light_service_node()

    parts = {**vars(reference), "light_service_node": light_service_node}
    with pytest.raises(MissionError) as caught:
        run_mission(parts, out=tmp_path, animation=False, time_limit=3)
    assert str(caught.value) == (
        "The /duckiebot/light_service_node logged an error: ValueError: no light for this tick. "
        f"The run's log is in {tmp_path / 'log.txt'}."
    )
