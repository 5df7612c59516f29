"""ROS time: :class:`Time` (a point in time) and :class:`Duration` (a span), as in genpy.

Both hold whole seconds ``secs`` and nanoseconds ``nsecs`` (0 <= nsecs < 1e9 after
normalisation), exactly as ROS 1 stores them in messages and bags. Arithmetic follows ROS:
``Time - Time`` is a ``Duration``, ``Time + Duration`` is a ``Time``, ``Duration * number``
is a ``Duration``. Conversions name their unit: :meth:`to_sec` gives seconds (float),
:meth:`to_nsec` gives integer nanoseconds.

Where the clock comes from (``Time.now()``) is the job of the ROS layer, not of this module.
"""

from __future__ import annotations

import math
from numbers import Integral, Real
from typing import Any, Dict, Tuple, Type, TypeVar

__all__ = ["NS_PER_S", "Time", "Duration"]

#: Nanoseconds in a second: ROS times are whole seconds and nanoseconds.
NS_PER_S = 1_000_000_000

_Value = TypeVar("_Value", bound="_TimeValue")


class _TimeValue:
    """Seconds and nanoseconds, normalised; the common part of Time and Duration."""

    __slots__ = ("secs", "nsecs")

    def __init__(self, secs: int | float = 0, nsecs: int = 0) -> None:
        if type(secs) is int and type(nsecs) is int:  # the common case
            if 0 <= nsecs < NS_PER_S:
                self.secs, self.nsecs = secs, nsecs
            else:
                self.secs, self.nsecs = divmod(secs * NS_PER_S + nsecs, NS_PER_S)
            return
        if not isinstance(secs, Real) or not isinstance(nsecs, Real):
            raise TypeError(
                f"{type(self).__name__} takes numbers of seconds and nanoseconds, "
                f"not {secs!r} and {nsecs!r}."
            )
        if not isinstance(secs, Integral):
            if not math.isfinite(secs):
                raise ValueError(f"{type(self).__name__} cannot hold {secs} seconds.")
            whole = math.floor(secs)
            nsecs = int(nsecs) + round((secs - whole) * NS_PER_S)
            secs = whole
        total = int(secs) * NS_PER_S + int(nsecs)
        self.secs, self.nsecs = divmod(total, NS_PER_S)

    @classmethod
    def from_sec(cls: Type[_Value], seconds: float) -> _Value:
        """Build from a number of seconds (float)."""
        return cls(seconds)

    @classmethod
    def from_nsec(cls: Type[_Value], nanoseconds: int) -> _Value:
        """Build from an integer number of nanoseconds."""
        return cls(0, int(nanoseconds))

    @classmethod
    def from_seconds(cls: Type[_Value], seconds: float) -> _Value:
        """Same as :meth:`from_sec` (rospy offers both names)."""
        return cls(seconds)

    def to_sec(self) -> float:
        """The value in seconds, as a float."""
        return self.secs + self.nsecs / NS_PER_S

    def to_nsec(self) -> int:
        """The value in integer nanoseconds."""
        return self.secs * NS_PER_S + self.nsecs

    def is_zero(self) -> bool:
        """True for the zero time (an unset header stamp) or the zero duration."""
        return self.secs == 0 and self.nsecs == 0

    def __bool__(self) -> bool:
        return not self.is_zero()

    def __eq__(self, other: object) -> bool:
        if not _same_kind(self, other):
            return NotImplemented
        return self.to_nsec() == other.to_nsec()  # type: ignore[attr-defined]

    def __lt__(self, other: object) -> bool:
        if not _same_kind(self, other):
            return NotImplemented
        return self.to_nsec() < other.to_nsec()  # type: ignore[attr-defined]

    def __le__(self, other: object) -> bool:
        if not _same_kind(self, other):
            return NotImplemented
        return self.to_nsec() <= other.to_nsec()  # type: ignore[attr-defined]

    def __gt__(self, other: object) -> bool:
        if not _same_kind(self, other):
            return NotImplemented
        return self.to_nsec() > other.to_nsec()  # type: ignore[attr-defined]

    def __ge__(self, other: object) -> bool:
        if not _same_kind(self, other):
            return NotImplemented
        return self.to_nsec() >= other.to_nsec()  # type: ignore[attr-defined]

    def __hash__(self) -> int:
        return hash((isinstance(self, Time), self.to_nsec()))

    def __repr__(self) -> str:
        return f"{type(self).__name__}[{self.to_nsec()}]"

    def __str__(self) -> str:
        return str(self.to_nsec())

    def __copy__(self: _Value) -> _Value:
        return type(self)(self.secs, self.nsecs)

    def __deepcopy__(self: _Value, memo: Dict[int, Any]) -> _Value:
        return type(self)(self.secs, self.nsecs)

    def __reduce__(self) -> Tuple[type, Tuple[int, int]]:
        return (type(self), (self.secs, self.nsecs))


class Time(_TimeValue):
    """A point in time: seconds and nanoseconds since the clock's epoch.

    ``Time(0)`` is "unset", as in a message whose header stamp was never filled in.

    Raises:
        ValueError: for a negative time, which ROS cannot store.
    """

    __slots__ = ()

    def __init__(self, secs: int | float = 0, nsecs: int = 0) -> None:
        _TimeValue.__init__(self, secs, nsecs)
        if self.secs < 0:
            raise ValueError(f"Time cannot be negative (got {self.to_sec()} s).")

    def __add__(self: _Value, other: object) -> _Value:
        if not isinstance(other, Duration):
            return NotImplemented
        return type(self)(0, self.to_nsec() + other.to_nsec())

    __radd__ = __add__

    def __sub__(self, other: object):
        if isinstance(other, Time):
            return _duration_type(other)(0, self.to_nsec() - other.to_nsec())
        if isinstance(other, Duration):
            return type(self)(0, self.to_nsec() - other.to_nsec())
        return NotImplemented


class Duration(_TimeValue):
    """A span of time, possibly negative.

    A negative duration keeps ``secs`` negative and ``nsecs`` in [0, 1e9), as ROS does:
    ``Duration(-0.5)`` is ``secs=-1, nsecs=500000000``.
    """

    __slots__ = ()

    def __neg__(self: _Value) -> _Value:
        return type(self)(0, -self.to_nsec())

    def __abs__(self: _Value) -> _Value:
        return type(self)(0, abs(self.to_nsec()))

    def __add__(self, other: object):
        if isinstance(other, Duration):
            return type(self)(0, self.to_nsec() + other.to_nsec())
        if isinstance(other, Time):
            return type(other)(0, self.to_nsec() + other.to_nsec())
        return NotImplemented

    __radd__ = __add__

    def __sub__(self: _Value, other: object) -> _Value:
        if not isinstance(other, Duration):
            return NotImplemented
        return type(self)(0, self.to_nsec() - other.to_nsec())

    def __mul__(self: _Value, factor: object) -> _Value:
        if not isinstance(factor, Real):
            return NotImplemented
        # int * Real is a Real, but typeshed's numbers module types the product as complex.
        return type(self)(0, round(self.to_nsec() * factor))  # type: ignore[call-overload]

    __rmul__ = __mul__

    def __truediv__(self, other: object):
        if isinstance(other, Duration):
            return self.to_nsec() / other.to_nsec()
        if isinstance(other, Real):
            # As in __mul__: int / Real is a Real, which typeshed cannot say.
            return type(self)(0, round(self.to_nsec() / other))  # type: ignore[call-overload]
        return NotImplemented

    def __floordiv__(self, other: object):
        # As rospy's (genpy's) Duration: by an int, seconds and nanoseconds are divided
        # apart (Duration(3) // 2 is 1 s); by a float, the seconds; by a Duration, a count.
        if isinstance(other, Duration):
            return int(self.to_sec() // other.to_sec())
        if isinstance(other, Integral) and not isinstance(other, bool):
            divisor = int(other)
            return type(self)(self.secs // divisor, self.nsecs // divisor)
        if isinstance(other, Real):
            return type(self).from_sec(self.to_sec() // float(other))
        return NotImplemented


def _same_kind(value: object, other: object) -> bool:
    """Whether two values are both times or both durations (of any rospy flavour).

    A message's ``header.stamp`` is this module's :class:`Time`, ``rospy.Time`` a subclass of
    it; they compare and hash as equals, as in rospy.
    """
    return isinstance(other, _TimeValue) and isinstance(other, Time) == isinstance(value, Time)


def _duration_type(time: Time) -> Type[Duration]:
    """The Duration class that goes with a Time class (rospy's goes with rospy's)."""
    return getattr(time, "duration_class", Duration)
