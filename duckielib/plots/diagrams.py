"""The notebooks' diagrams: each drawn with one call, so that a notebook cell stays short.

- :func:`plot_mission_states`: a mission's states as boxes in their LED colours, in order.

The nodes and topics of a graph are drawn from the graph itself, by
:func:`~duckielib.plots.rosgraph.plot_ros_graph`.

They need only matplotlib and the pure modules (:mod:`duckielib.leds`,
:mod:`duckielib.missions`), and draw on a :class:`~duckielib.plots.canvas.NotebookFigure` unless
given axes. Like every module of :mod:`duckielib.plots`, the library's only package that
imports matplotlib, it runs on the laptop only.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Optional

from matplotlib.patches import Rectangle

from duckielib.leds import pattern_colors, pattern_named
from duckielib.missions import Mission, describe_move
from duckielib.plots.canvas import NotebookFigure

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["plot_mission_states"]


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
        ax = NotebookFigure(figsize=(13, 3.2), layout="constrained").add_subplot()
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
