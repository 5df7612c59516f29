"""Encoders: 135 ticks per revolution, cumulative int32 counts, 30 Hz per wheel, sign rule."""

from __future__ import annotations

import math

import numpy as np
import pytest

from duckielib.config import DB21
from duckielib.errors import ConfigError
from duckielib.sim import EncoderReading, NoiseProfile, Simulator, World
from duckielib.sim.encoders import to_int32

BIG = World(tiles_x=8, tiles_y=8)
METRES_PER_TICK = 2 * math.pi * DB21.radius / DB21.resolution


def readings_of(readings, wheel):
    return [reading for reading in readings if reading.wheel == wheel]


def test_distance_from_ticks_matches_truth_within_one_tick():
    sim = Simulator(seed=5, world=BIG, start_pose=(0.5, 2.3, 0.0))
    start_ticks = sim.encoder_ticks
    sim.set_wheel_duties(0.7, 0.7)
    sim.run_until(3.0)
    sim.set_wheel_duties(0.0, 0.0)
    sim.run_until(4.0)
    left, right = (now - then for now, then in zip(sim.encoder_ticks, start_ticks))
    from_ticks = (left + right) / 2 * METRES_PER_TICK
    true_distance = sim.pose.x - 0.5
    assert true_distance > 1.5
    assert abs(from_ticks - true_distance) <= METRES_PER_TICK


def test_turn_from_ticks_matches_truth_within_one_tick_per_wheel():
    sim = Simulator(seed=5, world=BIG, start_pose=(2.0, 2.0, 0.0))
    start_ticks = sim.encoder_ticks
    sim.set_wheel_duties(-0.3, 0.3)
    sim.run_until(0.5)
    sim.set_wheel_duties(0.0, 0.0)  # coasting still turns it a little further
    sim.run_until(1.0)
    left, right = (now - then for now, then in zip(sim.encoder_ticks, start_ticks))
    # The left wheel coasts backwards under the zero command and counts up meanwhile, so
    # here only the right wheel's count tells the true rotation.
    from_right = right * METRES_PER_TICK / (DB21.baseline / 2)
    assert left < 0 < right
    assert from_right == pytest.approx(sim.pose.theta, abs=2 * METRES_PER_TICK / 0.05)


def test_each_wheel_publishes_at_30_hz_unsynchronised():
    sim = Simulator(seed=5)
    sim.set_wheel_duties(0.3, 0.3)
    sim.run_until(10.0)
    readings = sim.pop_encoder_readings()
    times = [reading.time for reading in readings]
    assert times == sorted(times)
    left = np.array([r.time for r in readings_of(readings, "left")])
    right = np.array([r.time for r in readings_of(readings, "right")])
    assert abs(len(left) - 300) <= 1
    assert abs(len(right) - 300) <= 1
    assert np.allclose(np.diff(left), 1 / 30)
    assert np.allclose(np.diff(right), 1 / 30)
    assert not np.isclose(left[0], right[0])
    assert all(0 < t <= 10.0 for t in times)
    assert sim.pop_encoder_readings() == []


def test_readings_carry_the_count_at_their_own_time():
    sim = Simulator(seed=5, world=BIG, start_pose=(0.5, 2.3, 0.0))
    sim.set_wheel_duties(1.0, 1.0)
    sim.run_until(2.0)
    readings = readings_of(sim.pop_encoder_readings(), "left")
    ticks = np.array([r.ticks for r in readings])
    times = np.array([r.time for r in readings])
    late = times > 0.5  # full speed: 27 rad/s * 135 / (2 pi) = 580 ticks/s
    rates = np.diff(ticks[late]) / np.diff(times[late])
    assert rates == pytest.approx(27.0 * 135 / (2 * math.pi), rel=0.05)
    assert all(isinstance(r, EncoderReading) and isinstance(r.ticks, int) for r in readings)


def test_realistic_jitter_statistics():
    jitter = 0.002
    sim = Simulator(seed=5, noise=NoiseProfile.realistic(encoder_jitter_s=jitter))
    sim.run_until(60.0)
    readings = sim.pop_encoder_readings()
    for wheel in ("left", "right"):
        times = np.array([r.time for r in readings_of(readings, wheel)])
        intervals = np.diff(times)
        assert intervals.mean() == pytest.approx(1 / 30, abs=1e-4)
        # Independent errors on each sample: intervals spread by sqrt(2) times the jitter.
        assert intervals.std() == pytest.approx(math.sqrt(2) * jitter, rel=0.15)
        # No drift: every sample stays near its nominal time.
        nominal = times[0] + np.arange(len(times)) / 30
        assert np.abs(times - nominal).max() < 1 / 90 + 1e-9


def test_counts_start_at_a_configurable_non_zero_value():
    default = Simulator(seed=5)
    assert all(abs(ticks) >= 10_000 for ticks in default.encoder_ticks)
    assert Simulator(seed=6).encoder_ticks != default.encoder_ticks
    chosen = Simulator(seed=5, initial_ticks=(12, -7))
    assert chosen.encoder_ticks == (12, -7)
    chosen.run_until(0.5)
    assert {r.ticks for r in chosen.pop_encoder_readings()} == {12, -7}
    with pytest.raises(ConfigError):
        Simulator(initial_ticks=(1.5, 2))


def test_driving_backwards_counts_down_and_goes_negative():
    sim = Simulator(seed=5, initial_ticks=(20, 20), world=BIG, start_pose=(2.0, 2.0, 0.0))
    sim.set_wheel_duties(-0.5, -0.5)
    sim.run_until(2.0)
    readings = sim.pop_encoder_readings()
    for wheel in ("left", "right"):
        ticks = [r.ticks for r in readings_of(readings, wheel)]
        assert len(ticks) >= 59
        assert all(later <= earlier for earlier, later in zip(ticks, ticks[1:]))
    assert all(ticks < -500 for ticks in sim.encoder_ticks)
    assert sim.pose.x < 1.3


#: The real encoder driver's counting rule, on otherwise ideal wheels.
BY_COMMAND = NoiseProfile.ideal(encoder_counts_by_command=True)


def test_coasting_after_a_reverse_command_counts_by_the_last_commands_sign():
    """The driver counts up for a command >= 0, whatever way the wheel really turns."""
    sim = Simulator(seed=5, world=BIG, start_pose=(2.0, 2.0, 0.0), noise=BY_COMMAND)
    sim.set_wheel_duties(-0.8, -0.8)
    sim.run_until(1.0)
    before = sim.encoder_ticks
    sim.set_wheel_duties(0.0, 0.0)
    sim.step(0.03)
    assert all(speed < -5.0 for speed in sim.wheel_speeds)  # still turning backwards
    sim.run_until(1.5)
    assert all(speed > -0.01 for speed in sim.wheel_speeds)
    coasted = [now - then for now, then in zip(sim.encoder_ticks, before)]
    assert all(ticks > 5 for ticks in coasted)  # counted up while rolling backwards


def test_a_reverse_command_counts_down_while_the_wheel_still_turns_forward():
    sim = Simulator(seed=5, world=BIG, start_pose=(2.0, 2.0, 0.0), noise=BY_COMMAND)
    sim.set_wheel_duties(0.8, 0.8)
    sim.run_until(1.0)
    before = sim.encoder_ticks
    sim.set_wheel_duties(-0.1, -0.1)
    sim.step(0.03)
    assert all(speed > 5.0 for speed in sim.wheel_speeds)  # still turning forwards
    assert all(now < then for now, then in zip(sim.encoder_ticks, before))


def test_the_realistic_profile_keeps_the_drivers_rule_and_the_ideal_one_counts_true_turns():
    assert NoiseProfile.realistic().encoder_counts_by_command
    ideal = Simulator(seed=5, world=BIG, start_pose=(2.0, 2.0, 0.0), noise="ideal")
    ideal.set_wheel_duties(0.8, 0.8)
    ideal.run_until(1.0)
    before = ideal.encoder_ticks
    angle_before = ideal.left_encoder.angle
    ideal.set_wheel_duties(-0.1, -0.1)  # the wheels coast forward, then turn back
    ideal.run_until(1.5)
    turned = (ideal.left_encoder.angle - angle_before) * DB21.resolution / math.tau
    counted = ideal.encoder_ticks[0] - before[0]
    assert turned > 5  # forward on balance
    assert abs(counted - turned) <= 1  # the count follows the wheel, up to one slot


def test_counts_wrap_as_int32():
    assert to_int32(2**31 - 1) == 2**31 - 1
    assert to_int32(2**31) == -(2**31)
    assert to_int32(-(2**31) - 1) == 2**31 - 1
    sim = Simulator(seed=5, initial_ticks=(2**31 - 10, 0), world=BIG, start_pose=(0.5, 2, 0))
    sim.set_wheel_duties(0.5, 0.5)
    sim.run_until(1.0)
    assert sim.encoder_ticks[0] < 0
    assert all(-(2**31) <= r.ticks < 2**31 for r in sim.pop_encoder_readings())


def test_next_encoder_time_is_the_next_sample():
    sim = Simulator(seed=5)
    due = sim.next_encoder_time
    assert 0 <= due < 1 / 30
    sim.run_until(due)
    first = sim.pop_encoder_readings()
    assert first
    assert first[0].time == due
