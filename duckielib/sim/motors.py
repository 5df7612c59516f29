"""The simulated wheels' steady speeds for the commands real Duckiebots were measured with.

Bags recorded on real DB21 robots during the course's exercise hold the wheel commands and both
encoders' ticks; over the second half of each command held 1 s or more, the wheels turned at
:data:`REAL_DB21` (rad/s, a range over the robots and bags measured). :func:`motor_table`
holds the same commands, from rest, on a simulated robot with a noise profile and measures its
wheels the same way, so a profile can be set next to the real figures (``duckie sim motors``).

Laptop side; never deployed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import List, Tuple, Union

from duckielib.sim.noise import NoiseProfile, noise_profile
from duckielib.sim.simulator import Simulator
from duckielib.sim.world import World

__all__ = ["REAL_DB21", "MotorRow", "motor_table"]

#: (what, left duty, right duty, real left speed range, real right speed range), speeds in
#: rad/s along each wheel's command, measured on real DB21 robots (public bags of the course's
#: exercise). Turning in place both wheels turn at about the same speed; on the arc the slow
#: wheel is dragged by the body faster than its command alone turns it.
REAL_DB21: Tuple[Tuple[str, float, float, Tuple[float, float], Tuple[float, float]], ...] = (
    ("turning in place", -0.175, 0.175, (1.6, 2.0), (1.6, 2.0)),
    ("straight, 0.30", 0.30, 0.30, (3.6, 3.7), (3.6, 3.7)),
    ("straight, 0.40", 0.40, 0.40, (6.1, 6.7), (6.1, 6.7)),
    ("arc, 0.18 inner, 0.62 outer", 0.18, 0.62, (5.0, 5.4), (6.7, 7.3)),
)

#: How long each command is held, and the part of it measured (its second half).
HOLD_S = 2.0


@dataclass(frozen=True)
class MotorRow:
    """One command held on the simulated robot, next to the real figures.

    Attributes:
        what: the command's description.
        duties: the (left, right) duty cycles.
        simulated: the simulated (left, right) speeds along each command, rad/s.
        real: the real robots' (low, high) speeds, left then right, rad/s.
    """

    what: str
    duties: Tuple[float, float]
    simulated: Tuple[float, float]
    real: Tuple[Tuple[float, float], Tuple[float, float]]

    def ratio(self) -> Tuple[float, float]:
        """Simulated speed over the middle of the real range, per wheel."""
        return tuple(  # type: ignore[return-value]
            speed / ((low + high) / 2) for speed, (low, high) in zip(self.simulated, self.real)
        )


def _held_speeds(profile: NoiseProfile, left: float, right: float) -> Tuple[float, float]:
    sim = Simulator(
        seed=0,
        noise=profile,
        world=World(tiles_x=20, tiles_y=20),
        start_pose=(5.0, 5.0, 0.0),
        trace_rate_hz=0,
    )
    sim.set_wheel_duties(left, right)
    sim.run_until(HOLD_S / 2)
    start = (sim.left_encoder.angle, sim.right_encoder.angle)
    sim.run_until(HOLD_S)
    turned = (sim.left_encoder.angle - start[0], sim.right_encoder.angle - start[1])
    return tuple(  # type: ignore[return-value]
        math.copysign(1.0, duty) * angle / (HOLD_S / 2)
        for duty, angle in zip((left, right), turned)
    )


def motor_table(noise: Union[str, NoiseProfile] = "realistic") -> List[MotorRow]:
    """Each command of :data:`REAL_DB21` held on a simulated robot, next to the real figures."""
    profile = noise_profile(noise)
    return [
        MotorRow(what, (left, right), _held_speeds(profile, left, right), (real_l, real_r))
        for what, left, right, real_l, real_r in REAL_DB21
    ]
