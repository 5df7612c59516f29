"""rospy's services: ``Service``, ``ServiceProxy``, ``wait_for_service``.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

from typing import Any, Callable, Dict, Optional, Type

from duckielib.errors import MessageError
from duckielib.messages import Message, get_service_class
from duckielib.messages import Service as ServiceType
from duckielib.ros.context import (
    current_node,
    node_context,
)
from duckielib.ros.exceptions import (
    ROSException,
    ROSInterruptException,
    ROSSerializationException,
    ServiceException,
)
from duckielib.ros.graph import current_graph
from duckielib.ros.log import ERROR, format_error
from duckielib.ros.node import Node, ServiceRecord
from duckielib.ros.rospy.client import spin
from duckielib.ros.rospy.core import _node_or_later
from duckielib.ros.rospy.timing import _to_ns
from duckielib.ros.rospy.topics import _course_equivalent, _to_message


# -- services -----------------------------------------------------------------------------------
def _course_service_class(service_class: Any, what: str) -> Any:
    """The class to use for ``service_class``: itself, or the course's class of its type.

    A class generated elsewhere (by genpy, in a catkin build) is replaced by the course's class
    of the same type and definition, as topics do with message classes.

    Raises:
        ValueError: if it is not a service class, or one generated elsewhere of a type the
            course does not know or with another definition (another md5 sum).
    """
    if not (isinstance(service_class, type) and hasattr(service_class, "_request_class")):
        raise ValueError(
            f"{what} needs a service class such as ChangePattern, not {service_class!r}."
        )
    if hasattr(service_class._request_class, "from_bytes"):
        return service_class  # the course's own
    return _course_equivalent(service_class, get_service_class, ".srv file in the srv/", what)


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
        service_class = _course_service_class(service_class, "rospy.Service")
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
        self._node.graph.history.add_server(self._node, self._record)

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
    if getattr(value, "_md5sum", None) == response_class._md5sum:
        return _to_message(response_class, (value,), {})  # a response generated elsewhere
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


#: The node a script's service calls come from when it never called ``init_node`` (rospy
#: lets a plain script call a service).
_SCRIPT_CLIENT = "rospy_script"


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
        service_class = _course_service_class(service_class, "rospy.ServiceProxy")
        self.resolved_name = self.name = name  # resolved once the node exists
        _node_or_later(self._attach)
        self.service_class = service_class
        self.request_class = service_class._request_class
        self.response_class = service_class._response_class
        self.persistent = persistent
        #: The connection header the service's handler sees with each request, as in rospy.
        self.headers: Dict[str, str] = {
            str(key): str(value) for key, value in (headers or {}).items()
        }
        if persistent:
            self.headers["persistent"] = "1"
        self._closed = False
        self._called: Optional[ServiceRecord] = None  # the service last called, for the history

    def _attach(self, node: Node) -> None:
        self._node = node
        self.resolved_name = self.name = node.resolve(self.name)

    def _caller(self) -> Node:
        """The calling node; a script that never called ``init_node`` calls as rospy lets it."""
        node: Optional[Node] = getattr(self, "_node", None)
        if node is None:
            graph = current_graph()
            node = graph.nodes.get("/" + _SCRIPT_CLIENT)
            if node is None or node.is_shutdown:
                node = graph.host_node(_SCRIPT_CLIENT)
            self._attach(node)
        return node

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
        caller = self._caller()
        record: Optional[ServiceRecord] = caller.graph.services.get(self.name)
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
        sent._connection_header = {
            "service": self.name,
            "md5sum": self.service_class._md5sum,
            "callerid": caller.name,
            **self.headers,
        }
        record.call_count += 1
        if self._called is not record:  # the proxy's node is the caller, as in ROS
            self._called = record
            caller.graph.history.add_client(caller, record)
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
        response = self.response_class.from_bytes(data)
        response._connection_header = {
            "service": self.name,
            "type": record.type,
            "md5sum": record.service_class._md5sum,
            "callerid": record.node.name,
        }
        return response

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
    node.waiting_for = (f"service {name}", graph.time)
    try:
        offered = graph.block(deadline, lambda: name in graph.services or node.is_shutdown)
    finally:
        node.waiting_for = None
    if offered:
        if node.is_shutdown and name not in graph.services:
            raise ROSInterruptException("rospy shutdown")
        return
    raise ROSException(f"timeout exceeded while waiting for service {name}")
