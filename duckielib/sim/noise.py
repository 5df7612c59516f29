"""Noise profiles: how far the virtual Duckiebot is from an ideal unicycle.

A :class:`NoiseProfile` is a frozen set of the imperfections the simulator reproduces. Two
profiles are named:

- :meth:`NoiseProfile.ideal`: equal wheels, tyres that never slip, encoders sampled on a perfectly
  regular schedule that count the way the wheel turns, the wheels and track odometry assumes,
  any PWM out of the driver's dead zone turns a wheel (the driver's linear law, 27 rad/s at duty
  1). Each wheel's ticks match its travel up to quantisation: odometry follows the truth (the two
  wheels are still sampled at different instants, which only hard reversals show).
- :meth:`NoiseProfile.realistic`: a robot like the real DB21s measured on the course's exercise
  (public bags of wheel commands and encoder ticks). Its wheels turn at these speeds (rad/s,
  real robots in brackets): 1.7 turning in place at duty 0.175 (1.6 to 2.0), 3.6 at 0.30 (3.6
  to 3.7), 6.3 at 0.40 (6.1 to 6.7), and on an arc of 0.62 and 0.18, 6.7 outer and 5.2 inner
  (6.7 to 7.3 and 5.0 to 5.4). That is a dead band up to duty 0.12, then about half the speed
  the driver's linear law promises: at the default kinematics gain the robot drives at about
  half the commanded speed. While it rolls, its tyres scrub: the ground lets through only 9 %
  of a small difference of the two motors' speeds and about 19 % of the arc's, dragging the
  slow wheel along, as a real robot's wheels answered different commands (a robot turning on
  the spot is not slowed). The right motor is 3 % weaker than the left (so trim matters); the
  wheels are 5 % smaller and the track 10 % wider than the nominal ones odometry uses, so
  odometry drifts as a real robot's does; tyres slip when asked for more than the mat's
  friction gives; encoder samples come a few milliseconds late or early and count by the
  encoder driver's rule (the sign of the last command); a wheel at rest needs the dead band's
  edge to break free.

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


#: The realistic motors' speed (rad/s) against the duty cycle: a dead band up to 0.12, then
#: about half the driver's linear law (27 rad/s at 1). On a straight line or turning in place
#: the wheels turn at these speeds; on an arc the tyres' scrub (:data:`REALISTIC_TURNING_SCRUB`)
#: drags the slow wheel along (``duckie sim motors`` sets them next to real DB21 robots').
REALISTIC_SPEED_CURVE = (
    (0.12, 0.0),
    (0.175, 1.8),
    (0.30, 3.65),
    (0.40, 6.4),
    (0.62, 10.4),
    (1.0, 14.9),
)
#: How the ground resists the realistic robot's turns while it rolls (see NoiseProfile): the
#: tyres' scrub and its width, rad/s of half the wheels' speed difference, and no further
#: resistance growing with the speed. Fitted to how a real DB21's wheels answered different
#: commands, half a second at a time, over 26 closed-loop runs (README, "On real robots"): a
#: small difference keeps 9 % of itself, the arc 0.18 / 0.62 about 19 %.
REALISTIC_TURNING_SCRUB = 6.45
REALISTIC_SCRUB_WIDTH = 7.12
REALISTIC_TURNING_RESISTANCE = 0.0
#: The realistic robot's calibrated kinematics gain: with it the robot drives within about
#: 20 % of the speed asked from 0.1 to 0.3 m/s (at the default 1.0, at about 40 %).
REALISTIC_KINEMATICS_GAIN = 2.0
#: The PWM of duty 0.12 (the dead band's edge): a wheel at rest needs it to start.
REALISTIC_BREAKAWAY_PWM = 83


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
        turning_resistance: how much the ground resists turning while the robot rolls, in
            s/rad: half the difference of the speeds the motors alone would give is divided by
            1 + turning_resistance * the wheels' mean speed (rad/s). On an arc the slow wheel
            is dragged along by the fast one; turning in place is not slowed.
        turning_scrub: the most the tyres' scrub takes off half the wheels' speed difference
            while the robot rolls, in rad/s: ``turning_scrub * tanh(d / scrub_width)`` off half
            the difference d of the speeds the motors alone would give, before
            ``turning_resistance`` divides what is left. A small difference keeps
            ``1 - turning_scrub / scrub_width`` of itself, a large one loses ``turning_scrub``.
            In full while the robot rolls more than it spins, nothing when turning in place.
        scrub_width: the half difference (rad/s) over which the scrub grows to its most; larger
            than ``turning_scrub``, so the ground never turns the robot the other way.
        kinematics_gain: the kinematics gain in the robot's calibration file, which its
            kinematics node starts with (``kinematics_node/gain``): a DB21's owner raises it
            from the default 1.0 until the robot drives at about the speed asked.
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
    turning_resistance: float = 0.0
    turning_scrub: float = 0.0
    scrub_width: float = 1.0
    kinematics_gain: float = 1.0

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
        gain = self.kinematics_gain
        if not (_is_number(gain) and 0.1 <= gain <= 10):
            raise ConfigError(
                f"NoiseProfile.kinematics_gain must be a number between 0.1 and 10, not {gain!r}."
            )
        self._check_ground()
        if not isinstance(self.encoder_counts_by_command, bool):
            raise ConfigError(
                "NoiseProfile.encoder_counts_by_command must be True or False, "
                f"not {self.encoder_counts_by_command!r}."
            )
        for field in ("speed_curve", "right_speed_curve"):
            if getattr(self, field) is not None:
                object.__setattr__(self, field, _check_curve(getattr(self, field), field))

    def _check_ground(self) -> None:
        """Raise a ConfigError if the ground's resistance or the tyres' scrub is impossible."""
        value = self.turning_resistance
        if not (_is_number(value) and 0 <= value <= 20):
            raise ConfigError(
                f"NoiseProfile.turning_resistance must be a number between 0 and 20, not {value!r}."
            )
        width = self.scrub_width
        if not (_is_number(width) and 0 < width <= 50):
            raise ConfigError(
                f"NoiseProfile.scrub_width must be a number of rad/s in (0, 50], not {width!r}."
            )
        value = self.turning_scrub
        if not (_is_number(value) and 0 <= value < width):
            raise ConfigError(
                "NoiseProfile.turning_scrub must be a number of rad/s from 0 to less than "
                f"scrub_width ({width!r}), not {value!r}."
            )

    @classmethod
    def ideal(cls, **changes: object) -> NoiseProfile:
        """No asymmetry, no slip, no jitter; ``changes`` override single parameters."""
        return cls(name="ideal").replace(**changes)

    @classmethod
    def realistic(cls, **changes: object) -> NoiseProfile:
        """A robot like the real DB21s measured (module doc); ``changes`` override."""
        profile = cls(
            name="realistic",
            left_gain=1.0,
            right_gain=0.97,
            friction_coefficient=0.8,
            encoder_jitter_s=0.002,
            breakaway_pwm=REALISTIC_BREAKAWAY_PWM,
            speed_curve=REALISTIC_SPEED_CURVE,
            wheel_radius_scale=0.95,
            baseline_scale=1.1,
            encoder_counts_by_command=True,
            turning_resistance=REALISTIC_TURNING_RESISTANCE,
            turning_scrub=REALISTIC_TURNING_SCRUB,
            scrub_width=REALISTIC_SCRUB_WIDTH,
            kinematics_gain=REALISTIC_KINEMATICS_GAIN,
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
    """The profile itself, the named one (``"ideal"``, ``"realistic"``) or a file.

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
        f"There is no noise profile called {str(profile)!r}; use 'ideal', 'realistic', "
        "a profile file (robot.json) or a NoiseProfile."
    )


def _is_number(value: object) -> bool:
    return (
        isinstance(value, (int, float))
        and not isinstance(value, bool)
        and math.isfinite(float(value))
    )
