"""Bags that come with the course, to analyse a run before you can record your own.

:func:`sample_bag` gives the path of one. ``square_then_circle_realistic`` is the course's task
driven on the ``realistic`` virtual Duckiebot (seed 0) by the course's own nodes, recorded as
``duckie mission`` records it: encoder ticks, odometry and true poses, commands, LED patterns
and the mission's states. Notebook 10 analyses it until your own mission runs.

To record it again (instructors, after the simulator or the recorded topics change)::

    duckie mission --noise realistic --seed 0 --no-animation --out runs/sample
    duckie bag repair runs/sample/mission.bag runs/sample/compressed.bag --compression bz2
    cp runs/sample/compressed.bag duckielib/bags/data/square_then_circle_realistic.bag

``square_then_circle_other_robot`` stands in for your own robot's mission bag in notebook 10's
calibration: the same task driven by the course's nodes (seed 0) on a virtual Duckiebot whose
motors are weaker than the realistic one's
(:data:`duckielib.sim.calibrate.CALIBRATION_SAMPLE_ROBOT`).
To record it again::

    python -c "from duckielib.sim.calibrate import record_other_robot_profile as r; r('other.json')"
    duckie mission --noise other.json --seed 0 --no-animation --out runs/other
    duckie bag repair runs/other/mission.bag compressed.bag --compression bz2
    cp compressed.bag duckielib/bags/data/square_then_circle_other_robot.bag

``calibration_drive`` stands in for a bag of your own robot's wheel calibration (notebook 10):
:func:`~duckielib.sim.calibrate.calibration_driver`'s commands and both encoders' ticks,
recorded on a virtual Duckiebot whose motors are weaker than the realistic one's
(:data:`duckielib.sim.calibrate.CALIBRATION_SAMPLE_ROBOT`: a dead band up to duty 0.15, a
right motor 7 % weaker, tyres that scrub less). To record it again::

    python -c "from duckielib.sim.calibrate import record_calibration_sample as r; r('c.bag')"
    duckie bag repair c.bag compressed.bag --compression bz2
    cp compressed.bag duckielib/bags/data/calibration_drive.bag
"""

from __future__ import annotations

from pathlib import Path
from typing import List

from duckielib.errors import BagError

__all__ = ["SAMPLES", "sample_bag"]

_FOLDER = Path(__file__).resolve().parent / "data"

#: The names of the sample bags.
SAMPLES: List[str] = sorted(path.stem for path in _FOLDER.glob("*.bag"))


def sample_bag(name: str = "square_then_circle_realistic") -> Path:
    """The path of the sample bag called ``name``.

    Raises:
        BagError: if there is no such sample (the message names those there are).
    """
    path = _FOLDER / f"{name}.bag"
    if not path.is_file():
        raise BagError(f"There is no sample bag {name!r}; the samples are: {', '.join(SAMPLES)}.")
    return path
