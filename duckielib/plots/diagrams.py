"""The notebooks' diagrams: each drawn with one call, so that a notebook cell stays short.

- :func:`plot_topic_ends`: each topic between the nodes that publish and subscribe to it.
- :func:`plot_mission_states`: a mission's states as boxes in their LED colours, in order.
- :func:`plot_mission_nodes`: the nodes of a mission run and the topics and services between
  them.

They need only matplotlib and the pure modules (:mod:`duckielib.leds`,
:mod:`duckielib.missions`), and draw on a :class:`~duckielib.plots.canvas.NotebookFigure` unless
given axes. Like every module of :mod:`duckielib.plots`, the library's only package that
imports matplotlib, it runs on the laptop only.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Mapping, Optional, Sequence, Tuple

from matplotlib.patches import Rectangle

from duckielib.leds import pattern_colors, pattern_named
from duckielib.missions import Mission, describe_move
from duckielib.plots.canvas import NotebookFigure

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["plot_mission_nodes", "plot_mission_states", "plot_topic_ends"]


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
        ax = NotebookFigure(figsize=(13, 4.2)).add_axes((0, 0, 1, 1))
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
        ax = NotebookFigure(figsize=(13, 0.9 * len(ends) + 0.3)).add_axes((0, 0, 1, 1))
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
