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
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Optional, Tuple, Union

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
        speed_curve: a motor's steady wheel speed against its duty cycle, as knots
            ``((duty, rad/s), ...)`` with rising duties in (0, 1] and speeds >= 0: linear
            between knots, 0 below the first knot (the motor's dead band), flat after the last.
            None: the driver's linear law, ``k`` rad/s at duty 1 (:class:`RobotConfig`).
        right_speed_curve: the right motor's own speed curve, when it differs from the left's
            (``duckie calibrate`` fits one per wheel); None: ``speed_curve`` for both.
        wheel_radius_scale: the wheels' true radius over the nominal one that odometry uses.
        baseline_scale: the true distance between the wheels' contact points over the nominal
            baseline that odometry uses.
        encoder_counts_by_command: True for the real encoder driver's rule, counting each pulse
            up or down by the sign of the last wheel command (so a wheel still coasting
            forward after a reverse command counts down); False counts by the way the wheel
            really turns.
    """

    name: str = "custom"
    left_gain: float = 1.0
    right_gain: float = 1.0
    friction_coefficient: Optional[float] = None
    encoder_jitter_s: float = 0.0
    breakaway_pwm: Optional[int] = None
    speed_curve: Optional[Tuple[Tuple[float, float], ...]] = None
    right_speed_curve: Optional[Tuple[Tuple[float, float], ...]] = None
    wheel_radius_scale: float = 1.0
    baseline_scale: float = 1.0
    encoder_counts_by_command: bool = False

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
        for field in ("wheel_radius_scale", "baseline_scale"):
            value = getattr(self, field)
            if not (_is_number(value) and 0.5 <= value <= 2.0):
                raise ConfigError(
                    f"NoiseProfile.{field} must be a number between 0.5 and 2, not {value!r}."
                )
        if not isinstance(self.encoder_counts_by_command, bool):
            raise ConfigError(
                "NoiseProfile.encoder_counts_by_command must be True or False, "
                f"not {self.encoder_counts_by_command!r}."
            )
        for field in ("speed_curve", "right_speed_curve"):
            if getattr(self, field) is not None:
                object.__setattr__(self, field, _check_curve(getattr(self, field), field))

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
            encoder_counts_by_command=True,
        )
        return profile.replace(**changes)

    def to_dict(self) -> Dict[str, Any]:
        """The parameters that differ from the ideal profile's, and the name, for JSON."""
        ideal = NoiseProfile()
        data: Dict[str, Any] = {"name": self.name}
        for item in dataclasses.fields(self):
            value = getattr(self, item.name)
            if item.name != "name" and value != getattr(ideal, item.name):
                curve = item.name.endswith("speed_curve")
                data[item.name] = [list(knot) for knot in value] if curve else value
        return data

    def save(self, path: Union[str, os.PathLike]) -> Path:
        """Write the profile to a JSON file (a reader never sees half of it); return its path."""
        target = Path(path)
        partial = target.with_name(target.name + ".partial")
        partial.write_text(json.dumps(self.to_dict(), indent=2) + "\n", encoding="utf-8")
        partial.replace(target)
        return target

    @classmethod
    def load(cls, path: Union[str, os.PathLike]) -> NoiseProfile:
        """The profile a JSON file holds (see :meth:`save`).

        Raises:
            ConfigError: if the file is missing, is not JSON, or holds an impossible profile.
        """
        target = Path(path)
        try:
            data = json.loads(target.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise ConfigError(f"There is no noise profile file {target}.") from None
        except (OSError, UnicodeDecodeError, ValueError) as error:
            raise ConfigError(f"The noise profile file {target} is not JSON: {error}") from None
        if not isinstance(data, dict):
            raise ConfigError(
                f"The noise profile file {target} must hold a JSON object of parameters."
            )
        data.setdefault("name", target.stem)
        try:
            return cls().replace(**data)
        except ConfigError as error:
            raise ConfigError(f"In {target}: {error}") from None

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


def _check_curve(curve: object, field: str) -> Tuple[Tuple[float, float], ...]:
    """The speed curve as a tuple of float pairs, or a ConfigError saying what is wrong."""
    try:
        knots = tuple((float(duty), float(speed)) for duty, speed in curve)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        knots = ()
    duties = [duty for duty, _ in knots]
    fine = (
        bool(knots)
        and all(math.isfinite(duty) and math.isfinite(speed) for duty, speed in knots)
        and all(0 < duty <= 1 for duty in duties)
        and all(speed >= 0 for _, speed in knots)
        and all(a < b for a, b in zip(duties, duties[1:]))
        and any(speed > 0 for _, speed in knots)
    )
    if not fine:
        raise ConfigError(
            f"NoiseProfile.{field} must be knots ((duty, rad/s), ...) with rising duties in "
            f"(0, 1], speeds >= 0 and one above 0, not {curve!r}."
        )
    return knots


def noise_profile(profile: Union[str, os.PathLike, NoiseProfile]) -> NoiseProfile:
    """The profile itself, the named one (``"ideal"`` or ``"realistic"``), or a profile file.

    A profile file is JSON, as :meth:`NoiseProfile.save` writes it (and ``duckie calibrate``):
    an object of the parameters that differ from the ideal profile's.

    Raises:
        ConfigError: if the name is not one of the named profiles nor a readable profile file.
    """
    if isinstance(profile, NoiseProfile):
        return profile
    if profile == "ideal":
        return NoiseProfile.ideal()
    if profile == "realistic":
        return NoiseProfile.realistic()
    path = Path(profile)
    if path.suffix == ".json" or path.is_file():
        return NoiseProfile.load(path)
    raise ConfigError(
        f"There is no noise profile called {str(profile)!r}; use 'ideal', 'realistic', a profile "
        "file (robot.json) or a NoiseProfile."
    )


def _is_number(value: object) -> bool:
    return (
        isinstance(value, (int, float))
        and not isinstance(value, bool)
        and math.isfinite(float(value))
    )
