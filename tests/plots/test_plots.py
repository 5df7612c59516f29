"""Plots of pose tracks (matplotlib's Agg backend, no display needed)."""

from __future__ import annotations

import ast
import math
import shutil
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.figure import Figure

from duckielib import plots
from duckielib.config import TILE_SIZE
from duckielib.errors import DuckielibError

# An animation that is made but never played or saved warns when it is garbage-collected.
pytestmark = pytest.mark.filterwarnings("ignore:Animation was deleted without rendering")

TWO_PI = 2 * math.pi


@dataclass
class Track:
    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    label: str


def circle(label: str = "ground truth", scale: float = 1.0) -> Track:
    """A counter-clockwise circle of radius 0.4 m at 1 rad/s; theta wraps once, at index 29."""
    t = np.linspace(0.0, 7.0, 36)  # 0.2 s apart
    theta = 0.5 + t  # passes 2*pi between t = 5.6 and t = 5.8
    x = 0.7 + scale * 0.4 * np.sin(theta)
    y = 0.3 - scale * 0.4 * np.cos(theta)
    return Track(t, x, y, theta, label)


def line(label: str = "odometry") -> Track:
    """A straight drive along y from t = 1 s to 3 s, at negative x."""
    t = np.linspace(1.0, 3.0, 5)
    return Track(t, np.full(5, -0.2), np.linspace(0.0, 1.0, 5), np.full(5, math.pi / 2), label)


def empty() -> Track:
    return Track(np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), "empty")


def track_lines(ax):
    labels = {text.get_text() for text in ax.get_legend().get_texts()}
    return [item for item in ax.get_lines() if item.get_label() in labels]


def tile_grid(ax):
    (grid,) = [item for item in ax.collections if item.get_gid() == "tile-grid"]
    return np.concatenate(grid.get_segments())


def test_plot_path_draws_each_track_with_its_data_and_label():
    tracks = [circle(), line()]
    ax = plots.plot_path(tracks)
    lines = track_lines(ax)
    assert [item.get_label() for item in lines] == ["ground truth", "odometry"]
    for item, track in zip(lines, tracks):
        np.testing.assert_allclose(item.get_xydata(), np.column_stack([track.x, track.y]))
    legend = [text.get_text() for text in ax.get_legend().get_texts()]
    assert legend == ["ground truth", "odometry", "start", "end (heading)"]
    assert ax.get_aspect() == 1.0
    assert ax.get_xlabel() == "x (m)"
    assert ax.get_ylabel() == "y (m)"
    assert isinstance(ax.figure, Figure)


def test_plot_path_marks_starts_and_end_headings():
    tracks = [circle(), line()]
    ax = plots.plot_path(tracks)
    starts = [item.get_offsets()[0] for item in ax.collections if item.get_gid() != "tile-grid"]
    np.testing.assert_allclose(
        starts, [[0.7 + 0.4 * math.sin(0.5), 0.3 - 0.4 * math.cos(0.5)], [-0.2, 0.0]]
    )
    arrows = [(text.xyann, text.xy) for text in ax.texts]
    assert len(arrows) == 2
    (x0, y0), (x1, y1) = arrows[1]
    assert (x0, y0) == pytest.approx((-0.2, 1.0))
    # The odometry ends heading along +y.
    assert x1 == pytest.approx(-0.2)
    assert y1 > y0
    (x0, y0), (x1, y1) = arrows[0]
    assert math.atan2(y1 - y0, x1 - x0) % TWO_PI == pytest.approx(7.5 % TWO_PI)


def test_plot_path_tile_grid_is_on_multiples_of_the_tile_and_covers_the_paths():
    tracks = [circle(), line()]
    ax = plots.plot_path(tracks)
    points = tile_grid(ax)
    tiles = points / TILE_SIZE
    np.testing.assert_allclose(tiles, np.round(tiles), atol=1e-9)
    # x from -0.2 to 1.1 m, y from -0.1 to 1.0 m (with the end arrows): padded to whole tiles.
    assert points[:, 0].min() == pytest.approx(-TILE_SIZE)
    assert points[:, 0].max() == pytest.approx(2 * TILE_SIZE)
    assert points[:, 1].min() == pytest.approx(-TILE_SIZE)
    assert points[:, 1].max() == pytest.approx(2 * TILE_SIZE)
    low, high = ax.get_xlim()
    assert low < -TILE_SIZE < 2 * TILE_SIZE < high
    assert high - low < 3 * TILE_SIZE + 0.1


def test_plot_path_without_grid_draws_no_tiles():
    ax = plots.plot_path(circle(), grid=False)
    assert all(item.get_gid() != "tile-grid" for item in ax.collections)


def test_plot_path_takes_one_track_and_single_samples():
    one = Track(np.array([0.0]), np.array([0.2]), np.array([0.3]), np.array([0.0]), "one")
    ax = plots.plot_path(one)
    (drawn,) = track_lines(ax)
    np.testing.assert_allclose(drawn.get_xydata(), [[0.2, 0.3]])
    assert drawn.get_marker() == "o"
    points = tile_grid(ax)
    assert points[:, 0].min() == pytest.approx(0.0)
    assert points[:, 0].max() == pytest.approx(TILE_SIZE)
    ax.figure.canvas.draw()


def test_plot_path_draws_the_reference_on_given_axes():
    ax = Figure().add_subplot()
    returned = plots.plot_path([circle()], ax=ax, reference=(1.2, 0.9, math.pi))
    assert returned is ax
    legend = [text.get_text() for text in ax.get_legend().get_texts()]
    assert "reference" in legend
    (star,) = [item for item in ax.collections if item.get_label() == "reference"]
    np.testing.assert_allclose(star.get_offsets(), [[1.2, 0.9]])
    (tail, tip) = ax.texts[-1].xyann, ax.texts[-1].xy
    assert tail == pytest.approx((1.2, 0.9))
    assert tip[0] < tail[0]
    assert tip[1] == pytest.approx(0.9)
    plots.plot_path([circle()], reference=[0.1, 0.2])


@pytest.mark.parametrize("reference", [(1.0,), (1.0, 2.0, 3.0, 4.0), (float("nan"), 0.0)])
def test_plot_path_rejects_a_bad_reference(reference):
    with pytest.raises(DuckielibError, match=r"reference must be a finite \(x, y\)"):
        plots.plot_path([circle()], reference=reference)


def test_theta_over_time_is_broken_exactly_at_the_wrap():
    track = circle()
    axes = plots.plot_pose_over_time([track])
    assert len(axes) == 3
    ax_x, ax_y, ax_theta = axes
    np.testing.assert_allclose(
        ax_x.get_lines()[0].get_xydata(), np.column_stack([track.t, track.x])
    )
    np.testing.assert_allclose(
        ax_y.get_lines()[0].get_xydata(), np.column_stack([track.t, track.y])
    )
    times, theta = ax_theta.get_lines()[0].get_data()
    assert len(theta) == len(track.t) + 1
    assert np.flatnonzero(np.isnan(theta)).tolist() == [29]
    assert times[29] == pytest.approx(5.7)
    finite = theta[np.isfinite(theta)]
    assert np.all((finite >= 0) & (finite < TWO_PI))
    np.testing.assert_allclose(finite, np.mod(track.theta, TWO_PI))
    np.testing.assert_allclose(np.delete(times, 29), track.t)


def test_theta_over_time_wraps_clockwise_and_tiny_negative_angles():
    t = np.arange(5.0)
    theta = np.array([0.6, 0.2, -1e-17, -0.4, -0.8])
    track = Track(t, np.zeros(5), np.zeros(5), theta, "clockwise")
    theta_line = plots.plot_pose_over_time(track)[2].get_lines()[0]
    _, drawn = theta_line.get_data()
    # -1e-17 wraps to 0 (not 2*pi), so the break is between 0 and -0.4.
    assert np.flatnonzero(np.isnan(drawn)).tolist() == [3]
    np.testing.assert_allclose(np.delete(drawn, 3), [0.6, 0.2, 0.0, TWO_PI - 0.4, TWO_PI - 0.8])


def test_theta_axis_ticks_limits_and_shared_time():
    axes = plots.plot_pose_over_time([circle(), line()])
    ax_theta = axes[2]
    assert list(ax_theta.get_yticks()) == pytest.approx(
        [0, math.pi / 2, math.pi, 1.5 * math.pi, TWO_PI]
    )
    labels = [label.get_text() for label in ax_theta.get_yticklabels()]
    assert labels == ["0", "π/2", "π", "3π/2", "2π"]
    assert ax_theta.get_ylim() == pytest.approx((0.0, TWO_PI))
    assert ax_theta.get_xlabel() == "t (s)"
    assert [ax.get_ylabel() for ax in axes] == ["x (m)", "y (m)", "θ (rad)"]
    assert axes[0].get_shared_x_axes().joined(axes[0], axes[2])
    legend = [text.get_text() for text in axes[0].get_legend().get_texts()]
    assert legend == ["ground truth", "odometry"]


def test_plot_pose_over_time_needs_three_axes():
    fig = Figure()
    with pytest.raises(DuckielibError, match="3 axes"):
        plots.plot_pose_over_time(circle(), axes=fig.subplots(2, 1))
    axes = fig.subplots(3, 1)
    assert plots.plot_pose_over_time(circle(), axes=axes) == list(axes)


def test_pose_figure_has_a_path_and_three_time_plots():
    fig = plots.pose_figure(
        [circle(), circle("odometry", scale=1.1)], title="Circle", reference=(0.7, 0.7)
    )
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 4
    path_ax = fig.axes[0]
    assert path_ax.get_aspect() == 1.0
    assert len(track_lines(path_ax)) == 2
    assert [ax.get_ylabel() for ax in fig.axes[1:]] == ["x (m)", "y (m)", "θ (rad)"]
    assert fig.get_suptitle() == "Circle"
    assert tuple(fig.get_size_inches()) == pytest.approx((12.0, 6.0))
    # The path sits left of the time plots, which are stacked top to bottom.
    boxes = [ax.get_position() for ax in fig.axes]
    assert boxes[0].x1 < min(box.x0 for box in boxes[1:])
    assert boxes[1].y0 > boxes[2].y0 > boxes[3].y0


def test_save_figure_writes_png_and_svg(tmp_path):
    fig = plots.plot_path(circle()).figure
    png = plots.save_figure(fig, tmp_path / "poses.png")
    assert png == tmp_path / "poses.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert png.stat().st_size > 10_000
    svg = plots.save_figure(fig, str(tmp_path / "poses.SVG"))
    assert b"<svg" in svg.read_bytes()[:1000]


def test_save_figure_rejects_a_bad_suffix_and_a_missing_folder(tmp_path):
    fig = plots.plot_path(circle()).figure
    with pytest.raises(DuckielibError) as caught:
        plots.save_figure(fig, "x.txt")
    assert str(caught.value) == (
        "Cannot save the figure as 'x.txt': use a name ending in .png, .svg or .pdf."
    )
    missing = tmp_path / "nowhere" / "poses.png"
    with pytest.raises(DuckielibError, match="does not exist; create it first"):
        plots.save_figure(fig, missing)
    assert not missing.parent.exists()


@pytest.mark.parametrize(
    "draw",
    [
        plots.plot_path,
        plots.plot_pose_over_time,
        plots.pose_figure,
        plots.animate_path,
    ],
)
def test_empty_input_raises(draw):
    with pytest.raises(DuckielibError, match="There are no tracks to plot"):
        draw([])
    with pytest.raises(DuckielibError, match="Track 'empty' has no samples"):
        draw([circle(), empty()])
    uneven = Track(np.arange(3.0), np.zeros(2), np.zeros(3), np.zeros(3), "uneven")
    with pytest.raises(DuckielibError, match="1-D arrays of the same length"):
        draw(uneven)


def test_animate_path_frames_cover_the_tracks_at_the_given_speed():
    anim = plots.animate_path([circle(), line()], fps=10.0, speed=3.0)
    frames = list(anim.new_saved_frame_seq())
    # 7 s of tracks at 3 times real time, 10 frames a second: 0.3 s apart, the last at the end.
    np.testing.assert_allclose(frames, [*(np.arange(24) * 0.3), 7.0])
    assert anim._interval == pytest.approx(100.0)

    ax = anim._fig.axes[0]
    drawn = track_lines(ax)
    anim._draw_frame(frames[0])
    assert [len(item.get_xdata()) for item in drawn] == [1, 0]
    assert ax.get_title() == "t = 0.00 s"
    anim._fig.canvas.draw()
    anim._draw_frame(frames[7])  # t = 2.1 s
    assert [len(item.get_xdata()) for item in drawn] == [11, 3]
    anim._draw_frame(frames[-1])
    np.testing.assert_allclose(drawn[0].get_xydata(), np.column_stack([circle().x, circle().y]))
    assert len(drawn[1].get_xdata()) == 5
    assert ax.get_title() == "t = 7.00 s"
    anim._fig.canvas.draw()


def test_animate_path_with_one_sample_has_one_frame():
    one = Track(np.array([4.0]), np.array([0.2]), np.array([0.3]), np.array([1.0]), "one")
    anim = plots.animate_path(one)
    assert list(anim.new_saved_frame_seq()) == [4.0]


@pytest.mark.parametrize(("fps", "speed"), [(0.0, 1.0), (15.0, -1.0), (float("nan"), 1.0)])
def test_animate_path_rejects_bad_rates(fps, speed):
    with pytest.raises(DuckielibError, match="needs a positive"):
        plots.animate_path(circle(), fps=fps, speed=speed)


def test_animate_path_rejects_time_going_back():
    track = circle()
    track.t = track.t[::-1].copy()
    with pytest.raises(DuckielibError, match="goes back in time"):
        plots.animate_path(track)


def imported_modules(nodes):
    """Modules imported by these statements, ``from a import b`` counting as ``a.b``."""
    names = set()
    for node in nodes:
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


#: The modules of the package that draw recorded runs: they need neither the simulator nor
#: rosbags (only world.py reads the simulator).
PURE_PLOTS = ("canvas", "diagrams", "files", "paths")


@pytest.mark.parametrize("name", PURE_PLOTS)
def test_plots_imports_only_numpy_matplotlib_and_the_pure_modules(name):
    tree = ast.parse(Path(plots.__file__).with_name(f"{name}.py").read_text())
    everywhere = imported_modules(ast.walk(tree))
    allowed_roots = {
        "__future__",
        "contextlib",
        "io",
        "math",
        "pathlib",
        "secrets",
        "typing",
        "numpy",
        "matplotlib",
        "PIL",  # Pillow, which matplotlib itself needs, writes the GIFs
    }
    outside = {
        name
        for name in everywhere
        if name.split(".")[0] not in allowed_roots
        and not name.startswith(
            ("duckielib.config.", "duckielib.errors.", "duckielib.leds.", "duckielib.missions.")
        )
        and not name.startswith(tuple(f"duckielib.plots.{pure}." for pure in PURE_PLOTS))
    }
    assert outside == set()
    # pyplot (which picks a GUI backend) is imported only inside animate_path.
    at_import = imported_modules(node for node in tree.body)
    assert ("matplotlib.pyplot" in everywhere) == (name == "paths")
    assert "matplotlib.pyplot" not in at_import


def test_the_package_exports_every_public_name_of_its_modules():
    import importlib

    for name in (*PURE_PLOTS, "world"):
        module = importlib.import_module(f"duckielib.plots.{name}")
        for public in module.__all__:
            assert getattr(plots, public) is getattr(module, public), f"{name}.{public}"
            assert public in plots.__all__
    # One function saves animations, one draws the tiles: no module keeps its own.
    assert not hasattr(plots.world, "save_animation")
    assert not hasattr(plots.paths, "save_animation")


def test_save_animation_writes_a_whole_gif_or_refuses(tmp_path):
    anim = plots.animate_path(line(), fps=2.0)
    path = plots.save_animation(anim, tmp_path / "run.gif", fps=2.0, dpi=20)
    assert path == tmp_path / "run.gif"
    assert path.read_bytes()[:6] == b"GIF89a"
    assert [item.name for item in tmp_path.iterdir()] == ["run.gif"]
    with pytest.raises(DuckielibError) as caught:
        plots.save_animation(anim, tmp_path / "run.avi")
    assert str(caught.value) == (
        f"Cannot save the animation as {str(tmp_path / 'run.avi')!r}: use a name ending in "
        f".gif or .mp4."
    )
    missing = tmp_path / "missing" / "run.gif"
    with pytest.raises(DuckielibError, match="does not exist; create it first"):
        plots.save_animation(anim, missing)
    assert not missing.parent.exists()
    assert [item.name for item in tmp_path.iterdir()] == ["run.gif"]


@pytest.mark.skipif(
    shutil.which("ffmpeg") is None, reason="ffmpeg is not installed; run `make ros` to install it"
)
def test_save_animation_writes_a_whole_mp4(tmp_path):
    anim = plots.animate_path(line(), fps=2.0)
    path = plots.save_animation(anim, tmp_path / "run.mp4", fps=2.0, dpi=20)
    assert path == tmp_path / "run.mp4"
    assert path.read_bytes()[4:8] == b"ftyp"  # an MP4 (ISO media) file
    assert [item.name for item in tmp_path.iterdir()] == ["run.mp4"]


def test_save_animation_without_ffmpeg_asks_for_it_or_a_gif(tmp_path, monkeypatch):
    from matplotlib import animation

    monkeypatch.setattr(animation.writers, "is_available", lambda name: False)
    anim = plots.animate_path(line(), fps=2.0)
    with pytest.raises(DuckielibError, match=r"needs ffmpeg.*or save a \.gif instead\.$"):
        plots.save_animation(anim, tmp_path / "run.mp4")
    assert list(tmp_path.iterdir()) == []


def test_a_failed_save_leaves_no_file_behind(tmp_path):
    from matplotlib import pyplot as plt
    from matplotlib.animation import FuncAnimation

    def draw(frame):
        if frame == 2:
            raise RuntimeError("frame 2 cannot be drawn")
        return []

    fig = plt.figure(figsize=(1, 1))
    anim = FuncAnimation(fig, draw, frames=4)
    with pytest.raises(RuntimeError, match="frame 2"):
        plots.save_animation(anim, tmp_path / "run.gif", fps=2.0, dpi=20)
    assert list(tmp_path.iterdir()) == []
    plt.close(fig)
    # A figure that cannot be drawn leaves nothing either, and an old file stays as it was.
    (tmp_path / "poses.png").write_bytes(b"old")
    broken = plots.plot_path(circle()).figure
    broken.axes[0].text(0, 0, "$\\undefined$")
    with pytest.raises(ValueError, match="undefined"):
        plots.save_figure(broken, tmp_path / "poses.png")
    assert [item.name for item in tmp_path.iterdir()] == ["poses.png"]
    assert (tmp_path / "poses.png").read_bytes() == b"old"


def test_a_write_that_fails_is_one_sentence_and_leaves_nothing(tmp_path, monkeypatch):
    anim = plots.animate_path(line(), fps=2.0)

    def full_disk(self, *args, **kwargs):
        Path(args[0]).write_bytes(b"GIF89a")  # half a file, then the disk is full
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(type(anim), "save", full_disk)
    with pytest.raises(DuckielibError) as caught:
        plots.save_animation(anim, tmp_path / "run.gif")
    assert str(caught.value) == (
        f"Cannot save the animation as {str(tmp_path / 'run.gif')!r}: No space left on "
        f"device; check that you may write there."
    )
    assert list(tmp_path.iterdir()) == []


def test_the_tracks_and_the_world_draw_the_same_tile_grid():
    from matplotlib.colors import to_hex

    from duckielib.sim import World

    world = World()
    # A track across the whole mat, inside its border: its grid is the mat's.
    inside = Track(
        np.array([0.0, 1.0]),
        np.array([0.05, world.width - 0.2]),
        np.array([0.05, world.height - 0.2]),
        np.zeros(2),
        "across",
    )
    ax_path = plots.plot_path(inside)
    ax_world = Figure().add_subplot()
    plots.draw_mat(ax_world, world)
    np.testing.assert_allclose(tile_grid(ax_world), tile_grid(ax_path), atol=1e-12)
    np.testing.assert_allclose(tile_grid(ax_world), np.concatenate(world.grid_lines()))
    # Under the paths; on the mat, in its own colour over its dark tiles, under the walls.
    (path_grid,) = [item for item in ax_path.collections if item.get_gid() == "tile-grid"]
    (mat_grid,) = [item for item in ax_world.collections if item.get_gid() == "tile-grid"]
    assert to_hex(path_grid.get_edgecolor()[0]) == "#d0d0d0"
    assert to_hex(mat_grid.get_edgecolor()[0]) == "#e8e8dc"
    assert path_grid.get_zorder() < min(line.get_zorder() for line in ax_path.get_lines())
    assert not ax_path.patches
    tiles = [patch for patch in ax_world.patches if patch.get_zorder() < mat_grid.get_zorder()]
    assert len(tiles) == world.tiles_x * world.tiles_y
    assert {to_hex(tile.get_facecolor()) for tile in tiles} == {"#3a3a3e", "#48484d"}
    (walls,) = [patch for patch in ax_world.patches if patch.get_zorder() > mat_grid.get_zorder()]
    assert walls.get_width() > world.width


def labels(ax):
    """The texts drawn on ``ax``, arrows' (empty) labels left out."""
    from matplotlib.text import Annotation

    return [text.get_text() for text in ax.texts if not isinstance(text, Annotation)]


def test_mission_states_are_boxes_in_their_led_colours_in_order():
    from matplotlib.colors import to_rgb
    from matplotlib.patches import Rectangle

    from duckielib.leds import pattern_colors, pattern_named
    from duckielib.missions import SQUARE_THEN_CIRCLE
    from duckielib.plots import plot_mission_states

    ax = plot_mission_states(SQUARE_THEN_CIRCLE)
    boxes = [patch for patch in ax.patches if isinstance(patch, Rectangle)]
    assert [box.get_x() for box in boxes] == sorted(box.get_x() for box in boxes)
    assert [to_rgb(box.get_facecolor()) for box in boxes] == [
        pattern_colors(pattern_named(state.color))[0] for state in SQUARE_THEN_CIRCLE.states
    ]
    texts = labels(ax)
    assert "square\n(GREEN)\n\nrotate -90°\nstraight 1.25 m\nrotate +90°" in texts[2]
    assert texts.count("after 5 s") == 3
    assert texts[-1] == "done"


def test_a_robot_is_drawn_at_its_pose_and_follows_each_new_one():
    from duckielib.config import DB21
    from duckielib.plots.world import RobotArtist
    from duckielib.sim.robot import AXLE_TO_FRONT_FRACTION

    ax = Figure().add_subplot()
    ax.set_xlim(-1.0, 3.0)
    ax.set_ylim(-1.0, 3.0)

    def drawn(patch):  # the patch's outline in world metres
        return ax.transData.inverted().transform(patch.get_verts())

    at_origin = [drawn(patch) for patch in plots.draw_robot(ax, (0.0, 0.0, 0.0), DB21)]
    chassis = at_origin[0]
    nose = AXLE_TO_FRONT_FRACTION * DB21.chassis_length + 0.02
    assert chassis[:, 0].max() == pytest.approx(nose)
    assert chassis[:, 1].max() == pytest.approx(DB21.chassis_width / 2)
    red = [(1.0, 0.0, 0.0)] * 5
    turned = plots.draw_robot(ax, (1.0, 0.5, math.pi / 2), DB21, red)
    assert len(turned) == 8  # chassis, two wheels, five LEDs
    for local, patch in zip(at_origin, turned):
        # A quarter turn to the left, then 1 m along x and 0.5 m along y: forward is world +y.
        expected = np.column_stack([1.0 - local[:, 1], 0.5 + local[:, 0]])
        np.testing.assert_allclose(drawn(patch), expected, atol=1e-9)
    assert [tuple(led.get_facecolor()[:3]) for led in turned[3:]] == red
    # The run player's robot moves from pose to pose, and hides without one.
    robot = RobotArtist(ax, DB21)
    robot.update((2.0, 1.0, math.pi), None)
    robot.update((0.3, -0.2, -math.pi / 2), red)
    expected = np.column_stack([0.3 + chassis[:, 1], -0.2 - chassis[:, 0]])
    np.testing.assert_allclose(drawn(robot.chassis), expected, atol=1e-9)
    assert all(not patch.get_visible() for patch in robot.update(None, None))
