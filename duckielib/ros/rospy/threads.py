"""Threads that a node's code starts run on the graph, so rospy works in them.

Real rospy lets a node start threads (a control loop beside ``rospy.spin()``, a
``threading.Timer``) and call rospy from them. On the in-process graph every node's code runs
only while the graph hands it the baton, so a thread started by a node's code (its main code
or a callback) is adopted by the graph: it runs as that node, on simulated time, whenever it
has the baton, exactly like the node's main code. ``join()`` on it waits simulated time, a
``threading.Timer`` waits simulated seconds, and a node whose main code returns lives on while
a thread it started that is not a daemon still runs, as a process does.

Threads of libraries (a thread pool's workers, Jupyter's own) are left alone: the graph adopts
a thread only when the code it runs is not in Python's library folders or in duckielib.

Importing this module installs the adoption in ``threading.Thread.start``; anywhere else than
in a node's code, ``start`` is the standard one.

Pure: standard library only, Python 3.8 (deployed to the robot, where rospy is the real one
and this module is never imported).
"""

from __future__ import annotations

import functools
import os
import site
import sysconfig
import threading
from pathlib import Path
from typing import Any, Callable, Optional, Tuple

from duckielib.ros.context import calling_actor, node_stack
from duckielib.ros.node import Node

__all__ = ["node_code"]

_ORIGINAL_START: Callable[[threading.Thread], None] = getattr(
    threading.Thread.start, "original_start", threading.Thread.start
)


def _library_folders() -> Tuple[str, ...]:
    folders = {
        os.path.realpath(path)
        for key in ("stdlib", "platstdlib", "purelib", "platlib")
        for path in [sysconfig.get_paths().get(key)]
        if path
    }
    folders.update(os.path.realpath(path) for path in getattr(site, "getsitepackages", list)())
    folders.add(
        str(Path(__file__).resolve().parents[2])
    )  # duckielib's own threads (the graph's, the recorder's)
    return tuple(folder.rstrip(os.sep) + os.sep for folder in sorted(folders))


_LIBRARIES = _library_folders()


def node_code(function: Any) -> bool:
    """Whether ``function`` is a node's own code (not a library's): the graph adopts it."""
    code = getattr(getattr(function, "__func__", function), "__code__", None)
    if code is None:
        return False  # a builtin, or a callable object of a library
    return not os.path.realpath(code.co_filename).startswith(_LIBRARIES)


def _starting_node() -> Tuple[Optional[Any], Optional[Node]]:
    """The graph and node whose code is calling (node None before ``init_node``), if any."""
    stack = node_stack()
    if stack:
        return stack[-1].graph, stack[-1]
    actor = calling_actor()
    if actor is not None:
        return actor.graph, actor.node
    return None, None


def _what_it_runs(thread: threading.Thread) -> Tuple[Any, Callable[[], None]]:
    """The code a thread runs (to tell a node's from a library's), and how to run it here."""
    if isinstance(thread, threading.Timer):
        return thread.function, functools.partial(_run_timer, thread)
    if type(thread).run is not threading.Thread.run:
        return type(thread).run, thread.run
    return getattr(thread, "_target", None), thread.run


def _run_timer(timer: threading.Timer) -> None:
    """A ``threading.Timer``'s wait, on simulated time: cancelling it still works."""
    from duckielib.ros.rospy.timing import sleep

    sleep(timer.interval)
    if not timer.finished.is_set():
        timer.function(*timer.args, **timer.kwargs)
    timer.finished.set()


def _join(thread: threading.Thread, timeout: Optional[float] = None) -> None:
    """``Thread.join`` for an adopted thread: wait simulated time for it to end."""
    graph = thread._duckie_graph  # type: ignore[attr-defined]
    actor = graph.thread_actor(thread)
    waiting = calling_actor()
    if actor is None or waiting is actor or not (waiting is not None or graph.driving_here()):
        threading.Thread.join(thread, timeout)
        return
    deadline = None if timeout is None else graph.now_ns + round(timeout * 1e9)
    graph.block(deadline, lambda: actor.finished, polled=True)


def _start(thread: threading.Thread) -> None:
    graph, node = _starting_node()
    if graph is not None and not graph.is_shutdown:
        code, run = _what_it_runs(thread)
        if node_code(code):
            keeps_node = not thread.daemon
            thread.daemon = True  # the graph ends it; what the flag meant is kept
            thread.run = graph.adopt_thread(thread, run, node, keeps_node)  # type: ignore
            thread._duckie_graph = graph  # type: ignore[attr-defined]
            thread.join = functools.partial(_join, thread)  # type: ignore[method-assign]
        else:  # a library's thread runs free, and is told so if it calls rospy
            who = node.name if node is not None else getattr(calling_actor(), "name", "?")
            thread.duckie_started_by = who  # type: ignore[attr-defined]
    _ORIGINAL_START(thread)


_start.original_start = _ORIGINAL_START  # type: ignore[attr-defined]
_start.__doc__ = _ORIGINAL_START.__doc__
threading.Thread.start = _start  # type: ignore[method-assign,assignment]
