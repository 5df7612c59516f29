"""Deliberately wrong solutions of notebook 08_leds, one dict entry per mistake.

Each value is the full source of a replacement for the graded cell named by the key; the test
cell ``test_<grade_id>`` must lose marks with it. None of them hangs: a node that never stops
is left waiting on the graph, and every check runs for a bounded simulated time.
"""

WRONG = {
    "light_service_node": {
        "forwards unknown colours to the emitter without an error": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=10.0)
    emitter = rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        emitter(String(data=name))
        return ChangePatternResponse()

    def on_shutdown_topic(msg):
        rospy.signal_shutdown("the shutdown topic asked to stop")

    rospy.Service("~set_color", ChangePattern, on_set_color)
    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)
    rospy.spin()
""",
        "offers set_pattern instead of set_color": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=10.0)
    emitter = rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        if name not in COLORS:
            raise rospy.ServiceException(
                f"unknown colour {name!r}: use one of {', '.join(COLORS)}"
            )
        emitter(String(data=name))
        return ChangePatternResponse()

    def on_shutdown_topic(msg):
        rospy.signal_shutdown("the shutdown topic asked to stop")

    rospy.Service("~set_pattern", ChangePattern, on_set_color)
    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)
    rospy.spin()
""",
        "ignores the shutdown topic": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=10.0)
    emitter = rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        if name not in COLORS:
            raise rospy.ServiceException(
                f"unknown colour {name!r}: use one of {', '.join(COLORS)}"
            )
        emitter(String(data=name))
        return ChangePatternResponse()

    def on_shutdown_topic(msg):
        rospy.loginfo("asked to stop, but carrying on")

    rospy.Service("~set_color", ChangePattern, on_set_color)
    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)
    rospy.spin()
""",
        "calls the emitter by a wrong service name, without waiting": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    emitter = rospy.ServiceProxy("led_emitter_node/set_color", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        if name not in COLORS:
            raise rospy.ServiceException(
                f"unknown colour {name!r}: use one of {', '.join(COLORS)}"
            )
        emitter(String(data=name))
        return ChangePatternResponse()

    def on_shutdown_topic(msg):
        rospy.signal_shutdown("the shutdown topic asked to stop")

    rospy.Service("~set_color", ChangePattern, on_set_color)
    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)
    rospy.spin()
""",
        "lower-cases the colour before forwarding it": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=10.0)
    emitter = rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        if name not in COLORS:
            raise rospy.ServiceException(
                f"unknown colour {name!r}: use one of {', '.join(COLORS)}"
            )
        emitter(String(data=name.lower()))
        return ChangePatternResponse()

    def on_shutdown_topic(msg):
        rospy.signal_shutdown("the shutdown topic asked to stop")

    rospy.Service("~set_color", ChangePattern, on_set_color)
    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)
    rospy.spin()
""",
        "the handler returns None": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=10.0)
    emitter = rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        if name not in COLORS:
            raise rospy.ServiceException(
                f"unknown colour {name!r}: use one of {', '.join(COLORS)}"
            )
        emitter(String(data=name))

    def on_shutdown_topic(msg):
        rospy.signal_shutdown("the shutdown topic asked to stop")

    rospy.Service("~set_color", ChangePattern, on_set_color)
    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)
    rospy.spin()
""",
        "the error does not name the valid colours": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=10.0)
    emitter = rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        if name not in COLORS:
            raise rospy.ServiceException(
                f"unknown colour {name!r}"
            )
        emitter(String(data=name))
        return ChangePatternResponse()

    def on_shutdown_topic(msg):
        rospy.signal_shutdown("the shutdown topic asked to stop")

    rospy.Service("~set_color", ChangePattern, on_set_color)
    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)
    rospy.spin()
""",
        "refuses with ValueError instead of rospy.ServiceException": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=10.0)
    emitter = rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        if name not in COLORS:
            raise ValueError(
                f"unknown colour {name!r}: use one of {', '.join(COLORS)}"
            )
        emitter(String(data=name))
        return ChangePatternResponse()

    def on_shutdown_topic(msg):
        rospy.signal_shutdown("the shutdown topic asked to stop")

    rospy.Service("~set_color", ChangePattern, on_set_color)
    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)
    rospy.spin()
""",
        "no rospy.spin(): the node ends at once": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=10.0)
    emitter = rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        if name not in COLORS:
            raise rospy.ServiceException(
                f"unknown colour {name!r}: use one of {', '.join(COLORS)}"
            )
        emitter(String(data=name))
        return ChangePatternResponse()

    def on_shutdown_topic(msg):
        rospy.signal_shutdown("the shutdown topic asked to stop")

    rospy.Service("~set_color", ChangePattern, on_set_color)
    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)
""",
        "hard-codes the robot's name": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    rospy.wait_for_service("/duckiebot/led_emitter_node/set_pattern", timeout=10.0)
    emitter = rospy.ServiceProxy("/duckiebot/led_emitter_node/set_pattern", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        if name not in COLORS:
            raise rospy.ServiceException(
                f"unknown colour {name!r}: use one of {', '.join(COLORS)}"
            )
        emitter(String(data=name))
        return ChangePatternResponse()

    def on_shutdown_topic(msg):
        rospy.signal_shutdown("the shutdown topic asked to stop")

    rospy.Service("~set_color", ChangePattern, on_set_color)
    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)
    rospy.spin()
""",
        "listens to a private ~shutdown topic": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=10.0)
    emitter = rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        if name not in COLORS:
            raise rospy.ServiceException(
                f"unknown colour {name!r}: use one of {', '.join(COLORS)}"
            )
        emitter(String(data=name))
        return ChangePatternResponse()

    def on_shutdown_topic(msg):
        rospy.signal_shutdown("the shutdown topic asked to stop")

    rospy.Service("~set_color", ChangePattern, on_set_color)
    rospy.Subscriber("~shutdown", Empty, on_shutdown_topic, queue_size=1)
    rospy.spin()
""",
        "withdraws the service on shutdown but keeps the node running": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=10.0)
    emitter = rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        if name not in COLORS:
            raise rospy.ServiceException(
                f"unknown colour {name!r}: use one of {', '.join(COLORS)}"
            )
        emitter(String(data=name))
        return ChangePatternResponse()

    service = rospy.Service("~set_color", ChangePattern, on_set_color)

    def on_shutdown_topic(msg):
        service.shutdown("asked to stop")

    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)
    rospy.spin()
""",
        "accepts every pattern the emitter knows": """import rospy
from duckietown_msgs.srv import ChangePattern, ChangePatternResponse
from std_msgs.msg import Empty, String

COLORS = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF")


def light_service_node():
    rospy.init_node("light_service_node")
    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=10.0)
    emitter = rospy.ServiceProxy("led_emitter_node/set_pattern", ChangePattern)

    def on_set_color(request):
        name = request.pattern_name.data
        if name not in COLORS and not name.startswith("CAR_"):
            raise rospy.ServiceException(
                f"unknown colour {name!r}: use one of {', '.join(COLORS)}"
            )
        emitter(String(data=name))
        return ChangePatternResponse()

    def on_shutdown_topic(msg):
        rospy.signal_shutdown("the shutdown topic asked to stop")

    rospy.Service("~set_color", ChangePattern, on_set_color)
    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)
    rospy.spin()
""",
    },
}
