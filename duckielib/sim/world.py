"""The world: a Duckietown mat of square tiles, seen from above, with optional boundary walls.

Frames and units: the world frame has its origin at the mat's corner, x along the first row
of tiles, y along the first column, z up; metres and radians, angles counter-clockwise seen
from above. The mat spans ``[0, width] x [0, height]``.

pymunk's defaults assume pixels (a collision slop of 0.1 would be 10 cm here), so the space
is set up for metres: half a millimetre of slop, no gravity (the view is top-down; the weight
of the robot enters only through the tyres' friction), no damping, no sleeping.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Callable, List, Tuple

import pymunk

from duckielib.config import TILE_SIZE
from duckielib.errors import ConfigError

__all__ = ["OPEN_MAT", "World", "WALL_THICKNESS", "build_space", "space_stepper"]

#: Thickness of the boundary walls, in metres (they lie outside the mat).
WALL_THICKNESS = 0.02

#: Allowed overlap of colliding shapes, in metres.
COLLISION_SLOP = 0.0005

#: Solver iterations per physics step.
SOLVER_ITERATIONS = 10


@dataclass(frozen=True)
class World:
    """The mat and its walls.

    Attributes:
        tiles_x: number of tiles along x.
        tiles_y: number of tiles along y.
        tile_size: side of a tile, in metres.
        walls: whether walls surround the mat (a robot driving off the mat hits them).
    """

    tiles_x: int = 4
    tiles_y: int = 4
    tile_size: float = TILE_SIZE
    walls: bool = True

    def __post_init__(self) -> None:
        for name in ("tiles_x", "tiles_y"):
            value = getattr(self, name)
            if not (isinstance(value, int) and not isinstance(value, bool) and value > 0):
                raise ConfigError(f"World.{name} must be a positive whole number, not {value!r}.")
        if not (
            isinstance(self.tile_size, (int, float))
            and math.isfinite(self.tile_size)
            and self.tile_size > 0
        ):
            raise ConfigError(
                f"World.tile_size must be a positive number of metres, not {self.tile_size!r}."
            )

    @property
    def width(self) -> float:
        """Extent of the mat along x, in metres."""
        return self.tiles_x * self.tile_size

    @property
    def height(self) -> float:
        """Extent of the mat along y, in metres."""
        return self.tiles_y * self.tile_size

    def contains(self, x: float, y: float, margin: float = 0.0) -> bool:
        """Whether the point (x, y), in metres, is on the mat at least ``margin`` from its edge."""
        return margin <= x <= self.width - margin and margin <= y <= self.height - margin

    def grid_lines(self) -> List[Tuple[Tuple[float, float], Tuple[float, float]]]:
        """The tile borders as segments ((x0, y0), (x1, y1)), in metres, edges included."""
        lines = []
        for i in range(self.tiles_x + 1):
            x = i * self.tile_size
            lines.append(((x, 0.0), (x, self.height)))
        for j in range(self.tiles_y + 1):
            y = j * self.tile_size
            lines.append(((0.0, y), (self.width, y)))
        return lines


#: The mat the missions are driven on: the course's mat lying on an open floor, as a real one
#: does. A robot whose odometry drifts drives off its edge and on, instead of being held by a
#: wall that no real floor has.
OPEN_MAT = World(walls=False)


def build_space(world: World) -> pymunk.Space:
    """A pymunk space in metres for ``world``, with its walls if it has any."""
    space = pymunk.Space()
    space.gravity = (0.0, 0.0)
    space.damping = 1.0
    space.iterations = SOLVER_ITERATIONS
    space.collision_slop = COLLISION_SLOP
    space.sleep_time_threshold = math.inf
    if world.walls:
        half = WALL_THICKNESS / 2
        w, h = world.width, world.height
        # Segment centre lines lie half a thickness outside the mat, so the inner faces
        # are exactly on its edges; the corners overlap so nothing slips through.
        ends = (
            ((-WALL_THICKNESS, -half), (w + WALL_THICKNESS, -half)),
            ((w + half, -WALL_THICKNESS), (w + half, h + WALL_THICKNESS)),
            ((w + WALL_THICKNESS, h + half), (-WALL_THICKNESS, h + half)),
            ((-half, h + WALL_THICKNESS), (-half, -WALL_THICKNESS)),
        )
        for start, end in ends:
            wall = pymunk.Segment(space.static_body, start, end, half)
            wall.friction = 0.5
            wall.elasticity = 0.0
            space.add(wall)
    return space


def space_stepper(space: pymunk.Space) -> Callable[[float], None]:
    """A fast function that steps ``space`` by ``dt`` seconds.

    ``Space.step`` adds bookkeeping for bodies and shapes added or removed during a step,
    which the simulator never does, and costs about three times Chipmunk's own step; fall back
    to it if this pymunk does not expose Chipmunk's function.
    """
    chipmunk = getattr(pymunk, "cp", None)
    handle = getattr(space, "_space", None)
    if chipmunk is None or handle is None or not hasattr(chipmunk, "cpSpaceStep"):
        return space.step
    return functools.partial(chipmunk.cpSpaceStep, handle)
