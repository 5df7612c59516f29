"""Node code written elsewhere runs unchanged on the virtual Duckiebot.

Each node in ``nodes/`` is a script written in the pattern of code the course did not write:
the rospy tutorials (a talker and a listener; a service with the package's own ``.srv``
beside it), a student's exercise node (DTROS, time.sleep, polling loops, LED patterns on the
emitter's topic), a Duckietown camera node (cv_bridge and OpenCV) and a dead-reckoning-style
node (message_filters, a bag written with rosbag's API). They run as scripts, with no edit,
and what they do is checked.
"""

from __future__ import annotations

import io
import math
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from duckielib.bags import Bag
from duckielib.leds import pattern_colors
from duckielib.messages import CompressedImage, Twist2DStamped
from duckielib.ros import Graph, NodeCrashed, node_script, rospy, uninstall_modules
from duckielib.ros.context import node_context
from duckielib.ros.log import ERROR, INFO
from duckielib.sim import VirtualDuckiebot

NODES = Path(__file__).resolve().parent / "nodes"

#: What the scripts import by the names robot code uses.
FOREIGN_IMPORTS = (
    "beginner_tutorials",
    "cv_bridge",
    "duckietown",
    "duckietown_msgs",
    "duckietown_utils",
    "message_filters",
    "rosbag",
    "rospy",
    "sensor_msgs",
    "std_msgs",
    "std_srvs",
)


@pytest.fixture
def bot(monkeypatch):
    monkeypatch.setenv("VEHICLE_NAME", "duckiebot")
    before = set(sys.modules)
    bot = VirtualDuckiebot(seed=0, graph=Graph(stdout=io.StringIO(), stderr=io.StringIO()))
    yield bot
    bot.shutdown()
    # What the scripts imported (rospy, std_msgs, their own package...) leaves with them, so
    # later tests meet Debian's real modules where they ask for them.
    uninstall_modules()
    for name in set(sys.modules) - before:
        if name.split(".")[0] in FOREIGN_IMPORTS:
            del sys.modules[name]


def lines(graph, level=INFO):
    return [record for record in graph.log if record.level == level]


def test_the_tutorial_talker_and_listener(bot):
    bot.graph.launch(node_script(NODES / "listener.py"))
    bot.graph.launch(node_script(NODES / "talker.py"))
    bot.run(1.0)
    heard = [r.text for r in lines(bot.graph) if "I heard hello world" in r.text]
    assert len(heard) == 11  # 10 Hz from 0.0 s to 1.0 s, both ends included
    assert heard[0].endswith("I heard hello world 0.0")
    assert not lines(bot.graph, ERROR)


def test_the_tutorial_service_with_its_packages_own_srv(bot):
    bot.graph.launch(node_script(NODES / "add_two_ints_server.py"))
    bot.graph.launch(node_script(NODES / "add_two_ints_client.py", "2", "40"))
    bot.run(1.0)
    assert "2 + 40 = 42" in [r.text for r in lines(bot.graph)]
    assert not lines(bot.graph, ERROR)


def test_connection_headers_of_each_publisher_and_service_client(bot):
    # tests/real_ros/test_foreign_on_real_rospy.py runs the same pair under Debian's rospy.
    bot.graph.launch(node_script(NODES / "tagged_talker.py"))
    bot.graph.launch(node_script(NODES / "tagged_listener.py"))
    bot.run(1.0)
    said = [r.text for r in lines(bot.graph)]
    assert "status ready from /tagged_talker as leader of fleet 7 (latching 1)" in said
    assert "service says: /tagged_listener with token abc123 (answered by /tagged_talker)" in said
    assert not lines(bot.graph, ERROR)


def test_a_tutorial_client_without_its_arguments_exits_as_on_a_robot(bot, capsys):
    bot.graph.launch(node_script(NODES / "add_two_ints_client.py"))
    with pytest.raises(NodeCrashed, match="add_two_ints_client stopped with SystemExit: 1"):
        bot.run(0.5)
    assert "usage:" in capsys.readouterr().out


def test_a_students_exercise_node_drives_a_square_with_its_lights(bot):
    bot.graph.launch(node_script(NODES / "square_student.py"))
    path = [bot.sim.pose]
    while "/square_student_node" in bot.graph.nodes or bot.time == 0.0:
        assert bot.time < 60.0, "the node did not finish in 60 s"
        bot.run(0.1)
        path.append(bot.sim.pose)
    assert not lines(bot.graph, ERROR)
    # Four sides of 0.4 m and four left turns. The first side is 0.4 m; the others come out
    # shorter, and the turns are not exact, because the node polls encoders that tick at 30 Hz
    # and counts ticks the wheels make while they coast, as it would on a robot.
    path = np.array(path)
    steps = np.hypot(np.diff(path[:, 0]), np.diff(path[:, 1]))
    first_turn = int(np.argmax(np.abs(np.diff(path[:, 2])) > 0.01))
    assert steps[:first_turn].sum() == pytest.approx(0.4, abs=0.03)
    assert 1.0 < steps.sum() < 1.8
    turned = np.abs(np.diff(np.unwrap(path[:, 2]))).sum()
    assert turned == pytest.approx(2 * math.pi, abs=0.6)
    # Its four time.sleep(1) stops took simulated time, with the robot still.
    assert bot.time > 4.0
    # Red stops, green sides, blue at the end: the LEDs showed what the node published,
    # then the emitter turned them off as the robot shut down.
    shown = [pattern_colors(pattern)[0] for _, pattern in bot.sim.trace.patterns]
    red, green, blue = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
    assert [color for color in shown if color in (red, green, blue)] == [red, green] * 4 + [blue]
    assert bot.sim.wheel_duties == (0.0, 0.0)


def test_a_duckietown_camera_node_with_cv_bridge_and_opencv(bot):
    frames = []
    probe = bot.graph.host_node("probe")
    with node_context(probe):
        rospy.Subscriber("/camera_annotator_node/image/compressed", CompressedImage, frames.append)
    bot.graph.launch(node_script(NODES / "camera_annotator.py"))
    bot.run(0.5)
    assert not lines(bot.graph, ERROR)
    assert 12 <= len(frames) <= 16  # the camera's 30 Hz, for half a second
    last = frames[-1]
    assert last.format.startswith("png")
    image = cv2.imdecode(np.frombuffer(bytes(last.data), np.uint8), cv2.IMREAD_COLOR)
    assert image.shape == (480, 640, 3)
    assert tuple(image[240, 320]) == (0, 0, 255), "the red square the node drew (BGR)"
    seen = bot.sim.camera.render(bot.sim.pose)  # RGB, what the camera sees now (robot still)
    assert tuple(image[10, 10][::-1]) == tuple(seen[10, 10]), "the rest is the camera's image"
    assert last.header.stamp.to_sec() == pytest.approx(bot.time, abs=0.04)


def test_a_node_that_pairs_encoders_and_writes_a_bag(bot, tmp_path):
    bag_path = tmp_path / "pairs.bag"
    bot.graph.launch(node_script(NODES / "encoder_pairs_to_bag.py", str(bag_path)))
    bot.launch(drive_forward)
    bot.run(2.0)
    bot.shutdown()  # the node's on_shutdown hook closes the bag
    assert not lines(bot.graph, ERROR)
    bag = Bag(bag_path)
    left = [item.message for item in bag.read("left")]
    right = [item.message for item in bag.read("right")]
    assert len(left) == len(right) >= 55  # both encoders tick at 30 Hz
    for one, other in zip(left, right):
        assert abs(one.header.stamp.to_sec() - other.header.stamp.to_sec()) < 1 / 30
    assert left[-1].data - left[0].data > 50, "the wheels turned while it recorded"


def drive_forward():
    rospy.init_node("forward")
    pub = rospy.Publisher("car_cmd_switch_node/cmd", Twist2DStamped, queue_size=1)
    rate = rospy.Rate(10)
    while not rospy.is_shutdown():
        pub.publish(Twist2DStamped(v=0.2, omega=0.0))
        rate.sleep()


def test_a_script_runs_as_main_without_taking_the_processs_main(bot):
    main = sys.modules["__main__"]
    bot.graph.launch(node_script(NODES / "listener.py"))
    bot.run(0.5)
    assert "/listener" in " ".join(bot.graph.nodes), "the script's __main__ block ran"
    assert sys.modules["__main__"] is main, "a process started now must not run the script"


def test_a_node_whose_loop_runs_in_a_thread_it_starts(bot):
    start = bot.sim.pose
    bot.graph.launch(node_script(NODES / "threaded_patrol.py"))
    while "/patrol_node" in bot.graph.nodes or bot.time == 0.0:
        assert bot.time < 20.0, "the node did not finish in 20 s"
        bot.run(0.1)
    assert not lines(bot.graph, ERROR)
    said = {r.text.split(" at ")[0].split(" after ")[0]: r for r in lines(bot.graph)}
    # The Timer fired after 2 simulated seconds, from its own thread, as the node.
    assert said["lights on"].time == pytest.approx(2.0)
    assert said["lights on"].node == "/patrol_node"
    # The loop drove for 3 s, counted encoder ticks its callback stored, and stopped.
    stopped = said["stopped"]
    assert stopped.time == pytest.approx(3.0, abs=0.06)
    assert int(stopped.text.split()[2]) > 50
    # rospy.spin() in the main thread returned once the loop's thread shut the node down,
    # 0.5 s (a time.sleep in the thread) after the stop.
    assert bot.time == pytest.approx(3.6, abs=0.15)
    moved = math.hypot(bot.sim.pose[0] - start[0], bot.sim.pose[1] - start[1])
    assert moved > 0.3
    assert bot.sim.wheel_duties == (0.0, 0.0)
    white = (1.0, 1.0, 1.0)
    assert white in [pattern_colors(pattern)[0] for _, pattern in bot.sim.trace.patterns]
