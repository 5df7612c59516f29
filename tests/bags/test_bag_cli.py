"""``duckie bag``: info, plot, odometry and repair, and their one-line errors."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path

import pytest
from bagtools import encoder, write_encoders

from duckielib.bags import BagWriter, sample_bag
from duckielib.messages import Pose2DStamped, String

S = 1_000_000_000
SOLUTION = Path(__file__).with_name("bagtools.py")


def duckie(*args):
    return subprocess.run(
        [sys.executable, "-m", "duckielib.tools.cli", "bag", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


def assert_one_line_error(result, text):
    assert result.returncode == 1
    assert result.stdout == ""
    assert result.stderr.count("\n") == 1
    assert "Traceback" not in result.stderr
    assert text in result.stderr


@pytest.fixture
def encoders(tmp_path):
    left = [(k * S // 30, 1000 + 2 * k) for k in range(90)]
    right = [(k * S // 30 + 5_000_000, -500 + 2 * k) for k in range(90)]
    return write_encoders(tmp_path / "ticks.bag", left, right)


def test_info(encoders):
    result = duckie("info", encoders)
    assert result.returncode == 0
    assert "messages:    180" in result.stdout
    assert "damage:" not in result.stdout


def test_info_on_a_bag_damaged_in_the_middle_says_where_and_exits_1(encoders, tmp_path):
    damaged = tmp_path / "mid.bag"
    data = bytearray(encoders.read_bytes())
    middle = len(data) // 2
    data[middle : middle + 64] = bytes(b ^ 0xFF for b in data[middle : middle + 64])
    damaged.write_bytes(bytes(data))
    result = duckie("info", damaged)
    assert result.returncode == 1
    assert "messages:    180" in result.stdout  # what the index lists...
    damage = result.stdout.split("damage:", 1)[1]
    assert "mid.bag is damaged in chunk" in " ".join(damage.split())  # ...and what is wrong
    assert "duckie bag repair" in " ".join(damage.split())
    quick = duckie("info", "--no-check", damaged)  # the index only, as rosbag info reads it
    assert quick.returncode == 0
    assert "damage:" not in quick.stdout


def test_odometry_prints_the_final_pose_and_json(encoders):
    result = duckie("odometry", encoders, "--solution", SOLUTION, "--json", "--start", 0, 0, 0)
    assert result.returncode == 0, result.stderr
    pose = json.loads(result.stdout)
    travelled = 2 * 89 * 2 * math.pi * 0.0318 / 135
    assert pose == pytest.approx({"x": travelled, "y": 0.0, "theta": 0.0}, abs=1e-9)
    text = duckie("odometry", encoders, "--solution", SOLUTION).stdout
    assert "final pose: x = 0.3200 m" in text
    reference = duckie("odometry", encoders, "--json", "--start", 0, 0, 0)
    assert reference.returncode == 0, reference.stderr
    assert json.loads(reference.stdout) == pytest.approx(pose, abs=1e-12), (
        "without --solution, the course's reference solution replays the same odometry"
    )


def test_plot_writes_a_figure(tmp_path):
    path = tmp_path / "poses.bag"
    with BagWriter(path) as writer:
        for k in range(20):
            pose = Pose2DStamped(x=0.32, y=0.32 + 0.01 * k, theta=math.pi / 2)
            pose.header.stamp.nsecs = k * 10_000_000
            writer.write("/duckiebot/pose", pose, k * 10_000_000)
    result = duckie("plot", path, "-o", tmp_path / "poses.png")
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "poses.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_animate_plays_a_bag_back_as_a_gif_or_says_why_not(tmp_path):
    from PIL import Image

    result = duckie("animate", sample_bag(), "-o", tmp_path / "run.gif", "--seconds", "4")
    assert result.returncode == 0, result.stderr
    assert "(33 frames)" in result.stdout  # 146 s in 4 s at 8 frames a second
    with Image.open(tmp_path / "run.gif") as gif:
        assert gif.size[0] >= 800
        assert gif.n_frames == 33
    refused = duckie("animate", sample_bag(), "-o", tmp_path / "run.avi")
    assert refused.returncode == 1
    assert refused.stderr.startswith("duckie: Cannot save the animation as")
    assert "Traceback" not in refused.stderr
    empty = tmp_path / "chatter.bag"
    with BagWriter(empty) as writer:
        writer.write("/chatter", String(data="hi"), 1)
    nothing = duckie("animate", empty, "-o", tmp_path / "chatter.gif")
    assert nothing.returncode == 1
    assert "nothing to play" in nothing.stderr
    assert not (tmp_path / "chatter.gif").exists()


def test_repair(tmp_path):
    whole = tmp_path / "whole.bag"
    with BagWriter(whole) as writer:
        writer.write("/s", String("a"), 1)
        writer.flush()
        writer.write("/s", String("b"), 2)
    broken = tmp_path / "broken.bag"
    broken.write_bytes(whole.read_bytes()[:-100])
    result = duckie("repair", broken, tmp_path / "fixed.bag")
    assert result.returncode == 0, result.stderr
    assert "Recovered" in result.stdout
    assert "/s:" in result.stdout


def test_bad_input_gets_one_line_and_status_1(tmp_path, encoders):
    assert_one_line_error(duckie("info", tmp_path / "nope.bag"), "There is no file")
    text = tmp_path / "notes.txt"
    text.write_text("hello")
    assert_one_line_error(duckie("info", text), "is not a ROS 1 bag")
    empty = tmp_path / "empty.bag"
    BagWriter(empty).close()
    assert_one_line_error(
        duckie("odometry", empty, "--solution", SOLUTION), "needs one left encoder topic"
    )
    unindexed = tmp_path / "open.bag"
    writer = BagWriter(unindexed)
    writer.write("/s", String("a"), 1)
    writer.flush()
    assert_one_line_error(duckie("info", unindexed), "duckie bag repair")
    writer.close()
    assert_one_line_error(
        duckie("plot", encoders, "-o", tmp_path / "x.png", "--topic", "/nope"),
        "has no topic /nope",
    )
    assert_one_line_error(
        duckie("odometry", encoders, "--solution", tmp_path / "none.py"),
        "no solution file or folder",
    )
    assert_one_line_error(duckie("plot", encoders, "-o", tmp_path / "x.png"), "Pose2DStamped")
    assert_one_line_error(
        duckie("odometry", encoders, "--solution", SOLUTION, "--left", "/nope"), "no topic /nope"
    )


def test_info_into_a_reader_that_stops_early_ends_quietly():
    # `duckie bag info run.bag | head -1`: the reader is gone before duckie writes.
    process = subprocess.Popen(
        [sys.executable, "-m", "duckielib.tools.cli", "bag", "info", str(sample_bag())],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    process.stdout.close()
    errors = process.stderr.read()
    process.stderr.close()
    assert process.wait(timeout=120) == 141
    assert errors == ""


def solution_with(tmp_path, source):
    """The bag tests' classic solution with ``source`` added (a part redefined)."""
    path = tmp_path / "mine.py"
    path.write_text(SOLUTION.read_text() + "\n\n" + source)
    return path


NAN_ONCE_MOVED = """
def estimate_pose(R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right):
    if x_prev > 0.1:
        return x_prev, y_prev, float("nan")
    return x_prev + R * (delta_phi_left + delta_phi_right) / 2, y_prev, theta_prev
"""


def test_a_non_finite_pose_is_named_with_the_call_that_returned_it(tmp_path, encoders):
    solution = solution_with(tmp_path, NAN_ONCE_MOVED)
    result = duckie("odometry", encoders, "--solution", solution, "--json", "--start", 0, 0, 0)
    assert_one_line_error(result, "duckie: estimate_pose(0.0318, 0.1, 0.10")
    assert re.search(
        r"^duckie: estimate_pose\(0\.0318, 0\.1, 0\.10\d+, 0\.0, 0\.0, 0\.09\d+, 0\.09\d+\), "
        r"from notebook 05_odometry, returned \(0\.10\d+, 0\.0, nan\): every number it returns "
        r"must be finite, not NaN or infinite \(",
        result.stderr,
    ), result.stderr


def test_a_start_that_is_not_a_finite_number_is_refused(encoders):
    for start in (("nan", 0, 0), (0, "inf", 0)):
        result = duckie("odometry", encoders, "--start", *start)
        assert result.returncode == 2
        bad = next(value for value in start if value != 0)
        assert result.stderr.splitlines()[-1] == (
            f"duckie bag odometry: error: argument --start: give a finite number, not '{bad}'"
        )


@pytest.fixture
def two_robots(tmp_path):
    """A bag of two robots' encoders: alice drives straight ahead, bob turns on the spot."""
    path = tmp_path / "two.bag"
    with BagWriter(path) as writer:
        for k in range(30):
            for robot, left, right in (("alice", 2 * k, 2 * k), ("bob", -k, k)):
                for side, ticks in (("left", left), ("right", right)):
                    topic = f"/{robot}/{side}_wheel_encoder_node/tick"
                    writer.write(topic, encoder(ticks, k * S // 30), k * S // 30)
    return path


def test_one_encoder_topic_given_pairs_with_its_twin(two_robots):
    def final_pose(*topics):
        result = duckie("odometry", two_robots, "--json", "--start", 0, 0, 0, *topics)
        assert result.returncode == 0, result.stderr
        return json.loads(result.stdout)

    bob = final_pose("--left", "/bob/left_wheel_encoder_node/tick")
    assert bob == final_pose(
        "--left",
        "/bob/left_wheel_encoder_node/tick",
        "--right",
        "/bob/right_wheel_encoder_node/tick",
    )
    assert bob["x"] == pytest.approx(0.0, abs=1e-12)
    assert bob["theta"] > 0.5, "bob turns counter-clockwise"
    alice = final_pose("--right", "/alice/right_wheel_encoder_node/tick")
    assert alice["x"] > 0.0
    assert alice["theta"] == pytest.approx(0.0, abs=1e-12)


def test_unclear_or_equal_encoder_topics_are_refused_in_the_options_words(two_robots):
    left = "/bob/left_wheel_encoder_node/tick"
    assert_one_line_error(
        duckie("odometry", two_robots, "--left", left, "--right", left),
        f"duckie: --left and --right are both {left}: give each wheel its own encoder topic.",
    )
    assert_one_line_error(
        duckie("odometry", two_robots),
        "duckie: two.bag has 2 left encoder topics (/alice/left_wheel_encoder_node/tick, "
        "/bob/left_wheel_encoder_node/tick): choose one with --left.",
    )
    assert_one_line_error(
        duckie("odometry", two_robots, "--left", "/alice/right_wheel_encoder_node/tick"),
        "choose the one that pairs with /alice/right_wheel_encoder_node/tick with --right.",
    )


def test_a_time_base_that_does_not_fit_is_said_with_the_option(tmp_path):
    # Every header stamp 0, as in some students' bags: only record times can be used.
    ticks = [(k * S // 30 + 1, k) for k in range(10)]
    path = write_encoders(tmp_path / "zero.bag", ticks, ticks, skew_ns=S)
    assert_one_line_error(
        duckie("odometry", path, "--time-base", "header"),
        "duckie: Every header stamp on /duckiebot/left_wheel_encoder_node/tick is 0; use "
        "--time-base record.\n",
    )


def test_odometry_plot_draws_the_path_the_ticks_give(encoders, tmp_path, monkeypatch, capsys):
    from duckielib import plots
    from duckielib.tools.cli import main

    drawn = []
    save_figure = plots.save_figure

    def spy(figure, path):
        drawn.append(figure)
        return save_figure(figure, path)

    monkeypatch.setattr(plots, "save_figure", spy)
    figure_path = tmp_path / "path.png"
    args = ["bag", "odometry", str(encoders), "--solution", str(SOLUTION), "--start", "0", "0", "0"]
    assert main([*args, "--plot", str(figure_path)]) == 0
    assert capsys.readouterr().out.endswith(f"Wrote {figure_path}.\n")
    assert figure_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    (figure,) = drawn
    path_axes, x_axes = figure.axes[:2]
    (line,) = path_axes.get_lines()
    assert line.get_label() == "odometry (your solution)"
    xy = line.get_xydata()
    travelled = 2 * 89 * 2 * math.pi * 0.0318 / 135
    assert xy[0] == pytest.approx([0.0, 0.0])
    assert xy[-1] == pytest.approx([travelled, 0.0], abs=1e-9)
    assert len(xy) == 90
    t, x = x_axes.get_lines()[0].get_xydata().T
    assert t[0] == 0.0
    assert t[-1] == pytest.approx(89 / 30)  # from the first pose on
    assert x[-1] == pytest.approx(travelled)
