"""Duckietown's node base class, ``DTROS``, on whichever rospy the node runs with.

On a Duckiebot, nodes derive from ``duckietown.dtros.DTROS``; after
:func:`duckielib.ros.install_modules` the same import gives this class, so a node written
for the robot runs unchanged in a notebook. It keeps the parts of Duckietown's class a course
node uses: ``init_node`` with the node's name, ``node_name``, ``log()`` (which prefixes the
node's name), the ``~switch`` service that turns the node on and off (calling
``on_switch_on()``/``on_switch_off()``), ``is_shutdown``, an ``on_shutdown()`` method called
when the node stops, and parameters declared with :class:`DTParam`.
"""

from __future__ import annotations

import enum
import os
from typing import Any, Callable, List, Optional

from duckielib.messages import get_service_class
from duckielib.ros import rospy
from duckielib.ros.context import current_node

__all__ = ["DTROS", "DTParam", "NodeHealth", "NodeType", "ParamType", "TopicDirection", "TopicType"]

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
    CALIBRATION = 13
    DEBUG = 20


#: Duckietown tags topics with the same kinds as nodes (``dt_topic_type=TopicType.CONTROL``).
TopicType = NodeType


class TopicDirection(enum.Enum):
    """Whether a topic comes into a node or goes out of it."""

    INBOUND = 0
    OUTBOUND = 1


class ParamType(enum.Enum):
    """The type of a :class:`DTParam`'s value."""

    UNKNOWN = 0
    STRING = 1
    INT = 2
    FLOAT = 3
    BOOL = 4
    LIST = 5
    DICT = 6


_CONVERT = {ParamType.STRING: str, ParamType.INT: int, ParamType.FLOAT: float, ParamType.BOOL: bool}


def _as_type(param_type: ParamType, value: Any) -> Any:
    convert = _CONVERT.get(param_type)
    return value if value is None or convert is None else convert(value)


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
        pkg_name: the node's package, accepted for compatibility.
        help: what the node does, in a sentence (for diagnostics).
        dt_ghost: accepted for compatibility; diagnostics skip ghost nodes.

    Raises:
        ValueError: if ``node_type`` is not a :class:`NodeType`.
    """

    def __init__(
        self,
        node_name: str,
        node_type: NodeType,
        pkg_name: Optional[str] = None,
        help: Optional[str] = None,
        dt_ghost: bool = False,
    ) -> None:
        if not isinstance(node_type, NodeType):
            raise ValueError(
                "DTROS 'node_type' parameter must be of type 'duckietown.NodeType', "
                f"got {type(node_type)} instead."
            )
        debug = os.environ.get("DEBUG", "0") in ("1", "true", "True", "enabled", "on", "On")
        rospy.init_node(node_name, log_level=rospy.DEBUG if debug else rospy.INFO)
        self._node = current_node("DTROS")
        self.node_name = rospy.get_name()
        self.node_type = node_type
        self.package_name = pkg_name
        self.node_help = help
        self.parameters: List[DTParam] = []
        self.is_shutdown = False
        self._is_ghost = dt_ghost
        self._health = NodeHealth.STARTING
        self._health_reason: Optional[str] = None
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

    @property
    def publishers(self) -> List[Any]:
        """The node's publishers (``rospy.Publisher``), in the order it made them."""
        return list(self._node.publishers)

    @property
    def subscribers(self) -> List[Any]:
        """The node's subscribers (``rospy.Subscriber``), in the order it made them."""
        return list(self._node.subscribers)

    def set_health(self, health: NodeHealth, reason: Optional[str] = None) -> None:
        """Say how the node is doing (diagnostics read it), with a reason if given.

        Raises:
            ValueError: if ``health`` is not a :class:`NodeHealth`.
        """
        if not isinstance(health, NodeHealth):
            raise ValueError(f"health must be a duckietown NodeHealth, not {health!r}.")
        self._health = health
        self._health_reason = reason

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
        (self.on_switch_on if self._switch else self.on_switch_off)()
        self.log(message)
        return SetBool._response_class(success=True, message=message)

    def on_switch_on(self) -> None:
        """Called when the node is switched on through ``~switch``; override it if needed."""

    def on_switch_off(self) -> None:
        """Called when the node is switched off through ``~switch``; override it if needed."""

    def _on_shutdown(self) -> None:
        self.log("Received shutdown request.")
        self.is_shutdown = True
        self.on_shutdown()

    def on_shutdown(self) -> None:
        """Called once when the node shuts down; override it to stop motors, close files..."""


class DTParam:
    """A parameter of a Duckietown node: read once, kept with its type, default and limits.

    Create it after the node's ``DTROS.__init__``, usually as ``self.gain = DTParam("~gain",
    default=1.0, param_type=ParamType.FLOAT)``, and read ``self.gain.value``. A parameter that
    is not set yet is set to the default.

    Args:
        name: the parameter's name (``~gain`` is private to the node).
        default: the value when the parameter is not set.
        help: what the parameter means.
        param_type: a :class:`ParamType`; values are converted to it.
        min_value: the smallest value allowed (int and float parameters).
        max_value: the largest value allowed (int and float parameters).

    Raises:
        ValueError: for a wrong ``param_type``, limits on a type without order, or a default
            outside the limits.
        KeyError: if the parameter is not set and there is no default.
    """

    def __init__(
        self,
        name: str,
        default: Any = None,
        help: Optional[str] = None,
        param_type: ParamType = ParamType.UNKNOWN,
        min_value: Any = None,
        max_value: Any = None,
    ) -> None:
        if not isinstance(param_type, ParamType):
            raise ValueError(
                f"DTParam's 'param_type' must be a duckietown ParamType, not {type(param_type)}."
            )
        ordered = param_type in (ParamType.INT, ParamType.FLOAT)
        if (min_value is not None or max_value is not None) and not ordered:
            raise ValueError(f"DTParam {name}: limits need an INT or FLOAT parameter.")
        self._name = rospy.resolve_name(name)
        self._help = help
        self._type = param_type
        self._min_value = _as_type(param_type, min_value)
        self._max_value = _as_type(param_type, max_value)
        self._default = _as_type(param_type, default)
        if self._default is not None:
            if self._min_value is not None and self._default < self._min_value:
                raise ValueError(f"DTParam {name}: the default is below min_value.")
            if self._max_value is not None and self._default > self._max_value:
                raise ValueError(f"DTParam {name}: the default is above max_value.")
        self._listeners: List[Callable[[], Any]] = []
        if rospy.has_param(self._name):
            self._value = _as_type(param_type, rospy.get_param(self._name))
        elif default is None:
            raise KeyError(f"Parameter `{self._name}` not found.")
        else:
            self._value = self._default
            rospy.set_param(self._name, self._default)

    @property
    def name(self) -> str:
        """The parameter's global name."""
        return self._name

    @property
    def help(self) -> Optional[str]:
        """What the parameter means."""
        return self._help

    @property
    def value(self) -> Any:
        """The parameter's value."""
        return self._value

    @property
    def default(self) -> Any:
        """The value used when it was not set."""
        return self._default

    @property
    def type(self) -> ParamType:
        """The parameter's type."""
        return self._type

    @property
    def min_value(self) -> Any:
        """The smallest value allowed, or None."""
        return self._min_value

    @property
    def max_value(self) -> Any:
        """The largest value allowed, or None."""
        return self._max_value

    def set_value(self, value: Any) -> None:
        """Change the value here (not on the parameter server) and tell the listeners."""
        self._value = value
        for listener in list(self._listeners):
            listener()

    def force_update(self) -> None:
        """Read the value from the parameter server again."""
        self.set_value(_as_type(self._type, rospy.get_param(self._name, self._default)))

    def register_update_callback(self, callback: Callable[[], Any]) -> None:
        """Call ``callback()`` whenever the value changes."""
        self._listeners.append(callback)

    def unregister_update_callback(self, callback: Callable[[], Any]) -> None:
        """Stop calling ``callback``."""
        if callback in self._listeners:
            self._listeners.remove(callback)
