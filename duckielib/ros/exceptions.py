"""The exceptions of rospy, with rospy's names and hierarchy.

They also derive from :class:`~duckielib.errors.DuckielibError`, so course tools can tell
them from bugs.
"""

from __future__ import annotations

from duckielib.errors import DuckielibError

__all__ = [
    "ROSException",
    "ROSInitException",
    "ROSInterruptException",
    "ROSSerializationException",
    "ROSTimeMovedBackwardsException",
    "ServiceException",
    "TransportException",
]


class ROSException(DuckielibError):
    """Base class of rospy's errors."""


class ROSInitException(ROSException):
    """The node is not initialised, or initialised twice with different arguments."""


class ROSInterruptException(ROSException, KeyboardInterrupt):
    """A blocking call (``rospy.sleep``, ``Rate.sleep``) was interrupted by shutdown."""


class ROSSerializationException(ROSException):
    """A message could not be sent: a field holds a value its type cannot carry."""


class ROSTimeMovedBackwardsException(ROSInterruptException):
    """The clock jumped backwards during a sleep."""


class ServiceException(ROSException):
    """A service call failed: the service is missing, or its handler failed."""


class TransportException(ROSException):
    """A connection between nodes failed."""
