"""rospy's topics: ``Publisher``, ``Subscriber``, ``AnyMsg``, ``wait_for_message``.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

import collections
import functools
import io
from typing import Any, Callable, Deque, Dict, List, Optional, Tuple, Type, Union, cast

from duckielib.errors import MessageError, UnknownTypeError
from duckielib.messages import Message
from duckielib.messages import get_message_class as messages_get_class
from duckielib.ros.context import (
    current_node,
    node_stack,
)
from duckielib.ros.exceptions import (
    ROSException,
    ROSInitException,
    ROSSerializationException,
)
from duckielib.ros.log import ERROR, WARN, format_error
from duckielib.ros.node import Node, TopicRecord
from duckielib.ros.rospy.core import _block, _node_or_later, _spend
from duckielib.ros.rospy.timing import _to_ns


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
    return _course_equivalent(data_class, messages_get_class, ".msg file in the msg/", what)


def _course_equivalent(
    generated: Any, course_class: Callable[[str], Any], folder: str, what: str
) -> Any:
    """The course's class of the type of a class generated elsewhere (a message or service).

    Raises:
        ValueError: if the course does not know its type (its ``folder`` file is then to put
            beside the node), or knows another definition of it (another md5 sum).
    """
    name = str(getattr(generated, "_type", generated.__name__))
    try:
        ours = course_class(name)
    except UnknownTypeError:
        raise ValueError(
            f"{what}: {name} comes from a module generated outside this course, for a type the "
            f"course does not know. Put its {folder} folder of your package, beside your node, "
            "and import it from there."
        ) from None
    theirs = getattr(generated, "_md5sum", "?")
    if ours._md5sum != theirs:
        raise ValueError(
            f"{what}: your {name} has another definition than the robot's (md5 sum "
            f"{theirs}, the robot's is {ours._md5sum}); use the robot's definition."
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
        #: Extra connection-header fields, as rospy sends them to each subscriber.
        self.headers: Dict[str, str] = {
            str(key): str(value) for key, value in (headers or {}).items()
        }
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
        node.graph.history.add_topic_user(node, self._record, publishes=True)
        for watch in node.graph.topic_watchers:
            watch(self, True)
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
        record.sender = self
        try:
            for subscriber in list(record.subscribers):
                subscriber._enqueue(data)
        finally:
            record.sender = None
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
        #: Messages waiting for the callback, each with its connection's header.
        self._queue: Deque[Tuple[bytes, Dict[str, str]]] = collections.deque(
            maxlen=queue_size or None
        )
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
        node.graph.history.add_topic_user(node, self._record, publishes=False)
        for watch in node.graph.topic_watchers:
            watch(self, False)
        record = self._record
        for publisher, data in list(record.latched.items()):
            record.sender = publisher
            try:
                self._enqueue(data)
            finally:
                record.sender = None
        for publisher in list(self._record.publishers):
            listener = publisher.subscriber_listener
            if listener is not None:
                listener.peer_subscribe(self.name, publisher.publish, self._peer_publish(publisher))

    def _peer_publish(self, publisher: Publisher) -> Callable[[Any], None]:
        """Publish from ``publisher`` to this subscriber only (a listener's ``peer_publish``)."""

        def peer_publish(message: Any) -> None:
            record = self._record
            if record is not None:
                data = _to_message(publisher.data_class, (message,), {}).to_bytes()
                record.sender = publisher
                try:
                    self._enqueue(data)
                finally:
                    record.sender = None

        return peer_publish

    @property
    def node(self) -> Node:
        """The node that owns this subscriber."""
        return self._node

    def _enqueue(self, data: bytes) -> None:
        if self._queue.maxlen is not None and len(self._queue) == self._queue.maxlen:
            self.dropped += 1
        record = self._record
        self._queue.append((data, record.delivery_header() if record is not None else {}))
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
            data, header = queue.popleft()
            message = self.data_class.from_bytes(data)
            message._connection_header = header
            if self.callback is None:
                continue
            stack.append(self._node)  # the callback runs as its node
            try:
                extra = () if self.callback_args is None else (self.callback_args,)
                call = functools.partial(self.callback, message, *extra)
                if not self._node.graph.run_callback(self._node, self.name, call):
                    return  # stopped: the run ends, saying why
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
    node.waiting_for = (f"a message on {subscriber.name}", node.graph.time)
    try:
        deadline = None if timeout is None else node.graph.now_ns + _to_ns(timeout)
        _block(node, deadline, lambda: bool(received) or node.is_shutdown)
    finally:
        node.waiting_for = None
        subscriber.unregister()
    if not received:
        raise ROSException(f"timeout exceeded while waiting for a message on {subscriber.name}")
    return received[0]
