"""The virtual Duckiebot: a pymunk simulator that behaves like the real robot.

This package is the only place pymunk is imported. It reproduces what makes the real robot
hard rather than an ideal unicycle: duty-cycle motors with the driver's dead zone and a lag,
unequal wheels, tyres that slip, encoders with 135 ticks per revolution sampled at 30 Hz on
unsynchronised schedules with the driver's sign rule. Ground truth comes from the physics.

Modules (one idea each):
    simulator: :class:`Simulator`, the robot in its world, and its clock.
    duckiebot: :class:`VirtualDuckiebot`, the simulator with its driver nodes on a ROS graph.
    drivers: the robot's driver nodes (wheels, encoders, kinematics, LEDs, camera).
    world: the mat grid and its walls (:class:`World`), the pymunk space in metres.
    robot: chassis, wheels and motors (:class:`Pose`, :class:`Twist`, :func:`pwm_from_duty`).
    encoders: the wheel encoders (:class:`EncoderReading`).
    noise: :class:`NoiseProfile`, ``ideal`` or ``realistic``, every parameter settable.
    camera: 640x480 JPEG frames of the mat, rendered on demand (needs Pillow).
    draw: matplotlib figures and animations of a run (imported only when used).
    examples: runnable examples, ``python -m duckielib.sim.examples.square``.

Example::

    from duckielib.sim import Simulator

    sim = Simulator(seed=1, noise="realistic")
    sim.set_wheel_duties(0.5, 0.5)
    sim.run_until(2.0)
    sim.pose, sim.pop_encoder_readings()
"""

from __future__ import annotations

from duckielib.sim.duckiebot import VirtualDuckiebot
from duckielib.sim.encoders import EncoderReading
from duckielib.sim.noise import NoiseProfile, noise_profile
from duckielib.sim.robot import Pose, Twist, pwm_from_duty, steady_speed
from duckielib.sim.simulator import START_POSE, LEDState, Simulator, Trace
from duckielib.sim.world import World

__all__ = [
    "Simulator",
    "VirtualDuckiebot",
    "World",
    "NoiseProfile",
    "noise_profile",
    "Pose",
    "Twist",
    "EncoderReading",
    "LEDState",
    "Trace",
    "START_POSE",
    "pwm_from_duty",
    "steady_speed",
]
