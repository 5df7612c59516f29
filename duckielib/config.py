"""The Duckiebot's constants: one frozen :class:`RobotConfig` with the DB21's defaults.

Units are SI (metres, seconds, radians) unless a name says otherwise; ``resolution`` is in
encoder ticks per wheel revolution. The values are those of a Duckietown DB21 and of its
drivers (see the course's interface notes). A robot that differs, for example after a
calibration, is a copy with some values changed::

    calibrated = DB21.replace(radius=0.0322, trim=-0.02)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict

from duckielib.errors import ConfigError

__all__ = ["RobotConfig", "DB21", "PROJECT_ROOT", "TILE_SIZE"]

#: The course's repository: the folder that holds ``duckielib/``, ``solutions/``, ``course/``
#: and ``pyproject.toml`` (where the library runs from a checkout).
PROJECT_ROOT = Path(__file__).resolve().parents[1]

#: Side of a Duckietown foam mat tile, in metres.
TILE_SIZE = 0.585


@dataclass(frozen=True)
class RobotConfig:
    """Physical constants and driver settings of a Duckiebot.

    Attributes:
        radius: wheel radius R, in metres.
        baseline: distance between the two wheels' contact points, in metres.
        resolution: encoder ticks per wheel revolution.
        encoder_rate_hz: how often each encoder publishes its count, in Hz.
        k: motor constant, wheel angular speed (rad/s) per unit of duty cycle.
        gain: kinematics gain (scales both wheels).
        trim: kinematics trim; negative trim steers right.
        limit: largest duty cycle magnitude the kinematics node sends, in [0, 1].
        v_max: largest forward speed the kinematics node accepts, in m/s.
        omega_max: largest turning rate the kinematics node accepts, in rad/s.
        duty_dead_zone: duty cycles with a smaller magnitude give PWM 0 in the wheels driver.
        pwm_min: PWM value of the smallest duty cycle above the dead zone (of 255).
        pwm_max: PWM value of duty cycle 1 (of 255).
        chassis_length: length of the chassis along x, in metres.
        chassis_width: width of the chassis along y, in metres.
        mass: mass of the robot, in kilograms.
        tile_size: side of a mat tile, in metres.
    """

    radius: float = 0.0318
    baseline: float = 0.1
    resolution: int = 135
    encoder_rate_hz: float = 30.0
    k: float = 27.0
    gain: float = 1.0
    trim: float = 0.0
    limit: float = 1.0
    v_max: float = 1.0
    omega_max: float = 8.0
    duty_dead_zone: float = 0.01
    pwm_min: int = 60
    pwm_max: int = 255
    chassis_length: float = 0.18
    chassis_width: float = 0.15
    mass: float = 1.2
    tile_size: float = TILE_SIZE

    def __post_init__(self) -> None:
        positive = (
            "radius",
            "baseline",
            "resolution",
            "encoder_rate_hz",
            "k",
            "v_max",
            "omega_max",
            "chassis_length",
            "chassis_width",
            "mass",
            "tile_size",
        )
        for name in positive:
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ConfigError(f"RobotConfig.{name} must be a positive number, not {value!r}.")
        if not 0 < self.limit <= 1:
            raise ConfigError(f"RobotConfig.limit must be in (0, 1], not {self.limit!r}.")
        if not 0 <= self.duty_dead_zone < 1:
            raise ConfigError(
                f"RobotConfig.duty_dead_zone must be in [0, 1), not {self.duty_dead_zone!r}."
            )
        if not 0 <= self.pwm_min < self.pwm_max <= 255:
            raise ConfigError("RobotConfig needs 0 <= pwm_min < pwm_max <= 255.")

    def replace(self, **changes: Any) -> RobotConfig:
        """A copy with some values changed (the original stays as it is).

        Raises:
            ConfigError: if a name is not a setting or a value is impossible.
        """
        unknown = set(changes) - {item.name for item in dataclasses.fields(self)}
        if unknown:
            raise ConfigError(
                f"RobotConfig has no setting {', '.join(sorted(unknown))}; "
                f"its settings are: {', '.join(item.name for item in dataclasses.fields(self))}."
            )
        return dataclasses.replace(self, **changes)

    def kinematics_params(self) -> Dict[str, float]:
        """The parameters of ``/VEH/kinematics_node/``, by their ROS names."""
        names = ("radius", "baseline", "gain", "trim", "k", "limit", "v_max", "omega_max")
        return {name: getattr(self, name) for name in names}


#: The Duckietown DB21's defaults.
DB21 = RobotConfig()
