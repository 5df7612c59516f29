"""Noise profiles: ideal, realistic, and every parameter settable on its own."""

from __future__ import annotations

import math

import pytest

from duckielib.errors import ConfigError
from duckielib.sim import NoiseProfile, Simulator, noise_profile


def test_ideal_has_no_imperfection():
    ideal = NoiseProfile.ideal()
    assert ideal.name == "ideal"
    assert (ideal.left_gain, ideal.right_gain) == (1.0, 1.0)
    assert ideal.friction_coefficient is None
    assert ideal.encoder_jitter_s == 0.0
    assert ideal.breakaway_pwm is None


def test_realistic_has_asymmetry_slip_and_jitter():
    realistic = NoiseProfile.realistic()
    assert realistic.name == "realistic"
    assert realistic.left_gain != realistic.right_gain
    assert realistic.friction_coefficient is not None
    assert realistic.encoder_jitter_s > 0
    assert realistic.breakaway_pwm > 60


def test_every_parameter_can_be_set_on_its_own():
    changed = NoiseProfile.realistic(encoder_jitter_s=0.0)
    assert changed.encoder_jitter_s == 0.0
    assert changed.right_gain == NoiseProfile.realistic().right_gain
    assert changed.name == "custom"
    assert NoiseProfile.ideal().replace(right_gain=0.9).right_gain == 0.9
    assert NoiseProfile.ideal(name="mine", breakaway_pwm=70).name == "mine"
    assert NoiseProfile.ideal().replace() == NoiseProfile.ideal()


def test_unknown_parameter_names_the_known_ones():
    with pytest.raises(ConfigError, match=r"no parameter wheel_gain.*right_gain"):
        NoiseProfile.ideal(wheel_gain=2.0)


@pytest.mark.parametrize(
    "changes",
    [
        {"left_gain": 0.0},
        {"right_gain": math.nan},
        {"friction_coefficient": -0.1},
        {"encoder_jitter_s": -0.001},
        {"breakaway_pwm": 300},
        {"breakaway_pwm": 65.5},
    ],
)
def test_impossible_values_are_rejected(changes):
    with pytest.raises(ConfigError):
        NoiseProfile.ideal(**changes)


def test_profiles_by_name():
    assert noise_profile("ideal") == NoiseProfile.ideal()
    assert noise_profile("realistic") == NoiseProfile.realistic()
    custom = NoiseProfile(right_gain=0.9)
    assert noise_profile(custom) is custom
    assert Simulator(noise="realistic").noise == NoiseProfile.realistic()
    with pytest.raises(ConfigError, match="no noise profile called 'noisy'"):
        noise_profile("noisy")
