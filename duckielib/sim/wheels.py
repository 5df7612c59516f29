"""The wheels alone: how far the simulator's motors turn each wheel over a run's commands.

In the simulator a wheel's speed comes from the commands only: the motor's speed curve and
gain, the ground's resistance to turning, the motor's first-order lag and static friction
(:mod:`.robot`). The body never feeds back into it (a slipping tyre slips on the ground; the
wheel and its encoder turn on). So the angle each encoder counts over a whole bag's commands
can be computed step by step as the simulator computes it, without the physics: in arrays,
thousands of times faster. ``duckie calibrate`` replays its candidate profiles this way
(:func:`counted_angles`); the fitted profile is then checked by the simulator itself.

The encoders count as the simulator's do (by the sign of the last command, or by the way the
wheel turns), without their slots: the count here is the angle, unrounded.

Laptop side; never deployed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Sequence, Tuple, Union

import numpy as np
from scipy.signal import lfilter

from duckielib.config import DB21, RobotConfig
from duckielib.sim.noise import NoiseProfile
from duckielib.sim.robot import MOTOR_TIME_CONSTANT_S, REST_SPEED, loaded_speeds
from duckielib.sim.simulator import PHYSICS_RATE_HZ

__all__ = ["CommandSteps", "command_steps", "counted_angles"]


@dataclass(frozen=True)
class CommandSteps:
    """A run's commands as the simulator's physics steps execute them.

    Attributes:
        dt: the physics step, in seconds.
        left, right: each step's executed duty cycle (clipped to [-1, 1]), shape (N,).
    """

    dt: float
    left: np.ndarray
    right: np.ndarray

    @property
    def times(self) -> np.ndarray:
        """The steps' boundaries, in seconds: N + 1 of them, from 0."""
        return np.arange(len(self.left) + 1) * self.dt


def command_steps(
    times: Union[Sequence[float], np.ndarray],
    left: Union[Sequence[float], np.ndarray],
    right: Union[Sequence[float], np.ndarray],
    end: float,
    physics_rate_hz: float = PHYSICS_RATE_HZ,
) -> CommandSteps:
    """The duty cycle each physics step executes, from commands sent at ``times`` (seconds).

    A command sent at t takes effect from the first step that starts at or after t, as
    :meth:`Simulator.run_until` then :meth:`Simulator.set_wheel_duties` give it; steps before
    the first command execute 0. The steps cover ``[0, end]``.
    """
    count = max(1, math.ceil(end * physics_rate_hz - 1e-9))
    first_step = np.ceil(np.asarray(times, float) * physics_rate_hz - 1e-9).astype(np.int64)
    index = np.searchsorted(first_step, np.arange(count), side="right") - 1
    duties = []
    for values in (left, right):
        padded = np.concatenate([[0.0], np.clip(np.asarray(values, float), -1.0, 1.0)])
        duties.append(padded[index + 1])
    return CommandSteps(1.0 / physics_rate_hz, duties[0], duties[1])


def _drives(
    duties: np.ndarray,
    gain: float,
    curve: Optional[Tuple[Tuple[float, float], ...]],
    config: RobotConfig,
) -> Tuple[np.ndarray, np.ndarray]:
    """Each step's speed the motor alone drives towards (rad/s), and its PWM."""
    magnitude = np.abs(duties)
    live = magnitude >= config.duty_dead_zone
    span = config.pwm_max - config.pwm_min
    pwm = np.where(live, np.floor(magnitude * span + config.pwm_min), 0.0)
    if curve is None:
        speed = config.k * gain * (pwm - config.pwm_min) / span
    else:
        knots = np.asarray(curve, float)
        speed = gain * np.interp(magnitude, knots[:, 0], knots[:, 1])
        speed[magnitude < knots[0, 0]] = 0.0
    return np.where(live, np.copysign(speed, duties), 0.0), pwm


def _loaded(
    left: np.ndarray, right: np.ndarray, ground: Tuple[float, float, float]
) -> Tuple[np.ndarray, np.ndarray]:
    """:func:`~duckielib.sim.robot.loaded_speeds`, for arrays."""
    turning, scrub, width = ground
    if not (turning or scrub):
        return left, right
    mean = 0.5 * (left + right)
    half = 0.5 * (right - left)
    if scrub:
        spin = np.abs(half)
        rolling = np.minimum(1.0, np.abs(mean) / np.where(spin > 0, spin, 1.0))
        half = half - scrub * np.where(spin > 0, rolling, 0.0) * np.tanh(half / width)
    half = half / (1.0 + turning * np.abs(mean))
    return mean - half, mean + half


def _speeds_with_breakaway(
    targets: Tuple[np.ndarray, np.ndarray],
    pwms: Tuple[np.ndarray, np.ndarray],
    breakaway: int,
    ground: Tuple[float, float, float],
    alpha: float,
) -> Tuple[np.ndarray, np.ndarray]:
    """Each step's wheel speeds when a wheel at rest needs the breakaway PWM (step by step)."""
    count = len(targets[0])
    out = (np.empty(count), np.empty(count))
    drive_l, drive_r = targets[0].tolist(), targets[1].tolist()
    pwm_l, pwm_r = pwms[0].tolist(), pwms[1].tolist()
    turning, scrub, width = ground
    left = right = 0.0
    for step in range(count):
        target_l = (
            0.0 if pwm_l[step] < breakaway and -REST_SPEED < left < REST_SPEED else drive_l[step]
        )
        target_r = (
            0.0 if pwm_r[step] < breakaway and -REST_SPEED < right < REST_SPEED else drive_r[step]
        )
        if turning or scrub:
            target_l, target_r = loaded_speeds(target_l, target_r, turning, scrub, width)
        left += (target_l - left) * alpha
        right += (target_r - right) * alpha
        out[0][step] = left
        out[1][step] = right
    return out


def counted_angles(
    steps: CommandSteps,
    profile: NoiseProfile,
    config: RobotConfig = DB21,
    motor_time_constant_s: float = MOTOR_TIME_CONSTANT_S,
) -> Tuple[np.ndarray, np.ndarray]:
    """The angle each encoder has counted at each step boundary (radians, from 0).

    As the simulator turns the wheels for ``steps`` with ``profile`` (module doc): each
    step's wheel speed is the one its motor reached in the step before.
    """
    alpha = 1.0 if motor_time_constant_s == 0 else -math.expm1(-steps.dt / motor_time_constant_s)
    right_curve = (
        profile.speed_curve if profile.right_speed_curve is None else profile.right_speed_curve
    )
    drive_l, pwm_l = _drives(steps.left, profile.left_gain, profile.speed_curve, config)
    drive_r, pwm_r = _drives(steps.right, profile.right_gain, right_curve, config)
    breakaway = config.pwm_min if profile.breakaway_pwm is None else profile.breakaway_pwm
    ground = (profile.turning_resistance, profile.turning_scrub, profile.scrub_width)
    if breakaway > config.pwm_min:
        speeds = _speeds_with_breakaway(
            (drive_l, drive_r), (pwm_l, pwm_r), breakaway, ground, alpha
        )
    else:
        targets = _loaded(drive_l, drive_r, ground)
        speeds = tuple(lfilter([alpha], [1.0, alpha - 1.0], target) for target in targets)
    counted = []
    for speed, duties in zip(speeds, (steps.left, steps.right)):
        turned = np.concatenate([[0.0], speed[:-1]]) * steps.dt  # the speed of the step before
        if profile.encoder_counts_by_command:
            turned = np.where(duties >= 0, 1.0, -1.0) * np.abs(turned)
        counted.append(np.concatenate([[0.0], np.cumsum(turned)]))
    return counted[0], counted[1]
