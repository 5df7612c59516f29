"""The virtual Duckiebot: one robot on the mat, driven by duty cycles, seen by its sensors.

:class:`Simulator` ties the pieces together and owns the clock. Time is simulated seconds and
advances in fixed physics steps (``1 / physics_rate_hz``); commands take effect at the next
step. Everything random (encoder start counts, schedules and jitter, wheel slot phases) comes
from one ``numpy.random.Generator`` seeded by ``seed``, so the same seed and the same commands
at the same simulated times give a bit-identical run, in any process.

What it offers, in the terms of the robot's ROS interface:

- :meth:`Simulator.set_wheel_duties`: ``wheels_driver_node/wheels_cmd`` (duty cycles).
- :meth:`Simulator.pop_encoder_readings`: the samples of ``left_wheel_encoder_node/tick`` and
  ``right_wheel_encoder_node/tick`` due since the last call, each with its own time.
- :meth:`Simulator.set_led_pattern` and :meth:`Simulator.set_custom_led_pattern`: the LED
  emitter's services; :attr:`Simulator.leds` is what the LEDs show.
- :meth:`Simulator.frame_jpeg`: ``camera_node/image/compressed``, rendered only when asked.
- :attr:`Simulator.pose` and :attr:`Simulator.twist`: ground truth, which the robot itself
  never knows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, List, Optional, Sequence, Tuple, Union

import numpy as np

from duckielib import leds as led_tables
from duckielib.config import DB21, RobotConfig
from duckielib.errors import ConfigError, SimulationError
from duckielib.missions import TASK_START
from duckielib.sim.encoders import Encoder, EncoderReading
from duckielib.sim.noise import NoiseProfile, noise_profile
from duckielib.sim.robot import MOTOR_TIME_CONSTANT_S, Pose, Robot, Twist
from duckielib.sim.world import World, build_space, space_stepper

if TYPE_CHECKING:
    from duckielib.sim.camera import Camera

__all__ = ["Simulator", "LEDState", "Trace", "START_POSE", "PHYSICS_RATE_HZ"]

#: Where the course's task starts: (x, y, theta) in metres and radians, on the mat grid
#: (:data:`duckielib.missions.TASK_START`).
START_POSE = TASK_START

#: Default physics rate, in Hz.
PHYSICS_RATE_HZ = 100.0

#: Default rate at which the true path is recorded, in Hz.
TRACE_RATE_HZ = 30.0
#: How close to a wall the chassis counts as touching it, in metres (pymunk's slop is 0.5 mm).
WALL_TOUCH_M = 0.002

#: Range the encoders' start counts are drawn from when none are given.
_INITIAL_TICKS_RANGE = (10_000, 60_000)

RGB = Tuple[float, float, float]


@dataclass(frozen=True)
class LEDState:
    """What the five LEDs show at one moment.

    Attributes:
        pattern: name of the pattern set (``"custom"`` for a custom one).
        colors: five RGB triples in [0, 1], by LED index (see :mod:`duckielib.leds`).
    """

    pattern: str
    colors: Tuple[RGB, ...]


@dataclass
class Trace:
    """The true path of a run, sampled at the trace rate, and the LED patterns shown.

    Attributes:
        times: sample times, in seconds.
        xs: true x of the axle midpoint at those times, in metres.
        ys: true y, in metres.
        thetas: true heading, in radians in [0, 2*pi).
        patterns: the LED patterns set, as (time set in seconds, pattern), in time order.
    """

    times: List[float] = field(default_factory=list)
    xs: List[float] = field(default_factory=list)
    ys: List[float] = field(default_factory=list)
    thetas: List[float] = field(default_factory=list)
    patterns: List[Tuple[float, led_tables.Pattern]] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.times)

    def poses(self) -> np.ndarray:
        """The true poses, shape (N, 3): x and y in metres, theta in radians."""
        return np.column_stack(
            (
                np.asarray(self.xs, dtype=float),
                np.asarray(self.ys, dtype=float),
                np.asarray(self.thetas, dtype=float),
            )
        ).reshape(-1, 3)

    def led_colors_at(self, t: float) -> Tuple[RGB, ...]:
        """The five LEDs' RGB colours at time ``t`` (seconds); all off before any pattern."""
        return led_tables.colors_shown(self.patterns, t)

    def led_colors(self) -> np.ndarray:
        """The LEDs' colours at every sample time, shape (N, 5, 3), RGB in [0, 1]."""
        colors = [self.led_colors_at(t) for t in self.times]
        return np.asarray(colors, dtype=float).reshape(-1, led_tables.LED_COUNT, 3)


def _check_duty(value: object, wheel: str) -> float:
    try:
        duty = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise SimulationError(
            f"The {wheel} wheel's duty cycle must be a number in [-1, 1], not {value!r}."
        ) from None
    if not math.isfinite(duty):
        raise SimulationError(
            f"The {wheel} wheel's duty cycle is {duty}; send a finite number in [-1, 1] "
            "(check the computation that produced it)."
        )
    return duty


def _checked_start(
    world: World,
    start_pose: Sequence[float],
    physics_rate_hz: float,
    trace_rate_hz: float,
) -> Tuple[float, float, float]:
    """The start pose (x, y in metres, theta in radians), once the simulator's settings hold.

    Raises:
        ConfigError: if a rate is too low or not a number, or the pose is not finite or off
            ``world``'s mat.
    """
    if not (math.isfinite(physics_rate_hz) and physics_rate_hz >= 10):
        raise ConfigError(
            f"physics_rate_hz must be at least 10 Hz, not {physics_rate_hz!r} "
            "(100 to 200 Hz is a good choice)."
        )
    if not (math.isfinite(trace_rate_hz) and trace_rate_hz >= 0):
        raise ConfigError(f"trace_rate_hz must be a number of Hz >= 0, not {trace_rate_hz!r}.")
    x, y, theta = (float(value) for value in start_pose)
    if not all(math.isfinite(value) for value in (x, y, theta)):
        raise ConfigError(f"The start pose must be finite numbers, not {tuple(start_pose)!r}.")
    if not world.contains(x, y):
        raise ConfigError(
            f"The start pose ({x}, {y}) is off the mat, which spans [0, {world.width}] x "
            f"[0, {world.height}] m; start on the mat or make the world bigger."
        )
    return x, y, theta


def _initial_ticks(given: Optional[Tuple[int, int]], rng: np.random.Generator) -> Tuple[int, int]:
    """The encoders' counts at power-on: ``given``, or drawn from ``rng`` when None.

    Raises:
        ConfigError: if ``given`` is not two integers.
    """
    if given is None:
        low, high = _INITIAL_TICKS_RANGE
        return (int(rng.integers(low, high)), int(rng.integers(low, high)))
    if len(given) != 2 or not all(isinstance(t, int) for t in given):
        raise ConfigError(f"initial_ticks must be two integers (left, right), not {given!r}.")
    return given


class Simulator:
    """A simulated Duckiebot on a Duckietown mat.

    Args:
        seed: seed of every random choice (the encoders' start counts, slot phases, schedules
            and jitter); the same seed and commands give the same run. The robot's physics
            is set by the noise profile, not the seed.
        noise: a :class:`NoiseProfile` or its name, ``"ideal"`` (default) or ``"realistic"``.
        config: the robot's constants.
        world: the mat and its walls.
        start_pose: the starting pose (x, y, theta), in metres and radians, on the mat.
        physics_rate_hz: physics steps per simulated second.
        initial_ticks: the encoders' counts at the start (left, right); drawn from the seed
            (tens of thousands, as on a robot that has been running) when not given.
        motor_time_constant_s: time constant of the motors' first-order response, in seconds.
        trace_rate_hz: how often the true path is recorded, in Hz; 0 records nothing.

    Raises:
        ConfigError: if a setting is impossible (a start pose off the mat, a negative rate).
    """

    def __init__(
        self,
        seed: int = 0,
        noise: Union[str, NoiseProfile] = "ideal",
        config: RobotConfig = DB21,
        world: Optional[World] = None,
        start_pose: Sequence[float] = START_POSE,
        physics_rate_hz: float = PHYSICS_RATE_HZ,
        initial_ticks: Optional[Tuple[int, int]] = None,
        motor_time_constant_s: float = MOTOR_TIME_CONSTANT_S,
        trace_rate_hz: float = TRACE_RATE_HZ,
    ) -> None:
        self.seed = seed
        self.noise = noise_profile(noise)
        self.config = config
        self.world = World() if world is None else world
        x, y, theta = _checked_start(self.world, start_pose, physics_rate_hz, trace_rate_hz)
        self.physics_rate_hz = float(physics_rate_hz)
        self.dt = 1.0 / self.physics_rate_hz
        self._steps = 0

        root = np.random.default_rng(seed)
        left_rng, right_rng, start_rng = root.spawn(3)
        initial_ticks = _initial_ticks(initial_ticks, start_rng)

        self.space = build_space(self.world)
        self.robot = Robot(
            self.space, config, self.noise, (x, y, theta), self.dt, motor_time_constant_s
        )
        self._space_step = space_stepper(self.space)
        self._readings: List[EncoderReading] = []
        rate = config.encoder_rate_hz
        jitter = self.noise.encoder_jitter_s
        by_command = self.noise.encoder_counts_by_command
        self.left_encoder = Encoder(
            "left",
            config.resolution,
            rate,
            initial_ticks[0],
            jitter,
            left_rng,
            self._readings,
            by_command,
        )
        self.right_encoder = Encoder(
            "right",
            config.resolution,
            rate,
            initial_ticks[1],
            jitter,
            right_rng,
            self._readings,
            by_command,
        )
        # Wheel speeds the chassis moves with during the coming step, in rad/s.
        self._applied = (0.0, 0.0)

        self.trace = Trace()
        self._show_pattern(led_tables.pattern_named(led_tables.START_PATTERN))
        self._camera: Optional[Camera] = None
        self._frame: Optional[Tuple[int, bytes]] = None
        self._trace_every = (
            0 if trace_rate_hz == 0 else max(1, round(self.physics_rate_hz / trace_rate_hz))
        )
        if self._trace_every:
            self._record()

    # Clock and stepping.

    @property
    def time(self) -> float:
        """Simulated time since the start, in seconds."""
        return self._steps * self.dt

    @property
    def steps(self) -> int:
        """Physics steps taken since the start."""
        return self._steps

    def step(self, dt: Optional[float] = None) -> None:
        """Advance one physics step, or by ``dt`` seconds rounded to whole physics steps.

        Raises:
            SimulationError: if ``dt`` is negative or not finite.
        """
        if dt is None:
            self._advance(1)
            return
        if not (math.isfinite(dt) and dt >= 0):
            raise SimulationError(f"step(dt) needs a finite number of seconds >= 0, not {dt!r}.")
        self._advance(round(dt * self.physics_rate_hz))

    def run_until(self, t: float) -> None:
        """Advance to simulated time ``t`` (seconds), to the nearest physics step at or after it.

        Nothing happens if ``t`` is not later than :attr:`time`.

        Raises:
            SimulationError: if ``t`` is not finite.
        """
        if not math.isfinite(t):
            raise SimulationError(f"run_until(t) needs a finite time in seconds, not {t!r}.")
        target = math.ceil(t * self.physics_rate_hz - 1e-9)
        if target > self._steps:
            self._advance(target - self._steps)

    def _advance(self, count: int) -> None:
        dt = self.dt
        left_encoder = self.left_encoder
        right_encoder = self.right_encoder
        drive = self.robot.drive
        space_step = self._space_step
        trace_every = self._trace_every
        steps = self._steps
        left, right = self._applied
        for _ in range(count):
            t0 = steps * dt
            left_encoder.advance(t0, dt, left)
            right_encoder.advance(t0, dt, right)
            left, right = drive()
            space_step(dt)
            steps += 1
            if trace_every and steps % trace_every == 0:
                self._steps = steps
                self._record()
        self._steps = steps
        self._applied = (left, right)

    def _record(self) -> None:
        trace = self.trace
        x, y, theta = self.robot.pose
        trace.times.append(self.time)
        trace.xs.append(x)
        trace.ys.append(y)
        trace.thetas.append(theta)

    # Wheels and encoders.

    def set_wheel_duties(self, left: float, right: float) -> Tuple[float, float]:
        """Command the wheels as ``wheels_driver_node/wheels_cmd`` does, with duty cycles.

        Duty cycles beyond [-1, 1] are clipped, as the driver does; the encoders take their
        counting direction from the executed values.

        Args:
            left: left wheel duty cycle, in [-1, 1] (positive drives forward).
            right: right wheel duty cycle, in [-1, 1].

        Returns:
            The executed duty cycles (left, right), as ``wheels_cmd_executed`` reports them.

        Raises:
            SimulationError: if a duty cycle is NaN, infinite or not a number.
        """
        left = _check_duty(left, "left")
        right = _check_duty(right, "right")
        robot = self.robot
        robot.left.command(left)
        robot.right.command(right)
        self.left_encoder.set_direction(robot.left.duty)
        self.right_encoder.set_direction(robot.right.duty)
        return robot.left.duty, robot.right.duty

    @property
    def wheel_duties(self) -> Tuple[float, float]:
        """The executed duty cycles (left, right)."""
        return self.robot.left.duty, self.robot.right.duty

    @property
    def wheel_speeds(self) -> Tuple[float, float]:
        """The wheels' true angular speeds (left, right), in rad/s."""
        return self.robot.left.speed, self.robot.right.speed

    def pop_encoder_readings(self) -> List[EncoderReading]:
        """The encoder samples due since the last call, both wheels, in time order."""
        readings = sorted(self._readings, key=lambda reading: reading.time)
        self._readings.clear()
        return readings

    @property
    def next_encoder_time(self) -> float:
        """Simulated time of the next encoder sample of either wheel, in seconds."""
        return min(self.left_encoder.next_time, self.right_encoder.next_time)

    @property
    def encoder_ticks(self) -> Tuple[int, int]:
        """The encoders' current counts (left, right), signed int32."""
        return self.left_encoder.ticks, self.right_encoder.ticks

    # Ground truth.

    @property
    def pose(self) -> Pose:
        """The true pose (x, y, theta) of the axle midpoint; metres, radians in [0, 2*pi)."""
        return self.robot.pose

    @property
    def touching_wall(self) -> bool:
        """Whether the robot's chassis touches one of the mat's walls (within 2 mm)."""
        if not self.world.walls:
            return False
        box = self.robot.chassis.bb
        width, height = self.world.width, self.world.height
        return (
            box.left <= WALL_TOUCH_M
            or box.bottom <= WALL_TOUCH_M
            or box.right >= width - WALL_TOUCH_M
            or box.top >= height - WALL_TOUCH_M
        )

    @property
    def twist(self) -> Twist:
        """The true velocity (v, omega, v_lateral) in the robot frame; m/s and rad/s."""
        return self.robot.twist

    # LEDs.

    def set_led_pattern(self, name: str) -> None:
        """Show a named pattern (see :data:`duckielib.leds.PATTERNS`).

        Raises:
            ConfigError: if there is no pattern of that name.
        """
        self._show_pattern(led_tables.pattern_named(name))

    def set_custom_led_pattern(
        self,
        color_list: Union[str, Sequence[Any]],
        frequency: float = 0.0,
        frequency_mask: Optional[Sequence[int]] = None,
    ) -> None:
        """Show a custom pattern (see :func:`duckielib.leds.custom_pattern`).

        Args:
            color_list: one colour for all LEDs or five, by LED index; names or RGB in [0, 1].
            frequency: blinking frequency in Hz, 0 for solid.
            frequency_mask: five 0/1 flags saying which LEDs blink.

        Raises:
            ConfigError: if the pattern is not valid.
        """
        self._show_pattern(led_tables.custom_pattern(color_list, frequency, frequency_mask))

    def show_led_pattern(self, pattern: led_tables.Pattern) -> None:
        """Show a pattern already checked (what the LED emitter node sends to the LEDs)."""
        self._show_pattern(pattern)

    def _show_pattern(self, pattern: led_tables.Pattern) -> None:
        self._pattern = pattern
        self._pattern_since = self.time
        self.trace.patterns.append((self.time, pattern))

    @property
    def led_pattern(self) -> led_tables.Pattern:
        """The pattern currently set."""
        return self._pattern

    @property
    def leds(self) -> LEDState:
        """What the LEDs show now: the pattern's name and five RGB colours."""
        pattern = self._pattern
        colors = led_tables.colors_at(pattern, self.time - self._pattern_since)
        return LEDState(pattern.name, colors)

    # Camera.

    @property
    def camera(self) -> Camera:
        """The robot's camera (created when first used)."""
        if self._camera is None:
            from duckielib.sim.camera import Camera

            self._camera = Camera(self.world)
        return self._camera

    def camera_image(self) -> np.ndarray:
        """What the camera sees now: an RGB image, shape (480, 640, 3), dtype uint8."""
        return self.camera.render(self.pose)

    def frame_jpeg(self) -> bytes:
        """The camera's latest JPEG frame (640x480).

        The camera runs at up to ``Camera.rate_hz`` (30 Hz): asking twice within one frame
        period returns the same frame. Nothing is rendered unless asked for.
        """
        camera = self.camera
        index = math.floor(self.time * camera.rate_hz + 1e-9)
        if self._frame is None or self._frame[0] != index:
            self._frame = (index, camera.jpeg(self.pose))
        return self._frame[1]
