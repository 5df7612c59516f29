"""Physics a student can check by hand: straight lines, turning in place, arcs, dead zone."""

from __future__ import annotations

import math

import numpy as np
import pytest

from duckielib.config import DB21
from duckielib.errors import ConfigError, SimulationError
from duckielib.sim import NoiseProfile, Simulator, World, pwm_from_duty
from duckielib.sim.robot import MOTOR_TIME_CONSTANT_S, loaded_speeds
from duckielib.sim.wheels import _loaded

BIG = World(tiles_x=8, tiles_y=8)


def fit_circle(xs, ys):
    """Centre and radius of the least-squares circle through the points."""
    a = np.column_stack((2 * xs, 2 * ys, np.ones_like(xs)))
    cx, cy, c = np.linalg.lstsq(a, xs**2 + ys**2, rcond=None)[0]
    return cx, cy, math.sqrt(c + cx**2 + cy**2)


@pytest.mark.parametrize("heading", [0.0, 1.0, math.pi, 5.5])
def test_equal_duties_drive_straight(heading):
    start = (2.3, 2.3)
    sim = Simulator(seed=3, world=BIG, start_pose=(*start, heading))
    sim.set_wheel_duties(0.6, 0.6)
    sim.run_until(4.0)  # about 2 m
    x, y, theta = sim.pose
    along = (x - start[0]) * math.cos(heading) + (y - start[1]) * math.sin(heading)
    lateral = -(x - start[0]) * math.sin(heading) + (y - start[1]) * math.cos(heading)
    assert along > 1.9
    assert abs(lateral) < 0.001
    assert abs(math.remainder(theta - heading, math.tau)) < 1e-6


def test_opposite_duties_rotate_in_place():
    sim = Simulator(seed=3, world=BIG, start_pose=(2.0, 2.0, 0.3))
    sim.set_wheel_duties(-0.5, 0.5)
    turned = 0.0
    previous = sim.pose.theta
    for _ in range(500):
        sim.step()
        turned += math.remainder(sim.pose.theta - previous, math.tau)
        previous = sim.pose.theta
    x, y, _ = sim.pose
    assert math.hypot(x - 2.0, y - 2.0) < 0.001
    # omega = 2 * R * k * u / baseline = 8.59 rad/s once the motors have caught up.
    assert turned == pytest.approx(8.586 * 5.0, rel=0.02)


@pytest.mark.parametrize(("left", "right"), [(0.4, 0.6), (0.2, 0.8), (0.7, 0.5)])
def test_arc_radius_matches_kinematics(left, right):
    sim = Simulator(seed=3, world=BIG, start_pose=(2.3, 2.3, 0.0))
    sim.set_wheel_duties(left, right)
    sim.run_until(1.0)
    xs, ys = [], []
    for _ in range(300):
        sim.step()
        xs.append(sim.pose.x)
        ys.append(sim.pose.y)
    _, _, radius = fit_circle(np.array(xs), np.array(ys))
    predicted = DB21.baseline / 2 * (left + right) / abs(right - left)
    assert radius == pytest.approx(predicted, rel=0.02)
    assert abs(sim.twist.v_lateral) < 1e-6


def test_full_duty_speed_is_k_times_radius():
    sim = Simulator(seed=3, world=BIG, start_pose=(0.5, 2.3, 0.0))
    sim.set_wheel_duties(1.0, 1.0)
    sim.run_until(1.0)
    assert sim.wheel_speeds == pytest.approx((27.0, 27.0), rel=1e-6)
    assert sim.twist.v == pytest.approx(27.0 * 0.0318, rel=1e-6)


def test_motor_has_a_first_order_response():
    sim = Simulator(seed=3, world=BIG, start_pose=(0.5, 2.3, 0.0), physics_rate_hz=200)
    sim.set_wheel_duties(1.0, 1.0)
    sim.run_until(MOTOR_TIME_CONSTANT_S)
    assert sim.wheel_speeds[0] == pytest.approx(27.0 * (1 - math.exp(-1)), rel=0.03)
    sim.run_until(5 * MOTOR_TIME_CONSTANT_S)
    assert sim.wheel_speeds[0] == pytest.approx(27.0 * (1 - math.exp(-5)), rel=0.03)


@pytest.mark.parametrize(
    ("duty", "pwm"),
    [(0.0, 0), (0.009, 0), (-0.0099, 0), (0.01, 61), (0.5, 157), (-0.5, 157), (1.0, 255), (4, 255)],
)
def test_pwm_follows_the_wheels_driver(duty, pwm):
    assert pwm_from_duty(duty, DB21) == pwm


def test_dead_zone_holds_the_robot_still():
    sim = Simulator(seed=3)
    start_pose, start_ticks = sim.pose, sim.encoder_ticks
    sim.set_wheel_duties(0.009, -0.009)
    sim.run_until(3.0)
    assert sim.pose == start_pose
    assert sim.encoder_ticks == start_ticks
    assert sim.wheel_speeds == (0.0, 0.0)


def test_small_duty_does_not_overcome_static_friction():
    sim = Simulator(seed=3, noise="realistic")
    start = sim.pose
    sim.set_wheel_duties(0.08, 0.08)  # PWM 75, below the realistic breakaway PWM 83
    sim.run_until(2.0)
    assert sim.pose == start
    sim.set_wheel_duties(0.2, 0.2)  # PWM 99
    sim.run_until(4.0)
    assert sim.pose.y - start.y > 0.1


def test_duties_beyond_one_are_clipped():
    clipped = Simulator(seed=3)
    assert clipped.set_wheel_duties(3.0, -7.5) == (1.0, -1.0)
    assert clipped.wheel_duties == (1.0, -1.0)
    reference = Simulator(seed=3)
    reference.set_wheel_duties(1.0, -1.0)
    clipped.run_until(1.0)
    reference.run_until(1.0)
    assert clipped.pose == reference.pose


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, "fast", None])
def test_bad_duties_are_rejected_and_the_last_command_kept(bad):
    sim = Simulator(seed=3)
    sim.set_wheel_duties(0.3, 0.3)
    with pytest.raises(SimulationError, match="duty cycle"):
        sim.set_wheel_duties(bad, 0.2)
    with pytest.raises(SimulationError, match="right wheel"):
        sim.set_wheel_duties(0.2, bad)
    assert sim.wheel_duties == (0.3, 0.3)


def test_realistic_tyres_slip_at_high_acceleration_only():
    def largest_slip(noise, duty, then):
        """The largest difference between rim and axle speed once ``duty`` turns to ``then``."""
        sim = Simulator(seed=3, noise=noise, world=BIG, start_pose=(0.5, 2.3, 0.0))
        radius = DB21.radius * sim.noise.wheel_radius_scale
        sim.set_wheel_duties(duty, duty)
        sim.run_until(1.0)
        sim.set_wheel_duties(then, then)
        slip = 0.0
        for _ in range(40):
            sim.step()
            slip = max(slip, abs(radius * sim.wheel_speeds[0] - sim.twist.v))
        return slip

    equal_wheels = NoiseProfile.realistic(right_gain=1.0)
    assert largest_slip(equal_wheels, 1.0, -1.0) > 0.05  # full speed reversed at once
    assert largest_slip(equal_wheels, 0.3, 0.0) < 1e-6  # a gentle stop
    assert largest_slip("ideal", 1.0, -1.0) < 1e-6


def test_unequal_wheels_veer_towards_the_weaker_one():
    def turned(noise, right=0.5):
        sim = Simulator(seed=3, noise=noise, world=BIG, start_pose=(0.5, 2.3, 0.0))
        sim.set_wheel_duties(0.5, right)
        sim.run_until(4.0)
        return math.remainder(sim.pose.theta, math.tau)

    # Turned clockwise (the right wheel is weaker), but the tyres' scrub lets only 9 % of the
    # motors' difference through: a tenth of what the motors alone would turn it.
    veer = turned("realistic")
    alone = turned(NoiseProfile.realistic(turning_scrub=0.0))
    assert -0.05 < veer < -0.01
    assert 0.05 < veer / alone < 0.15
    assert abs(turned("realistic", right=0.5 / 0.97)) < 0.005  # trimmed: a fifth of it


def test_theta_stays_in_zero_to_two_pi():
    sim = Simulator(seed=3, world=BIG, start_pose=(2.0, 2.0, 0.05))
    sim.set_wheel_duties(0.3, -0.3)
    for _ in range(200):
        sim.step()
        assert 0.0 <= sim.pose.theta < 2 * math.pi


@pytest.mark.parametrize(
    ("angle", "theta"),
    [(-1e-17, 0.0), (-0.5, math.tau - 0.5), (2 * math.tau + 1.0, 1.0), (math.tau, 0.0)],
)
def test_the_true_heading_is_the_bodys_angle_in_zero_to_two_pi(angle, theta):
    # pymunk counts whole turns in the body's angle; the ground truth reports the heading.
    sim = Simulator(seed=3, world=BIG, start_pose=(2.0, 2.0, 0.0))
    sim.robot.body.angle = angle
    sim.run_until(0.1)  # at rest: the angle stays, and the trace records a pose
    assert sim.pose.theta == pytest.approx(theta, abs=1e-12)
    assert 0.0 <= sim.pose.theta < math.tau
    assert sim.trace.thetas[-1] == sim.pose.theta


def test_walls_stop_the_robot():
    sim = Simulator(seed=3)
    sim.set_wheel_duties(1.0, 1.0)
    sim.run_until(4.0)
    front = sim.pose.y + 0.4 * DB21.chassis_length
    assert front == pytest.approx(sim.world.height, abs=0.002)
    assert abs(sim.twist.v) < 1e-3


def test_without_walls_the_robot_drives_off_the_mat():
    sim = Simulator(seed=3, world=World(walls=False))
    sim.set_wheel_duties(1.0, 1.0)
    sim.run_until(4.0)
    assert sim.pose.y > sim.world.height + 0.5


def test_start_pose_must_be_on_the_mat():
    with pytest.raises(ConfigError, match="off the mat"):
        Simulator(start_pose=(5.0, 0.3, 0.0))
    with pytest.raises(ConfigError, match="finite"):
        Simulator(start_pose=(math.nan, 0.3, 0.0))


def test_clock_advances_in_physics_steps():
    sim = Simulator(physics_rate_hz=200)
    assert sim.time == 0.0
    sim.step()
    assert sim.time == 0.005
    sim.step(0.1)
    assert sim.steps == 21
    sim.run_until(1.0)
    assert sim.steps == 200
    sim.run_until(0.5)
    assert sim.steps == 200
    with pytest.raises(SimulationError):
        sim.run_until(math.nan)
    with pytest.raises(SimulationError):
        sim.step(-1.0)


def test_motor_time_constant_is_settable():
    instant = Simulator(seed=3, motor_time_constant_s=0.0)
    instant.set_wheel_duties(1.0, 1.0)
    instant.step()
    assert instant.wheel_speeds == (27.0, 27.0)
    with pytest.raises(ConfigError, match="motor_time_constant_s"):
        Simulator(motor_time_constant_s=-0.1)


def test_the_tyres_scrub_takes_most_of_a_small_difference_and_a_set_amount_of_a_large_one():
    scrub, width = 6.45, 7.12
    # Rolling at 5 rad/s: a difference of 0.2 rad/s keeps 1 - scrub / width of itself (9 %).
    left, right = loaded_speeds(4.9, 5.1, 0.0, scrub, width)
    assert left + right == pytest.approx(10.0)
    assert (right - left) / 0.2 == pytest.approx(1 - scrub / width, rel=0.01)
    # A large difference (the arc 2 / 10 rad/s) keeps more of itself: about 19 %.
    left, right = loaded_speeds(2.0, 10.0, 0.0, scrub, width)
    assert 0.5 * (right - left) == pytest.approx(4.0 - scrub * math.tanh(4.0 / width))
    assert 0.15 < (right - left) / 8.0 < 0.25
    # Turning on the spot is not slowed; a pivot on one wheel rolls as much as it spins.
    assert loaded_speeds(-3.0, 3.0, 0.0, scrub, width) == (-3.0, 3.0)
    left, right = loaded_speeds(0.0, 4.0, 0.0, scrub, width)
    assert right - left == pytest.approx(4.0 - 2 * scrub * math.tanh(2.0 / width))
    # Never turned the other way, and the motors' speeds alone without a scrub.
    for difference in np.linspace(-12.0, 12.0, 49):
        left, right = loaded_speeds(6.0 - difference / 2, 6.0 + difference / 2, 0.0, scrub, width)
        assert (right - left) * difference >= 0
    assert loaded_speeds(2.0, 10.0, 0.0) == (2.0, 10.0)


def test_the_wheels_arrays_scrub_as_the_simulators_wheels_do():
    rng = np.random.default_rng(5)
    left, right = rng.uniform(-12, 12, 500), rng.uniform(-12, 12, 500)
    left[:50] = -right[:50]  # on the spot
    left[50:60] = right[50:60]  # straight
    arrays = _loaded(left, right, (0.4, 6.45, 7.12))
    for k in range(500):
        expected = loaded_speeds(left[k], right[k], 0.4, 6.45, 7.12)
        assert (arrays[0][k], arrays[1][k]) == pytest.approx(expected, abs=1e-12)
