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
    assert result.stdout.split("\n")[:4] == [
        "['duckietown', 'duckietown_msgs', 'sensor_msgs', 'std_msgs', 'std_srvs']",
        "True",
        "['duckietown', 'duckietown_msgs', 'rospy', 'sensor_msgs', 'std_msgs', 'std_srvs']",
        "False",
    ]
