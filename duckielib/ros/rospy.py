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
``time.sleep`` do that; anywhere else it is the wall clock's, as always).
"""

from __future__ import annotations

import collections
import io
import os
import sys
import time
from typing import Any, Callable, Deque, List, Optional, Type, Union, cast

from duckielib import rostime
from duckielib.errors import MessageError, UnknownTypeError
from duckielib.messages import Message
from duckielib.messages import Service as ServiceType
from duckielib.messages import get_message_class as messages_get_class
from duckielib.ros import names
from duckielib.ros.context import (
    calling_actor,
    current_node,
    latest_graph,
    node_context,
    node_stack,
    waiting_for_init,
)
from duckielib.ros.exceptions import (
    ROSException,
    ROSInitException,
    ROSInterruptException,
    ROSSerializationException,
    ROSTimeMovedBackwardsException,
    ServiceException,
    TransportException,
)
from duckielib.ros.graph import current_graph
from duckielib.ros.log import DEBUG, ERROR, FATAL, INFO, WARN, format_error
from duckielib.ros.node import Node, ServiceRecord, TopicRecord
from duckielib.ros.params import copy_tree
from duckielib.rostime import NS_PER_S

__all__ = [
    # nodes
    "init_node",
    "get_name",
    "get_caller_id",
    "get_namespace",
    "resolve_name",
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
    "DEBUG",
    "INFO",
    "WARN",
    "ERROR",
    "FATAL",
    # exceptions
    "ROSException",
    "ROSInitException",
    "ROSInterruptException",
    "ROSSerializationException",
    "ROSTimeMovedBackwardsException",
    "ServiceException",
    "TransportException",
]


class AnyMsg:
    """Subscribe with this class to receive any topic's messages undecoded, as ``rosbag record``.

    The callback gets an ``AnyMsg`` whose ``_buff`` holds the message's serialized bytes and
    whose ``_connection_header`` gives the topic's ``type``, ``md5sum``, ``message_definition``
    and the publishing node (``callerid``).
    """

    _type = "*"
    _md5sum = "*"
    _full_text = ""
    _has_header = False

    def __init__(self) -> None:
        self._buff = b""
        self._connection_header: dict = {}

    @classmethod
    def from_bytes(cls, data: bytes) -> AnyMsg:
        """Wrap serialized bytes."""
        message = cls()
        message._buff = data
        return message

    def __repr__(self) -> str:
        kind = self._connection_header.get("type", "?")
        return f"<AnyMsg {kind}, {len(self._buff)} bytes>"


_UNSET = object()


# -- time ---------------------------------------------------------------------------------------
class Duration(rostime.Duration):
    """A span of ROS time (see :class:`duckielib.rostime.Duration`)."""

    __slots__ = ()


class Time(rostime.Time):
    """A point in ROS time; :meth:`now` reads the graph's simulated clock."""

    __slots__ = ()
    duration_class = Duration

    @classmethod
    def now(cls) -> Time:
        """The current simulated time.

        Raises:
            ROSInitException: before ``rospy.init_node``.
        """
        node = current_node("rospy.Time.now()")
        _spend(node)
        return cls(0, node.graph.now_ns)


def get_rostime() -> Time:
    """The current simulated time, as a :class:`Time`."""
    return Time.now()


def get_time() -> float:
    """The current simulated time, in seconds."""
    return Time.now().to_sec()


def _to_ns(duration: Union[float, rostime.Duration]) -> int:
    if isinstance(duration, rostime.Duration):
        return duration.to_nsec()
    if isinstance(duration, rostime.Time):
        raise TypeError("rospy.sleep() takes a duration (seconds or rospy.Duration), not a Time.")
    return round(float(duration) * NS_PER_S)


def sleep(duration: Union[float, rostime.Duration]) -> None:
    """Sleep for a duration of simulated time (seconds or :class:`Duration`).

    Raises:
        ROSInterruptException: if the node shuts down before the time is up.
    """
    node = current_node("rospy.sleep()")
    if node.is_shutdown:
        return  # as rospy on a robot's clock: a sleep after shutdown (in a hook) just returns
    span = _to_ns(duration)
    if span <= 0:
        return
    _block(node, node.graph.now_ns + span, lambda: node.is_shutdown, polled=False)
    if node.is_shutdown:
        raise ROSInterruptException("ROS shutdown request")


#: Simulated time that one rospy call costs the main code of a node that never waits, in ns.
CALL_COST_NS = 100_000
#: A node that never waits waits once it owes this much simulated time, in ns.
_MAX_DEBT_NS = 1_000_000


def _block(
    node: Node, deadline_ns: Optional[int], predicate: Callable[[], bool], polled: bool = True
) -> bool:
    """Wait as ``node`` (see :meth:`Graph.block`); a node that waits owes no compute time."""
    node.compute_debt_ns = 0
    return node.graph.block(deadline_ns, predicate, polled=polled)


def _spend(node: Node) -> None:
    """Charge ``node``'s main code for one rospy call; make it wait once it owes 1 ms.

    Callbacks, and code that runs while the graph delivers events in this thread, are not
    charged: only code that could otherwise hold the clock still for ever.
    """
    if node.is_shutdown or node_stack():
        return
    if calling_actor() is None and node.graph.driving_here():
        return
    node.compute_debt_ns += CALL_COST_NS
    if node.compute_debt_ns >= _MAX_DEBT_NS:
        owed = node.compute_debt_ns
        _block(node, node.graph.now_ns + owed, lambda: node.is_shutdown, polled=False)


class Rate:
    """Sleep in a loop so that it runs at ``hz`` times per simulated second."""

    def __init__(self, hz: float, reset: bool = False) -> None:
        if not hz > 0:
            raise ValueError(f"rospy.Rate needs a positive frequency in Hz, not {hz!r}.")
        self.last_time = get_rostime()
        self.sleep_dur = Duration(0, int(NS_PER_S / hz))
        self._reset = reset

    def _remaining(self, curr_time: Time) -> Duration:
        self.last_time = min(self.last_time, curr_time)
        return self.sleep_dur - (curr_time - self.last_time)

    def remaining(self) -> Duration:
        """Time left until the next cycle is due."""
        return self._remaining(get_rostime())

    def sleep(self) -> None:
        """Sleep until the next cycle is due (at once if the loop is running late).

        Raises:
            ROSInterruptException: if the node shuts down while sleeping.
        """
        curr_time = get_rostime()
        sleep(self._remaining(curr_time))
        self.last_time = self.last_time + self.sleep_dur
        if curr_time - self.last_time > self.sleep_dur * 2:
            self.last_time = curr_time


class TimerEvent:
    """What a :class:`Timer` callback receives (times are :class:`Time`)."""

    def __init__(
        self,
        last_expected: Optional[Time],
        last_real: Optional[Time],
        current_expected: Time,
        current_real: Time,
        last_duration: Optional[float],
    ) -> None:
        self.last_expected = last_expected
        self.last_real = last_real
        self.current_expected = current_expected
        self.current_real = current_real
        self.last_duration = last_duration


class Timer:
    """Call ``callback(event)`` every ``period`` (a :class:`Duration`) of simulated time."""

    def __init__(
        self,
        period: rostime.Duration,
        callback: Callable[[TimerEvent], Any],
        oneshot: bool = False,
        reset: bool = False,
    ) -> None:
        self._node = current_node("rospy.Timer")
        self._period_ns = _to_ns(period)
        if self._period_ns <= 0:
            raise ValueError("rospy.Timer needs a positive period.")
        self._callback = callback
        self._oneshot = oneshot
        self._last: Optional[Time] = None
        self._expected_ns = self._node.graph.now_ns + self._period_ns
        self._event = self._node.graph.schedule(self._expected_ns, self._fire)
        self._node.timers.append(self)

    def _fire(self) -> None:
        graph = self._node.graph
        now = Time(0, graph.now_ns)
        event = TimerEvent(self._last, self._last, Time(0, self._expected_ns), now, 0.0)
        self._last = now
        with node_context(self._node):
            try:
                self._callback(event)
            except Exception as error:
                self._node.log(ERROR, "bad timer callback:\n" + format_error(error))
        if self._oneshot or self._node.is_shutdown or self._event is None:
            self.shutdown()
            return
        self._expected_ns += self._period_ns
        self._event = graph.schedule(self._expected_ns, self._fire)

    def shutdown(self) -> None:
        """Stop the timer."""
        if self._event is not None:
            self._event.cancel()
            self._event = None
        if self in self._node.timers:
            self._node.timers.remove(self)

    def is_alive(self) -> bool:
        """Whether the timer will fire again."""
        return self._event is not None


# -- nodes --------------------------------------------------------------------------------------
def init_node(
    name: str,
    argv: Optional[List[str]] = None,
    anonymous: bool = False,
    log_level: Optional[int] = None,
    disable_rostime: bool = False,
    disable_rosout: bool = False,
    disable_signals: bool = False,
    xmlrpc_port: int = 0,
    tcpros_port: int = 0,
) -> None:
    """Register the calling code as a node named ``name`` (a base name, no slashes).

    A node launched with a name or namespace (``Graph.launch``) takes those instead. Outside
    launched nodes (a notebook), the namespace comes from ``ROS_NAMESPACE``, as in ROS.
    ``argv`` may hold roslaunch-style arguments: remappings (``chatter:=/news``,
    ``~cmd:=/x``), ``__name:=``, ``__ns:=`` and private parameters (``_rate:=10``).

    Raises:
        ValueError: if ``name`` is not a legal base name.
        ROSException: if the caller already initialised a node with other arguments.
    """
    if not isinstance(name, str) or "/" in name:
        raise ValueError(
            f"rospy.init_node() takes a base name without '/', such as 'talker', not {name!r}; "
            "set the namespace with ROS_NAMESPACE or when launching the node."
        )
    if not names.is_legal_base_name(name):
        raise ValueError(f"{name!r} is not a legal node name: use letters, digits and '_'.")
    graph = current_graph()
    arguments = (name, anonymous, log_level)
    actor = graph.current_actor()
    existing = actor.node if actor is not None else graph.foreground_node()
    if existing is not None and not existing.is_shutdown:
        if existing.init_args == arguments:
            return
        raise ROSException(
            f"rospy.init_node() has already been called with different arguments "
            f"(this code is node {existing.name})."
        )
    launch = actor.launch if actor is not None else {}
    namespace = launch.get("namespace") or os.environ.get("ROS_NAMESPACE", "/")
    base = launch.get("name") or name
    remap = dict(launch.get("remap") or {})
    params = dict(launch.get("params") or {})
    for arg in argv or []:  # roslaunch-style arguments: name:=value
        key, sep, value = arg.partition(":=")
        if not sep:
            continue
        if key == "__name":
            base = value
        elif key == "__ns":
            namespace = value
        elif key.startswith("_") and not key.startswith("__"):
            params[key[1:]] = _argument_value(value)
        elif not key.startswith("__"):
            remap[key] = value
    if anonymous:
        base += graph.anonymous_suffix()
    namespace = names.normalize_namespace(namespace)
    full_name = names.canonical(namespace + base)
    remappings = {
        names.resolve(source, namespace, full_name): names.resolve(target, namespace, full_name)
        for source, target in remap.items()
    }
    node = Node(graph, base, namespace, remappings, log_level or INFO, arguments)
    for key, value in params.items():
        graph.set_param(node.resolve_param("~" + key.lstrip("~")), value)
    graph.add_node(node)
    _attach_waiting(node)


def _attach_waiting(node: Node) -> None:
    waiting = waiting_for_init()
    while waiting:
        waiting.pop(0)(node)


def _node_or_later(attach: Callable[[Node], None]) -> None:
    """Run ``attach(node)`` now, or once the calling code has called ``init_node``.

    rospy allows publishers, subscribers and service proxies made before ``init_node``.
    """
    try:
        node = current_node()
    except ROSInitException:
        waiting_for_init().append(attach)
    else:
        attach(node)


def _argument_value(text: str) -> Any:
    """A private parameter given as ``_name:=value``: a bool, int or float if it reads as one."""
    if text.lower() in ("true", "false"):
        return text.lower() == "true"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def myargv(argv: Optional[List[str]] = None) -> List[str]:
    """The command line without ROS's remapping arguments (those with ``:=``)."""
    return [arg for arg in (sys.argv if argv is None else argv) if ":=" not in arg]


def get_name() -> str:
    """The calling node's global name, for example ``/duckiebot/talker``."""
    return current_node("rospy.get_name()").name


get_caller_id = get_name


def get_namespace() -> str:
    """The calling node's namespace, with slashes: ``/duckiebot/``."""
    return current_node("rospy.get_namespace()").namespace


def resolve_name(name: str, caller_id: Optional[str] = None) -> str:
    """Resolve a name as the calling node sees it (global, relative or private ``~``)."""
    return current_node("rospy.resolve_name()").resolve(name)


def is_shutdown() -> bool:
    """Whether the calling node is shutting down (a loop's signal to stop)."""
    try:
        node = current_node()
    except ROSInitException:
        return current_graph().is_shutdown
    _spend(node)
    return node.is_shutdown


def signal_shutdown(reason: str) -> None:
    """Shut the calling node down: its shutdown hooks run, its topics and services close."""
    current_node("rospy.signal_shutdown()").shutdown(reason)


def on_shutdown(hook: Callable[[], Any]) -> None:
    """Call ``hook()`` (no arguments) when the calling node shuts down."""
    current_node("rospy.on_shutdown()").shutdown_hooks.append(hook)


def spin() -> None:
    """Keep the node alive, running its callbacks, until it shuts down."""
    node = current_node("rospy.spin()")
    _block(node, None, lambda: node.is_shutdown, polled=False)


# -- topics -------------------------------------------------------------------------------------
class SubscribeListener:
    """Told when subscribers come and go: give one to ``Publisher(subscriber_listener=...)``.

    Override the methods you need; the defaults do nothing.
    """

    def peer_subscribe(
        self,
        topic_name: str,
        topic_publish: Callable[[Any], None],
        peer_publish: Callable[[Any], None],
    ) -> None:
        """A subscriber connected: ``topic_publish`` sends to all, ``peer_publish`` to it only."""

    def peer_unsubscribe(self, topic_name: str, num_peers: int) -> None:
        """A subscriber left; ``num_peers`` are still connected."""


def _check_data_class(data_class: Any, what: str) -> None:
    md5sum = getattr(data_class, "_md5sum", None) if isinstance(data_class, type) else None
    if not md5sum:
        raise ValueError(
            f"{what} needs a message class such as String or WheelsCmdStamped, not {data_class!r}."
        )


def _course_class(data_class: Any, what: str) -> Any:
    """The class to use for ``data_class``: itself, or the course's class of its type.

    A class generated elsewhere (by genpy, in a catkin build) is replaced by the course's class
    of the same type and definition, so its messages travel the graph as bytes.

    Raises:
        ValueError: if a class generated elsewhere is of a type the course does not know, or
            has another definition than the course's (another md5 sum).
    """
    _check_data_class(data_class, what)
    if hasattr(data_class, "from_bytes"):
        return data_class  # the course's own (or AnyMsg)
    name = str(getattr(data_class, "_type", data_class.__name__))
    try:
        ours = messages_get_class(name)
    except UnknownTypeError:
        raise ValueError(
            f"{what}: {name} comes from a module generated outside this course, for a type the "
            "course does not know. Put its .msg file in the msg/ folder of your package, beside "
            "your node, and import it from there."
        ) from None
    if ours._md5sum != data_class._md5sum:
        raise ValueError(
            f"{what}: your {name} has another definition than the robot's (md5 sum "
            f"{data_class._md5sum}, the robot's is {ours._md5sum}); use the robot's definition."
        )
    return ours


def _check_dt_options(what: str, options: dict) -> None:
    """Accept Duckietown's extra keywords (``dt_topic_type``, ``dt_help``...), refuse others."""
    unknown = sorted(key for key in options if not key.startswith("dt_"))
    if unknown:
        raise TypeError(f"{what}() got an unexpected keyword argument {unknown[0]!r}")


def _to_message(data_class: Type[Message], args: tuple, kwds: dict) -> Any:
    """Build the message ``publish(...)`` or a service call means, as rospy does."""
    if args and kwds:
        raise TypeError("publish() can be called with arguments or keywords, but not both.")
    if kwds:
        return data_class(**kwds)
    if len(args) == 1:
        arg = args[0]
        if getattr(arg, "_md5sum", None) == data_class._md5sum:
            if not isinstance(arg, Message) and hasattr(arg, "serialize"):
                buffer = io.BytesIO()  # a message of a class generated elsewhere (genpy)
                arg.serialize(buffer)
                return data_class.from_bytes(buffer.getvalue())
            return arg
        if isinstance(arg, Message):
            expected = data_class._slot_types[0] if data_class._slot_types else ""
            if arg._type != expected:
                raise TypeError(
                    f"expected [{data_class._type}] but got [{arg._type}]: this topic or "
                    f"service carries {data_class._type} messages."
                )
    return data_class(*args)


class Publisher:
    """Publish messages of one type on a topic.

    Args:
        name: topic name (global, relative to the node's namespace, or private ``~name``).
        data_class: the message class, for example ``WheelsCmdStamped``.
        latch: keep the last message and give it to subscribers that connect later.
        queue_size: how many messages may wait to be sent (as rospy; give it explicitly).
        **dt_options: Duckietown's keywords (``dt_topic_type``, ``dt_help``), accepted as on a
            Duckiebot.
    """

    def __init__(
        self,
        name: str,
        data_class: Type[Message],
        subscriber_listener: Any = None,
        tcp_nodelay: bool = False,
        latch: bool = False,
        headers: Any = None,
        queue_size: Optional[int] = None,
        **dt_options: Any,
    ) -> None:
        _check_dt_options("rospy.Publisher", dt_options)
        data_class = _course_class(data_class, "rospy.Publisher")
        if data_class is AnyMsg:
            raise ValueError("rospy.Publisher needs a concrete message class, not AnyMsg.")
        self.resolved_name = self.name = name  # resolved once the node exists
        self.data_class = data_class
        self.type = data_class._type
        self.md5sum = data_class._md5sum
        self.latch = latch
        self.queue_size = queue_size
        self.subscriber_listener: Optional[SubscribeListener] = subscriber_listener
        self._seq = 0
        self._record: Optional[TopicRecord] = None
        _node_or_later(self._attach)

    def _attach(self, node: Node) -> None:
        self._node = node
        self.resolved_name = self.name = node.resolve(self.name)
        self._record = node.topic(self.name, self.data_class, "publish on")
        self._record.publishers.append(self)
        node.publishers.append(self)
        if self.queue_size is None:
            node.log(
                WARN,
                f"The publisher of {self.name} should be created with an explicit keyword "
                "argument 'queue_size'.",
            )

    @property
    def node(self) -> Node:
        """The node that owns this publisher."""
        return self._node

    def publish(self, *args: Any, **kwds: Any) -> None:
        """Publish a message, or build one from the arguments and publish it.

        Raises:
            ROSException: if the publisher was unregistered (for example after shutdown).
            ROSSerializationException: if a field holds a value its type cannot carry.
            TypeError: if the message is of another type than the topic's.
        """
        if self._record is None:
            if not hasattr(self, "_node"):
                raise ROSInitException(
                    f"publish() on {self.name} needs a node: call rospy.init_node('name') first."
                )
            if self._node.is_shutdown:
                return  # as rospy: a node that has shut down publishes nothing, quietly
            raise ROSException(f"publish() to an unregistered() handle (topic {self.name}).")
        try:
            message: Any
            if len(args) == 1 and not kwds and type(args[0]) is self.data_class:
                message = args[0]  # the common case, without the checks _to_message makes
            else:
                message = _to_message(self.data_class, args, kwds)
            self._seq += 1
            if message._has_header:
                message.header.seq = self._seq
            data = message.to_bytes()
        except MessageError as error:
            raise ROSSerializationException(str(error)) from None
        record = self._record
        record.message_count += 1
        if self.latch:
            record.latched[self] = data
        for subscriber in list(record.subscribers):
            subscriber._enqueue(data)
        _spend(self._node)

    def get_num_connections(self) -> int:
        """How many subscribers the topic has."""
        return len(self._record.subscribers) if self._record is not None else 0

    def unregister(self) -> None:
        """Stop publishing: the topic forgets this publisher (and its latched message)."""
        record, self._record = self._record, None
        if record is None:
            return
        record.publishers.remove(self)
        record.latched.pop(self, None)
        if self in self._node.publishers:
            self._node.publishers.remove(self)
        self._node.forget_topic_user(record)


class Subscriber:
    """Call ``callback(msg)`` (or ``callback(msg, callback_args)``) for each message on a topic.

    Args:
        name: topic name.
        data_class: the message class the topic carries.
        callback: the function that handles each message; it runs between node steps.
        callback_args: an extra argument passed to the callback.
        queue_size: how many messages may wait for the callback; when full, the oldest is
            dropped (None: no limit).
        **dt_options: Duckietown's keywords (``dt_topic_type``, ``dt_help``).
    """

    def __init__(
        self,
        name: str,
        data_class: Union[Type[Message], Type[AnyMsg]],
        callback: Optional[Callable[..., Any]] = None,
        callback_args: Any = None,
        queue_size: Optional[int] = None,
        buff_size: int = 65536,
        tcp_nodelay: bool = False,
        **dt_options: Any,
    ) -> None:
        _check_dt_options("rospy.Subscriber", dt_options)
        data_class = _course_class(data_class, "rospy.Subscriber")
        self.resolved_name = self.name = name  # resolved once the node exists
        self.data_class = data_class
        self.type = data_class._type
        self.callback = callback
        self.callback_args = callback_args
        self.queue_size = queue_size
        self._queue: Deque[bytes] = collections.deque(maxlen=queue_size or None)
        self._scheduled = False
        self.dropped = 0
        self._record: Optional[TopicRecord] = None
        _node_or_later(self._attach)

    def _attach(self, node: Node) -> None:
        self._node = node
        self.resolved_name = self.name = node.resolve(self.name)
        # AnyMsg stands for any message class: the topic record reads only its type names.
        data_class = cast(Type[Message], self.data_class)
        self._record = node.topic(self.name, data_class, "subscribe to")
        self._record.subscribers.append(self)
        node.subscribers.append(self)
        for data in self._record.latched.values():
            self._enqueue(data)
        for publisher in list(self._record.publishers):
            listener = publisher.subscriber_listener
            if listener is not None:
                listener.peer_subscribe(self.name, publisher.publish, self._peer_publish(publisher))

    def _peer_publish(self, publisher: Publisher) -> Callable[[Any], None]:
        """Publish from ``publisher`` to this subscriber only (a listener's ``peer_publish``)."""

        def peer_publish(message: Any) -> None:
            if self._record is not None:
                self._enqueue(_to_message(publisher.data_class, (message,), {}).to_bytes())

        return peer_publish

    @property
    def node(self) -> Node:
        """The node that owns this subscriber."""
        return self._node

    def _enqueue(self, data: bytes) -> None:
        if self._queue.maxlen is not None and len(self._queue) == self._queue.maxlen:
            self.dropped += 1
        self._queue.append(data)
        if not self._scheduled:
            self._scheduled = True
            self._node.graph.call_soon(self._drain)

    def _drain(self) -> None:
        # While a callback runs (even one that sleeps), new messages wait in the queue for
        # this loop: callbacks of one subscription never overlap, as in rospy, where each
        # subscription has a thread of its own.
        try:
            self._drain_queue()
        finally:
            self._scheduled = False

    def _drain_queue(self) -> None:
        queue = self._queue
        stack = node_stack()
        while queue and self._record is not None:
            message = self.data_class.from_bytes(queue.popleft())
            message._connection_header = self._record.shared_connection_header()
            if self.callback is None:
                continue
            stack.append(self._node)  # the callback runs as its node
            try:
                if self.callback_args is None:
                    self.callback(message)
                else:
                    self.callback(message, self.callback_args)
            except Exception as error:
                self._node.log(ERROR, f"bad callback on {self.name}:\n{format_error(error)}")
            finally:
                stack.pop()

    def get_num_connections(self) -> int:
        """How many publishers the topic has."""
        return len(self._record.publishers) if self._record is not None else 0

    def unregister(self) -> None:
        """Stop receiving messages."""
        record, self._record = self._record, None
        if record is None:
            return
        record.subscribers.remove(self)
        for publisher in list(record.publishers):
            listener = publisher.subscriber_listener
            if listener is not None:
                listener.peer_unsubscribe(self.name, len(record.subscribers))
        if self in self._node.subscribers:
            self._node.subscribers.remove(self)
        self._queue.clear()
        self._node.forget_topic_user(record)


def wait_for_message(topic: str, topic_type: Type[Message], timeout: Optional[float] = None) -> Any:
    """Wait for the next message on a topic and return it.

    Raises:
        ROSException: if ``timeout`` seconds pass first, or the node shuts down.
    """
    node = current_node("rospy.wait_for_message()")
    received: List[Any] = []
    subscriber = Subscriber(topic, topic_type, received.append, queue_size=1)
    try:
        deadline = None if timeout is None else node.graph.now_ns + _to_ns(timeout)
        _block(node, deadline, lambda: bool(received) or node.is_shutdown)
    finally:
        subscriber.unregister()
    if not received:
        raise ROSException(f"timeout exceeded while waiting for a message on {subscriber.name}")
    return received[0]


# -- services -----------------------------------------------------------------------------------
def _check_service_class(service_class: Any, what: str) -> None:
    if not (isinstance(service_class, type) and hasattr(service_class, "_request_class")):
        raise ValueError(
            f"{what} needs a service class such as ChangePattern, not {service_class!r}."
        )


class Service:
    """Offer a service: ``handler(request)`` returns the response.

    The handler may return the response message, a dict of its fields, a tuple of them, or a
    single value for a one-field response, as in rospy. Raising ``rospy.ServiceException``
    sends the caller that error.
    """

    def __init__(
        self,
        name: str,
        service_class: Type[ServiceType],
        handler: Callable[[Any], Any],
        buff_size: int = 65536,
        error_handler: Optional[Callable[..., Any]] = None,
    ) -> None:
        _check_service_class(service_class, "rospy.Service")
        self._node: Node = current_node("rospy.Service")
        self.resolved_name = self.name = self._node.resolve(name)
        self.service_class = service_class
        self.request_class = service_class._request_class
        self.response_class = service_class._response_class
        self.handler = handler
        existing = self._node.graph.services.get(self.name)
        if existing is not None and existing.node is self._node:
            raise ServiceException(f"service [{self.name}] already registered")
        self._record: Optional[ServiceRecord] = ServiceRecord(
            self.name, service_class, handler, self._node, error_handler
        )
        self._node.graph.services[self.name] = self._record
        self._node.services.append(self._record)

    def shutdown(self, reason: str = "") -> None:
        """Stop offering the service."""
        record, self._record = self._record, None
        if record is None:
            return
        if self._node.graph.services.get(self.name) is record:
            del self._node.graph.services[self.name]
        if record in self._node.services:
            self._node.services.remove(record)

    unregister = shutdown

    def spin(self) -> None:
        """Keep the node alive until it shuts down (as ``rospy.spin()``)."""
        spin()


def _response_from(value: Any, response_class: Type[Message]) -> Any:
    if isinstance(value, Message) and value._type == response_class._type:
        return value
    if isinstance(value, dict):
        try:
            return response_class(**value)
        except AttributeError as error:
            raise ServiceException(f"handler returned invalid value: {error}") from None
    if value is None:
        raise ServiceException("service handler returned None")
    try:
        if isinstance(value, (list, tuple)):
            return response_class(*value)
        return response_class(value)
    except TypeError as error:
        raise ServiceException(f"handler returned invalid value: {error}") from None


class ServiceProxy:
    """Call a service as a function: ``proxy(request)`` or ``proxy(field=value, ...)``.

    The call blocks the caller until the handler has answered, as in rospy.
    """

    def __init__(
        self,
        name: str,
        service_class: Type[ServiceType],
        persistent: bool = False,
        headers: Any = None,
    ) -> None:
        _check_service_class(service_class, "rospy.ServiceProxy")
        self.resolved_name = self.name = name  # resolved once the node exists
        _node_or_later(self._attach)
        self.service_class = service_class
        self.request_class = service_class._request_class
        self.response_class = service_class._response_class
        self.persistent = persistent
        self._closed = False

    def _attach(self, node: Node) -> None:
        self._node = node
        self.resolved_name = self.name = node.resolve(self.name)

    def wait_for_service(self, timeout: Optional[float] = None) -> None:
        """Wait until the service is offered (see :func:`wait_for_service`)."""
        wait_for_service(self.resolved_name, timeout)

    def __call__(self, *args: Any, **kwds: Any) -> Any:
        """Same as :meth:`call`."""
        return self.call(*args, **kwds)

    def call(self, *args: Any, **kwds: Any) -> Any:
        """Send a request and return the response.

        Raises:
            ServiceException: if nobody offers the service, the types differ, or the handler
                failed.
        """
        if self._closed:
            raise ServiceException(f"service [{self.name}] proxy was closed")
        request = _to_message(self.request_class, args, kwds)
        record: Optional[ServiceRecord] = self._node.graph.services.get(self.name)
        if record is None:
            raise ServiceException(f"service [{self.name}] unavailable")
        if record.service_class._md5sum != self.service_class._md5sum:
            raise ServiceException(
                f"service [{self.name}] is of type {record.type}, but this proxy calls it as "
                f"{self.service_class._type}."
            )
        try:
            sent = record.service_class._request_class.from_bytes(request.to_bytes())
        except MessageError as error:
            raise ROSSerializationException(str(error)) from None
        record.call_count += 1
        with node_context(record.node):
            try:
                response = _response_from(
                    record.handler(sent), record.service_class._response_class
                )
                data = response.to_bytes()
            except ServiceException as error:
                raise ServiceException(f"service cannot process request: {error}") from None
            except Exception as error:
                if record.error_handler is not None:
                    record.error_handler(error, type(error), error, error.__traceback__)
                else:
                    record.node.log(
                        ERROR, f"Error processing request: {error}\n{format_error(error)}"
                    )
                raise ServiceException(f"error processing request: {error}") from None
        return self.response_class.from_bytes(data)

    def close(self) -> None:
        """Close a persistent connection."""
        self._closed = True


def wait_for_service(service: str, timeout: Optional[float] = None) -> None:
    """Block until a service is offered.

    Args:
        service: the service name.
        timeout: the longest wait, in simulated seconds (None: no limit).

    Raises:
        ROSException: if the timeout passes first.
        ROSInterruptException: if the node shuts down while waiting.
    """
    node = current_node("rospy.wait_for_service()")
    name = node.resolve(service)
    graph = node.graph
    deadline = None if timeout is None else graph.now_ns + _to_ns(timeout)
    if graph.block(deadline, lambda: name in graph.services or node.is_shutdown):
        if node.is_shutdown and name not in graph.services:
            raise ROSInterruptException("rospy shutdown")
        return
    raise ROSException(f"timeout exceeded while waiting for service {name}")


# -- parameters ---------------------------------------------------------------------------------
def _param_name(name: str) -> str:
    try:
        node = current_node()
    except ROSInitException:
        if name.startswith("~"):
            raise
        return names.resolve(name, os.environ.get("ROS_NAMESPACE", "/"))
    return node.resolve_param(name)


def get_param(param_name: str, default: Any = _UNSET) -> Any:
    """A parameter's value (a namespace gives a dict).

    Raises:
        KeyError: if it is not set and no default is given.
    """
    name = _param_name(param_name)
    try:
        return current_graph().get_param(name)
    except KeyError:
        if default is _UNSET:
            raise KeyError(param_name) from None
        return default


def get_param_cached(param_name: str, default: Any = _UNSET) -> Any:
    """A parameter's value, as :func:`get_param`, for code that reads it very often.

    The value is kept between calls until any parameter is set or deleted, so a new value
    still reaches the next call (rospy keeps its cache up to date the same way).

    Raises:
        KeyError: if it is not set and no default is given.
    """
    graph = current_graph()
    try:
        node: Optional[Node] = current_node()
    except ROSInitException:
        node = None
    key = (node.name if node is not None else "", param_name)
    try:
        value = graph.param_cache[key]
    except KeyError:
        try:
            value = graph.param_cache[key] = graph.get_param(_param_name(param_name))
        except KeyError:
            if default is _UNSET:
                raise KeyError(param_name) from None
            return default
    return copy_tree(value) if isinstance(value, (dict, list)) else value


def set_param(param_name: str, param_value: Any) -> None:
    """Set a parameter (a dict sets a whole namespace).

    Raises:
        ROSException: if the value is of a type ROS's parameter server cannot store (it
            stores bool, int, float, str, lists and dicts of them).
    """
    problem = _unstorable(param_value)
    if problem:
        raise ROSException(
            f"rospy.set_param({param_name!r}, ...): the parameter server cannot store {problem}; "
            "convert it to a plain Python value first (float(x), int(x), list(a) or a.tolist())."
        )
    current_graph().set_param(_param_name(param_name), param_value)


#: The types the parameter server stores (XML-RPC's), by exact type, as a robot's master does.
_STORABLE = (bool, int, float, str, bytes)


def _unstorable(value: Any) -> Optional[str]:
    """What in ``value`` a robot's parameter server would refuse, or None."""
    if type(value) is int and not -(2**31) <= value < 2**31:
        return f"the integer {value} (it must fit in 32 bits)"
    if type(value) in _STORABLE:
        return None
    if type(value) is dict and not all(isinstance(key, str) for key in value):
        return "a dict with keys that are not strings"
    if type(value) in (list, tuple, dict):
        items = value.values() if type(value) is dict else value
        return next(filter(None, (_unstorable(item) for item in items)), None)
    return "None" if value is None else f"a {type(value).__module__}.{type(value).__name__}"


def has_param(param_name: str) -> bool:
    """Whether a parameter is set."""
    return current_graph().has_param(_param_name(param_name))


def delete_param(param_name: str) -> None:
    """Delete a parameter.

    Raises:
        KeyError: if it is not set.
    """
    current_graph().delete_param(_param_name(param_name))


def search_param(param_name: str) -> Optional[str]:
    """Find a parameter in the node's namespace or the nearest enclosing one.

    Returns:
        Its global name, or None if no enclosing namespace has it.
    """
    graph = current_graph()
    try:
        namespace = current_node().namespace
    except ROSInitException:
        namespace = "/"
    parts = [part for part in namespace.split("/") if part]
    key = param_name.lstrip("/")
    for depth in range(len(parts), -1, -1):
        candidate = "/" + "/".join([*parts[:depth], key])
        if graph.has_param(candidate):
            return candidate
    return None


def get_param_names() -> List[str]:
    """Every parameter's global name."""
    return current_graph().param_names()


# -- logging ------------------------------------------------------------------------------------
def _log(level: int, msg: Any, args: tuple) -> None:
    text = str(msg) % args if args else str(msg)
    try:
        current_node().log(level, text)
    except ROSInitException:
        current_graph().log_message(level, "/unnamed", text)


def _call_site() -> Any:
    frame = sys._getframe(2)
    return (frame.f_code.co_filename, frame.f_lineno)


def logdebug(msg: Any, *args: Any) -> None:
    """Log a debug line (shown when the node's log_level is rospy.DEBUG)."""
    _log(DEBUG, msg, args)


def loginfo(msg: Any, *args: Any) -> None:
    """Log an information line (printed to stdout)."""
    _log(INFO, msg, args)


def logwarn(msg: Any, *args: Any) -> None:
    """Log a warning (printed to stderr)."""
    _log(WARN, msg, args)


def logerr(msg: Any, *args: Any) -> None:
    """Log an error (printed to stderr)."""
    _log(ERROR, msg, args)


def logfatal(msg: Any, *args: Any) -> None:
    """Log a fatal error (printed to stderr)."""
    _log(FATAL, msg, args)


def _throttled(level: int) -> Callable[..., None]:
    def log(period: float, msg: Any, *args: Any) -> None:
        text = str(msg) % args if args else str(msg)
        current_node().log_throttled(_call_site(), period, level, text)

    log.__doc__ = "Log at most once every ``period`` simulated seconds from this line."
    return log


def _once(level: int) -> Callable[..., None]:
    def log(msg: Any, *args: Any) -> None:
        text = str(msg) % args if args else str(msg)
        current_node().log_once(_call_site(), level, text)

    log.__doc__ = "Log only the first time this line runs."
    return log


logdebug_throttle, loginfo_throttle = _throttled(DEBUG), _throttled(INFO)
logwarn_throttle, logerr_throttle = _throttled(WARN), _throttled(ERROR)
logdebug_once, loginfo_once = _once(DEBUG), _once(INFO)
logwarn_once, logerr_once = _once(WARN), _once(ERROR)


# -- time.sleep in node code ----------------------------------------------------------------------
_WALL_SLEEP: Callable[[float], None] = getattr(time.sleep, "wall_sleep", time.sleep)
_TIME_SLEEP_NOTE = (
    "time.sleep() waits on the wall clock, but this graph's time is simulated: here it waits "
    "simulated seconds, as rospy.sleep() does. Use rospy.sleep() or rospy.Rate in ROS code."
)


def _sleeping_node() -> Optional[Node]:
    """The in-process node whose code calls ``time.sleep``, or None (then it is wall time)."""
    stack = node_stack()
    if stack:
        return stack[-1]  # a callback
    actor = calling_actor()
    if actor is not None:
        return actor.node  # a launched node's main code (None before init_node)
    graph = latest_graph()
    node = graph.foreground_node() if graph is not None else None
    if node is not None and not node.graph.driving_here():
        return node  # a notebook's own node
    return None


def _time_sleep(seconds: Any) -> None:
    node = _sleeping_node()
    if node is None or node.is_shutdown:
        _WALL_SLEEP(seconds)
        return
    with node_context(node):
        logwarn_once(_TIME_SLEEP_NOTE)
    sleep(seconds)


_time_sleep.wall_sleep = _WALL_SLEEP  # type: ignore[attr-defined]
_time_sleep.__doc__ = (
    "``time.sleep``, except in the code of a node on the in-process graph: there it waits "
    "simulated seconds, as ``rospy.sleep`` does, and says so once."
)
time.sleep = _time_sleep
