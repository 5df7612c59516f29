"""The simulated Duckiebot's body: chassis, two driven wheels and their duty-cycle motors.

Robot frame: origin at the midpoint of the wheel axle, x forward, y to the left. The chassis
is a rigid box of the DB21's size and mass in the pymunk space, its centre of mass on the
axle. A caster at the rear carries part of the weight and rolls freely.

Motors mirror the wheels driver. A duty cycle u in [-1, 1] becomes a PWM value
(:func:`pwm_from_duty`: 0 in the dead zone, else ``floor(|u| * (pwm_max - pwm_min) + pwm_min)``);
the motor's steady speed is ``k * gain * (pwm - pwm_min) / (pwm_max - pwm_min)`` rad/s, the PWM
offset being what overcomes the gearbox's friction (so duty 1 gives k = 27 rad/s). A wheel at
rest stays at rest below the noise profile's breakaway PWM (static friction). A noise profile
may give a measured speed curve instead of that linear law (``speed_curve``), and a ground that
resists turning while the robot rolls (``turning_scrub``, ``turning_resistance``,
:func:`loaded_speeds`): both wheels' targets then come from both motors. The speed follows its
target with a first-order lag of time constant :data:`MOTOR_TIME_CONSTANT_S`.

Tyres: each wheel is a velocity constraint between the chassis at the wheel's contact point and
a kinematic "ground" body moving at the wheel's rim speed along the heading. Its force is capped
by friction (coefficient times the wheel's share of the weight), so below the cap the wheel
neither slips along nor sideways, and above it (hard acceleration, pushing a wall) it slips.
pymunk moves bodies with the velocities solved in the previous step, so the wheels' common
velocity is aimed along the heading the robot will have half-way through the step in which it
applies.
"""

from __future__ import annotations

import bisect
import functools
import math
from typing import Callable, NamedTuple, Optional, Sequence, Tuple

import pymunk

from duckielib.config import RobotConfig
from duckielib.errors import ConfigError
from duckielib.sim.noise import NoiseProfile

__all__ = [
    "Pose",
    "Twist",
    "Motor",
    "Robot",
    "pwm_from_duty",
    "steady_speed",
    "loaded_speeds",
    "MOTOR_TIME_CONSTANT_S",
    "WHEEL_LOAD_FRACTION",
    "GRAVITY",
]

#: Time constant of a motor's first-order speed response, in seconds.
MOTOR_TIME_CONSTANT_S = 0.06

#: Share of the robot's weight carried by the two driven wheels together (the rest by the caster).
WHEEL_LOAD_FRACTION = 0.8

#: Gravitational acceleration, in m/s^2.
GRAVITY = 9.81

#: Friction coefficient used when the noise profile says tyres never slip: high enough that no
#: motor can reach it, finite so a wall still wins against a wheel.
NO_SLIP_FRICTION = 100.0

#: Distance from the axle to the front of the chassis, as a fraction of the chassis length.
AXLE_TO_FRONT_FRACTION = 0.4

#: Wheel speed below which a wheel counts as at rest (static friction applies), in rad/s.
REST_SPEED = 0.05


def _velocity_setter(body: pymunk.Body) -> Callable[[Tuple[float, float]], None]:
    """A fast function that sets ``body``'s velocity, in m/s.

    The drive sets two velocities per physics step, and pymunk's property setter costs about
    twice Chipmunk's own function, which ``pymunk.cp`` exposes; fall back to the property if
    this pymunk does not expose it.
    """
    chipmunk = getattr(pymunk, "cp", None)
    handle = getattr(body, "_body", None)
    if chipmunk is None or handle is None or not hasattr(chipmunk, "cpBodySetVelocity"):

        def set_velocity(velocity: Tuple[float, float]) -> None:
            body.velocity = velocity

        return set_velocity
    return functools.partial(chipmunk.cpBodySetVelocity, handle)


class Pose(NamedTuple):
    """A planar pose in the world frame: x, y in metres, theta in radians in [0, 2*pi)."""

    x: float
    y: float
    theta: float


class Twist(NamedTuple):
    """A planar velocity in the robot frame.

    Attributes:
        v: forward speed of the axle midpoint, in m/s.
        omega: turning rate, in rad/s, counter-clockwise positive.
        v_lateral: sideways speed of the axle midpoint (to the left), in m/s; 0 unless the
            tyres slip.
    """

    v: float
    omega: float
    v_lateral: float


def pwm_from_duty(duty: float, config: RobotConfig) -> int:
    """The PWM value (0..255) the wheels driver sends to a motor for a duty cycle.

    Args:
        duty: duty cycle, clipped to [-1, 1]; its sign is the direction, not part of the PWM.
        config: the robot (dead zone, pwm_min, pwm_max).
    """
    magnitude = min(abs(duty), 1.0)
    if magnitude < config.duty_dead_zone:
        return 0
    return math.floor(magnitude * (config.pwm_max - config.pwm_min) + config.pwm_min)


def steady_speed(curve: Sequence[Tuple[float, float]], duty: float) -> float:
    """A motor's steady wheel speed (rad/s) for a duty cycle's magnitude, from its speed curve.

    Linear between the curve's knots, 0 below the first (the dead band), flat after the last.
    """
    duties = [knot[0] for knot in curve]
    if duty < duties[0]:
        return 0.0
    index = bisect.bisect_right(duties, duty)
    if index == len(curve):
        return curve[-1][1]
    (d0, s0), (d1, s1) = curve[index - 1], curve[index]
    return s0 + (s1 - s0) * (duty - d0) / (d1 - d0)


def loaded_speeds(
    left: float, right: float, turning: float, scrub: float = 0.0, width: float = 1.0
) -> Tuple[float, float]:
    """The wheels' steady speeds (rad/s) on the ground, from the speeds the motors alone give.

    The ground resists turning while the robot rolls. First the tyres' scrub takes up to
    ``scrub`` rad/s off half the wheels' speed difference d: ``scrub * tanh(d / width)``, so a
    small difference keeps only ``1 - scrub / width`` of itself and a large one loses
    ``scrub``. It acts in full while the robot rolls more than it spins (its mean wheel speed at
    least half the difference), and in proportion below: turning on the spot is not slowed.
    Then what is left is divided by ``1 + turning * |mean speed|``. On an arc the slow wheel is
    dragged along by the fast one.
    """
    mean = 0.5 * (left + right)
    half_difference = 0.5 * (right - left)
    if scrub and mean:
        rolling = min(1.0, abs(mean) / abs(half_difference)) if half_difference else 1.0
        half_difference -= scrub * rolling * math.tanh(half_difference / width)
    half_difference /= 1.0 + turning * abs(mean)
    return mean - half_difference, mean + half_difference


class Motor:
    """One wheel's motor: duty cycle in, wheel angular speed out.

    Attributes:
        duty: the executed duty cycle, clipped to [-1, 1].
        pwm: the PWM value the driver sends (0..255).
        speed: the wheel's angular speed, in rad/s (positive drives the robot forward).
    """

    __slots__ = (
        "_alpha",
        "_breakaway",
        "_curve",
        "_drive",
        "_full_scale",
        "_gain",
        "config",
        "duty",
        "pwm",
        "speed",
    )

    def __init__(
        self,
        config: RobotConfig,
        gain: float,
        breakaway_pwm: int,
        alpha: float,
        curve: Optional[Tuple[Tuple[float, float], ...]] = None,
    ) -> None:
        self.config = config
        self._full_scale = config.k * gain
        self._gain = gain
        self._curve = curve
        self._breakaway = breakaway_pwm
        self._alpha = alpha
        self._drive = 0.0
        self.duty = 0.0
        self.pwm = 0
        self.speed = 0.0

    def command(self, duty: float) -> None:
        """Execute a duty cycle (already checked finite); values beyond [-1, 1] are clipped."""
        duty = max(-1.0, min(1.0, duty))
        config = self.config
        pwm = pwm_from_duty(duty, config)
        self.duty = duty
        self.pwm = pwm
        if pwm == 0:
            self._drive = 0.0
        elif self._curve is not None:
            self._drive = math.copysign(self._gain * steady_speed(self._curve, abs(duty)), duty)
        else:
            fraction = (pwm - config.pwm_min) / (config.pwm_max - config.pwm_min)
            self._drive = math.copysign(self._full_scale * fraction, duty)

    def target(self) -> float:
        """The speed the motor alone drives the wheel towards, in rad/s.

        It is 0 while the wheel rests and the PWM is below the breakaway PWM.
        """
        if self.pwm < self._breakaway and -REST_SPEED < self.speed < REST_SPEED:
            return 0.0
        return self._drive

    def follow(self, target: float) -> float:
        """Advance the speed by one physics step towards ``target`` and return it, in rad/s."""
        self.speed += (target - self.speed) * self._alpha
        return self.speed

    def update(self) -> float:
        """Advance the speed by one physics step towards :meth:`target` and return it."""
        return self.follow(self.target())


class Robot:
    """The Duckiebot's rigid body and drive in a pymunk space.

    Args:
        space: the pymunk space (metres) to add the robot to.
        config: the robot's constants.
        noise: the imperfections to reproduce.
        pose: the starting pose (x, y in metres, theta in radians).
        dt: the physics step, in seconds.
        motor_time_constant_s: time constant of the motors' first-order response, in seconds
            (0 for an instant response).
    """

    def __init__(
        self,
        space: pymunk.Space,
        config: RobotConfig,
        noise: NoiseProfile,
        pose: Tuple[float, float, float],
        dt: float,
        motor_time_constant_s: float = MOTOR_TIME_CONSTANT_S,
    ) -> None:
        if not (math.isfinite(motor_time_constant_s) and motor_time_constant_s >= 0):
            raise ConfigError(
                "motor_time_constant_s must be a number of seconds >= 0, "
                f"not {motor_time_constant_s!r}."
            )
        self.config = config
        self.dt = dt
        length, width = config.chassis_length, config.chassis_width
        front = AXLE_TO_FRONT_FRACTION * length
        self.outline: Tuple[Tuple[float, float], ...] = (
            (front, width / 2),
            (front - length, width / 2),
            (front - length, -width / 2),
            (front, -width / 2),
        )
        moment = config.mass * (length**2 + width**2) / 12.0
        self.body = pymunk.Body(config.mass, moment)
        self.body.position = (pose[0], pose[1])
        self.body.angle = pose[2]
        chassis = pymunk.Poly(self.body, self.outline)
        chassis.friction = 0.5
        chassis.elasticity = 0.0
        space.add(self.body, chassis)
        #: The chassis' outline in the space (its bounding box says where the robot reaches).
        self.chassis = chassis

        mu = noise.friction_coefficient
        mu = NO_SLIP_FRICTION if mu is None else mu
        self.traction_limit = mu * config.mass * GRAVITY * WHEEL_LOAD_FRACTION / 2.0
        self.grounds = []
        #: The wheels' true radius and half the true distance between their contact points.
        self.radius = config.radius * noise.wheel_radius_scale
        half_track = config.baseline * noise.baseline_scale / 2
        for side in (1.0, -1.0):
            ground = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            ground.position = self.body.local_to_world((0.0, side * half_track))
            joint = pymunk.PivotJoint(ground, self.body, (0.0, 0.0), (0.0, side * half_track))
            joint.max_bias = 0.0
            joint.max_force = self.traction_limit
            space.add(ground, joint)
            self.grounds.append(ground)
        self._set_left_ground = _velocity_setter(self.grounds[0])
        self._set_right_ground = _velocity_setter(self.grounds[1])

        alpha = 1.0 if motor_time_constant_s == 0 else -math.expm1(-dt / motor_time_constant_s)
        breakaway = config.pwm_min if noise.breakaway_pwm is None else noise.breakaway_pwm
        curve = noise.speed_curve
        right_curve = curve if noise.right_speed_curve is None else noise.right_speed_curve
        self.left = Motor(config, noise.left_gain, breakaway, alpha, curve)
        self.right = Motor(config, noise.right_gain, breakaway, alpha, right_curve)
        self._turning = noise.turning_resistance
        self._scrub = noise.turning_scrub
        self._scrub_width = noise.scrub_width

    def drive(self) -> Tuple[float, float]:
        """Advance both motors by one step and aim the tyres; return the wheel speeds in rad/s.

        Call it just before stepping the space.
        """
        if self._turning or self._scrub:
            left, right = loaded_speeds(
                self.left.target(),
                self.right.target(),
                self._turning,
                self._scrub,
                self._scrub_width,
            )
            left = self.left.follow(left)
            right = self.right.follow(right)
        else:
            left = self.left.update()
            right = self.right.update()
        body = self.body
        omega = body.angular_velocity
        # pymunk moves the body with the velocity it solved in the previous step, so the
        # velocity solved in the coming step applies from the heading after that move (where
        # the joints' anchors will be) through one more step. The rim speeds split into a
        # common part, aimed along the heading half-way through that step so the axle follows
        # the chord of its arc, and a differential part that turns the chassis about the axle
        # midpoint, along the wheels' direction at the anchors. Both wheels' targets then
        # belong to one rigid motion, which the solver meets exactly below the friction cap.
        anchor_heading = body.angle + omega * self.dt
        mid_heading = anchor_heading + 0.5 * omega * self.dt
        radius = self.radius
        common = 0.5 * radius * (left + right)
        differential = 0.5 * radius * (right - left)
        common_x = common * math.cos(mid_heading)
        common_y = common * math.sin(mid_heading)
        turn_x = differential * math.cos(anchor_heading)
        turn_y = differential * math.sin(anchor_heading)
        self._set_left_ground((common_x - turn_x, common_y - turn_y))
        self._set_right_ground((common_x + turn_x, common_y + turn_y))
        return left, right

    @property
    def pose(self) -> Pose:
        """The true pose of the axle midpoint in the world frame, theta in [0, 2*pi).

        pymunk keeps the body's angle unbounded (it counts whole turns); the pose reports it
        as the one heading in [0, 2*pi) that the course uses everywhere.
        """
        x, y = self.body.position
        theta = self.body.angle % math.tau
        # A tiny negative angle wraps to exactly 2*pi in floating point: that heading is 0.
        return Pose(x, y, 0.0 if theta >= math.tau else theta)

    @property
    def twist(self) -> Twist:
        """The true velocity of the axle midpoint in the robot frame."""
        body = self.body
        vx, vy = body.velocity
        omega = body.angular_velocity
        # This velocity moves the body during the next step: measure it against the heading
        # half-way through that step.
        heading = body.angle + 0.5 * omega * self.dt
        cos_h, sin_h = math.cos(heading), math.sin(heading)
        return Twist(vx * cos_h + vy * sin_h, omega, -vx * sin_h + vy * cos_h)
