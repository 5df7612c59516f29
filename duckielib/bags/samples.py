"""Bags that come with the course, to analyse a run before you can record your own.

:func:`sample_bag` gives the path of one. ``square_then_circle_realistic`` is the course's task
driven on the ``realistic`` virtual Duckiebot (seed 0) by the course's own nodes, recorded as
``duckie mission`` records it: encoder ticks, odometry and true poses, commands, LED patterns
and the mission's states. Notebook 10 analyses it until your own mission runs.

To record it again (instructors, after the simulator or the recorded topics change)::

    duckie mission --noise realistic --seed 0 --no-animation --out runs/sample
    duckie bag repair runs/sample/mission.bag runs/sample/compressed.bag --compression bz2
    cp runs/sample/compressed.bag duckielib/bags/data/square_then_circle_realistic.bag
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
