"""message_filters: pair the messages of several topics by their stamps, as on a Duckiebot.

Use it exactly as ROS's ``message_filters``, for example to pair the two wheel encoders::

    import message_filters

    left = message_filters.Subscriber("left_wheel_encoder_node/tick", WheelEncoderStamped)
    right = message_filters.Subscriber("right_wheel_encoder_node/tick", WheelEncoderStamped)
    pairs = message_filters.ApproximateTimeSynchronizer([left, right], 10, 0.05)
    pairs.registerCallback(on_ticks)          # on_ticks(left_msg, right_msg)

The filters pass messages along on the in-process graph (:mod:`duckielib.ros.rospy`) with the
real filters' rules:

- :class:`TimeSynchronizer` calls back with one message of each input whose header stamps are
  equal, oldest stamps first; each input keeps its ``queue_size`` newest stamps.
- :class:`ApproximateTimeSynchronizer` calls back when a new message and one waiting message of
  each other input have stamps at most ``slop`` seconds from the new one's and less than
  ``slop`` apart from each other, taking the closest first. Messages without a header are
  dropped with a warning unless ``allow_headerless``, which stamps them with the current ROS
  time.
- :class:`Cache` keeps the newest messages of an input for queries by time.

Differences from the real ones, on purpose: a message without a header reaching a
:class:`TimeSynchronizer` is dropped with an error in the log instead of failing in the
callback; :class:`Cache` keeps its messages in stamp order even when they arrive out of it.

Laptop side; never deployed (the robot has the real message_filters).
"""

from __future__ import annotations

import bisect
import itertools
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

from duckielib.ros import rospy

__all__ = [
    "ApproximateTimeSynchronizer",
    "Cache",
    "SimpleFilter",
    "Subscriber",
    "TimeSynchronizer",
]

_HEADERLESS = (
    "Cannot use message filters with messages that have no header stamp: use stamped "
    "messages, or pass allow_headerless=True to stamp them with the current ROS time."
)


def _stamp(message: Any) -> Optional[Any]:
    """A message's header stamp, or None if it has none."""
    header = getattr(message, "header", None)
    return getattr(header, "stamp", None)


def _stamp_or_now(message: Any, allow_headerless: bool) -> Optional[Any]:
    """A message's stamp, or the current ROS time for one without if that is allowed.

    Returns None, and says why in the log, for a message without a stamp otherwise.
    """
    stamp = _stamp(message)
    if stamp is not None:
        return stamp
    if not allow_headerless:
        rospy.logwarn(_HEADERLESS)
        return None
    return rospy.Time.now()


class SimpleFilter:
    """A filter: what it outputs goes to the callbacks registered on it."""

    def __init__(self) -> None:
        self.callbacks: Dict[int, Tuple[Callable[..., Any], Tuple[Any, ...]]] = {}

    def registerCallback(self, cb: Callable[..., Any], *args: Any) -> int:  # noqa: N802
        """Call ``cb(*output, *args)`` with each output of this filter.

        Returns:
            The connection's number.
        """
        connection = len(self.callbacks)
        self.callbacks[connection] = (cb, args)
        return connection

    def signalMessage(self, *msg: Any) -> None:  # noqa: N802
        """Pass an output (one message, or one of each input) to every registered callback."""
        for callback, args in list(self.callbacks.values()):
            callback(*(msg + args))


class Subscriber(SimpleFilter):
    """A topic's messages, as the input of other filters.

    Takes ``rospy.Subscriber``'s arguments but the callback: register callbacks, or connect
    the subscriber to a synchronizer or cache. ``rospy.Subscriber``'s attributes and methods
    (``unregister``, ``resolved_name``...) work on it.

    Raises:
        TypeError: if a callback is given (it goes to :meth:`registerCallback`).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        SimpleFilter.__init__(self)
        if len(args) > 2 or "callback" in kwargs:
            raise TypeError(
                "message_filters.Subscriber(topic, type) takes no callback: pass it to "
                "registerCallback(), or connect the subscriber to a synchronizer."
            )
        if not args:
            raise TypeError("message_filters.Subscriber needs a topic name and a message class.")
        self.topic = args[0]
        kwargs["callback"] = self.callback
        self.sub = rospy.Subscriber(*args, **kwargs)

    def callback(self, msg: Any) -> None:
        """Pass a message received on the topic along."""
        self.signalMessage(msg)

    def getTopic(self) -> str:  # noqa: N802
        """The topic's name, as given."""
        return self.topic

    def __getattr__(self, name: str) -> Any:
        if name == "sub":
            raise AttributeError(name)
        return getattr(self.sub, name)


class Cache(SimpleFilter):
    """The newest ``cache_size`` messages of an input, for queries by stamp.

    Each message is passed along as it arrives.

    Args:
        f: the input filter (a :class:`Subscriber`...).
        cache_size: how many messages to keep.
        allow_headerless: keep messages without a header, stamped with the current ROS time.
    """

    def __init__(
        self, f: SimpleFilter, cache_size: int = 1, allow_headerless: bool = False
    ) -> None:
        SimpleFilter.__init__(self)
        self.cache_size = cache_size
        self.allow_headerless = allow_headerless
        self.cache_msgs: List[Any] = []
        self.cache_times: List[Any] = []
        self._keys: List[int] = []
        self.connectInput(f)

    def connectInput(self, f: SimpleFilter) -> None:  # noqa: N802
        """Take the messages of ``f``."""
        self.incoming_connection = f.registerCallback(self.add)

    def add(self, msg: Any) -> None:
        """Keep a message (dropping the oldest beyond ``cache_size``) and pass it along."""
        stamp = _stamp_or_now(msg, self.allow_headerless)
        if stamp is None:
            return
        key = stamp.to_nsec()
        index = bisect.bisect_right(self._keys, key)
        self._keys.insert(index, key)
        self.cache_times.insert(index, stamp)
        self.cache_msgs.insert(index, msg)
        while len(self._keys) > self.cache_size:
            del self._keys[0], self.cache_times[0], self.cache_msgs[0]
        self.signalMessage(msg)

    def getInterval(self, from_stamp: Any, to_stamp: Any) -> List[Any]:  # noqa: N802
        """The messages stamped from ``from_stamp`` to ``to_stamp``, both included."""
        first, last = from_stamp.to_nsec(), to_stamp.to_nsec()
        if first > last:
            raise ValueError("Cache.getInterval() needs from_stamp <= to_stamp.")
        return [msg for key, msg in zip(self._keys, self.cache_msgs) if first <= key <= last]

    def getElemAfterTime(self, stamp: Any) -> Optional[Any]:  # noqa: N802
        """The oldest message stamped at or after ``stamp``, or None."""
        index = bisect.bisect_left(self._keys, stamp.to_nsec())
        return self.cache_msgs[index] if index < len(self._keys) else None

    def getElemBeforeTime(self, stamp: Any) -> Optional[Any]:  # noqa: N802
        """The newest message stamped at or before ``stamp``, or None."""
        index = bisect.bisect_right(self._keys, stamp.to_nsec())
        return self.cache_msgs[index - 1] if index > 0 else None

    def getLatestTime(self) -> Optional[Any]:  # noqa: N802
        """The newest stamp kept, or None."""
        return self.cache_times[-1] if self.cache_times else None

    getLastestTime = getLatestTime  # noqa: N815 - the real module's misspelt name too

    def getOldestTime(self) -> Optional[Any]:  # noqa: N802
        """The oldest stamp kept, or None."""
        return self.cache_times[0] if self.cache_times else None

    def getLast(self) -> Optional[Any]:  # noqa: N802
        """The newest message kept (the first of those with the newest stamp), or None."""
        latest = self.getLatestTime()
        return None if latest is None else self.getElemAfterTime(latest)


class TimeSynchronizer(SimpleFilter):
    """Calls back with one message of each input when their header stamps are equal.

    The callback gets the messages in the order of ``fs``: ``callback(msg1, ..., msgN)``.

    Args:
        fs: the input filters.
        queue_size: how many stamps each input keeps while waiting for the others.
        reset: forget waiting messages when ROS time jumps back.
    """

    def __init__(self, fs: Sequence[SimpleFilter], queue_size: int, reset: bool = False) -> None:
        SimpleFilter.__init__(self)
        self.queue_size = queue_size
        self.enable_reset = reset
        self.connectInput(fs)

    def connectInput(self, fs: Sequence[SimpleFilter]) -> None:  # noqa: N802
        """Take the messages of each filter of ``fs``."""
        self.queues: List[Dict[int, Any]] = [{} for _ in fs]
        self.latest_stamps: List[int] = [0 for _ in fs]
        self.input_connections = [
            f.registerCallback(self.add, queue, index)
            for index, (f, queue) in enumerate(zip(fs, self.queues))
        ]

    def _time_went_back(self, my_queue: Dict[int, Any], my_queue_index: Optional[int]) -> bool:
        """With ``reset``: clear an input's queue when time went back; whether to wait."""
        if not self.enable_reset or my_queue_index is None:
            return False
        now = rospy.Time.now().to_nsec()
        if now < self.latest_stamps[my_queue_index]:
            my_queue.clear()
        self.latest_stamps[my_queue_index] = now
        return max(self.latest_stamps) != now

    def _trim(self, queue: Dict[int, Any]) -> None:
        while len(queue) > self.queue_size:
            del queue[min(queue)]

    def add(self, msg: Any, my_queue: Dict[int, Any], my_queue_index: Optional[int] = None) -> None:
        """Take a message of one input; call back for every stamp all inputs now have."""
        stamp = _stamp(msg)
        if stamp is None:
            rospy.logerr(
                "A TimeSynchronizer pairs messages by their header stamps, and this one has "
                "none: use ApproximateTimeSynchronizer(..., allow_headerless=True) instead."
            )
            return
        waiting = self._time_went_back(my_queue, my_queue_index)
        my_queue[stamp.to_nsec()] = msg
        self._trim(my_queue)
        if waiting:
            return
        common = set(self.queues[0]).intersection(*self.queues[1:])
        for key in sorted(common):
            self.signalMessage(*[queue.pop(key) for queue in self.queues])


class ApproximateTimeSynchronizer(TimeSynchronizer):
    """Calls back with one message of each input when their stamps are within ``slop``.

    When a message arrives, the waiting messages of each other input stamped at most ``slop``
    from it are candidates, closest first; the first combination whose stamps all lie less
    than ``slop`` apart is passed on (in the order of ``fs``) and leaves the queues.

    Args:
        fs: the input filters.
        queue_size: how many stamps each input keeps while waiting for the others.
        slop: the largest difference between stamps, in seconds.
        allow_headerless: take messages without a header, stamped with the current ROS time.
        reset: forget waiting messages when ROS time jumps back.
    """

    def __init__(
        self,
        fs: Sequence[SimpleFilter],
        queue_size: int,
        slop: float,
        allow_headerless: bool = False,
        reset: bool = False,
    ) -> None:
        TimeSynchronizer.__init__(self, fs, queue_size, reset)
        self.slop = rospy.Duration.from_sec(slop)
        self.allow_headerless = allow_headerless
        self._last_added = 0

    def add(self, msg: Any, my_queue: Dict[int, Any], my_queue_index: Optional[int] = None) -> None:
        """Take a message of one input; call back if it completes a set within ``slop``."""
        stamp = _stamp_or_now(msg, self.allow_headerless)
        if stamp is None:
            return
        key = stamp.to_nsec()
        waiting = self._time_went_back(my_queue, my_queue_index)
        my_queue[key] = msg
        now = rospy.Time.now().to_nsec()
        if now < self._last_added:
            rospy.loginfo("ApproximateTimeSynchronizer: ROS time went back; clearing its queues.")
            for queue in self.queues:
                queue.clear()
        self._last_added = now
        self._trim(my_queue)
        if waiting:
            return
        slop = self.slop.to_nsec()
        others = [q for index, q in enumerate(self.queues) if index != my_queue_index]
        candidates = []
        for queue in others:
            near = sorted((k for k in queue if abs(k - key) <= slop), key=lambda k: abs(k - key))
            if not near:
                return
            candidates.append(near)
        for choice in itertools.product(*candidates):
            keys = list(choice)
            if my_queue_index is not None:
                keys.insert(my_queue_index, key)
            if max(keys) - min(keys) < slop and all(
                k in queue for k, queue in zip(keys, self.queues)
            ):
                self.signalMessage(*[queue.pop(k) for k, queue in zip(keys, self.queues)])
                return
