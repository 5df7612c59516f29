"""Camera frames, drawing and animation (matplotlib's Agg backend, no display needed)."""

from __future__ import annotations

import io
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from PIL import Image

from duckielib import plots
from duckielib.errors import DuckielibError, SimulationError
from duckielib.sim import Simulator, VirtualDuckiebot


def test_frame_is_a_640x480_jpeg():
    sim = Simulator(seed=2)
    frame = sim.frame_jpeg()
    assert frame[:2] == b"\xff\xd8"
    image = np.asarray(Image.open(io.BytesIO(frame)).convert("RGB"))
    assert image.shape == (480, 640, 3)
    raw = sim.camera_image()
    assert raw.shape == (480, 640, 3)
    assert raw.dtype == np.uint8


def test_frames_come_at_most_30_per_second_and_change_as_the_robot_moves():
    sim = Simulator(seed=2)
    first = sim.frame_jpeg()
    sim.step()
    assert sim.frame_jpeg() is first  # still within the same 1/30 s
    sim.set_wheel_duties(0.5, 0.2)
    sim.run_until(0.5)
    second = sim.frame_jpeg()
    assert second != first
    assert len(second) != len(first)


def test_camera_sees_the_wall_ahead():
    sim = Simulator(seed=2, start_pose=(1.2, 2.2, np.pi / 2))  # 0.14 m from the far wall
    image = sim.camera_image()
    assert (image[0] == image[0, 320]).all()  # the top row is beyond the wall
    assert image[-1, 320].tolist() != image[0, 320].tolist()


def test_plot_writes_a_png(tmp_path):
    sim = Simulator(seed=2)
    sim.set_led_pattern("RED")
    sim.set_wheel_duties(0.5, 0.4)
    sim.run_until(2.0)
    estimate = sim.trace.poses() + 0.02
    ax = plots.plot_run(sim, estimate=estimate)
    labels = [line.get_label() for line in ax.get_lines()]
    assert "true" in labels
    assert "estimate" in labels
    path = tmp_path / "run.png"
    ax.figure.savefig(path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    matplotlib.pyplot.close("all")


def test_estimate_of_the_wrong_shape_is_rejected():
    sim = Simulator(seed=2)
    with pytest.raises(SimulationError, match=r"shape \(N, 2\) or \(N, 3\)"):
        plots.plot_run(sim, estimate=[1.0, 2.0, 3.0])
    matplotlib.pyplot.close("all")


def test_animation_plays_as_html_and_saves_as_gif(tmp_path):
    sim = Simulator(seed=2, trace_rate_hz=10)
    sim.set_led_pattern("CAR_SIGNAL_A")
    sim.set_wheel_duties(0.5, 0.3)
    sim.run_until(1.0)
    anim = plots.animate_run(sim, estimate=sim.trace.poses()[:, :2], fps=5)
    html = plots.animation_html(anim)
    assert "<script" in html
    assert "Animation" in html
    gif = plots.save_animation(anim, tmp_path / "run.gif", fps=5)
    assert gif.read_bytes()[:6] in (b"GIF89a", b"GIF87a")
    with pytest.raises(DuckielibError, match=r"\.gif or \.mp4"):
        plots.save_animation(anim, tmp_path / "run.avi")
    assert [item.name for item in tmp_path.iterdir()] == ["run.gif"]


def test_mp4_needs_ffmpeg(tmp_path):
    sim = Simulator(seed=2, trace_rate_hz=5)
    sim.run_until(0.4)
    anim = plots.animate_run(sim, fps=5)
    if matplotlib.animation.writers.is_available("ffmpeg"):
        mp4 = plots.save_animation(anim, tmp_path / "run.mp4", fps=5)
        assert mp4.stat().st_size > 0
        assert mp4.read_bytes()[4:8] == b"ftyp"
    else:
        with pytest.raises(DuckielibError, match="ffmpeg"):
            plots.save_animation(anim, tmp_path / "run.mp4")
        assert "<script" in plots.animation_html(anim)
    assert [item.name for item in tmp_path.iterdir()] == (
        ["run.mp4"] if matplotlib.animation.writers.is_available("ffmpeg") else []
    )


def test_nothing_recorded_cannot_be_animated():
    with pytest.raises(SimulationError, match="trace_rate_hz"):
        plots.animate_run(Simulator(trace_rate_hz=0))


def test_importing_the_simulator_loads_no_plotting_or_imaging():
    script = (
        "import sys, duckielib.sim\n"
        "sim = duckielib.sim.Simulator()\n"
        "sim.run_until(0.5)\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('matplotlib', 'PIL')))"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "[]"


def test_the_simulator_leaves_drawing_to_the_plots():
    from import_graph import graph

    # The simulator never imports the plots (its example scripts are users of both).
    arrows = [
        arrow
        for arrow in graph().arrows("duckielib.sim", "duckielib.plots")
        if not arrow.startswith("duckielib.sim.examples.")
    ]
    assert arrows == []
    for drawn in (Simulator, VirtualDuckiebot):
        assert not hasattr(drawn, "plot")
        assert not hasattr(drawn, "animate")
