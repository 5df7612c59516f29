"""Topics as arrays, time bases, and odometry replayed from encoder ticks."""

from __future__ import annotations

import math

import bagtools
import numpy as np
import pytest
from bagtools import LEFT, write_encoders

from duckielib.bags import BagWriter, read_encoders, read_topic, replay_odometry
from duckielib.errors import BagError
from duckielib.messages import Pose2DStamped, String
from duckielib.solution import SolutionError

S = 1_000_000_000
R, BASELINE = 0.0318, 0.1
REVOLUTION = 2 * math.pi * R  # metres per wheel revolution


def test_read_topic_gives_arrays_and_chooses_the_time_base(tmp_path):
    path = tmp_path / "p.bag"
    with BagWriter(path) as writer:
        for k in range(3):
            pose = Pose2DStamped(x=0.1 * k, y=0.0, theta=0.0)
            pose.header.stamp.secs = 100 + k
            writer.write("/pose", pose, (100 + k) * S + 20_000_000)
    arrays = read_topic(path, "/pose")
    assert arrays.time_base == "header"
    np.testing.assert_allclose(arrays.t, [100.0, 101.0, 102.0])
    np.testing.assert_allclose(arrays.record_t, [100.02, 101.02, 102.02])
    np.testing.assert_allclose(arrays["x"], [0.0, 0.1, 0.2])
    assert arrays["header.seq"].tolist() == [0, 0, 0]
    assert arrays.notes == [], "20 ms of skew is normal"
    assert read_topic(path, "/pose", time_base="record").time_base == "record"
    with pytest.raises(KeyError, match="no numeric field 'z'"):
        arrays["z"]


def test_zero_stamps_and_large_skew_are_noted(tmp_path):
    zero = write_encoders(tmp_path / "z.bag", [(S, 1), (2 * S, 2)], [(S, 1)], skew_ns=10**20)
    arrays = read_topic(zero, LEFT)
    assert arrays.time_base == "record"
    assert "every header stamp is 0" in arrays.notes[0]
    with pytest.raises(BagError, match="use time_base='record'"):
        read_topic(zero, LEFT, time_base="header")
    skewed = write_encoders(tmp_path / "s.bag", [(S, 1), (2 * S, 2)], [(S, 1)], skew_ns=400_000_000)
    notes = read_topic(skewed, LEFT).notes
    assert "differ from record times" in notes[0]
    assert "0.400 s" in notes[0]
    strings = tmp_path / "str.bag"
    with BagWriter(strings) as writer:
        writer.write("/chatter", String("hi"), 5)
    assert read_topic(strings, "/chatter").time_base == "record"


def ticks_for(metres):
    return round(metres / REVOLUTION * 135)


def test_straight_drive_replays_to_the_travelled_distance(tmp_path):
    # 1 m forward in 100 steps, both wheels, counts starting far from 0.
    step = ticks_for(1.0) / 100
    left = [(k * S // 30, 40_000 + round(k * step)) for k in range(101)]
    right = [(k * S // 30 + 7_000_000, -25_000 + round(k * step)) for k in range(101)]
    path = write_encoders(tmp_path / "straight.bag", left, right)
    track = replay_odometry(path, bagtools, start=(0.32, 0.32, math.pi / 2))
    x, y, theta = track.final_pose
    travelled = ticks_for(1.0) * REVOLUTION / 135
    assert x == pytest.approx(0.32, abs=1e-12)
    assert y == pytest.approx(0.32 + travelled, abs=1e-12)
    assert theta == pytest.approx(math.pi / 2)
    assert len(track) == 101, "the start, then one pose per pair"
    assert track.distance_to((0.32, 0.32 + travelled)) == pytest.approx(0.0, abs=1e-12)


def test_backwards_through_zero_and_negative_counts(tmp_path):
    left = [(k * S, 10 - 5 * k) for k in range(6)]  # 10, 5, 0, -5, -10, -15
    right = [(k * S + 1, 10 - 5 * k) for k in range(6)]
    track = replay_odometry(
        write_encoders(tmp_path / "back.bag", left, right),
        bagtools,
        start=(0.0, 0.0, 0.0),
    )
    assert track.final_pose[0] == pytest.approx(-25 * REVOLUTION / 135)


def test_one_wheel_reporting_several_times_is_accumulated(tmp_path):
    # The left wheel reports three times (+10 each) before the right reports once (+30).
    left = [(0, 0), (S, 10), (2 * S, 20), (3 * S, 30)]
    right = [(0, 0), (3 * S + 1, 30)]
    readings = []

    class Spy(bagtools.WheelPairing):
        def add(self, wheel, ticks):
            readings.append((wheel, ticks))
            return super().add(wheel, ticks)

    solution = {**vars(bagtools), "WheelPairing": Spy}
    track = replay_odometry(
        write_encoders(tmp_path / "acc.bag", left, right), solution, start=(0, 0, 0)
    )
    assert readings == [
        ("left", 0),
        ("right", 0),
        ("left", 10),
        ("left", 20),
        ("left", 30),
        ("right", 30),
    ], "every reading, in time order, the left wheel first at equal times"
    assert track.final_pose == pytest.approx((30 * REVOLUTION / 135, 0.0, 0.0))
    assert len(track) == 2


def test_streams_of_unequal_length(tmp_path):
    left = [(k * S, k) for k in range(10)]
    right = [(k * 3 * S + 1, 3 * k) for k in range(3)]  # a third as many
    track = replay_odometry(
        write_encoders(tmp_path / "uneq.bag", left, right),
        bagtools,
        start=(0, 0, 0),
    )
    assert len(track) == 3, "the start and two paired updates"
    assert track.final_pose[0] == pytest.approx(6 * REVOLUTION / 135)


def test_errors_name_the_problem(tmp_path):
    strings = tmp_path / "str.bag"
    with BagWriter(strings) as writer:
        writer.write("/chatter", String("hi"), 5)
    with pytest.raises(BagError, match="needs one left encoder topic"):
        replay_odometry(strings, bagtools)
    path = write_encoders(tmp_path / "e.bag", [(0, 0), (S, 5)], [(1, 0), (S + 1, 5)])

    def unfinished(R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right):  # noqa: N803
        raise NotImplementedError

    with pytest.raises(SolutionError, match=r"05_odometry: estimate_pose is not implemented"):
        replay_odometry(path, {**vars(bagtools), "estimate_pose": unfinished})

    class Single(bagtools.WheelPairing):
        def add(self, wheel, ticks):
            return 1.0

    with pytest.raises(SolutionError, match="must return None or two numbers"):
        replay_odometry(path, {**vars(bagtools), "WheelPairing": Single})
    with pytest.raises(SolutionError, match="Finish notebook 05_odometry: the solution has no"):
        replay_odometry(path, {"delta_phi": bagtools.delta_phi})
    with pytest.raises(BagError, match="time_base must be one of"):
        read_encoders(path, time_base="wall")
