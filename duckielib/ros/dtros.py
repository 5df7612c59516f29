"""Duckietown's node base class, ``DTROS``, on whichever rospy the node runs with.

On a Duckiebot, nodes derive from ``duckietown.dtros.DTROS``; after
:func:`duckielib.ros.install_modules` the same import gives this class, so a node written
for the robot runs unchanged in a notebook. It keeps the parts of Duckietown's class a course
node uses: ``init_node`` with the node's name, ``node_name``, ``log()`` (which prefixes the
node's name), the ``~switch`` service that turns the node on and off, ``is_shutdown`` and an
``on_shutdown()`` method called when the node stops.
"""

from __future__ import annotations

import enum
import os
from typing import Any

from duckielib.messages import get_service_class
from duckielib.ros import rospy

__all__ = ["DTROS", "NodeHealth", "NodeType", "TopicType"]

SetBool = get_service_class("std_srvs/SetBool")


class NodeType(enum.Enum):
    """What kind of node this is (Duckietown uses it for diagnostics)."""

    GENERIC = 0
    DRIVER = 1
    PERCEPTION = 2
    CONTROL = 3
    PLANNING = 4
    LOCALIZATION = 5
    MAPPING = 6
    SWARM = 7
    BEHAVIOR = 8
    VISUALIZATION = 9
    INFRASTRUCTURE = 10
    COMMUNICATION = 11
    DIAGNOSTICS = 12
    DEBUG = 20


#: Duckietown tags topics with the same kinds as nodes (``dt_topic_type=TopicType.CONTROL``).
TopicType = NodeType


class NodeHealth(enum.Enum):
    """How a node reports it is doing."""

    UNKNOWN = 0
    STARTING = 1
    STARTED = 2
    HEALTHY = 3
    WARNING = 4
    ERROR = 5
    FATAL = 6


_LOGGERS = {
    "debug": (rospy.logdebug, None),
    "info": (rospy.loginfo, None),
    "warn": (rospy.logwarn, NodeHealth.WARNING),
    "warning": (rospy.logwarn, NodeHealth.WARNING),
    "err": (rospy.logerr, NodeHealth.ERROR),
    "error": (rospy.logerr, NodeHealth.ERROR),
    "fatal": (rospy.logfatal, NodeHealth.FATAL),
}


class DTROS:
    """Parent class of Duckietown nodes.

    Args:
        node_name: the node's name (a base name such as ``"odometry_node"``).
        node_type: a :class:`NodeType`.
        dt_ghost: accepted for compatibility; diagnostics skip ghost nodes.

    Raises:
        ValueError: if ``node_type`` is not a :class:`NodeType`.
    """

    def __init__(self, node_name: str, node_type: NodeType, dt_ghost: bool = False) -> None:
        if not isinstance(node_type, NodeType):
            raise ValueError(
                "DTROS 'node_type' parameter must be of type 'duckietown.NodeType', "
                f"got {type(node_type)} instead."
            )
        debug = os.environ.get("DEBUG", "0") in ("1", "true", "True", "enabled", "on", "On")
        rospy.init_node(node_name, log_level=rospy.DEBUG if debug else rospy.INFO)
        self.node_name = rospy.get_name()
        self.node_type = node_type
        self.is_shutdown = False
        self._is_ghost = dt_ghost
        self._health = NodeHealth.STARTING
        self._switch = True
        self.log("Initializing...")
        self.srv_switch = rospy.Service("~switch", SetBool, self._srv_switch)
        self._health = NodeHealth.STARTED
        rospy.on_shutdown(self._on_shutdown)

    @property
    def switch(self) -> bool:
        """Whether the node is on (set through its ``~switch`` service)."""
        return self._switch

    @property
    def is_ghost(self) -> bool:
        """Whether diagnostics skip this node."""
        return self._is_ghost

    @property
    def health(self) -> NodeHealth:
        """The node's health, lowered by warnings and errors it logs."""
        return self._health

    def log(self, msg: Any, type: str = "info") -> None:
        """Log ``msg`` prefixed with the node's name.

        Args:
            msg: the text.
            type: one of ``debug``, ``info``, ``warn``, ``err``, ``fatal``.

        Raises:
            ValueError: for another ``type``.
        """
        if type not in _LOGGERS:
            raise ValueError(f"Type argument value {type} is not supported!")
        logger, health = _LOGGERS[type]
        text = f"[{self.node_name}] {msg}"
        if health is not None:
            self._health = health
        logger(text)

    def loginfo(self, msg: Any) -> None:
        """Log at info level."""
        self.log(msg, "info")

    def logwarn(self, msg: Any) -> None:
        """Log a warning."""
        self.log(msg, "warn")

    def logerr(self, msg: Any) -> None:
        """Log an error."""
        self.log(msg, "err")

    def logdebug(self, msg: Any) -> None:
        """Log at debug level."""
        self.log(msg, "debug")

    def logfatal(self, msg: Any) -> None:
        """Log a fatal error."""
        self.log(msg, "fatal")

    def _srv_switch(self, request: Any) -> Any:
        old, self._switch = self._switch, bool(request.data)
        message = (
            f"Node switched from [{'on' if old else 'off'}] to [{'on' if self._switch else 'off'}]"
        )
        self.log(message)
        return SetBool._response_class(success=True, message=message)

    def _on_shutdown(self) -> None:
        self.log("Received shutdown request.")
        self.is_shutdown = True
        self.on_shutdown()

    def on_shutdown(self) -> None:
        """Called once when the node shuts down; override it to stop motors, close files..."""
