"""rospy's time: ``Time``, ``Duration``, ``sleep``, ``Rate`` and ``Timer`` on simulated time.

Importing it makes ``time.sleep`` in a node's code wait simulated seconds, as ``rospy.sleep``
does (anywhere else it is the wall clock's, as always).

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

import time
from typing import Any, Callable, Optional, Union

from duckielib import rostime
from duckielib.ros.context import (
    calling_actor,
    current_node,
    node_context,
    node_stack,
)
from duckielib.ros.exceptions import (
    ROSInterruptException,
)
from duckielib.ros.log import ERROR, format_error
from duckielib.ros.node import Node
from duckielib.ros.rospy.core import _block, _spend
from duckielib.ros.rospy.logs import logwarn_once
from duckielib.rostime import NS_PER_S


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
        if node.in_shutdown_hooks:
            # A hook that waits for its last command to take effect: on a robot's wall clock
            # rospy sleeps and returns; the graph's clock has stopped, so it returns at once.
            return
        # As rospy on simulated time (on a robot's wall clock it would sleep and return): it
        # is what ends a loop like ``while True: ...; rospy.sleep(1)`` once the node is over.
        raise ROSInterruptException("ROS shutdown request")
    span = _to_ns(duration)
    if span <= 0:
        return
    _block(node, node.graph.now_ns + span, lambda: node.is_shutdown, polled=False)
    if node.is_shutdown:
        raise ROSInterruptException("ROS shutdown request")


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


# -- time.sleep in node code ----------------------------------------------------------------------
_WALL_SLEEP: Callable[[float], None] = getattr(time.sleep, "wall_sleep", time.sleep)
_TIME_SLEEP_NOTE = (
    "time.sleep() waits on the wall clock, but this graph's time is simulated: here it waits "
    "simulated seconds, as rospy.sleep() does. Use rospy.sleep() or rospy.Rate in ROS code."
)


def calling_node() -> Optional[Node]:
    """The in-process node whose code is running now (its main code or a callback), or None.

    ``time.sleep`` waits simulated time in such code only (else it is wall time).
    """
    stack = node_stack()
    if stack:
        return stack[-1]  # a callback
    actor = calling_actor()
    if actor is not None:
        return actor.node  # a launched node's main code (None before init_node)
    # A notebook's own code (and the libraries it calls, Jupyter's among them) keeps the wall
    # clock: the graph does not run between cells anyway.
    return None


def _time_sleep(seconds: Any) -> None:
    node = calling_node()
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
