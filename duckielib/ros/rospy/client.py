"""rospy's node and parameter functions: ``init_node``, names, shutdown, ``spin``, parameters.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

import os
import sys
from typing import Any, Callable, List, Optional

from duckielib.ros import names
from duckielib.ros.context import (
    current_node,
)
from duckielib.ros.exceptions import (
    ROSException,
    ROSInitException,
)
from duckielib.ros.graph import current_graph
from duckielib.ros.log import INFO
from duckielib.ros.node import Node
from duckielib.ros.params import copy_tree
from duckielib.ros.rospy.core import _attach_waiting, _block, _spend


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


def remap_name(name: str, caller_id: Optional[str] = None, resolved: bool = True) -> str:
    """The name a remapping gives ``name`` (resolved), or ``name`` itself when none does."""
    node = current_node("rospy.remap_name()")
    full = node.resolve(name)
    return full if full != names.resolve(name, node.namespace, node.name) else name


def get_published_topics(namespace: str = "/") -> List[List[str]]:
    """The topics with a publisher under ``namespace``: ``[[name, type], ...]``, as rospy."""
    prefix = names.canonical(names.resolve(namespace, "/")).rstrip("/") + "/"
    return [
        [name, record.type]
        for name, record in sorted(current_graph().topics.items())
        if record.publishers and (prefix == "/" or name.startswith(prefix))
    ]


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


_UNSET = object()  # a default nobody passes


# -- parameters ---------------------------------------------------------------------------------
def _param_name(name: str) -> str:
    try:
        node = current_node()
    except ROSInitException:
        if name.startswith("~"):
            raise
        return names.resolve(name, os.environ.get("ROS_NAMESPACE", "/"))
    return node.resolve_param(name)


def get_param(param_name: str, default: Any = _UNSET, **dt_options: Any) -> Any:
    """A parameter's value (a namespace gives a dict).

    ``dt_help=``, ``dt_type=`` and the other ``dt_`` options Duckietown's rospy takes are
    accepted and change nothing.

    Raises:
        KeyError: if it is not set and no default is given.
        TypeError: for a keyword argument that is not a ``dt_`` option.
    """
    unknown = [key for key in dt_options if not key.startswith("dt_")]
    if unknown:
        raise TypeError(f"get_param() got an unexpected keyword argument {unknown[0]!r}")
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
