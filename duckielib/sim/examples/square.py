"""Drive a 1.25 m square open-loop and compare where the robot went with what its ticks say.

Run it with::

    python -m duckielib.sim.examples.square                 # ideal robot, table only
    python -m duckielib.sim.examples.square --noise realistic --plot square.png

The robot starts at the task's start pose and drives the square clockwise with fixed duty
cycles for fixed times (open loop: nothing corrects it). For every leg the table shows the
ticks each encoder counted next to the ticks the wheel's true travel over the mat is worth,
and the true distance and turn; the "stop" legs show how far the robot coasts, and that a
wheel coasting backwards after a turn counts up (the encoder takes its sign from the last
command). With the ideal profile counts and travel agree to a tick and the square closes
within a few centimetres; with the realistic one the weaker right wheel bends the straight
legs and the square does not close (slip shows only in harder starts and reversals than these).
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import List, NamedTuple, Optional, Sequence, Tuple

import numpy as np

from duckielib.sim.simulator import Simulator

__all__ = ["Leg", "LegReport", "SquareRun", "SQUARE", "main"]


class Leg(NamedTuple):
    """One open-loop command: duty cycles held for a time.

    Attributes:
        name: what the leg is meant to do.
        left: left duty cycle.
        right: right duty cycle.
        seconds: how long the duty cycles are held, in seconds.
    """

    name: str
    left: float
    right: float
    seconds: float


#: A clockwise square of 1.25 m sides; the times were tuned by hand on the ideal robot.
SQUARE: Tuple[Leg, ...] = tuple(
    leg
    for _ in range(4)
    for leg in (
        Leg("forward 1.25 m", 0.5, 0.5, 2.93),
        Leg("stop", 0.0, 0.0, 0.5),
        Leg("turn right 90 deg", 0.3, -0.3, 0.31),
        Leg("stop", 0.0, 0.0, 0.5),
    )
)


class LegReport(NamedTuple):
    """What happened during one leg.

    Attributes:
        leg: the command.
        ticks_counted: ticks the encoders counted (left, right).
        ticks_travelled: ticks the wheels' true travel over the mat is worth (left, right).
        distance: true distance the axle midpoint moved, in metres.
        turn_deg: true change of heading, in degrees (counter-clockwise positive).
    """

    leg: Leg
    ticks_counted: Tuple[int, int]
    ticks_travelled: Tuple[float, float]
    distance: float
    turn_deg: float


class SquareRun:
    """Drives the square in a simulator and reports truth against ticks.

    Args:
        seed: the simulator's seed.
        noise: the noise profile, ``"ideal"`` or ``"realistic"``.
        legs: the open-loop commands.
    """

    def __init__(self, seed: int = 0, noise: str = "ideal", legs: Sequence[Leg] = SQUARE) -> None:
        self.sim = Simulator(seed=seed, noise=noise, trace_rate_hz=100.0)
        self.legs = tuple(legs)
        self.reports: List[LegReport] = []

    def run(self) -> List[LegReport]:
        """Drive every leg, then stop; return one report per leg."""
        sim = self.sim
        for leg in self.legs:
            start_index = len(sim.trace) - 1
            start_ticks = sim.encoder_ticks
            sim.set_wheel_duties(leg.left, leg.right)
            sim.run_until(sim.time + leg.seconds)
            end_ticks = sim.encoder_ticks
            poses = sim.trace.poses()[start_index:]
            heading = np.unwrap(poses[:, 2])  # rad, without the jumps at the wrap
            self.reports.append(
                LegReport(
                    leg,
                    (end_ticks[0] - start_ticks[0], end_ticks[1] - start_ticks[1]),
                    self._ticks_travelled(poses),
                    float(np.hypot(*(poses[-1, :2] - poses[0, :2]))),
                    math.degrees(float(heading[-1] - heading[0])),
                )
            )
        sim.set_wheel_duties(0.0, 0.0)
        sim.run_until(sim.time + 1.0)
        return self.reports

    def _ticks_travelled(self, poses: np.ndarray) -> Tuple[float, float]:
        """Ticks worth of each wheel's true travel along its rolling direction."""
        config = self.sim.config
        ticks_per_metre = config.resolution / (2 * math.pi * config.radius)
        heading = np.unwrap(poses[:, 2])
        # Each step rolls along the heading half-way through it.
        mid = (heading[:-1] + heading[1:]) / 2
        travelled = []
        for side in (1.0, -1.0):
            normal = np.column_stack((-np.sin(poses[:, 2]), np.cos(poses[:, 2])))
            contact = poses[:, :2] + side * config.baseline / 2 * normal
            step = np.diff(contact, axis=0)
            along = step[:, 0] * np.cos(mid) + step[:, 1] * np.sin(mid)
            travelled.append(float(np.sum(along)) * ticks_per_metre)
        return travelled[0], travelled[1]

    def table(self) -> str:
        """The reports as a text table, with the start and end poses."""
        sim = self.sim
        x0, y0, theta0 = sim.trace.poses()[0]
        lines = [
            f"noise profile: {sim.noise.name}, seed {sim.seed}",
            f"{'leg':<20}{'ticks L':>9}{'true L':>9}{'ticks R':>9}{'true R':>9}"
            f"{'dist m':>9}{'turn deg':>10}",
        ]
        for report in self.reports:
            lines.append(
                f"{report.leg.name:<20}"
                f"{report.ticks_counted[0]:>9d}{report.ticks_travelled[0]:>9.1f}"
                f"{report.ticks_counted[1]:>9d}{report.ticks_travelled[1]:>9.1f}"
                f"{report.distance:>9.3f}{report.turn_deg:>10.1f}"
            )
        x, y, theta = sim.pose
        lines.append(
            f"start pose: x={x0:.3f} m, y={y0:.3f} m, theta={math.degrees(theta0):.1f} deg"
        )
        lines.append(f"end pose:   x={x:.3f} m, y={y:.3f} m, theta={math.degrees(theta):.1f} deg")
        lines.append(f"the square misses closing by {math.hypot(x - x0, y - y0) * 100:.1f} cm")
        return "\n".join(lines)

    def save_plot(self, path: str) -> None:
        """Save a figure of the mat and the true path to ``path`` (PNG, SVG, ...)."""
        import matplotlib

        matplotlib.use("Agg")
        from matplotlib import pyplot as plt

        from duckielib.plots import plot_run

        figure, ax = plt.subplots(figsize=(6, 6))
        plot_run(self.sim, ax=ax)
        figure.savefig(path, dpi=120, bbox_inches="tight")


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the example from the command line."""
    parser = argparse.ArgumentParser(
        prog="python -m duckielib.sim.examples.square", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--noise", choices=("ideal", "realistic"), default="ideal")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--plot", metavar="FILE", help="save a figure of the run to FILE")
    args = parser.parse_args(argv)
    square = SquareRun(seed=args.seed, noise=args.noise)
    square.run()
    print(square.table())
    if args.plot:
        square.save_plot(args.plot)
        print(f"figure saved to {args.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
