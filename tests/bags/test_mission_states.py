"""A mission's bag cut at its states: poses per state, path lengths, turns on the spot."""

from __future__ import annotations

import math

import numpy as np
import pytest

from duckielib.bags import BagWriter
from duckielib.bags.mission_states import path_length, poses_by_state, turns_on_the_spot
from duckielib.errors import BagError
from duckielib.messages import Pose2DStamped, Twist2DStamped
from duckielib.messages.std_msgs.msg import String

S = 1_000_000_000
NS = "/duckiebot/"


def mission_bag(path):
    """States at 1 s, 2 s, then done at 3 s; the truth turning past 2 pi; four commands."""
    with BagWriter(path) as writer:
        for t, state in ((1, "square"), (2, "circle"), (3, "done")):
            writer.write(NS + "mission_node/state", String(data=state), t * S)
        for k in range(1, 31):
            t = k * S // 10
            theta = (0.5 * k) % (2 * math.pi)
            pose = Pose2DStamped(x=0.1 * k, y=0.0, theta=theta)
            pose.header.stamp.secs, pose.header.stamp.nsecs = divmod(t, S)
            writer.write(NS + "simulator_node/ground_truth_pose", pose, t)
        for t, v, omega in ((1.0, 0.2, 0.0), (1.5, 0.0, -2.0), (2.0, 0.0, -0.5), (2.5, 0.2, 0.0)):
            writer.write(
                NS + "car_cmd_switch_node/cmd", Twist2DStamped(v=v, omega=omega), int(t * S)
            )
    return path


def test_poses_are_cut_at_the_states_and_theta_is_unwrapped(tmp_path):
    square, circle = poses_by_state(mission_bag(tmp_path / "run.bag"), "simulator_node")
    assert np.allclose(square[0], [0.1 * k for k in range(10, 21)])
    assert np.allclose(circle[0], [0.1 * k for k in range(20, 31)])
    assert np.allclose(np.diff(circle[2]), 0.5)  # no jump at 2 pi
    with pytest.raises(BagError, match="no pose topic of odometry_node"):
        poses_by_state(tmp_path / "run.bag", "odometry_node")


def test_path_length_adds_the_steps():
    assert path_length(np.array([0.0, 3.0, 3.0]), np.array([0.0, 4.0, 5.0])) == pytest.approx(6.0)
    assert path_length(np.array([1.0]), np.array([1.0])) == 0.0


def test_one_turn_on_the_spot_and_its_gentle_part(tmp_path):
    turns = turns_on_the_spot(mission_bag(tmp_path / "run.bag"), below=1.0)
    assert turns.count == 1
    assert turns.seconds == pytest.approx(1.0)
    assert turns.longest == pytest.approx(1.0)
    assert turns.weak == pytest.approx(0.5)
