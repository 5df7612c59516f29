"""Robot code's own imports, served by the in-process graph."""

from __future__ import annotations

import io
import subprocess
import sys

import pytest

from duckielib.ros import Graph, modules

ROBOT_NODE = """
import rospy
from duckietown.dtros import DTROS, NodeType, TopicType
from duckietown_msgs.msg import WheelsCmdStamped
from duckietown_msgs.srv import ChangePattern
from std_msgs.msg import String
from std_srvs.srv import SetBool


class StraightNode(DTROS):
    def __init__(self, node_name):
        super().__init__(node_name=node_name, node_type=NodeType.CONTROL)
        self.pub = rospy.Publisher("~wheels_cmd", WheelsCmdStamped, queue_size=1,
                                   dt_topic_type=TopicType.CONTROL, dt_help="duty cycles")
        self.stopped = []

    def run(self):
        rate = rospy.Rate(10)
        while not rospy.is_shutdown() and rospy.get_time() < 1.0:
            self.pub.publish(WheelsCmdStamped(vel_left=0.3, vel_right=0.3))
            rate.sleep()

    def on_shutdown(self):
        self.stopped.append(rospy.get_time())
"""


@pytest.fixture
def robot_imports():
    # Replace even a real ROS on the path: these tests are about the in-process graph.
    installed = modules.install_modules(replace_real=True)
    yield installed
    modules.uninstall_modules()


def test_robot_code_runs_unchanged(robot_imports):
    assert set(robot_imports) >= {"rospy", "std_msgs", "duckietown_msgs", "duckietown"}
    namespace = {}
    exec(compile(ROBOT_NODE, "straight_node.py", "exec"), namespace)
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    nodes = []

    def main():
        node = namespace["StraightNode"]("straight_node")
        nodes.append(node)
        node.run()

    graph.launch(main, namespace="/duckiebot")
    graph.run(2.0)
    node = nodes[0]
    assert node.node_name == "/duckiebot/straight_node"
    assert node.stopped == [1.0]
    assert node.is_shutdown
    assert "[/duckiebot/straight_node] Initializing..." in [r.text for r in graph.log]


def test_dtros_switch_service_and_log(robot_imports):
    import rospy
    from duckietown.dtros import DTROS, NodeType
    from std_srvs.srv import SetBool

    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    node = DTROS("switchable", NodeType.GENERIC)
    reply = rospy.ServiceProxy("/switchable/switch", SetBool)(data=False)
    assert (reply.success, reply.message) == (True, "Node switched from [on] to [off]")
    assert node.switch is False
    node.log("careful", type="warn")
    assert node.health.name == "WARNING"
    with pytest.raises(ValueError, match="not supported"):
        node.log("?", type="shout")
    with pytest.raises(ValueError, match=r"must be of type 'duckietown\.NodeType'"):
        DTROS("other", "GENERIC")
    graph.shutdown()


def test_unknown_publisher_keywords_are_refused(robot_imports):
    import rospy
    from std_msgs.msg import String

    graph = Graph(stdout=io.StringIO())
    rospy.init_node("strict")
    with pytest.raises(TypeError, match="unexpected keyword argument 'queue_sise'"):
        rospy.Publisher("chatter", String, queue_sise=1)
    graph.shutdown()


def test_a_real_ros_installation_is_not_shadowed(tmp_path):
    fake = tmp_path / "rospy"
    fake.mkdir()
    (fake / "__init__.py").write_text("REAL = True\n")
    script = (
        f"import sys; sys.path.append({str(tmp_path)!r})\n"
        "from duckielib.ros import install_modules\n"
        "print(sorted(install_modules()))\n"
        "import rospy; print(getattr(rospy, 'REAL', False))\n"
        "print(sorted(install_modules(replace_real=True)))\n"
        "import rospy; print(getattr(rospy, 'REAL', False))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True
    )
    served = ["duckietown", *modules._MESSAGE_PACKAGES]  # every package of the definitions
    assert {"geometry_msgs", "nav_msgs", "std_msgs", "duckietown_msgs"} <= set(served)
    assert result.stdout.split("\n")[:4] == [
        str(sorted(served)),
        "True",
        str(sorted([*served, "rospy"])),
        "False",
    ]


def run_python(script):
    """Run ``script`` in a fresh Python (a fresh kernel's view of the imports); its stdout."""
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_robot_imports_need_no_set_up_call_once_the_graph_is_imported():
    out = run_python(
        "import duckielib.ros\n"
        "import rospy\n"
        "from duckietown.dtros import DTROS\n"
        "from duckietown_msgs.msg import Pose2DStamped\n"
        "from std_msgs.msg import *\n"
        "print(rospy.__name__, Pose2DStamped.__module__, String._type, Empty._type)\n"
    )
    assert out.split() == [
        "duckielib.ros.rospy",
        "duckielib.messages.duckietown_msgs.msg",
        "std_msgs/String",
        "std_msgs/Empty",
    ]


def test_a_real_ros_on_the_path_wins_over_the_served_modules(tmp_path):
    for package in ("rospy", "std_msgs"):
        (tmp_path / package).mkdir()
        (tmp_path / package / "__init__.py").write_text("REAL = True\n")
    (tmp_path / "std_msgs" / "msg.py").write_text("REAL = True\n")
    out = run_python(
        "import sys\n"
        "import duckielib.ros\n"
        f"sys.path.append({str(tmp_path)!r})  # as use_debian_ros() does\n"
        "import rospy, std_msgs.msg, duckietown_msgs.msg\n"
        "print(getattr(rospy, 'REAL', False), getattr(std_msgs.msg, 'REAL', False),\n"
        "      duckietown_msgs.msg.__name__)\n"
    )
    assert out.split() == ["True", "True", "duckielib.messages.duckietown_msgs.msg"]


@pytest.mark.parametrize("real_ros_on_path", [False, True])
def test_the_library_odometry_node_runs_whatever_was_imported_before(tmp_path, real_ros_on_path):
    # The cell order of notebook 07: the node and the graph, never `import duckietown_msgs`.
    # With another duckietown_msgs on the path (a robot's, Debian's), the node on the
    # in-process graph still uses the graph's own message classes.
    (tmp_path / "duckietown_msgs").mkdir()
    (tmp_path / "duckietown_msgs" / "__init__.py").write_text("")
    (tmp_path / "duckietown_msgs" / "msg.py").write_text("REAL = True\n")
    path = f"import sys; sys.path.append({str(tmp_path)!r})\n" if real_ros_on_path else ""
    out = run_python(
        path + "from duckielib.messages import Pose2DStamped\n"
        "from duckielib.missions import TASK_START\n"
        "from duckielib.nodes import odometry_node\n"
        "from duckielib.ros import rospy\n"
        "from duckielib.sim import VirtualDuckiebot\n"
        "from duckielib.solution import load_solution\n"
        "import sys\n"
        "assert 'duckietown_msgs' not in sys.modules\n"
        "bot = VirtualDuckiebot(seed=0)\n"
        "bot.launch(odometry_node, rospy, load_solution(), TASK_START)\n"
        "seen = []\n"
        "def listener():\n"
        "    rospy.init_node('listener')\n"
        "    rospy.Subscriber('odometry_node/pose', Pose2DStamped,\n"
        "                     lambda msg: seen.append((msg.x, msg.y)))\n"
        "    rospy.spin()\n"
        "bot.launch(listener)\n"
        "bot.run(1.0)\n"
        "print(len(seen), round(seen[-1][0], 2), round(seen[-1][1], 2))\n"
    )
    count, x, y = out.split()
    assert int(count) >= 25  # about 30 pairs of encoder readings a second
    assert (float(x), float(y)) == (0.32, 0.32)  # standing still at the task's start
