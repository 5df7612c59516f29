"""Habits of real node code that simulated time must survive.

Students and Duckietown nodes poll without sleeping, sleep with ``time.sleep``, and write
callbacks that take their time. On a robot each of these works because rospy runs callbacks in
threads of their own beside the main code and time passes by itself. On the graph, time moves
only while nodes wait, so each habit gets a rule (rospy's module docstring) and a test here.
"""

from __future__ import annotations

import io
import math
import time as wallclock

import pytest

from duckielib.messages import Pose2DStamped, String, Twist2DStamped
from duckielib.ros import Graph, rospy
from duckielib.ros.log import WARN
from duckielib.sim import VirtualDuckiebot


@pytest.fixture(params=["greenlets", "threads"])
def graph(request):
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO(), threads=request.param == "threads")
    yield graph
    graph.shutdown()


def warnings(graph):
    return [record.text for record in graph.log if record.level == WARN]


def test_a_loop_that_never_sleeps_lets_time_go_on(graph):
    seen = []

    def poller():
        rospy.init_node("poller")
        pub = rospy.Publisher("chatter", String, queue_size=1)
        count = 0
        while not rospy.is_shutdown() and rospy.get_time() < 2.0:
            pub.publish(String(data="busy"))
            count += 1
        seen.append((rospy.get_time(), count))

    def listener():
        rospy.init_node("listener")
        rospy.Subscriber("chatter", String, lambda msg: seen.append(msg.data), queue_size=1)
        rospy.spin()

    graph.launch(listener)
    graph.launch(poller)
    graph.run(3.0)
    end, count = seen[-1]
    assert 2.0 <= end < 2.002
    # Three calls per loop (is_shutdown, get_time, publish), 0.1 ms of simulated time each.
    assert count == pytest.approx(2.0 / (3 * rospy.CALL_COST_NS / 1e9), rel=0.01)
    assert seen.count("busy") > 100, "the listener's callbacks ran during the loop"


def test_a_node_that_polls_the_odometry_drives_the_robot_and_stops():
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    bot = VirtualDuckiebot(seed=1, graph=graph)
    ended = []

    def driver():
        # As students write it: drive until the odometry says 0.3 m, no sleep in the loop.
        rospy.init_node("driver")
        pose = {}
        rospy.Subscriber(
            "/duckiebot/simulator_node/ground_truth_pose",
            Pose2DStamped,
            lambda msg: pose.update(x=msg.x, y=msg.y),
        )
        cmd = rospy.Publisher("/duckiebot/car_cmd_switch_node/cmd", Twist2DStamped, queue_size=1)
        while not pose:
            rospy.sleep(0.1)
        start = dict(pose)
        while math.hypot(pose["x"] - start["x"], pose["y"] - start["y"]) < 0.3:
            cmd.publish(Twist2DStamped(v=0.2, omega=0.0))
        cmd.publish(Twist2DStamped(v=0.0, omega=0.0))
        ended.append(rospy.get_time())

    x0, y0, _ = bot.sim.pose
    try:
        graph.launch(driver)
        bot.run(5.0)
        assert ended, "the polling loop ended"
        assert 1.3 < ended[0] < 2.5  # 0.3 m at about 0.2 m/s, after the first pose
        x, y, _ = bot.sim.pose
        moved = math.hypot(x - x0, y - y0)
        assert 0.3 <= moved < 0.4
    finally:
        bot.shutdown()


def test_callbacks_of_one_subscription_never_overlap(graph):
    calls = []

    def slow_listener():
        rospy.init_node("slow")

        def on_message(msg):
            calls.append(("enter", msg.data, rospy.get_time()))
            rospy.sleep(0.25)  # a callback that takes its time
            calls.append(("exit", msg.data, rospy.get_time()))

        rospy.Subscriber("chatter", String, on_message, queue_size=10)
        rospy.spin()

    def talker():
        rospy.init_node("talker")
        pub = rospy.Publisher("chatter", String, queue_size=10)
        rate = rospy.Rate(10)
        for number in range(5):
            pub.publish(String(data=str(number)))
            rate.sleep()

    graph.launch(slow_listener)
    graph.launch(talker)
    graph.run(3.0)
    kinds = [kind for kind, _, _ in calls]
    assert kinds == ["enter", "exit"] * 5, "each callback ends before the next begins"
    assert [data for kind, data, _ in calls if kind == "enter"] == ["0", "1", "2", "3", "4"]
    starts = [t for kind, _, t in calls if kind == "enter"]
    assert starts == pytest.approx([0.0, 0.25, 0.5, 0.75, 1.0])


def test_time_sleep_in_a_node_waits_simulated_seconds_and_says_so(graph):
    times = []

    def stopper():
        rospy.init_node("stopper")
        times.append(rospy.get_time())
        wallclock.sleep(5.0)  # "stand still 5 s", as many students write it
        times.append(rospy.get_time())
        wallclock.sleep(1.0)
        times.append(rospy.get_time())

    started = wallclock.perf_counter()
    graph.launch(stopper)
    graph.run(10.0)
    assert wallclock.perf_counter() - started < 1.0, "no wall-clock wait"
    assert times == pytest.approx([0.0, 5.0, 6.0])
    said = [text for text in warnings(graph) if "time.sleep()" in text]
    assert len(said) == 1
    assert "rospy.sleep()" in said[0]


def test_time_sleep_in_a_notebooks_own_code_is_the_wall_clock(graph):
    # Jupyter and the libraries a notebook calls sleep too; between cells the graph is still.
    rospy.init_node("notebook")
    started = wallclock.perf_counter()
    wallclock.sleep(0.05)
    assert wallclock.perf_counter() - started >= 0.05
    assert rospy.get_time() == 0.0
    assert not [text for text in warnings(graph) if "time.sleep()" in text]


def test_time_sleep_outside_nodes_is_the_wall_clock():
    started = wallclock.perf_counter()
    wallclock.sleep(0.05)
    assert wallclock.perf_counter() - started >= 0.05


def test_a_loop_with_no_shutdown_check_ends_when_the_graph_shuts_down(graph):
    steps = []

    def forever():
        rospy.init_node("forever")
        while True:  # as many student nodes loop
            steps.append(rospy.get_time())
            rospy.sleep(0.5)

    graph.launch(forever)
    graph.run(1.0)
    graph.shutdown()
    assert steps == [0.0, 0.5, 1.0]
    assert all(actor.finished for actor in graph._actors)
