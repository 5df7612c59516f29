"""The actors of the in-process graph: who holds the baton, and the watchdog that takes it back.

:class:`~duckielib.ros.graph.Graph` runs one piece of node code at a time. Each node's main
code is an :class:`Actor`, in a greenlet (or a thread where the ``greenlet`` package is
missing) that runs only while it holds the baton; a thread a node's code starts is a
:class:`ThreadActor`, adopted the same way. :class:`Signal` hands the baton between threads;
:class:`Event` is something scheduled at a simulated time. The :data:`watchdog` stops code
that holds the baton too long on the wall clock without waiting (it raises :class:`Stalled`
in it), since the simulated clock cannot move meanwhile.

Robot side: standard library only.
"""

from __future__ import annotations

import ctypes
import threading
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Optional, Protocol

from duckielib.ros import context
from duckielib.ros.exceptions import ROSInterruptException
from duckielib.ros.log import ERROR, format_error

if TYPE_CHECKING:
    from duckielib.ros.node import Node

__all__ = [
    "Stage",
    "Actor",
    "Callback",
    "Event",
    "Signal",
    "Stalled",
    "ThreadActor",
    "Watchdog",
    "parked",
    "stall_message",
    "watchdog",
]

#: Launched nodes' greenlets that have started and not finished. Kept alive so that a graph
#: dropped without a shutdown leaves its nodes parked for good, as threads would be, instead
#: of running their clean-up code at some garbage collection.
parked: set = set()


class Stage(Protocol):
    """What the actors need of the graph that runs them (:class:`~duckielib.ros.graph.Graph`)."""

    #: Real seconds a node's code may hold the baton without waiting.
    stall_limit: float
    #: Set when an actor's code ends, so that the thread driving the graph goes on.
    _driver_wake: Signal

    def log_message(self, level: int, node: str, text: str) -> None:
        """Log ``text`` as ``node``'s, at ``level``."""

    def block(
        self, deadline_ns: Optional[int], predicate: Callable[[], bool], polled: bool = True
    ) -> bool:
        """Hand the baton back until ``predicate()`` is true (or the clock reaches a deadline)."""

    def threads_keeping(self, node: Node) -> List[threading.Thread]:
        """The threads ``node``'s code started that keep it alive."""


class Stalled(BaseException):
    """Raised in a node's code that held the baton too long.

    Not an ``Exception``, so that ``except Exception`` in the node's loop does not swallow it.
    """


class Watchdog:
    """Stops a node's code that runs for too long on the wall clock without ever waiting.

    Simulated time moves only while every node waits, so a loop that waits for something
    without calling rospy (``while not self.got_message: pass``) would freeze the graph for
    ever, silently. The watchdog, a daemon thread, checks twice a second which node holds
    the baton; after ``graph.stall_limit`` real seconds it says so in the node's log and
    raises an exception in the node's code, which stops the node with a sentence saying why.
    """

    def __init__(self) -> None:
        self.lock = threading.Lock()
        #: graph -> (actor, the thread its code runs in, when it took the baton, warned)
        self.holding: Dict[Any, List[Any]] = {}
        self.thread: Optional[threading.Thread] = None

    def hold(self, graph: Stage, actor: Actor, thread_id: int) -> None:
        """Note that ``actor``'s code, in thread ``thread_id``, took ``graph``'s baton now."""
        with self.lock:
            self.holding[graph] = [actor, thread_id, time.monotonic(), False]
            if self.thread is None:
                self.thread = threading.Thread(target=self._watch, name="graph-watchdog")
                self.thread.daemon = True
                self.thread.start()

    def release(self, graph: Stage) -> None:
        """Note that the code holding ``graph``'s baton gave it back."""
        with self.lock:
            self.holding.pop(graph, None)

    def watch_callback(
        self, graph: Stage, node: str, topic: str, call: Callable[[], None]
    ) -> Optional[Stalled]:
        """Run a subscription's callback of ``node`` as watched code; why it stalled, or None.

        Callbacks run in the thread that drives the graph, between its events, not as actors:
        one that computes for ``graph.stall_limit`` real seconds without calling rospy is
        stopped as a node's main code would be.
        """
        watched = Callback(node, topic)
        self.hold(graph, watched, threading.get_ident())  # type: ignore[arg-type]
        try:
            call()
        except Stalled:
            return Stalled(stall_message(graph.stall_limit, watched))
        finally:
            self.release(graph)
        return None

    def _watch(self) -> None:
        while True:
            time.sleep(0.25)  # the wall clock: this thread runs no node code
            now = time.monotonic()
            with self.lock:
                for graph, held in list(self.holding.items()):
                    actor, thread_id, since, warned = held
                    if now - since < graph.stall_limit:
                        continue
                    if not warned:
                        held[3] = True
                        why = stall_message(graph.stall_limit, actor)
                        graph.log_message(ERROR, actor.name, f"stopped: {why}.")
                    held[2] = now  # raise again later if the code swallows it
                    ctypes.pythonapi.PyThreadState_SetAsyncExc(
                        ctypes.c_ulong(thread_id), ctypes.py_object(Stalled)
                    )


watchdog = Watchdog()


@dataclass(frozen=True)
class Callback:
    """A subscription's callback, as the watchdog names it (:meth:`Watchdog.watch_callback`)."""

    name: str
    topic: str


def stall_message(limit: float, actor: Any) -> str:
    """Why the watchdog stopped ``actor``'s code (a node's, or a callback): it never waited."""
    if isinstance(actor, Callback):
        return (
            f"its callback on {actor.topic} ran for {limit:g} s of real time without calling "
            "rospy, and simulated time cannot move while a node's code runs: no message can "
            "arrive while the callback waits. Do the work and return; keep what the next "
            "callback needs in a variable"
        )
    return (
        f"its code ran for {limit:g} s of real time without calling rospy, and simulated time "
        "cannot move while a node's code runs: a loop that waits for a callback or another "
        "thread never sees it happen. Wait inside the loop with rospy.sleep() or rate.sleep()"
    )


class Event:
    """Something scheduled to happen at a simulated time; cancel() makes it a no-op."""

    __slots__ = ("action", "cancelled")

    def __init__(self, action: Callable[[], None]) -> None:
        self.action = action
        self.cancelled = False

    def cancel(self) -> None:
        """Make the event do nothing when its time comes."""
        self.cancelled = True


class Signal:
    """A one-shot wake-up between two threads: ``set`` lets one ``wait`` through, once.

    Like a ``threading.Event`` that clears itself when a waiter gets through, built on a bare
    lock, which hands the baton between threads about a third faster than an event.
    """

    __slots__ = ("_lock",)

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._lock.acquire()

    def set(self) -> None:
        """Let the next ``wait`` through (setting twice is the same as once)."""
        if self._lock.locked():
            self._lock.release()

    def wait(self) -> None:
        """Block until set, and take the signal."""
        self._lock.acquire()

    def clear(self) -> None:
        """Take back a signal that no one waited for."""
        self._lock.acquire(blocking=False)


class Actor:
    """A node's main code, in a greenlet or a thread that runs only while it holds the baton."""

    def __init__(
        self,
        graph: Stage,
        target: Callable[..., Any],
        args: tuple,
        kwargs: dict,
        launch: Dict[str, Any],
        threads: bool,
    ) -> None:
        self.graph = graph
        self.target = target
        self.args = args
        self.kwargs = kwargs
        self.launch = launch
        self.node: Optional[Node] = None
        self.wake = Signal()
        self.finished = False
        self.error: Optional[BaseException] = None
        self.predicate: Optional[Callable[[], bool]] = None
        self.polled = True
        self.token = 0
        self.resumes_after_shutdown = 0
        #: A Ctrl-C that reached the node's code (greenlets run in the driving thread).
        self.interrupt: Optional[KeyboardInterrupt] = None
        self.stack: List[Node] = []  # the nodes whose callbacks run inside this node's code
        self.label = str(launch.get("name") or getattr(target, "__name__", "node"))
        #: Handles its code made before init_node, attached to its node then.
        self.waiting_for_init: List[Callable[[Node], None]] = []
        self.thread: Optional[threading.Thread] = None
        self.greenlet: Any = None
        self.home: Optional[int] = None  # the thread a greenlet runs in
        if threads:
            self.thread = threading.Thread(
                target=self._main, name=f"node:{self.label}", daemon=True
            )

    @property
    def name(self) -> str:
        """The node's name, or the launch name before ``init_node``."""
        return self.node.name if self.node is not None else self.label

    def _main(self) -> None:
        self.wake.wait()
        context.enter_actor(self)
        try:
            self._run()
        finally:
            self.graph._driver_wake.set()

    def _run(self) -> None:
        try:
            self.target(*self.args, **self.kwargs)
            self._wait_for_threads()
        except ROSInterruptException:
            pass  # shutdown during a sleep ends a node normally
        except KeyboardInterrupt as error:  # Ctrl-C while the node's code ran: the driver raises it
            self.interrupt = error
        except Stalled:  # the watchdog logged why
            self.error = Stalled(stall_message(self.graph.stall_limit, self))
        except BaseException as error:
            self.error = error
            self.graph.log_message(ERROR, self.name, format_error(error))
        finally:
            watchdog.release(self.graph)
            self.finished = True
            parked.discard(self.greenlet)
            if self.node is not None and not self.node.is_shutdown:
                reason = "the node's code raised an exception" if self.error else "node finished"
                self.stack.append(self.node)
                try:
                    self.node.shutdown(reason)
                finally:
                    self.stack.pop()

    def _wait_for_threads(self) -> None:
        """Keep the node alive while threads its code started (not daemons) still run.

        On a robot a node's process lives until its last non-daemon thread ends, even when its
        main code has returned.
        """
        node = self.node
        if node is not None and not node.is_shutdown:
            graph = self.graph
            graph.block(None, lambda: node.is_shutdown or not graph.threads_keeping(node))


class ThreadActor(Actor):
    """A thread that a node's code started: it runs, as the node, only with the baton.

    Its node is the one whose code started it (or that node once its code calls
    ``init_node``); it ends without shutting the node down. An exception it raises is logged
    as the node's error, as rospy prints it, and the node goes on.
    """

    def __init__(
        self,
        graph: Stage,
        thread: threading.Thread,
        run: Callable[[], Any],
        node: Optional[Node],
        parent: Optional[Actor],
        keeps_node: bool,
    ) -> None:
        Actor.__init__(self, graph, run, (), {}, {"name": thread.name}, threads=False)
        self.thread = thread
        self.parent = parent
        self.keeps_node = keeps_node
        self.node = node

    @property
    def node(self) -> Optional[Node]:
        """Its own node, or else the node of the code that started it."""
        if self._node is None and self.parent is not None:
            return self.parent.node
        return self._node

    @node.setter
    def node(self, node: Optional[Node]) -> None:
        self._node = node

    def _run(self) -> None:
        try:
            self.target()
        except ROSInterruptException:
            pass
        except KeyboardInterrupt as error:
            self.interrupt = error
        except Stalled:
            pass  # the watchdog logged why
        except BaseException as error:
            self.graph.log_message(
                ERROR, self.name, f"thread {self.label} stopped:\n{format_error(error)}"
            )
        finally:
            watchdog.release(self.graph)
            self.finished = True
