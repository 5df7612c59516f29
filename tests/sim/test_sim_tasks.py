"""The notebooks' driving experiments: moves planned, runs reported, nodes that end."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from duckielib.missions import TASK_START
from duckielib.sim import tasks
from duckielib.solution import SolutionError, load_solution


def made_up_run(log, moves, truth):
    """A run with a robot that is nowhere in particular, and a recorded truth."""
    bot = SimpleNamespace(time=12.0, sim=SimpleNamespace(pose=(0.32, 0.42, 0.0)))
    store = {"simulator_node/ground_truth_pose": truth, "odometry_node/pose": []}
    return tasks.TaskRun(bot, moves, log, store)


def test_planned_poses_follow_the_moves_and_keep_theta_in_0_to_2_pi():
    poses = tasks.planned_poses((0.0, 0.0, 0.0), [("straight", 1.0), ("rotate", -math.pi / 2)])
    assert poses[0] == pytest.approx((1.0, 0.0, 0.0))
    assert poses[1] == pytest.approx((1.0, 0.0, 1.5 * math.pi))
    back = tasks.planned_poses((0.5, 0.5, math.pi / 2), [("straight", -0.25)])
    assert back[0] == pytest.approx((0.5, 0.25, math.pi / 2))


def test_amounts_and_expected_time_of_moves():
    assert tasks.describe_amount(("straight", 1.25)) == "+1.25 m"
    assert tasks.describe_amount(("rotate", -math.pi / 2)) == "-90°"
    moves = [("straight", 1.0), ("rotate", -math.pi)]
    assert tasks.expected_seconds(moves, 0.5, math.pi, 1.0) == pytest.approx(2 + 1 + 1 + 1)


def test_truth_at_takes_the_last_sample_at_or_before_the_time():
    run = made_up_run([], [], [(0.0, 1.0, 2.0, 0.0), (1.0, 3.0, 4.0, 0.5)])
    assert run.truth_at(0.5) == (1.0, 2.0, 0.0)
    assert run.truth_at(1.0) == (3.0, 4.0, 0.5)
    assert run.truth_at(-1.0) == (1.0, 2.0, 0.0)
    assert list(run.truth.x) == [1.0, 3.0]
    assert len(run.odometry) == 0


def test_moves_done_says_which_move_the_driver_never_finished():
    run = made_up_run([{"move": ("straight", 1.25)}], [("straight", 1.25), ("straight", -1.25)], [])
    assert tasks.moves_done(run, 1) == run.log
    with pytest.raises(SolutionError, match=r"never finished move 2 of 2 \(straight -1\.25 m\)"):
        tasks.moves_done(run)


def test_the_report_compares_plan_odometry_and_truth(capsys):
    start = (0.0, 0.0, 0.0)
    record = {"move": ("straight", 1.0), "t_end": 5.0, "at_end": (1.02, 0.0, 0.0)}
    run = made_up_run([record], [("straight", 1.0), ("rotate", 1.0)], [(5.0, 0.97, 0.04, 0.1)])
    tasks.print_task_report(run, start, lambda target, current: target - current)
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("move ")
    assert lines[0].endswith("truth \N{MINUS SIGN} planned")
    assert lines[1] == (
        "straight  +1.00 m  (1.000, 0.000, 0.000)  (1.020, 0.000, 0.000)  "
        "(0.970, 0.040, 0.100)    5.0 cm,  +5.7°"
    )
    assert lines[2].startswith("The driver finished 1 of the 2 moves in 12 simulated seconds")


def test_a_speed_sweep_row_and_its_table():
    record = {"move": ("straight", 1.0), "t_end": 5.0, "at_end": (1.1, 0.0, 0.0)}
    run = made_up_run([record, record], [], [(5.0, 0.9, 0.05, 0.0)])
    along = lambda start, pose: pose[0] - start[0]  # noqa: E731 - facing +x
    lateral = lambda start, pose: pose[1] - start[1]  # noqa: E731
    row = tasks.speed_sweep_row(run, 0.2, (0.0, 0.0, 0.0), 1.0, along, lateral)
    assert row["along"] == pytest.approx(-0.1)
    assert row["side"] == pytest.approx(0.05)
    assert row["odometry_along"] == pytest.approx(0.2)
    assert row["odometry_side"] == pytest.approx(-0.05)
    assert row["from_start"] == pytest.approx(math.hypot(0.32, 0.42))
    stuck = {"v": 0.03, "done": 0, "seconds": 90.0, "from_start": 0.001}
    table = tasks.speed_sweep_table([stuck, row], moves=2).splitlines()
    assert (
        table[2] == "   0.030   did not finish: 0 of 2 moves in 90 s, ending 0.1 cm from the start"
    )
    assert table[3].split() == ["0.200", "-10.0", "5.0", "20.0", "-5.0", "20.6", "52.8"]


def test_a_far_odometry_is_said_in_words(capsys):
    assert not tasks.warn_if_odometry_is_far((0.0, 0.0), (0.3, 0.4), far=1.0)
    assert tasks.warn_if_odometry_is_far((0.0, 0.0), (3.0, 4.0), far=1.0)
    said = capsys.readouterr().out
    assert said.startswith("Your odometry ended 500 cm from where the robot really was")
    assert "fix notebook 05 first" in said


def test_the_ideal_robot_turns_on_the_spot_and_clockwise_is_positive():
    turned = tasks.turned_on_the_spot("ideal", -1.5, seconds=0.5)
    assert 20.0 < turned < 60.0
    assert tasks.turned_on_the_spot("ideal", 0.0, seconds=0.2) == pytest.approx(0.0, abs=1e-6)


def test_a_node_that_returns_and_one_that_is_killed():
    solution = load_solution(required=["delta_phi", "estimate_pose", "WheelPairing"])

    def quick_driver():
        tasks.rospy.init_node("quick_driver")  # and returns at once

    def sitting_driver():
        tasks.rospy.init_node("sitting_driver")
        tasks.rospy.spin()

    how, ended_at, alive, rolled = tasks.how_a_node_ends(
        quick_driver, name="quick_driver", solution=solution, start=TASK_START, watch_for=0.5
    )
    assert (how, alive, rolled) == ("returned", False, 0.0)
    assert ended_at < 1.0
    how, ended_at, alive, _ = tasks.how_a_node_ends(
        sitting_driver, name="sitting_driver", solution=solution, kill_after=0.3, watch_for=0.2
    )
    assert (how, alive) == ("killed", False)
    assert ended_at == pytest.approx(0.3)


def test_encoders_fall_silent_while_the_robot_drives():
    def driver(v):
        rospy = tasks.rospy
        rospy.init_node("driver")
        cmd = rospy.Publisher("car_cmd_switch_node/cmd", tasks.Twist2DStamped, queue_size=1)
        rate = rospy.Rate(20)
        while not rospy.is_shutdown():
            cmd.publish(tasks.Twist2DStamped(v=v, omega=0.0))
            rate.sleep()

    bot, times, distances = tasks.drive_until_encoders_fall_silent(
        driver, 0.2, silence_at=0.3, end_at=0.6, noise="ideal"
    )
    assert times[0] == pytest.approx(0.02)
    assert times[-1] >= 0.6
    assert np.all(np.diff(distances) >= -1e-9)
    assert distances[-1] > 0.02
    encoder = bot.graph.nodes.get(f"{bot.namespace}left_wheel_encoder_node")
    assert encoder is None or encoder.is_shutdown
    bot.shutdown()
