"""Keeping the wheels safe while a student's node drives: stop them whenever something ends.

A node that drives the robot can end in many ways: it finishes, it is shut down, someone
presses Ctrl-C, its code raises an exception, or the robot's encoders go silent (a driver
crashed, a cable came loose) while it keeps sending commands. :class:`SafetyGuard` makes each
of these end with the wheels at zero:

- normal end, shutdown and Ctrl-C (SIGINT): a shutdown hook publishes zero commands;
- an exception in the node's main code: :meth:`SafetyGuard.run` stops the wheels, then lets
  the exception through (the node ends with an error);
- an exception in a subscriber's callback: rospy only logs those, and the node would go on
  driving blind, so the guard shuts the node down as Ctrl-C would (which stops the wheels);
- encoder silence: when no encoder tick arrives for :data:`ENCODER_TIMEOUT_S` after the first
  one, the guard engages the wheels driver's emergency stop (the driver then ignores every
  command) and releases it when ticks come back.

"Zero" is sent twice, as a chassis command (``car_cmd_switch_node/cmd``, what the course's
nodes drive with) and as wheel duty cycles (``wheels_driver_node/wheels_cmd``), so it also
stops a node that talks to the wheels directly.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

import logging
import os
import signal
import threading
import time
from typing import Any, Callable, List, Optional

from duckielib.ros.backend import is_in_process, message_classes

__all__ = ["ENCODER_TIMEOUT_S", "SafetyGuard", "guarded_init"]

#: How long the encoders may stay silent, in seconds of wall-clock time, before the guard
#: engages the emergency stop (on the in-process graph, simulated seconds).
ENCODER_TIMEOUT_S = 0.5

#: How long a stop keeps sending zero commands (wall-clock seconds; on the in-process graph,
#: simulated seconds).
_HOLD_S = 0.3


class _CallbackErrors(logging.Handler):
    """Notices rospy's "bad callback" log lines (an exception raised in a callback)."""

    def __init__(self, notice: Callable[[str], None]) -> None:
        super().__init__(level=logging.ERROR)
        self.notice = notice

    def emit(self, record: logging.LogRecord) -> None:
        text = record.getMessage()
        if text.startswith("bad callback"):
            self.notice(text.splitlines()[-1] if text.strip() else text)


class SafetyGuard:
    """Stops the wheels when the node that drives them ends, fails, or loses its encoders.

    Create it after ``rospy.init_node``, in the robot's namespace. Then either run the node's
    main code through :meth:`run`, or call :meth:`stop` yourself.

    Args:
        rospy: the rospy the node runs with.
        encoder_timeout: seconds of encoder silence (wall clock) before the emergency stop.

    Attributes:
        stops: why the wheels were stopped, in order (for logs and tests).
        estop_engaged: whether the guard holds the emergency stop now.
        callback_error: the first exception a callback raised (``"Type: message"``), or None.
    """

    def __init__(self, rospy: Any, encoder_timeout: float = ENCODER_TIMEOUT_S) -> None:
        self.rospy = rospy
        self.encoder_timeout = encoder_timeout
        self.stops: List[str] = []
        self.estop_engaged = False
        self.callback_error: Optional[str] = None
        msg = message_classes(rospy)
        self._msg = msg
        self._lock = threading.Lock()
        self._last_tick: Optional[float] = None  # watched from the first tick on
        self._ended = threading.Event()
        self._shutdown_reason = "the node is shutting down"
        self._car_cmd = rospy.Publisher("car_cmd_switch_node/cmd", msg.Twist2DStamped, queue_size=1)
        self._wheels = rospy.Publisher(
            "wheels_driver_node/wheels_cmd", msg.WheelsCmdStamped, queue_size=1
        )
        self._estop = rospy.Publisher(
            "wheels_driver_node/emergency_stop", msg.BoolStamped, queue_size=1, latch=True
        )
        self._ticks = [
            rospy.Subscriber(
                f"{wheel}_wheel_encoder_node/tick", msg.WheelEncoderStamped, self._on_tick
            )
            for wheel in ("left", "right")
        ]
        self._errors = _CallbackErrors(self._on_callback_error)
        logging.getLogger("rosout").addHandler(self._errors)
        rospy.on_shutdown(self._on_shutdown)
        # On the in-process graph (duckie run), the node lives on simulated time, run as fast
        # as the laptop goes: its guard keeps that clock, so a run is the same each time.
        self._simulated = is_in_process(rospy)
        self._timer: Any = None
        if self._simulated:
            self._timer = rospy.Timer(
                rospy.Duration(self.encoder_timeout / 5), lambda _event: self._check()
            )
        else:
            self._watchdog = threading.Thread(
                target=self._watch, name="safety-watchdog", daemon=True
            )
            self._watchdog.start()

    def _now(self) -> float:
        """The guard's clock: the wall clock, or the graph's simulated one (see above)."""
        return float(self.rospy.get_time()) if self._simulated else time.monotonic()

    # -- the ways a node ends ------------------------------------------------------------------
    def run(self, main: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        """Run ``main(*args, **kwargs)``; stop the wheels however it ends.

        Returns:
            What ``main`` returns.
        """
        try:
            result = main(*args, **kwargs)
        except BaseException as error:
            self.stop(f"the node's code raised {type(error).__name__}: {error}")
            raise
        self.stop("the node finished")
        return result

    def stop(self, reason: str) -> None:
        """Command zero to the chassis and the wheels, and remember why.

        The zeros are sent again every 50 ms for :data:`_HOLD_S` (wall clock): while rospy
        runs its shutdown hooks, the node's other threads (a timer, a callback) may still send
        a command; the last word must be zero.
        """
        with self._lock:
            self.stops.append(reason)
        self.rospy.logwarn(f"Wheels stopped: {reason}.")
        deadline = self._now() + _HOLD_S
        while True:
            self._publish_zero()
            if self._now() >= deadline or (self._simulated and self.rospy.is_shutdown()):
                break  # (a graph that shut down has stopped its clock: once is the last word)
            time.sleep(0.05)

    def _publish_zero(self) -> None:
        zero_cmd = self._msg.Twist2DStamped(v=0.0, omega=0.0)
        zero_wheels = self._msg.WheelsCmdStamped(vel_left=0.0, vel_right=0.0)
        for publisher, message in ((self._car_cmd, zero_cmd), (self._wheels, zero_wheels)):
            try:
                publisher.publish(message)
            except Exception:  # a closed topic (after shutdown) must not hide the stop reason
                return

    def close(self) -> None:
        """Stop watching (the node is done); the emergency stop is released if held."""
        self._stop_watching()
        if self.estop_engaged:
            self._set_estop(False)

    # -- callbacks -----------------------------------------------------------------------------
    def _on_shutdown(self) -> None:
        self.stop(self._shutdown_reason)
        self._stop_watching()

    def _stop_watching(self) -> None:
        self._ended.set()
        if self._timer is not None:
            self._timer.shutdown()
        logging.getLogger("rosout").removeHandler(self._errors)

    def _on_tick(self, _message: Any) -> None:
        self._last_tick = self._now()
        if self.estop_engaged:
            self._set_estop(False)
            self.rospy.loginfo("Encoder ticks are back: emergency stop released.")

    def _on_callback_error(self, text: str) -> None:
        if self._ended.is_set() or self.callback_error is not None:
            return
        self.callback_error = text
        self._shutdown_reason = f"a callback raised an exception ({text})"
        ros_handler = getattr(getattr(self.rospy, "core", None), "_ros_signal", None)
        if ros_handler is not None and signal.getsignal(signal.SIGINT) is ros_handler:
            # Shut down as Ctrl-C does, in the main thread, where the node's loop runs: the
            # loop waits while the zeros go out, then finds rospy shut down. Shut down from
            # this callback's thread, the loop could send one more command after the last zero.
            os.kill(os.getpid(), signal.SIGINT)
        else:  # rospy's signal handlers are off (init_node(disable_signals=True))
            self.rospy.signal_shutdown(self._shutdown_reason)

    def _watch(self) -> None:
        while not self._ended.wait(self.encoder_timeout / 5):
            self._check()

    def _check(self) -> None:
        """Engage the emergency stop if the encoders have been silent too long."""
        if self._last_tick is None or self._ended.is_set():
            return
        silent = self._now() - self._last_tick
        if silent > self.encoder_timeout and not self.estop_engaged:
            self._set_estop(True)
            self.stop(f"no encoder tick for {silent:.1f} s")

    def _set_estop(self, engaged: bool) -> None:
        self.estop_engaged = engaged
        self._estop.publish(self._msg.BoolStamped(data=engaged))


def guarded_init(rospy: Any, on_init: Callable[[], None]) -> Callable[[], None]:
    """Call ``on_init()`` right after the node's own ``rospy.init_node`` returns.

    The course's mission node calls ``init_node`` itself, inside the student's function; the
    guard can only be built after that. This wraps ``rospy.init_node`` once, and returns a
    function that puts the original back.
    """
    original = rospy.init_node

    def init_node(*args: Any, **kwargs: Any) -> Any:
        result = original(*args, **kwargs)
        rospy.init_node = original
        on_init()
        return result

    rospy.init_node = init_node

    def restore() -> None:
        rospy.init_node = original

    return restore
