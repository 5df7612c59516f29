"""Noise profiles: ideal, realistic, and every parameter settable on its own."""

from __future__ import annotations

import json
import math

import pytest

from duckielib.config import DB21
from duckielib.errors import ConfigError
from duckielib.sim import NoiseProfile, Simulator, World, noise_profile


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
        {"wheel_radius_scale": 0.1},
        {"baseline_scale": math.inf},
        {"encoder_counts_by_command": 1},
        {"speed_curve": ((0.3, 3.0), (0.2, 4.0))},
        {"speed_curve": ((0.0, 0.0), (1.0, 10.0))},
        {"speed_curve": ((0.1, -1.0), (1.0, 10.0))},
        {"speed_curve": ((0.1, 0.0),)},
        {"speed_curve": "fast"},
        {"turning_resistance": -0.5},
        {"turning_resistance": math.nan},
        {"turning_scrub": -0.5},
        {"turning_scrub": 1.0},  # as large as its width (1 by default): turns the robot back
        {"scrub_width": 0.0},
    ],
)
def test_impossible_values_are_rejected(changes):
    with pytest.raises(ConfigError):
        NoiseProfile.ideal(**changes)


def test_profiles_by_name():
    assert noise_profile("ideal") == NoiseProfile.ideal()
    assert noise_profile("realistic") == NoiseProfile.realistic()
    assert NoiseProfile.realistic().speed_curve[0] == (0.12, 0.0)  # the measured dead band
    custom = NoiseProfile(right_gain=0.9)
    assert noise_profile(custom) is custom
    assert Simulator(noise="realistic").noise == NoiseProfile.realistic()
    with pytest.raises(ConfigError, match="no noise profile called 'noisy'"):
        noise_profile("noisy")
    with pytest.raises(ConfigError, match="no noise profile called 'db21'"):
        noise_profile("db21")  # the measured robot is the realistic one


def steady(noise, duty, seconds=2.0):
    """The left wheel's speed after ``seconds`` at ``duty`` on both wheels, in rad/s."""
    sim = Simulator(noise=noise, world=BIG_WORLD, start_pose=(2.0, 2.0, 0.0), trace_rate_hz=0)
    sim.set_wheel_duties(duty, duty)
    sim.run_until(seconds)
    return sim.wheel_speeds[0], sim


BIG_WORLD = World(tiles_x=8, tiles_y=8)
CURVE = ((0.1, 0.0), (0.3, 3.6), (0.4, 6.4), (1.0, 15.0))


def test_a_speed_curve_sets_the_dead_band_and_the_steady_speeds():
    curved = NoiseProfile.ideal(speed_curve=CURVE)
    assert steady(curved, 0.08)[0] == 0.0  # in the dead band
    assert steady(curved, 0.3)[0] == pytest.approx(3.6, rel=1e-3)
    assert steady(curved, 0.35)[0] == pytest.approx(5.0, rel=1e-3)  # between two knots
    assert steady(curved, -0.4)[0] == pytest.approx(-6.4, rel=1e-3)
    assert steady(curved, 1.0)[0] == pytest.approx(15.0, rel=1e-3)
    # Without a curve: the driver's linear law, k = 27 rad/s at duty 1.
    assert steady("ideal", 1.0)[0] == pytest.approx(27.0, rel=1e-3)


def test_true_wheels_and_baseline_differ_from_the_nominal_ones():
    small = NoiseProfile.ideal(wheel_radius_scale=0.9)
    speed, sim = steady(small, 0.5)
    assert sim.twist.v == pytest.approx(0.9 * DB21.radius * speed, rel=1e-3)
    wide = NoiseProfile.ideal(baseline_scale=1.2)
    sim = Simulator(noise=wide, world=BIG_WORLD, start_pose=(2.0, 2.0, 0.0), trace_rate_hz=0)
    sim.set_wheel_duties(-0.4, 0.4)
    sim.run_until(1.0)
    left, right = sim.wheel_speeds
    nominal = DB21.radius * (right - left) / DB21.baseline
    assert sim.twist.omega == pytest.approx(nominal / 1.2, rel=1e-3)


def test_a_profile_file_round_trips_and_bad_files_say_why(tmp_path):
    mine = NoiseProfile.realistic(name="ente", speed_curve=CURVE, wheel_radius_scale=0.93)
    path = mine.save(tmp_path / "ente.json")
    assert [p.name for p in tmp_path.iterdir()] == ["ente.json"]
    assert noise_profile(str(path)) == mine
    assert NoiseProfile.load(path) == mine
    assert Simulator(noise=str(path)).noise == mine
    assert json.loads(path.read_text())["wheel_radius_scale"] == 0.93
    with pytest.raises(ConfigError, match="There is no noise profile file"):
        noise_profile(str(tmp_path / "missing.json"))
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(ConfigError, match="is not JSON"):
        noise_profile(str(tmp_path / "bad.json"))
    (tmp_path / "odd.json").write_text('{"left_gain": -1}')
    with pytest.raises(ConfigError, match=r"In .*odd\.json: NoiseProfile\.left_gain must be"):
        noise_profile(str(tmp_path / "odd.json"))
