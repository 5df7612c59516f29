"""rospy's API on the in-process graph: the same names, arguments and behaviour.

Use it exactly as rospy::

    from duckielib.ros import rospy
    from duckielib.messages import String

    def talker():
        rospy.init_node("talker")
        pub = rospy.Publisher("chatter", String, queue_size=10)
        rate = rospy.Rate(10)  # 10 Hz of simulated time
        while not rospy.is_shutdown():
            pub.publish(String(data="hello"))
            rate.sleep()

The graph (:class:`~duckielib.ros.graph.Graph`) runs such code on simulated time. Differences
from rospy are deliberate and small: several nodes share one process (each has its own
``init_node``); a message published to a topic of another type, or with a bad field value,
fails at once with a sentence saying why; ``Time.now()`` is the simulator's clock.

Simulated time moves only while every node waits. A node's main code that never waits (a
loop that polls, ``while distance < goal: pub.publish(cmd)``) is charged
:data:`CALL_COST_NS` of simulated time for each ``publish``, ``is_shutdown``, ``get_time``,
``get_rostime`` or ``Time.now`` it calls, and waits whenever it owes a millisecond: its loop
then runs about ten thousand times per simulated second, and the robot, the clock and the
other nodes go on meanwhile. Callbacks are not charged. ``time.sleep`` in a node's code waits
simulated seconds, as ``rospy.sleep`` does, and says so once (importing this module makes
``time.sleep`` do that; anywhere else it is the wall clock's, as always). A thread a node's
code starts runs as the node, on the graph's baton (:mod:`.threads`), and code that runs 10 s of
real time without calling rospy is stopped with a sentence (see :class:`~duckielib.ros.Graph`).

The package is split as rospy itself is: :mod:`.client` (nodes, names, parameters),
:mod:`.topics`, :mod:`.services`, :mod:`.timing` (time, sleeping, rates and timers),
:mod:`.logs`, and :mod:`.core` (waiting as a node); every name is here, at the top.
"""

from __future__ import annotations

import types

from duckielib.ros.exceptions import (
    ROSException,
    ROSInitException,
    ROSInterruptException,
    ROSSerializationException,
    ROSTimeMovedBackwardsException,
    ServiceException,
    TransportException,
)
from duckielib.ros.log import DEBUG, ERROR, FATAL, INFO, WARN
from duckielib.ros.rospy import client as _client_module
from duckielib.ros.rospy import threads as _threads  # noqa: F401  (adopts node threads)
from duckielib.ros.rospy import topics as _topics_module
from duckielib.ros.rospy.client import (
    delete_param,
    get_caller_id,
    get_name,
    get_namespace,
    get_param,
    get_param_cached,
    get_param_names,
    get_published_topics,
    has_param,
    init_node,
    is_shutdown,
    myargv,
    on_shutdown,
    remap_name,
    resolve_name,
    search_param,
    set_param,
    signal_shutdown,
    spin,
)
from duckielib.ros.rospy.core import (
    CALL_COST_NS,
)
from duckielib.ros.rospy.logs import (
    logdebug,
    logdebug_once,
    logdebug_throttle,
    logdebug_throttle_identical,
    logerr,
    logerr_once,
    logerr_throttle,
    logerr_throttle_identical,
    logfatal,
    logfatal_once,
    logfatal_throttle,
    logfatal_throttle_identical,
    loginfo,
    loginfo_once,
    loginfo_throttle,
    loginfo_throttle_identical,
    logwarn,
    logwarn_once,
    logwarn_throttle,
    logwarn_throttle_identical,
)
from duckielib.ros.rospy.services import (
    Service,
    ServiceProxy,
    wait_for_service,
)
from duckielib.ros.rospy.timing import (
    Duration,
    Rate,
    Time,
    Timer,
    TimerEvent,
    get_rostime,
    get_time,
    sleep,
)
from duckielib.ros.rospy.topics import (
    AnyMsg,
    Publisher,
    SubscribeListener,
    Subscriber,
    wait_for_message,
)

__all__ = [
    # nodes
    "init_node",
    "get_name",
    "get_caller_id",
    "get_namespace",
    "resolve_name",
    "remap_name",
    "is_shutdown",
    "signal_shutdown",
    "on_shutdown",
    "spin",
    "myargv",
    # topics and services
    "Publisher",
    "SubscribeListener",
    "Subscriber",
    "Service",
    "ServiceProxy",
    "wait_for_service",
    "wait_for_message",
    "AnyMsg",
    # parameters
    "get_param",
    "get_param_cached",
    "set_param",
    "has_param",
    "delete_param",
    "search_param",
    "get_param_names",
    "get_published_topics",
    # time
    "Time",
    "Duration",
    "Rate",
    "Timer",
    "TimerEvent",
    "sleep",
    "get_rostime",
    "get_time",
    # logging
    "logdebug",
    "loginfo",
    "logwarn",
    "logerr",
    "logfatal",
    "logdebug_throttle",
    "loginfo_throttle",
    "logwarn_throttle",
    "logerr_throttle",
    "logdebug_once",
    "loginfo_once",
    "logwarn_once",
    "logerr_once",
    "logfatal_throttle",
    "logfatal_once",
    "logdebug_throttle_identical",
    "loginfo_throttle_identical",
    "logwarn_throttle_identical",
    "logerr_throttle_identical",
    "logfatal_throttle_identical",
    "Header",
    "DEBUG",
    "INFO",
    "WARN",
    "ERROR",
    "FATAL",
    "CALL_COST_NS",
    # exceptions
    "ROSException",
    "ROSInitException",
    "ROSInterruptException",
    "ROSSerializationException",
    "ROSTimeMovedBackwardsException",
    "ServiceException",
    "TransportException",
]


def _header() -> type:
    from duckielib import messages

    return messages.std_msgs.msg.Header  # type: ignore[attr-defined]


#: std_msgs' Header, as rospy offers it (``rospy.Header``).
Header = _header()


def _flat(name: str, doc: str, **own: object) -> types.ModuleType:
    """A module of rospy's (``rospy.rostime``...): its own names, then every name of rospy's."""
    module = types.ModuleType(f"rospy.{name}", doc)
    module.__dict__.update(own)
    module.__dict__["_duckielib_alias"] = True  # uninstall_modules knows it as ours

    def rospy_name(attr: str) -> object:
        if attr in globals() and not attr.startswith("_"):
            return globals()[attr]
        raise AttributeError(f"module 'rospy.{name}' has no attribute {attr!r}")

    module.__getattr__ = rospy_name  # type: ignore[method-assign]
    return module


def _names_module() -> types.ModuleType:
    from duckielib.ros import names as _ros_names

    return _flat(
        "names",
        "rospy.names: resolving names (as rospy's).",
        ns_join=lambda ns, name: (
            name if name.startswith(("/", "~")) else _ros_names.normalize_namespace(ns) + name
        ),
        canonicalize_name=_ros_names.canonical,
        is_global=lambda name: name.startswith("/"),
        is_private=lambda name: name.startswith("~"),
    )


#: rospy's submodules, which code imports by name (``from rospy.rostime import Time``).
rostime = _flat("rostime", "rospy.rostime: ROS time (as rospy's).")
names = _names_module()
exceptions = _flat("exceptions", "rospy.exceptions: rospy's exceptions.")
msg = _flat("msg", "rospy.msg: AnyMsg (as rospy's).")
timer = _flat("timer", "rospy.timer: Rate, Timer, TimerEvent and sleep (as rospy's).")
service = _flat("service", "rospy.service: ServiceException (as rospy's).")
#: Every module of rospy's this serves, by name (``rospy.core`` holds rospy's own names there).
SUBMODULES = {
    "rostime": rostime,
    "names": names,
    "exceptions": exceptions,
    "msg": msg,
    "timer": timer,
    "service": service,
    "topics": _topics_module,
    "client": _client_module,
    "core": _flat(
        "core", "rospy.core: shutting down (as rospy's).", is_shutdown_requested=is_shutdown
    ),
}
