"""The simulator's world: the mat, the robot and its LEDs, and its recorded runs.

- :func:`draw_mat`: the mat's tiles (:func:`~duckielib.plots.canvas.draw_tile_grid`, as the
  mat looks) and its walls.
- :func:`draw_robot`: the robot at a pose, with its five LEDs in their colours.
- :func:`plot_run`: a figure of a run: the mat, the true path, the robot where it ended, and an
  estimated path (for example from odometry) when given.
- :func:`animate_run`: the same as an animation; :func:`animation_html` turns it into HTML
  that plays inline in a notebook, :func:`~duckielib.plots.save_animation` writes it to a file.

Everything is drawn in the world frame, in metres, seen from above, with equal scales on both
axes. This module reads the simulator (:mod:`duckielib.sim`) but the simulator never imports
it: a notebook draws a run with ``plot_run(bot.sim)``. Like every module of
:mod:`duckielib.plots`, the library's only package that imports matplotlib, it runs on the
laptop only.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, List, Optional, Sequence, Tuple

import numpy as np
from matplotlib import animation, patches
from matplotlib import pyplot as plt
from matplotlib.transforms import Affine2D

from duckielib.config import RobotConfig
from duckielib.errors import SimulationError
from duckielib.plots.canvas import draw_tile_grid
from duckielib.sim.robot import AXLE_TO_FRONT_FRACTION
from duckielib.sim.world import WALL_THICKNESS, World

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes

    from duckielib.sim.simulator import Simulator

__all__ = [
    "draw_mat",
    "draw_robot",
    "plot_run",
    "animate_run",
    "animation_html",
]

RGB = Tuple[float, float, float]

_WALL_COLOR = "#966e46"
_TRUE_COLOR = "#1f77b4"
_ESTIMATE_COLOR = "#ff7f0e"
_LED_RADIUS = 0.012


def draw_mat(ax: Axes, world: World) -> None:
    """Draw the mat's tiles, their borders and the walls on ``ax``, and fit the view to them."""
    draw_tile_grid(
        ax, (0.0, world.width), (0.0, world.height), on_mat=True, tile_size=world.tile_size
    )
    margin = 0.05
    if world.walls:
        ax.add_patch(
            patches.Rectangle(
                (-WALL_THICKNESS / 2, -WALL_THICKNESS / 2),
                world.width + WALL_THICKNESS,
                world.height + WALL_THICKNESS,
                fill=False,
                edgecolor=_WALL_COLOR,
                linewidth=4,
                zorder=1,
            )
        )
    ax.set_xlim(-margin, world.width + margin)
    ax.set_ylim(-margin, world.height + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def _chassis_outline(config: RobotConfig) -> np.ndarray:
    front = AXLE_TO_FRONT_FRACTION * config.chassis_length
    rear = front - config.chassis_length
    half = config.chassis_width / 2
    nose = front + 0.02
    return np.array([(front, half), (rear, half), (rear, -half), (front, -half), (nose, 0.0)])


def _wheel_outline(config: RobotConfig, side: float) -> np.ndarray:
    y = side * config.baseline / 2
    half_width = 0.011
    return np.array(
        [
            (config.radius, y + half_width),
            (-config.radius, y + half_width),
            (-config.radius, y - half_width),
            (config.radius, y - half_width),
        ]
    )


def _led_positions(config: RobotConfig) -> np.ndarray:
    """Robot-frame (x, y) of the five LEDs, by index, in metres."""
    front = AXLE_TO_FRONT_FRACTION * config.chassis_length - 0.015
    rear = front - config.chassis_length + 0.03
    side = config.chassis_width / 2 - 0.015
    return np.array(
        [(front, side), (rear, side), (front - 0.03, 0.0), (rear, -side), (front, -side)]
    )


class RobotArtist:
    """The patches of one drawn robot, movable from pose to pose.

    The patches keep the robot's shape in the robot frame; matplotlib's own transform places
    them at the pose (rotated by theta, then moved to x, y) when the axes are drawn.

    Args:
        ax: the axes to draw on.
        config: the robot's size.
        ghost: draw only a dashed outline in ``color``, without LEDs (where odometry believes
            the robot is).
        color: the ghost's colour.
    """

    def __init__(
        self, ax: Axes, config: RobotConfig, ghost: bool = False, color: str = _ESTIMATE_COLOR
    ) -> None:
        self.config = config
        self.chassis_local = _chassis_outline(config)
        self.wheels_local = [_wheel_outline(config, 1.0), _wheel_outline(config, -1.0)]
        self.leds_local = _led_positions(config) if not ghost else np.zeros((0, 2))
        # Robot frame to world frame: set at each update, shared by every patch.
        self.placement = Affine2D()
        robot_to_axes = self.placement + ax.transData
        self.chassis = patches.Polygon(
            self.chassis_local,
            closed=True,
            facecolor="none" if ghost else "#f2c200",
            edgecolor=color if ghost else "black",
            linestyle="--" if ghost else "-",
            linewidth=2 if ghost else 1,
            zorder=3.5 if ghost else 4,
            transform=robot_to_axes,
        )
        self.wheels = [
            patches.Polygon(
                w,
                closed=True,
                facecolor="none" if ghost else "#222222",
                edgecolor=color if ghost else "none",
                zorder=3.5 if ghost else 5,
                transform=robot_to_axes,
            )
            for w in self.wheels_local
        ]
        self.leds = [
            patches.Circle(
                (float(x), float(y)),
                _LED_RADIUS,
                edgecolor="black",
                linewidth=0.5,
                zorder=6,
                transform=robot_to_axes,
            )
            for x, y in self.leds_local
        ]
        for artist in (self.chassis, *self.wheels, *self.leds):
            ax.add_patch(artist)

    def update(
        self, pose: Optional[Sequence[float]], led_colors: Optional[Sequence[RGB]]
    ) -> List[Artist]:
        """Move the robot to ``pose`` (hidden when None) with its LEDs in ``led_colors``."""
        artists: List[Artist] = [self.chassis, *self.wheels, *self.leds]
        for artist in artists:
            artist.set_visible(pose is not None)
        if pose is None:
            return artists
        x, y, theta = (float(value) for value in pose)
        self.placement.clear().rotate(theta).translate(x, y)
        for artist in artists:
            artist.stale = True  # the placement moved them: redraw
        colors = led_colors if led_colors is not None else [(0.0, 0.0, 0.0)] * len(self.leds)
        for led, (red, green, blue) in zip(self.leds, colors):
            led.set_facecolor((float(red), float(green), float(blue)))
        return artists


def draw_robot(
    ax: Axes,
    pose: Sequence[float],
    config: RobotConfig,
    led_colors: Optional[Sequence[RGB]] = None,
) -> List[Artist]:
    """Draw the robot at ``pose`` (x, y, theta in metres and radians) with its LEDs.

    Args:
        ax: the axes to draw on.
        pose: where the robot is.
        config: the robot (chassis size, wheel radius, baseline).
        led_colors: the five LEDs' RGB colours in [0, 1], by index; black when None.

    Returns:
        The matplotlib patches drawn.
    """
    return RobotArtist(ax, config).update(pose, led_colors)


def _estimate_xy(estimate: Optional[object]) -> Optional[np.ndarray]:
    if estimate is None:
        return None
    points = np.asarray(estimate, dtype=float)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise SimulationError(
            f"An estimated path must have shape (N, 2) or (N, 3) (x, y and theta), not "
            f"{points.shape}."
        )
    return points[:, :2]


def plot_run(sim: Simulator, estimate: Optional[object] = None, ax: Optional[Axes] = None) -> Axes:
    """Draw a run: the mat, the true path, the robot now with its LEDs, and an estimate.

    Args:
        sim: the simulator whose recorded run to draw.
        estimate: an estimated path, shape (N, 2) or (N, 3): x, y in metres (and theta).
        ax: the axes to draw on; a new figure when None.

    Returns:
        The axes drawn on.

    Raises:
        SimulationError: if ``estimate`` does not have the right shape.
    """
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    draw_mat(ax, sim.world)
    poses = sim.trace.poses()
    if len(poses):
        ax.plot(poses[:, 0], poses[:, 1], color=_TRUE_COLOR, linewidth=2, label="true", zorder=3)
    points = _estimate_xy(estimate)
    if points is not None:
        ax.plot(
            points[:, 0],
            points[:, 1],
            color=_ESTIMATE_COLOR,
            linewidth=2,
            linestyle="--",
            label="estimate",
            zorder=3,
        )
    draw_robot(ax, sim.pose, sim.config, sim.leds.colors)
    ax.set_title(f"t = {sim.time:.2f} s")
    ax.legend(loc="upper right")
    return ax


def animate_run(
    sim: Simulator,
    estimate: Optional[object] = None,
    fps: float = 15.0,
    speed: float = 1.0,
    max_frames: int = 300,
) -> animation.FuncAnimation:
    """An animation of the recorded run: the robot with its LEDs moving along its true path.

    Args:
        sim: the simulator whose recorded run to animate (its trace).
        estimate: an estimated path, shape (N, 2) or (N, 3), drawn growing with the run
            (its samples are taken as evenly spread over the run's duration).
        fps: frames per second of the animation.
        speed: simulated seconds per second of animation.
        max_frames: the most frames to draw (the run is sampled more sparsely if needed).

    Returns:
        The animation; show it in a notebook with :func:`animation_html`.

    Raises:
        SimulationError: if nothing was recorded or ``estimate`` has the wrong shape.
    """
    trace = sim.trace
    if len(trace) == 0:
        raise SimulationError(
            "There is no recorded run to animate; create the Simulator with trace_rate_hz > 0 "
            "and run it first."
        )
    times = np.asarray(trace.times)
    poses = trace.poses()
    points = _estimate_xy(estimate)
    duration = times[-1] - times[0]
    count = int(min(max_frames, max(1, math.ceil(duration / speed * fps) + 1), len(times)))
    indices = np.unique(np.linspace(0, len(times) - 1, count).round().astype(int))

    fig, ax = plt.subplots(figsize=(6, 6))
    draw_mat(ax, sim.world)
    (true_line,) = ax.plot([], [], color=_TRUE_COLOR, linewidth=2, label="true", zorder=3)
    estimate_line = None
    if points is not None:
        (estimate_line,) = ax.plot(
            [], [], color=_ESTIMATE_COLOR, linewidth=2, linestyle="--", label="estimate", zorder=3
        )
    robot = RobotArtist(ax, sim.config)
    title = ax.set_title("")
    ax.legend(loc="upper right")

    def frame(number: int) -> List[Artist]:
        index = int(indices[number])
        true_line.set_data(poses[: index + 1, 0], poses[: index + 1, 1])
        artists: List[Artist] = [true_line, title]
        if estimate_line is not None and points is not None:
            fraction = 1.0 if duration <= 0 else (times[index] - times[0]) / duration
            shown = max(1, math.ceil(fraction * len(points)))
            estimate_line.set_data(points[:shown, 0], points[:shown, 1])
            artists.append(estimate_line)
        title.set_text(f"t = {times[index]:.2f} s")
        artists.extend(robot.update(poses[index], trace.led_colors_at(float(times[index]))))
        return artists

    anim = animation.FuncAnimation(
        fig, frame, frames=len(indices), interval=1000.0 / fps, blit=False
    )
    plt.close(fig)
    return anim


def animation_html(anim: animation.FuncAnimation) -> str:
    """The animation as self-contained HTML (JavaScript player) that plays inline in Jupyter."""
    return anim.to_jshtml()
