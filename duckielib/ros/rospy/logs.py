"""rospy's logging: ``loginfo`` and its kin, throttled and once-only variants.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

import sys
from typing import Any, Callable

from duckielib.ros.context import (
    current_node,
)
from duckielib.ros.exceptions import (
    ROSInitException,
)
from duckielib.ros.graph import current_graph
from duckielib.ros.log import DEBUG, ERROR, FATAL, INFO, WARN


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


def _throttled_identical(level: int) -> Callable[..., None]:
    def log(period: float, msg: Any, *args: Any) -> None:
        text = str(msg) % args if args else str(msg)
        current_node().log_throttled_identical(_call_site(), period, level, text)

    log.__doc__ = (
        "Log when the message differs from the last one from this line, or when ``period`` "
        "simulated seconds have passed since this line last logged."
    )
    return log


def _once(level: int) -> Callable[..., None]:
    def log(msg: Any, *args: Any) -> None:
        text = str(msg) % args if args else str(msg)
        current_node().log_once(_call_site(), level, text)

    log.__doc__ = "Log only the first time this line runs."
    return log


logdebug_throttle, loginfo_throttle = _throttled(DEBUG), _throttled(INFO)
logwarn_throttle, logerr_throttle = _throttled(WARN), _throttled(ERROR)
logfatal_throttle = _throttled(FATAL)
logdebug_throttle_identical = _throttled_identical(DEBUG)
loginfo_throttle_identical = _throttled_identical(INFO)
logwarn_throttle_identical = _throttled_identical(WARN)
logerr_throttle_identical = _throttled_identical(ERROR)
logfatal_throttle_identical = _throttled_identical(FATAL)
logdebug_once, loginfo_once = _once(DEBUG), _once(INFO)
logwarn_once, logerr_once = _once(WARN), _once(ERROR)
logfatal_once = _once(FATAL)
