"""Which node is calling: the context rospy's functions find their node in.

On a robot each node is a process, so ``rospy.get_name()`` knows its node. On the in-process
graph many nodes share one process, so the calling node is kept per thread: the launched node
whose code is running (its *actor*), and the stack of nodes whose callbacks run inside it
(innermost last). The graph sets them when it hands a node the baton; a notebook's own node is
the graph's *foreground* node of the notebook's thread.

Nodes and rospy's functions depend on this context, not on the graph that keeps it.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

import contextlib
import threading
from typing import Any, Callable, Iterator, List, Optional

from duckielib.ros.exceptions import ROSException, ROSInitException

__all__ = [
    "acting_as",
    "calling_actor",
    "current_node",
    "waiting_for_init",
    "enter_actor",
    "latest_graph",
    "make_latest",
    "node_context",
    "node_stack",
    "refuse_library_thread",
]

_local = threading.local()
_latest: List[Any] = []  # the graph created last, which a notebook's own node joins


def make_latest(graph: Any) -> None:
    """Make ``graph`` the one a caller without a node talks to."""
    _latest[:] = [graph]


def latest_graph() -> Optional[Any]:
    """The graph created last, or None if there is none yet."""
    return _latest[0] if _latest else None


def calling_actor() -> Optional[Any]:
    """The launched node's actor whose code runs in this thread, if any."""
    return getattr(_local, "actor", None)


def enter_actor(actor: Any) -> None:
    """Make ``actor`` (and its callback stack) the calling one in this thread for good."""
    _local.actor, _local.stack = actor, actor.stack


@contextlib.contextmanager
def acting_as(actor: Any) -> Iterator[Any]:
    """Run code as ``actor`` in this thread, then restore whoever was calling before."""
    state = _local.__dict__
    saved = state.get("actor"), state.get("stack")
    enter_actor(actor)
    try:
        yield actor
    finally:
        for key, value in zip(("actor", "stack"), saved):
            if value is None:
                state.pop(key, None)
            else:
                state[key] = value


def waiting_for_init() -> List[Callable[[Any], None]]:
    """What the calling code created before ``rospy.init_node``, to attach to its node then.

    rospy lets a publisher, subscriber or service proxy be made before ``init_node`` (the
    tutorials' talker does); each registers here and is attached when the node exists.
    """
    actor = calling_actor()
    if actor is not None:
        return actor.waiting_for_init
    graph = latest_graph()
    owner, waiting = getattr(_local, "waiting_for_init", (None, []))
    if owner is not graph:  # what was made for an earlier graph never joins this one
        waiting = []
        _local.waiting_for_init = (graph, waiting)
    return waiting


def node_stack() -> List[Any]:
    """The calling thread's stack of nodes whose callbacks are running (innermost last)."""
    try:
        return _local.stack
    except AttributeError:
        _local.stack = []
        return _local.stack


@contextlib.contextmanager
def node_context(node: Any) -> Iterator[Any]:
    """Run code as ``node``: callbacks and service handlers run inside this context."""
    stack = node_stack()
    stack.append(node)
    try:
        yield node
    finally:
        stack.pop()


def current_node(required_by: str = "this call") -> Any:
    """The node whose code is running: a callback's node, a launched node, or the caller's own.

    Raises:
        ROSInitException: if the calling code has not called ``rospy.init_node`` yet.
    """
    stack = getattr(_local, "stack", None)
    if stack:
        return stack[-1]
    actor = calling_actor()
    if actor is not None:
        if actor.node is None:
            raise ROSInitException(
                f"{required_by} needs a node: call rospy.init_node('name') first."
            )
        return actor.node
    graph = latest_graph()
    if graph is not None:
        node = graph.foreground_node()
        if node is not None:
            return node
    refuse_library_thread()
    raise ROSInitException(f"{required_by} needs a node: call rospy.init_node('name') first.")


def refuse_library_thread() -> None:
    """Refuse rospy to a thread a library started from a node's code (a pool's worker).

    Such a thread runs beside the graph, not on its baton, so it cannot use the graph.

    Raises:
        ROSException: in such a thread, saying what to start instead.
    """
    started_by = getattr(threading.current_thread(), "duckie_started_by", None)
    if started_by is not None:
        raise ROSException(
            f"rospy was called from a thread that a library started for node {started_by} "
            "(a thread pool's worker, for example). On the virtual Duckiebot only the threads "
            "a node starts itself, threading.Thread(target=your_function), run as the node "
            "and can call rospy: start one of those for this work."
        )
