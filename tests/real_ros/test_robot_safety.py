"""The wheels stop however a driving node ends, on a real roscore with the virtual Duckiebot.

Each test runs ``robot_nodes``' mission node (so :class:`duckielib.nodes.safety.SafetyGuard` guards
it) with a mission that would drive forward for ever, then ends it one way: it finishes, it
is interrupted (SIGINT), its main code raises, a callback raises, or the encoders go silent.
What must follow is read from a bag recorded by Debian's rosbag: the executed wheel commands
end at zero and the robot's true position stops changing.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import time
from pathlib import Path
from typing import List, Tuple

import pytest

from duckielib.bags import Bag

pytestmark = [pytest.mark.ros, pytest.mark.slow]

VEH = "/duckiebot/"
TOPICS = [
    VEH + "simulator_node/ground_truth_pose",
    VEH + "wheels_driver_node/wheels_cmd_executed",
    VEH + "wheels_driver_node/emergency_stop",
]

#: A mission node that drives forward at 0.2 m/s until ``ending`` says otherwise. It replaces
#: the reference's ``mission_node``; the reference's other parts stay.
DRIVER = """

def mission_node(mission):
    import rospy
    from duckietown_msgs.msg import Pose2DStamped, Twist2DStamped

    rospy.init_node("mission_node")
    command = rospy.Publisher("car_cmd_switch_node/cmd", Twist2DStamped, queue_size=1)
    ENDING = {ending!r}

    def on_pose(pose):
        if ENDING == "callback" and pose.header.stamp.to_sec() > 3.0:
            raise RuntimeError("a bug in a callback")

    rospy.Subscriber("simulator_node/ground_truth_pose", Pose2DStamped, on_pose, queue_size=1)
    rate = rospy.Rate({hz})
    while not rospy.is_shutdown():
        now = rospy.get_time()
        if ENDING == "finish" and now > 3.0:
            return
        if ENDING == "raise" and now > 3.0:
            raise RuntimeError("a bug in the main loop")
        command.publish(Twist2DStamped(v=0.2, omega=0.0))
        rate.sleep()
"""


def _drive(master, tmp_path: Path, ending: str, mute: str = "", hz: int = 10) -> Tuple[Bag, int]:
    """Run the virtual Duckiebot and a forward-driving mission node ended by ``ending``.

    Returns:
        The recorded bag, and the mission node's exit status.
    """
    solution = tmp_path / "solution.py"
    solution.write_text(master.solution.read_text() + DRIVER.format(ending=ending, hz=hz))
    bag = tmp_path / f"{ending}.bag"
    recorder = master.record(bag, TOPICS)
    robot = master.start(
        [
            "roslaunch",
            "course_nodes",
            "virtual_duckiebot.launch",
            f"rate:={master.rate}",
            f"mute_encoders_after:={mute}",
            "paused:=true",
        ],
        f"robot_{ending}",
    )
    env = dict(master.env, DUCKIE_SOLUTION=str(solution), ROS_NAMESPACE=VEH)
    node = subprocess.Popen(
        [
            str(Path(master.env["ROS_PACKAGE_PATH"]) / "course_nodes/src/mission_node.py"),
            "__name:=mission_node",
        ],
        env=env,
        stdout=(tmp_path / f"mission_{ending}.log").open("w"),
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )
    try:
        # The clock starts once the recorder hears the robot and the mission node's guard (the
        # only publisher of emergency_stop): the bag has every instant, and each wait below
        # is at least as long in simulated time, however slowly the nodes started.
        master.start_clock(TOPICS)
        if ending == "sigint":
            time.sleep(3.0 / master.rate + 2.0)  # driving for a few simulated seconds
            os.killpg(node.pid, signal.SIGINT)
        if ending == "silence":
            time.sleep(10.0 / master.rate + 2.0)  # the guard must hold the robot meanwhile
            master.stop(node)
        status = node.wait(timeout=60)
        time.sleep(2.0)  # two more wall seconds: the robot must stay where it stopped
    finally:
        master.stop(node)
        master.stop(robot)
        master.stop(recorder)
    return Bag(master.wait_for_bag(bag)), status


def _truth(bag: Bag) -> List[Tuple[float, float, float]]:
    return [
        (item.time, item.message.x, item.message.y)
        for item in bag.read(VEH + "simulator_node/ground_truth_pose")
    ]


def _assert_stopped(bag: Bag, still_for: float = 1.5) -> None:
    truth = _truth(bag)
    start, end = truth[0], truth[-1]
    assert math.dist(start[1:], end[1:]) > 0.1, "the robot never drove"
    last = [pose for pose in truth if pose[0] >= end[0] - still_for]
    moved = math.dist(last[0][1:], last[-1][1:])
    assert moved < 0.002, f"the robot still moved {moved * 100:.1f} cm in its last {still_for} s"
    executed = list(bag.read(VEH + "wheels_driver_node/wheels_cmd_executed"))
    assert (executed[-1].message.vel_left, executed[-1].message.vel_right) == (0.0, 0.0)


def test_wheels_stop_when_the_mission_finishes(master, tmp_path):
    bag, status = _drive(master, tmp_path, "finish")
    assert status == 0
    _assert_stopped(bag)


def test_wheels_stop_on_sigint(master, tmp_path):
    bag, status = _drive(master, tmp_path, "sigint")
    _assert_stopped(bag)
    assert (
        "Wheels stopped: the node is shutting down" in (tmp_path / "mission_sigint.log").read_text()
    )
    assert status is not None


def test_wheels_stop_when_the_main_code_raises(master, tmp_path):
    bag, status = _drive(master, tmp_path, "raise")
    assert status == 1
    _assert_stopped(bag)
    log = (tmp_path / "mission_raise.log").read_text()
    assert "the mission stopped with RuntimeError: a bug in the main loop" in log


def test_wheels_stop_when_a_callback_raises(master, tmp_path):
    # A fast loop: shut down from the callback's thread, its next command came after the zeros.
    bag, status = _drive(master, tmp_path, "callback", hz=1000)
    assert status == 1
    _assert_stopped(bag)
    log = (tmp_path / "mission_callback.log").read_text()
    assert "Wheels stopped: a callback raised an exception (RuntimeError: a bug" in log
    assert "mission_node: a callback raised RuntimeError: a bug in a callback" in log


def test_emergency_stop_when_the_encoders_go_silent(master, tmp_path):
    bag, _ = _drive(master, tmp_path, "silence", mute="4.0")
    stops = [
        (item.time, item.message.data)
        for item in bag.read(VEH + "wheels_driver_node/emergency_stop")
    ]
    engaged = [t for t, data in stops if data]
    assert engaged, stops
    assert 4.0 < engaged[0] < 6.0, stops
    truth = _truth(bag)
    # Encoders silent from 4 s: the robot stands still well before the node is stopped.
    held = [pose for pose in truth if 6.0 <= pose[0] <= 10.0]
    assert math.dist(held[0][1:], held[-1][1:]) < 0.002
    assert math.dist(truth[0][1:], held[0][1:]) > 0.1, "the robot never drove"


def test_a_paused_robot_keeps_its_clock_at_zero_until_started(master):
    robot = master.start(
        ["roslaunch", "course_nodes", "virtual_duckiebot.launch", "paused:=true"], "robot_paused"
    )
    listener = master.start(
        ["rostopic", "echo", "-n", "1", "/clock", "__name:=clock_listener"], "clock_listener"
    )
    try:
        deadline = time.monotonic() + 60
        while not master.connected("/clock", "clock_listener"):
            assert listener.poll() is None, "a /clock message came while paused"
            assert time.monotonic() < deadline, "rostopic echo did not connect to /clock"
            time.sleep(0.2)
        time.sleep(2.0)  # two simulated seconds, were the clock running
        assert listener.poll() is None, "a /clock message came while paused"
        master.start_clock([])
        assert listener.wait(timeout=60) == 0
        assert "secs:" in master.log("clock_listener")
    finally:
        master.stop(listener)
        master.stop(robot)
