"""Plots of robot pose tracks: odometry estimates against the ground truth.

These plots look at recorded runs (ROS bags, :mod:`duckielib.bags`); they need only numpy and
matplotlib, not the simulator nor rosbags. Figures are made without pyplot
(:class:`~duckielib.plots.canvas.NotebookFigure`), so they work headless and from the
``duckie`` command; only :func:`animate_path` uses pyplot.

A *track* is any object with these attributes (a dataclass, a named tuple, what the bags module
reads):

- ``t``: sample times, shape (N,), in seconds, in increasing order.
- ``x``, ``y``: positions in the world frame, shape (N,), in metres.
- ``theta``: headings, shape (N,), in radians, counter-clockwise from the world x axis.
- ``label``: the name shown in legends, such as ``"odometry"`` or ``"ground truth"``.

Conventions: SI units, the world frame seen from above with x to the right and y up, equal
scales on both axes, and theta shown wrapped into [0, 2*pi). The light grid drawn under the
paths is the mat's tiles (:func:`~duckielib.plots.canvas.draw_tile_grid`).

- :func:`plot_path`: the x-y paths on the mat, with where each track started and ended.
- :func:`plot_pose_over_time`: x(t), y(t) and theta(t), one above the other.
- :func:`pose_figure`: both in one figure, the usual way to compare two tracks.
- :func:`animate_path`: the paths growing over time; :func:`~duckielib.plots.save_animation`
  writes it to a file.

Like every module of :mod:`duckielib.plots`, the library's only package that imports
matplotlib, it runs on the laptop only.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, List, NamedTuple, Optional, Sequence, Tuple, Union, cast

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from duckielib.config import TILE_SIZE
from duckielib.errors import DuckielibError
from duckielib.plots.canvas import NotebookFigure, draw_tile_grid, tile_span

if TYPE_CHECKING:
    from typing import Protocol

    from matplotlib.animation import FuncAnimation
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.typing import ColorType

    class _Track(Protocol):
        """What a track must provide (see the module docstring)."""

        @property
        def t(self) -> np.ndarray: ...

        @property
        def x(self) -> np.ndarray: ...

        @property
        def y(self) -> np.ndarray: ...

        @property
        def theta(self) -> np.ndarray: ...

        @property
        def label(self) -> str: ...

    Tracks = Union[_Track, Sequence[_Track]]

__all__ = ["animate_path", "plot_path", "plot_pose_over_time", "pose_figure"]

_TWO_PI = 2.0 * math.pi
#: Length of the arrows that show a heading, in metres (about a Duckiebot's length).
_HEADING_LENGTH = 0.12
_REFERENCE_COLOR = "#d62728"
#: Space left around the tile grid, in metres.
_GRID_MARGIN = 0.02 * TILE_SIZE
_THETA_TICKS = (0.0, math.pi / 2, math.pi, 3 * math.pi / 2, _TWO_PI)
_THETA_TICK_LABELS = ("0", "π/2", "π", "3π/2", "2π")


class _Samples(NamedTuple):
    """A checked track: float arrays of shape (N,), N >= 1."""

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    label: str


def _as_samples(tracks: Tracks) -> List[_Samples]:
    """The tracks as a checked list; one track on its own counts as a list of one."""
    if hasattr(tracks, "t"):
        tracks = [cast("_Track", tracks)]
    tracks = list(tracks)
    if not tracks:
        raise DuckielibError(
            "There are no tracks to plot; pass at least one track with t, x, y, theta and label."
        )
    checked = []
    for index, track in enumerate(tracks):
        missing = [name for name in ("t", "x", "y", "theta") if not hasattr(track, name)]
        if missing:
            raise DuckielibError(
                f"Track {index} has no {', '.join(missing)}; a track needs the attributes t, x, "
                f"y, theta (1-D arrays) and label."
            )
        label = str(getattr(track, "label", f"track {index}"))
        arrays = [
            np.asarray(getattr(track, name), dtype=float) for name in ("t", "x", "y", "theta")
        ]
        shapes = {array.shape for array in arrays}
        if len(shapes) != 1 or arrays[0].ndim != 1:
            raise DuckielibError(
                f"Track {label!r} needs t, x, y and theta as 1-D arrays of the same length, "
                f"not of shapes {', '.join(str(array.shape) for array in arrays)}."
            )
        if arrays[0].size == 0:
            raise DuckielibError(
                f"Track {label!r} has no samples; check that its topic was recorded in the bag."
            )
        t, x, y, theta = arrays
        checked.append(_Samples(t, x, y, theta, label))
    return checked


def _break_at_wraps(t: np.ndarray, theta: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Wrapped theta with a NaN between samples where it jumps by more than pi.

    Args:
        t: times, shape (N,), in seconds.
        theta: headings, shape (N,), in radians, any range.

    Returns:
        Times and wrapped headings, shape (N + K,) for K jumps; each NaN sits at the midpoint
        time between the two samples around the jump, so that matplotlib breaks the line there.
    """
    wrapped = np.mod(theta, _TWO_PI)
    # A tiny negative angle wraps to 2*pi - tiny, which rounds to 2*pi itself: that is 0.
    wrapped[wrapped >= _TWO_PI] = 0.0
    jumps = np.flatnonzero(np.abs(np.diff(wrapped)) > math.pi) + 1
    times = np.insert(t, jumps, (t[jumps - 1] + t[jumps]) / 2)
    return times, np.insert(wrapped, jumps, np.nan)


def _heading_end(x: float, y: float, theta: float) -> Tuple[float, float]:
    """The tip, in metres, of a heading arrow from (x, y) along theta."""
    return x + _HEADING_LENGTH * math.cos(theta), y + _HEADING_LENGTH * math.sin(theta)


def _reference_pose(reference: Optional[Sequence[float]]) -> Optional[Tuple[float, ...]]:
    """The reference as (x, y) or (x, y, theta) floats, or None."""
    if reference is None:
        return None
    values = np.asarray(reference, dtype=float).ravel()
    if values.size not in (2, 3) or not np.all(np.isfinite(values)):
        raise DuckielibError(
            f"A reference must be a finite (x, y) or (x, y, theta) in metres and radians, "
            f"not {reference!r}."
        )
    return tuple(float(value) for value in values)


def _draw_paths(
    ax: Axes,
    samples: List[_Samples],
    pose: Optional[Tuple[float, ...]],
    grid: bool,
    ends: bool,
) -> List[Line2D]:
    """Draw the paths, their starts, their ends' headings when ``ends``, and the reference.

    Returns:
        The tracks' lines, in the tracks' order.
    """
    lines = []
    # Everything drawn, arrow tips included, for the tile grid to cover.
    xs: List[np.ndarray] = []
    ys: List[np.ndarray] = []
    for track in samples:
        (line,) = ax.plot(
            track.x,
            track.y,
            linewidth=2,
            marker="o" if len(track.t) == 1 else "None",
            label=track.label,
            zorder=3,
        )
        lines.append(line)
        color = line.get_color()
        ax.scatter(track.x[:1], track.y[:1], s=50, facecolors="white", edgecolors=color, zorder=4)
        xs.append(track.x)
        ys.append(track.y)
        end = (float(track.x[-1]), float(track.y[-1]), float(track.theta[-1]))
        if all(math.isfinite(value) for value in end):
            tip = _heading_end(*end)
            if ends:
                _draw_heading(ax, end, color, zorder=4)
            xs.append(np.array([tip[0]]))
            ys.append(np.array([tip[1]]))
    if pose is not None:
        ax.scatter(
            [pose[0]],
            [pose[1]],
            s=180,
            marker="*",
            color=_REFERENCE_COLOR,
            edgecolors="black",
            linewidths=0.5,
            label="reference",
            zorder=5,
        )
        xs.append(np.array([pose[0]]))
        ys.append(np.array([pose[1]]))
        if len(pose) == 3:
            tip = _draw_heading(ax, pose, _REFERENCE_COLOR, zorder=5)
            xs.append(np.array([tip[0]]))
            ys.append(np.array([tip[1]]))
    if grid:
        # The grid covers everything drawn, padded to whole tiles, and the view fits the grid.
        x_low, x_high = tile_span(np.concatenate(xs))
        y_low, y_high = tile_span(np.concatenate(ys))
        draw_tile_grid(ax, (x_low, x_high), (y_low, y_high))
        ax.set_xlim(x_low - _GRID_MARGIN, x_high + _GRID_MARGIN)
        ax.set_ylim(y_low - _GRID_MARGIN, y_high + _GRID_MARGIN)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    handles, labels = ax.get_legend_handles_labels()
    handles.append(
        Line2D([], [], color="gray", marker="o", markerfacecolor="white", linestyle="None")
    )
    labels.append("start")
    if ends:
        handles.append(
            Line2D([], [], color="gray", marker=r"$\rightarrow$", markersize=12, linestyle="None")
        )
        labels.append("end (heading)")
    ax.legend(handles, labels, loc="best", fontsize="small")
    return lines


def _draw_heading(
    ax: Axes, pose: Sequence[float], color: ColorType, zorder: float
) -> Tuple[float, float]:
    """Draw an arrow from (x, y) along theta; return its tip, in metres."""
    tip = _heading_end(*pose)
    ax.annotate(
        "",
        xy=tip,
        xytext=(pose[0], pose[1]),
        arrowprops={"arrowstyle": "-|>", "color": color, "linewidth": 2, "shrinkA": 0},
        zorder=zorder,
    )
    return tip


def plot_path(
    tracks: Tracks,
    ax: Optional[Axes] = None,
    reference: Optional[Sequence[float]] = None,
    grid: bool = True,
) -> Axes:
    """Draw the tracks' x-y paths on the mat, seen from above.

    Each track is a line with its label, an open circle where it starts and an arrow along its
    last heading where it ends. Under them, a light grid shows the mat's tiles, covering the
    paths padded to whole tiles.

    Args:
        tracks: one track or a sequence of them (see the module docstring).
        ax: the axes to draw on; a new figure when None.
        reference: a target pose drawn as a star labelled "reference": (x, y) in metres, or
            (x, y, theta) with theta in radians, also drawn as an arrow.
        grid: whether to draw the tile grid (and fit the view to it).

    Returns:
        The axes drawn on.

    Raises:
        DuckielibError: if there is no track, a track has no samples or arrays of different
            lengths, or ``reference`` is not an (x, y) or (x, y, theta).
    """
    samples = _as_samples(tracks)
    pose = _reference_pose(reference)
    if ax is None:
        ax = NotebookFigure(figsize=(6, 6), layout="constrained").add_subplot()
    _draw_paths(ax, samples, pose, grid=grid, ends=True)
    return ax


def _draw_pose_over_time(samples: List[_Samples], axes: Sequence[Axes], legend: bool) -> None:
    ax_x, ax_y, ax_theta = axes
    for track in samples:
        marker = "o" if len(track.t) == 1 else "None"
        (line,) = ax_x.plot(track.t, track.x, marker=marker, label=track.label)
        color = line.get_color()
        ax_y.plot(track.t, track.y, marker=marker, color=color, label=track.label)
        times, theta = _break_at_wraps(track.t, track.theta)
        ax_theta.plot(times, theta, marker=marker, color=color, label=track.label)
    ax_x.set_ylabel("x (m)")
    ax_y.set_ylabel("y (m)")
    ax_theta.set_ylabel("θ (rad)")
    ax_theta.set_yticks(_THETA_TICKS, _THETA_TICK_LABELS)
    ax_theta.set_ylim(0.0, _TWO_PI)
    ax_theta.set_xlabel("t (s)")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    for ax in axes[:2]:
        ax.tick_params(labelbottom=False)
    if legend:
        ax_x.legend(loc="best", fontsize="small")


def plot_pose_over_time(tracks: Tracks, axes: Optional[Sequence[Axes]] = None) -> List[Axes]:
    """Draw x(t), y(t) and theta(t) of the tracks, one above the other, on a shared time axis.

    Theta is wrapped into [0, 2*pi) and its line is broken (a NaN is inserted) where it jumps by
    more than pi between two samples, so a wrap shows as the line leaving at the top and coming
    back at the bottom (or the other way), not as a vertical stroke.

    Args:
        tracks: one track or a sequence of them (see the module docstring).
        axes: three axes to draw x, y and theta on, top to bottom, used as they are (share
            their x axis yourself); a new figure with a shared time axis when None.

    Returns:
        The three axes: x (m), y (m) and theta (rad), against t (s).

    Raises:
        DuckielibError: if there is no track, a track has no samples, or ``axes`` does not hold
            three axes.
    """
    samples = _as_samples(tracks)
    if axes is None:
        axes = list(
            NotebookFigure(figsize=(7, 6), layout="constrained").subplots(3, 1, sharex=True)
        )
    axes = list(axes)
    if len(axes) != 3:
        raise DuckielibError(
            f"plot_pose_over_time draws on 3 axes (x, y and theta), not {len(axes)}; pass three "
            f"or none."
        )
    _draw_pose_over_time(samples, axes, legend=True)
    return axes


def pose_figure(
    tracks: Tracks, title: Optional[str] = None, reference: Optional[Sequence[float]] = None
) -> Figure:
    """A figure comparing tracks: the paths on the left, x, y and theta over time on the right.

    Args:
        tracks: one track or a sequence of them (see the module docstring).
        title: the figure's title, if any.
        reference: a target pose for the path plot: (x, y) in metres or (x, y, theta).

    Returns:
        The figure, 12 x 6 inches, with four axes: the path, then x(t), y(t) and theta(t).

    Raises:
        DuckielibError: if there is no track, a track has no samples, or ``reference`` is not
            an (x, y) or (x, y, theta).
    """
    samples = _as_samples(tracks)
    fig = NotebookFigure(figsize=(12, 6), layout="constrained")
    grid = fig.add_gridspec(3, 2)
    path_ax = fig.add_subplot(grid[:, 0])
    ax_x = fig.add_subplot(grid[0, 1])
    ax_y = fig.add_subplot(grid[1, 1], sharex=ax_x)
    ax_theta = fig.add_subplot(grid[2, 1], sharex=ax_x)
    plot_path(samples, ax=path_ax, reference=reference)
    # The path's legend names the tracks and their colours for all four plots.
    _draw_pose_over_time(samples, [ax_x, ax_y, ax_theta], legend=False)
    if title is not None:
        fig.suptitle(title)
    return fig


def animate_path(tracks: Tracks, fps: float = 15.0, speed: float = 1.0) -> FuncAnimation:
    """An animation of the tracks' paths growing over time on the mat.

    Frame k shows every sample with ``t <= t0 + k * speed / fps``, where t0 is the earliest
    start of all tracks, and a marker with a heading tick at each track's latest pose. The
    frames cover the union of the tracks' time spans; the last one shows them whole.

    Args:
        tracks: one track or a sequence of them (see the module docstring); their ``t`` must
            not decrease.
        fps: frames per second of the animation.
        speed: seconds of the tracks per second of animation (2.0 plays twice as fast).

    Returns:
        The animation; each frame's data is its time in seconds. In a notebook, show it with
        ``IPython.display.HTML(anim.to_jshtml())``.

    Raises:
        DuckielibError: if there is no track, a track has no samples or goes back in time, or
            ``fps`` or ``speed`` is not a positive number.
    """
    from matplotlib import animation
    from matplotlib import pyplot as plt

    samples = _as_samples(tracks)
    for name, value in (("fps", fps), ("speed", speed)):
        if not (math.isfinite(value) and value > 0):
            raise DuckielibError(f"animate_path needs a positive {name}, not {value!r}.")
    for track in samples:
        if np.any(np.diff(track.t) < 0):
            raise DuckielibError(
                f"Track {track.label!r} goes back in time; sort its samples by t before "
                f"animating it."
            )
    start = min(float(track.t[0]) for track in samples)
    end = max(float(track.t[-1]) for track in samples)
    step = speed / fps
    # The small tolerance keeps a span of exactly k steps from getting a frame k + 1.
    count = math.ceil((end - start) / step - 1e-9) + 1
    times = [min(start + k * step, end) for k in range(count)]

    fig = plt.figure(figsize=(6, 6))
    ax = fig.add_subplot()
    moving = []
    for line in _draw_paths(ax, samples, None, grid=True, ends=False):
        line.set_data([], [])
        color = line.get_color()
        (marker,) = ax.plot([], [], marker="o", color=color, markersize=8, zorder=5)
        (heading,) = ax.plot([], [], color=color, linewidth=2, zorder=5)
        moving.append((line, marker, heading))
    text = ax.set_title("")

    def draw(time: float) -> List[Artist]:
        artists: List[Artist] = [text]
        for track, (line, marker, heading) in zip(samples, moving):
            shown = int(np.searchsorted(track.t, time, side="right"))
            line.set_data(track.x[:shown], track.y[:shown])
            if shown:
                x, y, theta = track.x[shown - 1], track.y[shown - 1], track.theta[shown - 1]
                marker.set_data([x], [y])
                tip = _heading_end(x, y, theta)
                heading.set_data([x, tip[0]], [y, tip[1]])
            else:
                marker.set_data([], [])
                heading.set_data([], [])
            artists += [line, marker, heading]
        text.set_text(f"t = {time:.2f} s")
        return artists

    anim = animation.FuncAnimation(fig, draw, frames=times, interval=1000.0 / fps, blit=False)
    # The animation keeps the figure; closing it keeps a notebook from also showing it still.
    plt.close(fig)
    return anim
