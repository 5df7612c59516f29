"""Log levels and log lines of the in-process graph, as rospy names them.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

import traceback

__all__ = ["DEBUG", "ERROR", "FATAL", "INFO", "LEVEL_NAMES", "WARN", "LogRecord", "format_error"]

DEBUG, INFO, WARN, ERROR, FATAL = 1, 2, 4, 8, 16
LEVEL_NAMES = {DEBUG: "DEBUG", INFO: "INFO", WARN: "WARN", ERROR: "ERROR", FATAL: "FATAL"}


class LogRecord:
    """One logged line: simulated time (s), level, node name and text."""

    __slots__ = ("level", "node", "text", "time")

    def __init__(self, time: float, level: int, node: str, text: str) -> None:
        self.time = time
        self.level = level
        self.node = node
        self.text = text

    def __repr__(self) -> str:
        return f"[{LEVEL_NAMES[self.level]}] [{self.time:.3f}] [{self.node}]: {self.text}"


def format_error(error: BaseException) -> str:
    """An exception with its traceback, as Python prints it, for the log."""
    return "".join(traceback.format_exception(type(error), error, error.__traceback__)).rstrip()
