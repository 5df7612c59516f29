"""The DB21's constants and their checks."""

from __future__ import annotations

import dataclasses

import pytest

from duckielib import DB21, TILE_SIZE, RobotConfig
from duckielib.errors import ConfigError


def test_db21_defaults_match_the_robot():
    assert DB21.radius == 0.0318
    assert DB21.baseline == 0.1
    assert DB21.resolution == 135
    assert DB21.encoder_rate_hz == 30.0
    assert DB21.k == 27.0
    assert (DB21.gain, DB21.trim, DB21.limit) == (1.0, 0.0, 1.0)
    assert (DB21.v_max, DB21.omega_max) == (1.0, 8.0)
    assert (DB21.chassis_length, DB21.chassis_width) == (0.18, 0.15)
    assert (DB21.duty_dead_zone, DB21.pwm_min, DB21.pwm_max) == (0.01, 60, 255)
    assert DB21.tile_size == TILE_SIZE == 0.585


def test_config_is_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        DB21.radius = 0.05  # type: ignore[misc]


def test_replace_makes_a_changed_copy():
    calibrated = DB21.replace(radius=0.0322, trim=-0.02)
    assert calibrated.radius == 0.0322
    assert calibrated.trim == -0.02
    assert DB21.radius == 0.0318
    with pytest.raises(ConfigError, match="has no setting wheel_radius; its settings are: radius"):
        DB21.replace(wheel_radius=0.03)


@pytest.mark.parametrize(
    ("changes", "expected"),
    [
        ({"radius": 0.0}, "radius must be a positive number, not 0.0"),
        ({"baseline": -0.1}, "baseline must be a positive number"),
        ({"k": float("nan")}, "k must be a positive number"),
        ({"limit": 1.5}, r"limit must be in \(0, 1\]"),
        ({"duty_dead_zone": 1.0}, r"duty_dead_zone must be in \[0, 1\)"),
        ({"pwm_min": 255}, "pwm_min < pwm_max"),
    ],
)
def test_impossible_values_are_refused(changes, expected):
    with pytest.raises(ConfigError, match=expected):
        RobotConfig(**changes)


def test_kinematics_params_use_the_ros_parameter_names():
    assert DB21.kinematics_params() == {
        "radius": 0.0318,
        "baseline": 0.1,
        "gain": 1.0,
        "trim": 0.0,
        "k": 27.0,
        "limit": 1.0,
        "v_max": 1.0,
        "omega_max": 8.0,
    }
