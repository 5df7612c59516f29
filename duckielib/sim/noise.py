"""Noise profiles: how far the virtual Duckiebot is from an ideal unicycle.

A :class:`NoiseProfile` is a frozen set of the imperfections the simulator reproduces. Three
profiles are named:

- :meth:`NoiseProfile.ideal`: equal wheels, tyres that never slip, encoders sampled on a perfectly
  regular schedule that count the way the wheel turns, the wheels and track odometry assumes,
  any PWM out of the driver's dead zone turns a wheel (the driver's linear law, 27 rad/s at duty
  1). Each wheel's ticks match its travel up to quantisation: odometry follows the truth (the two
  wheels are still sampled at different instants, which only hard reversals show).
- :meth:`NoiseProfile.realistic`: the right wheel is 3 % weaker than the left (so trim matters),
  tyres slip when asked for more than the mat's friction gives (hard starts and stops), encoder
  samples come a few milliseconds late or early and count by the encoder driver's rule, and a
  wheel at rest needs a bit more than the driver's smallest PWM to break free.
- :meth:`NoiseProfile.db21`: the realistic robot with motors and wheels as measured on real DB21
  robots: a dead band up to duty 0.12, then about half the speed the driver's linear law
  promises (3.65 rad/s at 0.30, 6.4 at 0.40), wheels 5 % smaller and a track 10 % wider than the
  nominal ones odometry uses (tyres scrub in turns). At the robot's default kinematics gain it
  drives at about 40 % of the commanded speed, and its odometry drifts as a real robot's does.

Every parameter can be set on its own, starting from any of them::

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


#: The db21 profile's steady wheel speed (rad/s) against the duty cycle, fitted to real DB21
#: robots (``duckie sim motors``): a dead band up to 0.12, then 1.8 rad/s at 0.175 (turning in
#: place, 1.6 to 2.0 measured), 3.65 at 0.30 (3.6 to 3.7), 6.4 at 0.40 (6.1 to 6.7), 9.5 at
#: 0.62 and 14 at 1, about half the driver's linear law (27 rad/s at 1).
DB21_SPEED_CURVE = (
    (0.12, 0.0),
    (0.175, 1.8),
    (0.30, 3.65),
    (0.40, 6.4),
    (0.62, 9.5),
    (1.0, 14.0),
)
#: The PWM of duty 0.12 (the dead band's edge): a wheel at rest needs it to start.
DB21_BREAKAWAY_PWM = 83


@dataclass(frozen=True)
class NoiseProfile:
    """The imperfections of one simulated Duckiebot.

    Attributes:
        name: the profile's name, for reports (``"ideal"``, ``"realistic"``, ``"db21"`` or
            ``"custom"``).
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

    @classmethod
    def db21(cls, **changes: object) -> NoiseProfile:
        """The realistic robot, its motors and wheels as measured on DB21s; ``changes`` override."""
        profile = cls.realistic(
            name="db21",
            breakaway_pwm=DB21_BREAKAWAY_PWM,
            speed_curve=DB21_SPEED_CURVE,
            wheel_radius_scale=0.95,
            baseline_scale=1.1,
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
    """The profile itself, the named one (``"ideal"``, ``"realistic"``, ``"db21"``) or a file.

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
    if profile == "db21":
        return NoiseProfile.db21()
    path = Path(profile)
    if path.suffix == ".json" or path.is_file():
        return NoiseProfile.load(path)
    raise ConfigError(
        f"There is no noise profile called {str(profile)!r}; use 'ideal', 'realistic', 'db21', "
        "a profile file (robot.json) or a NoiseProfile."
    )


def _is_number(value: object) -> bool:
    return (
        isinstance(value, (int, float))
        and not isinstance(value, bool)
        and math.isfinite(float(value))
    )
