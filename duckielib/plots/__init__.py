"""Pictures with matplotlib: pose tracks, the mat and the robot, the notebooks' diagrams.

This package is the library's only place that imports matplotlib (laptop only).

- :mod:`~duckielib.plots.paths`: pose tracks (odometry against the ground truth) as paths
  on the mat and over time, their animation, and the notebooks' diagrams;
- :mod:`~duckielib.plots.world`: the simulator's mat, the robot with its LEDs, and its runs.
"""

from duckielib.plots.paths import (
    animate_path,
    plot_mission_nodes,
    plot_mission_states,
    plot_path,
    plot_pose_over_time,
    plot_topic_ends,
    pose_figure,
    save_animation,
    save_figure,
)

__all__ = [
    "animate_path",
    "plot_mission_nodes",
    "plot_mission_states",
    "plot_path",
    "plot_pose_over_time",
    "plot_topic_ends",
    "pose_figure",
    "save_animation",
    "save_figure",
]
