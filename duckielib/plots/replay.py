"""The figure of a replay (:func:`duckielib.sim.replay.replay_bag`).

Where odometry puts the robot from a bag's ticks and from the simulated ones, and where the
simulated robot really went.

Made without pyplot, so it draws headless and from the ``duckie`` command.
"""

from __future__ import annotations

import os
from typing import Any, Union

import numpy as np
from matplotlib.figure import Figure

__all__ = ["replay_figure"]


def replay_figure(report: Any, path: Union[str, os.PathLike[str]]) -> str:
    """Draw a replay's paths and headings to ``path`` (a PNG).

    Left: where odometry puts the robot from the bag's ticks and from the simulated ones, and
    the simulated robot's true path, all from (0, 0) facing +x. Right: their headings over time.

    Args:
        report: a :class:`~duckielib.sim.replay.ReplayReport` made with a solution (its
            ``paths``).
        path: the file to write.

    Returns:
        The path written.

    Raises:
        ValueError: if the report has no paths (the replay was made without a solution).
    """
    if report.paths is None:
        raise ValueError("The replay compared no paths: give it a solution's odometry.")
    tracks = (
        (report.paths.real, "odometry from the bag's ticks", "tab:blue", "-"),
        (report.paths.sim, "odometry from the simulated ticks", "tab:orange", "-"),
        (report.paths.truth, "the simulated robot's true path", "tab:gray", "--"),
    )
    fig = Figure(figsize=(12, 5))
    where, heading = fig.subplots(1, 2)
    for track, label, color, style in tracks:
        where.plot(track.x, track.y, style, color=color, label=label)
        heading.plot(track.t, np.unwrap(track.theta), style, color=color, label=label)
    where.plot([0.0], [0.0], "ko", label="start")
    where.set_aspect("equal", adjustable="datalim")
    where.set_xlabel("x (m), facing +x at the start")
    where.set_ylabel("y (m)")
    where.legend(fontsize=8)
    heading.set_xlabel("t (s) from the first command")
    heading.set_ylabel("heading (rad), unwrapped")
    figures = report.paths.figures()
    real, simulated = figures["heading_change_real_rad"], figures["heading_change_sim_rad"]
    fig.suptitle(
        f"{report.bag} replayed on {report.noise}\nheading {real:+.2f} rad on the bag, "
        f"{simulated:+.2f} rad simulated"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    return str(path)
