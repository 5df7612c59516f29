"""Plots of robot pose tracks with matplotlib: odometry estimates against the ground truth.

This is the module where matplotlib is imported to look at recorded runs (ROS bags); it needs
only numpy and matplotlib, not the simulator nor rosbags. Figures are made with
:class:`matplotlib.figure.Figure` rather than pyplot, so they work headless and from the
``duckie`` command; only :func:`animate_path` uses pyplot.

A *track* is any object with these attributes (a dataclass, a named tuple, what the bags module
reads):

- ``t``: sample times, shape (N,), in seconds, in increasing order.
- ``x``, ``y``: positions in the world frame, shape (N,), in metres.
- ``theta``: headings, shape (N,), in radians, counter-clockwise from the world x axis.
- ``label``: the name shown in legends, such as ``"odometry"`` or ``"ground truth"``.

Conventions: SI units, the world frame seen from above with x to the right and y up, equal
scales on both axes, and theta shown wrapped into [0, 2*pi). The light grid drawn under the
paths is the mat's tiles, :data:`duckielib.config.TILE_SIZE` metres apart.

- :func:`plot_path`: the x-y paths on the mat, with where each track started and ended.
- :func:`plot_pose_over_time`: x(t), y(t) and theta(t), one above the other.
- :func:`pose_figure`: both in one figure, the usual way to compare two tracks.
- :func:`animate_path`: the paths growing over time.
- :func:`save_figure`: write a figure as PNG, SVG or PDF.

Diagrams of the notebooks live here too, so that a notebook shows each with one call:

- :func:`plot_topic_ends`: each topic between the nodes that publish and subscribe to it.

- :func:`plot_mission_states`: a mission's states as boxes in their LED colours, in order.
- :func:`plot_mission_nodes`: the nodes of a mission run and the topics and services between
  them.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import (
    TYPE_CHECKING,
    List,
    Mapping,
    NamedTuple,
    Optional,
    Sequence,
    Tuple,
    Union,
)

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle

from duckielib.config import TILE_SIZE
from duckielib.errors import DuckielibError
from duckielib.leds import pattern_colors, pattern_named
from duckielib.missions import Mission, describe_move

if TYPE_CHECKING:
    from typing import Protocol

    from matplotlib.animation import FuncAnimation
    from matplotlib.axes import Axes

    class _Track(Protocol):
        """What a track must provide (see the module docstring)."""

        t: np.ndarray
        x: np.ndarray
        y: np.ndarray
        theta: np.ndarray
        label: str

    Tracks = Union[_Track, Sequence[_Track]]

__all__ = [
    "plot_mission_nodes",
    "plot_mission_states",
    "plot_path",
    "plot_pose_over_time",
    "plot_topic_ends",
    "pose_figure",
    "animate_path",
    "save_animation",
    "save_figure",
]

_TWO_PI = 2.0 * math.pi


class _Figure(Figure):
    """A figure that shows itself in a notebook as a picture.

    Jupyter draws pyplot's figures once pyplot's backend has started; a figure made without
    pyplot, as here (headless, for the ``duckie`` command too), would otherwise be shown as the
    text ``<Figure size ...>`` until some cell has used pyplot.
    """

    def _repr_png_(self) -> bytes:
        from io import BytesIO

        buffer = BytesIO()
        self.savefig(buffer, format="png", bbox_inches="tight")
        return buffer.getvalue()


#: Length of the arrows that show a heading, in metres (about a Duckiebot's length).
_HEADING_LENGTH = 0.12
_GRID_COLOR = "#d0d0d0"
_REFERENCE_COLOR = "#d62728"
_THETA_TICKS = (0.0, math.pi / 2, math.pi, 3 * math.pi / 2, _TWO_PI)
_THETA_TICK_LABELS = ("0", "π/2", "π", "3π/2", "2π")
_FIGURE_FORMATS = (".png", ".svg", ".pdf")


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
        tracks = [tracks]  # type: ignore[list-item]
    tracks = list(tracks)  # type: ignore[arg-type]
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
        checked.append(_Samples(*arrays, label=label))
    return checked


def _wrap(theta: np.ndarray) -> np.ndarray:
    """Angles in radians wrapped into [0, 2*pi), same shape."""
    wrapped = np.mod(theta, _TWO_PI)
    # A tiny negative angle wraps to 2*pi - tiny, which rounds to 2*pi itself.
    return np.where(wrapped >= _TWO_PI, 0.0, wrapped)


def _break_at_wraps(t: np.ndarray, theta: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Wrapped theta with a NaN between samples where it jumps by more than pi.

    Args:
        t: times, shape (N,), in seconds.
        theta: headings, shape (N,), in radians, any range.

    Returns:
        Times and wrapped headings, shape (N + K,) for K jumps; each NaN sits at the midpoint
        time between the two samples around the jump, so that matplotlib breaks the line there.
    """
    wrapped = _wrap(theta)
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


def _tile_range(values: np.ndarray) -> Tuple[float, float]:
    """The smallest run of whole tiles, in metres, that covers ``values`` (at least one tile)."""
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return 0.0, TILE_SIZE
    low = math.floor(float(finite.min()) / TILE_SIZE)
    high = math.ceil(float(finite.max()) / TILE_SIZE)
    if high <= low:
        high = low + 1
    return low * TILE_SIZE, high * TILE_SIZE


def _draw_tile_grid(ax: Axes, xs: np.ndarray, ys: np.ndarray) -> None:
    """Draw the mat's tile borders under everything and fit the view to them.

    The grid covers ``xs`` and ``ys`` (positions in metres, any shape) padded to whole tiles.
    """
    x_low, x_high = _tile_range(xs)
    y_low, y_high = _tile_range(ys)
    columns = round((x_high - x_low) / TILE_SIZE)
    rows = round((y_high - y_low) / TILE_SIZE)
    segments = [
        [(x_low + i * TILE_SIZE, y_low), (x_low + i * TILE_SIZE, y_high)]
        for i in range(columns + 1)
    ]
    segments += [
        [(x_low, y_low + j * TILE_SIZE), (x_high, y_low + j * TILE_SIZE)] for j in range(rows + 1)
    ]
    ax.add_collection(
        LineCollection(segments, colors=_GRID_COLOR, linewidths=1.0, zorder=0.5, gid="tile-grid"),
        autolim=False,
    )
    margin = 0.02 * TILE_SIZE
    ax.set_xlim(x_low - margin, x_high + margin)
    ax.set_ylim(y_low - margin, y_high + margin)


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
        _draw_tile_grid(ax, np.concatenate(xs), np.concatenate(ys))
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
    ax: Axes, pose: Sequence[float], color: str, zorder: float
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
        ax = _Figure(figsize=(6, 6), layout="constrained").add_subplot()
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
        axes = list(_Figure(figsize=(7, 6), layout="constrained").subplots(3, 1, sharex=True))
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
    fig = _Figure(figsize=(12, 6), layout="constrained")
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

    def draw(time: float) -> List[object]:
        artists: List[object] = [text]
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


def save_figure(fig: Figure, path: Union[str, Path]) -> Path:
    """Save ``fig`` as PNG, SVG or PDF, chosen by the suffix of ``path``.

    Args:
        fig: the figure to save.
        path: the file to write, ending in .png, .svg or .pdf; its folder must exist.

    Returns:
        The path written.

    Raises:
        DuckielibError: if the suffix is none of those, the folder does not exist, or the file
            cannot be written.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in _FIGURE_FORMATS:
        raise DuckielibError(
            f"Cannot save the figure as {str(path)!r}: use a name ending in .png, .svg or .pdf."
        )
    if not path.parent.is_dir():
        raise DuckielibError(
            f"Cannot save the figure as {str(path)!r}: the folder {str(path.parent)!r} does not "
            f"exist; create it first or choose another path."
        )
    try:
        fig.savefig(path, format=suffix[1:], dpi=150 if suffix == ".png" else "figure")
    except OSError as error:
        raise DuckielibError(
            f"Cannot save the figure as {str(path)!r}: {error.strerror or error}; check that "
            f"you may write there."
        ) from error
    return path


def save_animation(
    anim: FuncAnimation, path: Union[str, Path], fps: float = 15.0, dpi: float = 72.0
) -> Path:
    """Save an animation from :func:`animate_path` as an animated GIF, and return the path.

    The file appears whole or not at all: it is written under another name first.

    Args:
        anim: the animation.
        path: the ``.gif`` to write.
        fps: frames per second of the GIF (give the ``fps`` the animation was made with).
        dpi: resolution; the animation's figure is 6 x 6 inches.

    Raises:
        DuckielibError: if ``path`` does not end in ``.gif`` or its folder does not exist.
    """
    from matplotlib.animation import PillowWriter

    path = Path(path)
    if path.suffix.lower() != ".gif":
        raise DuckielibError(f"{path} must end in .gif: animations are saved as GIFs.")
    if not path.parent.is_dir():
        raise DuckielibError(f"There is no folder {path.parent} to write {path.name} into.")
    partial = path.with_name(path.stem + ".partial.gif")
    anim.save(str(partial), writer=PillowWriter(fps=fps), dpi=dpi)
    partial.replace(path)
    return path


def plot_mission_states(mission: Mission, ax: Optional[Axes] = None) -> Axes:
    """Draw a mission's states as boxes in their LED colours, joined by their transitions.

    Each box holds the state's name, its colour and its moves; each arrow says when the state
    moves on (after its stop, or when its moves are done).

    Args:
        mission: the mission (:mod:`duckielib.missions`).
        ax: the axes to draw on; a new figure when None.

    Returns:
        The axes drawn on.
    """
    if ax is None:
        ax = _Figure(figsize=(13, 3.2), layout="constrained").add_subplot()
    width, gap = 1.6, 0.7
    end = 0.0
    for index, state in enumerate(mission.states):
        left = index * (width + gap)
        fill = pattern_colors(pattern_named(state.color))[0]
        ax.add_patch(Rectangle((left, 0), width, 1, facecolor=fill, alpha=0.35, edgecolor="black"))
        moves = "\n".join(describe_move(move) for move in state.moves)
        text = f"{state.name}\n({state.color})\n\n{moves}"
        ax.text(left + width / 2, 0.95, text, ha="center", va="top", fontsize=8)
        label = f"after {state.stop_seconds:g} s" if state.is_stop else "moves\ndone"
        end = left + width + gap
        ax.annotate("", (end, 0.5), (left + width, 0.5), arrowprops={"arrowstyle": "->"})
        ax.text(left + width + gap / 2, 0.56, label, ha="center", va="bottom", fontsize=7)
    ax.text(end + 0.05, 0.5, "done", va="center", fontsize=9, fontweight="bold")
    ax.set_xlim(-0.1, end + 0.6)
    ax.set_ylim(-0.05, 1.05)
    ax.set_title(f"{mission.name}: {mission.description}", fontsize=10)
    ax.axis("off")
    return ax


#: The boxes of :func:`plot_mission_nodes`: name -> (x, y, text, whose node it is).
_MISSION_BOXES = {
    "encoders": (0.0, 2.0, "left/right_wheel_encoder_node\n[the robot]", "robot"),
    "odometry": (4.5, 2.0, "odometry_node\n[your 05 functions]", "yours"),
    "mission": (9.0, 2.0, "mission_node\n[yours: notebook 09]", "yours"),
    "wheels": (13.6, 2.0, "car_cmd_switch_node\n→ the wheels\n[the robot]", "robot"),
    "light": (9.0, 0.0, "light_service_node\n[yours: notebook 08]", "yours"),
    "leds": (13.6, 0.0, "led_emitter_node\n[the robot]", "robot"),
    "bag": (9.0, 3.6, "the bag, the grader\n[run_mission]", "runner"),
}
#: Its links: (from, to, topic or service name, whether it is a service call).
_MISSION_LINKS = (
    ("encoders", "odometry", "~tick", False),
    ("odometry", "mission", "odometry_node/pose", False),
    ("mission", "wheels", "car_cmd_switch_node/cmd", False),
    ("mission", "light", "light_service_node/set_color", True),
    ("mission", "light", "shutdown", False),
    ("light", "leds", "led_emitter_node/set_pattern", True),
    ("mission", "bag", "~state", False),
)
_BOX_FILL = {"yours": "#ffe9a8", "robot": "#e4e4e4", "runner": "#f6f6f6"}


def plot_mission_nodes(ax: Optional[Axes] = None) -> Axes:
    """Draw the nodes of a mission run and how they talk: topics solid, service calls dashed.

    Yellow boxes are the student's nodes, grey ones the robot's drivers; names are relative to
    the robot's namespace ``/VEH/``.

    Args:
        ax: the axes to draw on; a new figure when None.

    Returns:
        The axes drawn on.
    """
    if ax is None:
        ax = _Figure(figsize=(13, 4.2)).add_axes((0, 0, 1, 1))
    boxes = {
        name: ax.text(
            x,
            y,
            text,
            ha="center",
            va="center",
            fontsize=9,
            bbox={"boxstyle": "round,pad=0.5", "facecolor": _BOX_FILL[whose]},
        )
        for name, (x, y, text, whose) in _MISSION_BOXES.items()
    }
    for source, target, label, service in _MISSION_LINKS:
        (x0, y0, _, _), (x1, y1, _, _) = _MISSION_BOXES[source], _MISSION_BOXES[target]
        # Two links join the mission and the light service: side by side, not on top.
        shift = (-0.5 if service else 0.5) if (source, target) == ("mission", "light") else 0.0
        color = "tab:blue" if service else "black"
        ax.annotate(
            "",
            (x1 + shift, y1),
            (x0 + shift, y0),
            arrowprops={
                "arrowstyle": "-|>",
                "linestyle": "--" if service else "-",
                "color": color,
                "patchA": boxes[source].get_bbox_patch(),
                "patchB": boxes[target].get_bbox_patch(),
            },
        )
        if y0 == y1:
            ax.text(
                (x0 + x1) / 2, y0 + 0.12, label, ha="center", va="bottom", fontsize=8, color=color
            )
        else:
            ax.text(
                x0 + shift + (0.1 if shift >= 0 else -0.1),
                (y0 + y1) / 2,
                label,
                ha="left" if shift >= 0 else "right",
                va="center",
                fontsize=8,
                color=color,
            )
    ax.set_xlim(-1.7, 15.1)
    ax.set_ylim(-0.7, 4.2)
    ax.text(
        -1.5,
        -0.55,
        "solid: a topic (publisher → subscriber)\ndashed: a service call (client → server)",
        fontsize=8,
    )
    ax.axis("off")
    return ax


def plot_topic_ends(
    ends: Mapping[str, Tuple[Sequence[str], Sequence[str]]], ax: Optional[Axes] = None
) -> Axes:
    """Draw each topic with the nodes that publish to it (left) and subscribe to it (right).

    Args:
        ends: ``{topic: (publishers, subscribers)}``, node names as ``rosnode list`` gives them.
        ax: the axes to draw on; a new figure when None.

    Returns:
        The axes drawn on.
    """
    if ax is None:
        ax = _Figure(figsize=(13, 0.9 * len(ends) + 0.3)).add_axes((0, 0, 1, 1))
    node_box = {"boxstyle": "round", "facecolor": "#cfe2f3"}
    topic_box = {"boxstyle": "square", "facecolor": "#fce5cd"}
    arrow = {"arrowstyle": "->", "shrinkA": 4, "shrinkB": 4}
    for row, (topic, (publishers, subscribers)) in enumerate(ends.items()):
        middle = ax.text(0.5, -row, topic, ha="center", va="center", bbox=topic_box, size=9)
        left, right = (
            ax.text(x, -row, "\n".join(nodes) or "(nobody)", ha="center", va="center",
                    bbox=node_box, size=9)
            for x, nodes in ((0.1, publishers), (0.9, subscribers))
        )  # fmt: skip
        for start, end in ((left, middle), (middle, right)):
            ax.annotate(
                "", xy=(0, 0.5), xycoords=end, xytext=(1, 0.5), textcoords=start, arrowprops=arrow
            )
    ax.set_xlim(-0.05, 1.05)
    ax.set_ylim(-len(ends) + 0.5, 0.5)
    ax.axis("off")
    return ax
