"""Figures of the driving experiments (matplotlib's Agg backend, no display needed)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.figure import Figure

from duckielib import plots


def axes_pair(**options):
    return Figure().subplots(2, 1, **options)


def test_a_speed_sweep_draws_finished_speeds_in_cm_and_crosses_the_stuck_ones():
    rows = [
        {"v": 0.03, "done": 0, "seconds": 90.0, "from_start": 0.0},
        {"v": 0.2, "done": 2, "along": -0.06, "side": 0.01, "odometry": 0.02, "from_start": 0.1},
        {"v": 0.4, "done": 2, "along": -0.03, "side": 0.02, "odometry": 0.04, "from_start": 0.2},
    ]
    left, right = axes_pair()
    plots.plot_speed_sweep(rows, (left, right), moves=2, slowest_moving=0.05)
    along, side, _zero, _slowest, stuck = left.get_lines()
    assert list(along.get_xdata()) == [0.2, 0.4]
    assert np.allclose(along.get_ydata(), [-6.0, -3.0])
    assert np.allclose(side.get_ydata(), [1.0, 2.0])
    assert list(stuck.get_xdata()) == [0.03]
    assert stuck.get_label() == "did not finish"
    odometry, home = right.get_lines()[:2]
    assert np.allclose(odometry.get_ydata(), [2.0, 4.0])
    assert np.allclose(home.get_ydata(), [10.0, 20.0])
    assert right.get_xlabel() == "v (m/s)"
    assert right.get_ylabel() == "cm"
    assert "slowest that moves" in [text.get_text() for text in left.get_legend().get_texts()]


def test_the_ticks_around_a_stop_start_from_the_zero_command():
    ax = Figure().subplots()
    ticks = [(0.9, 100), (1.0, 102), (1.1, 103), (1.2, 104), (2.0, 110)]
    truth_t = np.array([0.9, 1.0, 1.1, 1.2])
    truth_along = np.array([0.50, 0.51, 0.515, 0.5175])
    plots.plot_ticks_around_stop(ax, ticks, 1.05, truth_t, truth_along, one_tick=0.005)
    counted, truth = ax.get_lines()[:2]
    assert np.allclose(counted.get_xdata(), [-0.15, -0.05, 0.05, 0.15])
    assert list(counted.get_ydata()) == [-2, 0, 1, 2]
    assert np.allclose(truth.get_ydata(), [-2.0, 0.0, 1.0, 1.5])
    assert ax.get_xlabel() == "t \N{MINUS SIGN} t(zero command) (s)"


def test_silent_encoders_show_distance_in_cm_and_the_commands_as_steps():
    top, bottom = axes_pair(sharex=True)
    runs = {"with the watchdog": (np.array([1.0, 2.0]), np.array([0.1, 0.2]), [(1.0, 0.2, 0.9)])}
    plots.plot_encoder_silence(runs, (top, bottom), silence_at=2.0)
    assert np.allclose(top.get_lines()[0].get_ydata(), [10.0, 20.0])
    assert list(bottom.get_lines()[0].get_ydata()) == [0.2]
    assert [text.get_text() for text in top.texts] == [" ticks stop", " + 0.5 s"]
    assert bottom.get_ylabel() == "v sent (m/s)"


def test_the_gap_over_time_is_in_cm_and_degrees():
    top, bottom = axes_pair(sharex=True)
    gaps = np.array([[0.01, 0.0], [0.02, np.pi / 180]])
    plots.plot_gap_over_time((top, bottom), [0.0, 1.0], gaps)
    assert np.allclose(top.get_lines()[0].get_ydata(), [1.0, 2.0])
    assert bottom.get_lines()[0].get_ydata()[1] == pytest.approx(1.0)
    assert (top.get_ylabel(), bottom.get_ylabel()) == ("position gap (cm)", "heading gap (deg)")
