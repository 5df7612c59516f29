"""Wheel encoders as the DB21's encoder driver has them.

Each wheel has a single-channel optical encoder: a pulse every ``2*pi / resolution`` radians
of wheel rotation (135 per revolution), whichever way the wheel turns. The driver cannot see
the direction; it adds or subtracts each pulse by the sign of the last executed wheel command
(``>= 0`` counts up, ``< 0`` counts down), so a wheel still coasting forward after a reverse
command already counts down. The realistic noise profile keeps that rule; the ideal one counts
by the way the wheel really turns. The count is cumulative since the driver started, starts
anywhere, and is published as a signed int32 (it wraps as one).

Each encoder publishes its count on its own timer, ``encoder_rate_hz`` (30 Hz) on average, the
two timers out of phase; with a jittery noise profile each sample comes a little early or late
(normally distributed, clipped to a third of a period), without drift.
"""

from __future__ import annotations

import math
from typing import List, NamedTuple

import numpy as np

__all__ = ["EncoderReading", "Encoder", "to_int32"]

_JITTER_CLIP = 1.0 / 3.0


class EncoderReading(NamedTuple):
    """One encoder sample, as the encoder node publishes it.

    Attributes:
        wheel: ``"left"`` or ``"right"``.
        time: simulated time of the sample, in seconds.
        ticks: the cumulative tick count at that time (signed int32).
    """

    wheel: str
    time: float
    ticks: int


def to_int32(value: int) -> int:
    """``value`` wrapped to a signed 32-bit integer, as an int32 message field holds it."""
    return ((value + 0x80000000) & 0xFFFFFFFF) - 0x80000000


class Encoder:
    """One wheel's encoder and its publishing schedule.

    Args:
        wheel: ``"left"`` or ``"right"``.
        resolution: pulses per wheel revolution.
        rate_hz: average sampling rate, in Hz.
        initial_ticks: the count when the simulation starts.
        jitter_s: standard deviation of each sample's time error, in seconds.
        rng: the random generator of this encoder (start phase, slot phase, jitter).
        out: the list new readings are appended to.
        counts_by_command: count each pulse by the sign of the last wheel command, as the
            real driver does (True), or by the way the wheel turns (False, an ideal encoder).
    """

    __slots__ = (
        "_inv_pitch",
        "_jitter_s",
        "_k",
        "_by_command",
        "_out",
        "_period",
        "_phase",
        "_rng",
        "angle",
        "count",
        "direction",
        "next_time",
        "slot",
        "wheel",
    )

    def __init__(
        self,
        wheel: str,
        resolution: int,
        rate_hz: float,
        initial_ticks: int,
        jitter_s: float,
        rng: np.random.Generator,
        out: List[EncoderReading],
        counts_by_command: bool = True,
    ) -> None:
        self.wheel = wheel
        self._by_command = counts_by_command
        self._inv_pitch = resolution / math.tau
        self._period = 1.0 / rate_hz
        self._jitter_s = jitter_s
        self._rng = rng
        self._out = out
        self.count = int(initial_ticks)
        self.direction = 1
        # The wheel sits anywhere between two slots, and the timer starts anywhere in its period.
        self.angle = float(rng.uniform(0.0, math.tau / resolution))
        self.slot = math.floor(self.angle * self._inv_pitch)
        self._phase = float(rng.uniform(0.0, self._period))
        self._k = 0
        self.next_time = self._phase

    def set_direction(self, duty: float) -> None:
        """Take the counting direction from an executed duty cycle (if it counts by command)."""
        if self._by_command:
            self.direction = 1 if duty >= 0 else -1

    @property
    def ticks(self) -> int:
        """The current count as published (signed int32)."""
        return to_int32(self.count)

    def advance(self, t0: float, dt: float, speed: float) -> None:
        """Turn the wheel at ``speed`` rad/s from time ``t0`` for ``dt`` seconds.

        Samples due in ``(t0, t0 + dt]`` are appended to the output list with the count at
        their own time (the wheel turns at a constant rate within a step).
        """
        if not self._by_command and speed:
            self.direction = 1 if speed > 0 else -1
        angle0 = self.angle
        angle1 = angle0 + speed * dt
        slot1 = math.floor(angle1 * self._inv_pitch)
        t1 = t0 + dt
        while self.next_time <= t1:
            when = self.next_time
            partial = angle0 + speed * (when - t0)
            crossed = abs(math.floor(partial * self._inv_pitch) - self.slot)
            self._out.append(
                EncoderReading(self.wheel, when, to_int32(self.count + self.direction * crossed))
            )
            self._schedule()
        if slot1 != self.slot:
            self.count += self.direction * abs(slot1 - self.slot)
            self.slot = slot1
        self.angle = angle1

    def _schedule(self) -> None:
        self._k += 1
        nominal = self._phase + self._k * self._period
        if self._jitter_s > 0:
            limit = _JITTER_CLIP * self._period
            error = min(limit, max(-limit, float(self._rng.normal(0.0, self._jitter_s))))
            self.next_time = nominal + error
        else:
            self.next_time = nominal
