"""Noise profiles: how far the virtual Duckiebot is from an ideal unicycle.

A :class:`NoiseProfile` is a frozen set of the imperfections the simulator reproduces. Two
profiles are named:

- :meth:`NoiseProfile.ideal`: equal wheels, tyres that never slip, encoders sampled on a perfectly
  regular schedule, any PWM out of the dead zone turns a wheel. Each wheel's ticks match its
  travel up to quantisation; odometry still drifts a little, as on any robot, because the two
  wheels are sampled at different instants and a wheel that coasts after its command changed
  sign counts by the new sign (the real encoder driver's rule).
- :meth:`NoiseProfile.realistic`: the right wheel is 3 % weaker than the left (so trim matters),
  tyres slip when asked for more than the mat's friction gives (hard starts and stops), encoder
  samples come a few milliseconds late or early, and a wheel at rest needs a bit more than the
  driver's smallest PWM to break free.

Every parameter can be set on its own, starting from either profile::

    NoiseProfile.realistic(encoder_jitter_s=0.0)
    NoiseProfile.ideal().replace(right_gain=0.97)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Optional, Union

from duckielib.errors import ConfigError

__all__ = ["NoiseProfile", "noise_profile"]


@dataclass(frozen=True)
class NoiseProfile:
    """The imperfections of one simulated Duckiebot.

    Attributes:
        name: the profile's name, for reports (``"ideal"``, ``"realistic"`` or ``"custom"``).
        left_gain: factor on the left motor's speed (1 is nominal).
        right_gain: factor on the right motor's speed (1 is nominal).
        friction_coefficient: tyre-to-mat friction coefficient; the largest force a wheel can
            pass to the mat is this times the wheel's share of the robot's weight. None means
            the tyres never slip.
        encoder_jitter_s: standard deviation of the time error of each encoder sample, in
            seconds (samples are due every 1 / encoder_rate_hz on average).
        breakaway_pwm: PWM (of 255) a wheel at rest needs before it starts turning (static
            friction in the gearbox); None means the driver's smallest PWM is enough.
    """

    name: str = "custom"
    left_gain: float = 1.0
    right_gain: float = 1.0
    friction_coefficient: Optional[float] = None
    encoder_jitter_s: float = 0.0
    breakaway_pwm: Optional[int] = None

    def __post_init__(self) -> None:
        for field in ("left_gain", "right_gain"):
            value = getattr(self, field)
            if not (_is_number(value) and value > 0):
                raise ConfigError(f"NoiseProfile.{field} must be a positive number, not {value!r}.")
        mu = self.friction_coefficient
        if mu is not None and not (_is_number(mu) and mu > 0):
            raise ConfigError(
                f"NoiseProfile.friction_coefficient must be a positive number or None (no slip), "
                f"not {mu!r}."
            )
        if not (_is_number(self.encoder_jitter_s) and self.encoder_jitter_s >= 0):
            raise ConfigError(
                "NoiseProfile.encoder_jitter_s must be a number of seconds >= 0, "
                f"not {self.encoder_jitter_s!r}."
            )
        pwm = self.breakaway_pwm
        if pwm is not None and not (isinstance(pwm, int) and 0 <= pwm <= 255):
            raise ConfigError(
                f"NoiseProfile.breakaway_pwm must be an integer PWM in [0, 255] or None, "
                f"not {pwm!r}."
            )

    @classmethod
    def ideal(cls, **changes: object) -> NoiseProfile:
        """No asymmetry, no slip, no jitter; ``changes`` override single parameters."""
        return cls(name="ideal").replace(**changes)

    @classmethod
    def realistic(cls, **changes: object) -> NoiseProfile:
        """Unequal wheels, slip at high acceleration, jittered encoders; ``changes`` override."""
        profile = cls(
            name="realistic",
            left_gain=1.0,
            right_gain=0.97,
            friction_coefficient=0.8,
            encoder_jitter_s=0.002,
            breakaway_pwm=68,
        )
        return profile.replace(**changes)

    def replace(self, **changes: object) -> NoiseProfile:
        """A copy with some parameters changed (its name becomes ``"custom"`` unless given).

        Raises:
            ConfigError: if a name is not a parameter or a value is impossible.
        """
        if not changes:
            return self
        names = [item.name for item in dataclasses.fields(self)]
        unknown = set(changes) - set(names)
        if unknown:
            raise ConfigError(
                f"NoiseProfile has no parameter {', '.join(sorted(unknown))}; "
                f"its parameters are: {', '.join(names)}."
            )
        changes.setdefault("name", "custom")
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]


def noise_profile(profile: Union[str, NoiseProfile]) -> NoiseProfile:
    """The profile itself, or the named one (``"ideal"`` or ``"realistic"``).

    Raises:
        ConfigError: if the name is not one of the named profiles.
    """
    if isinstance(profile, NoiseProfile):
        return profile
    if profile == "ideal":
        return NoiseProfile.ideal()
    if profile == "realistic":
        return NoiseProfile.realistic()
    raise ConfigError(
        f"There is no noise profile called {profile!r}; use 'ideal', 'realistic' or a NoiseProfile."
    )


def _is_number(value: object) -> bool:
    return (
        isinstance(value, (int, float))
        and not isinstance(value, bool)
        and math.isfinite(float(value))
    )
