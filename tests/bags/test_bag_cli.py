"""``duckie bag``: info, plot, odometry and repair, and their one-line errors."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
from bagtools import write_encoders

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
