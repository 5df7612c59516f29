"""Figures of the driving experiments: speed sweeps, the last ticks of a stop, silent encoders.

Each function draws on axes the notebook made (``plt.subplots``), so that the notebook still
chooses the figure's size and shows it where its printouts expect it. They take plain numbers
and arrays (what :mod:`duckielib.sim.tasks` returns), never the student's functions.

- :func:`plot_speed_sweep`: where the robot stopped, and how wrong its odometry was, by speed;
- :func:`plot_ticks_around_stop`: an encoder's count around a zero command, against the truth;
- :func:`plot_encoder_silence`: distance and commands of runs whose encoders fell silent;
- :func:`plot_gap_over_time`: the odometry's position and heading gaps over a run.

Like every module of :mod:`duckielib.plots`, the library's only package that imports
matplotlib, it runs on the laptop only.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Mapping, Sequence, Tuple

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = [
    "plot_encoder_silence",
    "plot_gap_over_time",
    "plot_speed_sweep",
    "plot_ticks_around_stop",
]

#: The minus sign of the labels (a typographic minus, not a hyphen).
MINUS = "\N{MINUS SIGN}"


def plot_speed_sweep(
    rows: Sequence[Mapping[str, float]],
    axes: Sequence[Axes],
    moves: int,
    slowest_moving: float,
) -> None:
    """Draw a speed sweep of the straight-line task on two axes, in centimetres.

    Left: where the robot really stopped after the first move (along the heading minus the
    goal, and to the left). Right: the odometry's position error there, and how far from the
    start the robot ended after the way back. Speeds that did not finish are crosses at 0.

    Args:
        rows: one mapping per speed (see :func:`duckielib.sim.tasks.speed_sweep_row`), in
            metres: ``v``, ``done``, and for finished runs ``along``, ``side``, ``odometry``,
            ``from_start``.
        axes: the two axes, left and right.
        moves: how many moves a finished run did.
        slowest_moving: the slowest speed that moves the robot, m/s, drawn as a dashed line.
    """
    ax_truth, ax_odometry = axes
    finished = [row for row in rows if row["done"] == moves]
    stuck = [row["v"] for row in rows if row["done"] < moves]
    v_values = [row["v"] for row in finished]
    ax_truth.plot(
        v_values,
        [100 * row["along"] for row in finished],
        "o-",
        label="along the heading, minus 1.25 m",
    )
    ax_truth.plot(v_values, [100 * row["side"] for row in finished], "s-", label="to the left")
    ax_truth.axhline(0.0, color="black", linewidth=0.8)
    ax_truth.set_title("Where the robot really stopped, after 1.25 m")
    ax_odometry.plot(
        v_values,
        [100 * row["odometry"] for row in finished],
        "o-",
        label=f"odometry {MINUS} truth, after 1.25 m",
    )
    ax_odometry.plot(
        v_values,
        [100 * row["from_start"] for row in finished],
        "s-",
        label=f"truth {MINUS} start, after the way back",
    )
    ax_odometry.set_title("How wrong the odometry is, and the return")
    for ax in (ax_truth, ax_odometry):
        ax.axvline(
            slowest_moving, color="tab:red", linestyle="--", linewidth=1, label="slowest that moves"
        )
        if stuck:
            ax.plot(
                stuck,
                [0.0] * len(stuck),
                "x",
                color="tab:red",
                markersize=10,
                label="did not finish",
            )
        ax.set_xlabel("v (m/s)")
        ax.set_ylabel("cm")
        ax.grid(alpha=0.3)
        ax.legend()


def plot_ticks_around_stop(
    ax: Axes,
    ticks: Sequence[Sequence[float]],
    t_stop: float,
    truth_t: Sequence[float],
    truth_along: Sequence[float],
    one_tick: float,
    before: float = 0.4,
    after: float = 0.6,
) -> None:
    """Draw an encoder's count around a zero command, and the true travel in ticks' worth.

    Both curves are drawn from the zero command on the time axis (t - t_stop) and from their
    values at the zero command, so that a count going the wrong way shows at once.

    Args:
        ax: the axes.
        ticks: the encoder's readings, ``(t in s, cumulative count)`` in time order, at least
            one at or before ``t_stop``.
        t_stop: when the zero command was sent, s.
        truth_t: times of the true poses, s, shape (N,).
        truth_along: the true distance along the move's heading at those times, m, shape (N,).
        one_tick: a tick's worth of wheel travel, m.
        before: how long before the zero command to draw, s.
        after: how long after it, s.
    """
    readings = np.asarray(ticks, dtype=float)
    near = (readings[:, 0] > t_stop - before) & (readings[:, 0] < t_stop + after)
    at_stop = readings[readings[:, 0] <= t_stop][-1, 1]
    ax.plot(
        readings[near, 0] - t_stop,
        readings[near, 1] - at_stop,
        "o-",
        label="right wheel: counted ticks",
    )
    times = np.asarray(truth_t, dtype=float)
    along = np.asarray(truth_along, dtype=float)
    near_truth = (times > t_stop - before) & (times < t_stop + after)
    along_at_stop = along[max(0, int(np.searchsorted(times, t_stop, side="right")) - 1)]
    ax.plot(
        times[near_truth] - t_stop,
        (along[near_truth] - along_at_stop) / one_tick,
        "--",
        label="truth: travel in ticks' worth",
    )
    ax.axvline(0.0, color="grey", linewidth=1)
    ax.set_xlabel(f"t {MINUS} t(zero command) (s)")
    ax.grid(alpha=0.3)


def plot_encoder_silence(
    runs: Mapping[str, Tuple[np.ndarray, np.ndarray, Sequence[Tuple[float, float, object]]]],
    axes: Sequence[Axes],
    silence_at: float,
    grace: float = 0.5,
) -> None:
    """Draw runs whose encoders fell silent: distance from the start, and the speed sent.

    Args:
        runs: by label, ``(times, distances, commands)``: sample times (s), the true distance
            from the start (m) and the commands sent, ``(t, v, ...)``.
        axes: the distance's axes above, the commands' below.
        silence_at: when the encoders fell silent, s.
        grace: how long a watchdog waits for a tick before stopping, s.
    """
    ax_distance, ax_command = axes
    for label, (times, distances, commands) in runs.items():
        ax_distance.plot(times, 100 * np.asarray(distances), label=label)
        if commands:
            command_t = [command[0] for command in commands]
            command_v = [command[1] for command in commands]
            ax_command.step(command_t, command_v, where="post", label=label)
    for ax in (ax_distance, ax_command):
        ax.axvline(silence_at, color="gray", linestyle="--")
        ax.axvline(silence_at + grace, color="gray", linestyle=":")
        ax.grid(alpha=0.3)
    ax_distance.text(silence_at, 2, " ticks stop", color="gray")
    ax_distance.text(silence_at + grace, 2, f" + {grace:g} s", color="gray")
    ax_distance.set_ylabel("distance from the start (cm)")
    ax_distance.legend(loc="upper left")
    ax_command.set_ylabel("v sent (m/s)")
    ax_command.set_xlabel("t (s)")


def plot_gap_over_time(
    axes: Sequence[Axes],
    t: Sequence[float],
    gaps: np.ndarray,
) -> None:
    """Draw the odometry's position gap (cm) and heading gap (deg) over a run, one above the other.

    Args:
        axes: the position's axes above, the heading's below (sharing x).
        t: the times, s, shape (N,).
        gaps: (position gap in m, heading gap in rad) at those times, shape (N, 2).
    """
    ax_position, ax_heading = axes
    gaps = np.asarray(gaps, dtype=float)
    ax_position.plot(t, 100 * gaps[:, 0], color="black")
    ax_heading.plot(t, np.degrees(gaps[:, 1]), color="black")
    ax_position.set_ylabel("position gap (cm)")
    ax_heading.set_ylabel("heading gap (deg)")
    ax_heading.set_xlabel("t (s)")
    ax_position.set_title("Odometry minus truth, all along the mission")
    for ax in (ax_position, ax_heading):
        ax.grid(alpha=0.3)
