"""Pictures with matplotlib: pose tracks, the simulator's world, the notebooks' diagrams.

This package is the only place of the library that imports matplotlib (laptop only); nothing
outside it draws, and the modules it draws (the simulator, the bags) never import it back.

- :mod:`~duckielib.plots.paths`: pose tracks (odometry against the ground truth) as paths on
  the mat and over time, and their animation;
- :mod:`~duckielib.plots.world`: the simulator's mat, the robot with its LEDs, and its runs;
- :mod:`~duckielib.plots.player`: a run played back: robot, LEDs, paths, state and camera,
  with play, pause and a time slider in a notebook, or as a GIF or MP4;
- :mod:`~duckielib.plots.camera`: an image topic on screen, live or from a bag;
- :mod:`~duckielib.plots.diagrams`: the notebooks' diagrams of missions;
- :mod:`~duckielib.plots.driving`: the driving experiments' figures (speed sweeps, the last
  ticks of a stop, silent encoders, the odometry's gap over a run);
- :mod:`~duckielib.plots.rosgraph`: the ROS graph drawn from the graph itself (``rqt_graph``);
- :mod:`~duckielib.plots.files`: every figure and animation written to a file, whole or not
  at all;
- :mod:`~duckielib.plots.canvas`: what they share: a figure that shows itself in a notebook,
  and the one drawing of the mat's tiles.

Every name in a module's ``__all__`` is imported here, so ``from duckielib.plots import ...``
is all a notebook or a command needs; other names are the package's own.
"""

from duckielib.plots.camera import ImageView
from duckielib.plots.canvas import draw_tile_grid
from duckielib.plots.diagrams import plot_mission_states
from duckielib.plots.driving import (
    plot_encoder_silence,
    plot_gap_over_time,
    plot_speed_sweep,
    plot_ticks_around_stop,
)
from duckielib.plots.files import save_animation, save_figure, save_gif_frames
from duckielib.plots.paths import animate_path, plot_path, plot_pose_over_time, pose_figure
from duckielib.plots.player import Recording, RunPlayer
from duckielib.plots.replay import replay_figure
from duckielib.plots.rosgraph import plot_ros_graph
from duckielib.plots.world import animate_run, animation_html, draw_mat, draw_robot, plot_run

__all__ = [
    "ImageView",
    "Recording",
    "RunPlayer",
    "animate_path",
    "animate_run",
    "animation_html",
    "draw_mat",
    "draw_robot",
    "draw_tile_grid",
    "plot_encoder_silence",
    "plot_gap_over_time",
    "plot_mission_states",
    "plot_path",
    "plot_pose_over_time",
    "plot_ros_graph",
    "plot_run",
    "plot_speed_sweep",
    "plot_ticks_around_stop",
    "pose_figure",
    "replay_figure",
    "save_animation",
    "save_figure",
    "save_gif_frames",
]
