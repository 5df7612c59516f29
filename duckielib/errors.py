"""Errors raised by duckielib.

Every error the library raises on purpose derives from :class:`DuckielibError`, so a caller
(a notebook, the ``duckie`` command, the autograder) can tell "the user must fix something"
apart from a bug. Messages are whole sentences that say what to do next.
"""

from __future__ import annotations

__all__ = [
    "DuckielibError",
    "ConfigError",
    "MessageError",
    "MessageDefinitionError",
    "UnknownTypeError",
    "NotBuiltError",
    "SimulationError",
    "BagError",
]


class DuckielibError(Exception):
    """Base class of every error duckielib raises on purpose."""


class ConfigError(DuckielibError, ValueError):
    """A robot or simulator setting has an impossible value."""


class MessageError(DuckielibError, ValueError):
    """A message field got a value of the wrong type or out of its range."""


class MessageDefinitionError(DuckielibError):
    """A ``.msg`` or ``.srv`` text could not be parsed."""


class UnknownTypeError(DuckielibError, KeyError):
    """A message or service type name is not one the course knows.

    It derives from ``KeyError`` as a lookup in a registry does, but prints its sentence
    without the quotes ``KeyError`` adds.
    """

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class NotBuiltError(DuckielibError):
    """A part of the course that is asked for does not exist yet."""


class SimulationError(DuckielibError):
    """The simulator was asked for something it cannot do, such as driving with a NaN duty cycle."""


class BagError(DuckielibError):
    """A bag cannot be read, written or repaired (the message says why and what to do)."""
