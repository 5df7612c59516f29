"""Watching a run: the robot on the mat, its LEDs, its paths, its state and its camera.

- :class:`Recording`: what a run shows over time: the true poses, odometry's poses, the LED
  patterns, the mission's states and the camera's frames. Made from a bag
  (:meth:`Recording.from_bag`: the simulator's, the mission's or a real robot's) or from the
  simulator's own record of a run (:meth:`Recording.from_simulator`).
- :class:`RunPlayer`: plays a recording. In a notebook it is a picture with play, pause and a
  time slider (ipywidgets); :meth:`RunPlayer.save` writes the same frames as a GIF or an MP4,
  as ``duckie mission`` does for ``mission.gif``.

A frame shows the mat with its tiles, the robot drawn to scale at its true pose with its five
LEDs in the colours they showed, the true path so far (solid) and odometry's path so far
(dashed) with a dashed outline of the robot where odometry believes it is; beside the mat, the
time, the mission's state, its LEDs and the legend; and the camera's latest frame beside them
when the recording has one. Where there is no ground truth (a real robot's bag), the robot is
drawn where odometry puts it. A frame is wider than tall (800 by 460 pixels without the
camera), and the notebook's player puts its controls above it: on a laptop's screen the play
button and the whole mat are in view together.

Like every module of :mod:`duckielib.plots`, it runs on the laptop only.
"""

# Over 600 lines: one player, whose recording (a run read from its bag), the frame it draws and
# the notebook's controls share the frame's layout; the Recording class (about 160 lines) is
# the seam to split along should it grow.

from __future__ import annotations

import io
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Optional, Tuple, Union

import numpy as np

from duckielib import leds as led_tables
from duckielib.config import RobotConfig
from duckielib.errors import DuckielibError
from duckielib.plots.canvas import NotebookFigure, draw_tile_grid, tile_span
from duckielib.plots.world import RobotArtist, draw_mat
from duckielib.rostime import NS_PER_S
from duckielib.sim.world import OPEN_MAT, World

if TYPE_CHECKING:
    from matplotlib.animation import FuncAnimation
    from matplotlib.artist import Artist

    from duckielib.bags.reader import Bag
    from duckielib.sim.simulator import Simulator

__all__ = ["Recording", "RunPlayer"]

RGB = Tuple[float, float, float]
Poses = np.ndarray

#: Frames are this many pixels wide at least (the mat and its panel; with the camera, wider).
FRAME_WIDTH = 800
#: Frames are this many pixels tall: with the player's controls, within a laptop's screen.
FRAME_HEIGHT = 460
_DPI = 100
#: With the camera beside the mat, the figure is this many times wider.
_CAMERA_SCALE = 1.75
#: Where the panel beside the mat starts, as a fraction of the width without the camera.
_PANEL_LEFT = 0.62
_TRUE_COLOR = "#1f9bff"
_ODOMETRY_COLOR = "#ff9d2e"
_IMAGE_TYPE = "sensor_msgs/CompressedImage"
_STRING_TYPE = "std_msgs/String"
_LED_TYPE = "duckietown_msgs/LEDPattern"


@dataclass
class Recording:
    """What a run shows over time, every time in seconds on one clock.

    Attributes:
        truth_t, truth: times and true poses (N, 3): x, y in metres, theta in radians; empty
            when the run has no ground truth (a real robot).
        odometry_t, odometry: times and odometry's poses, likewise.
        patterns: the LED patterns, as (time set, pattern), in time order.
        states: the mission's states, as (time announced, name), in time order.
        frames: the camera's frames, as (time, JPEG bytes), in time order.
        world: the mat to draw, or None to draw tiles under the poses, without walls.
        config: the robot's size, to draw it to scale.
        title: what the run is, shown beside the mat.
        camera_topic: the topic the frames came from.
    """

    truth_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    truth: Poses = field(default_factory=lambda: np.zeros((0, 3)))
    odometry_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    odometry: Poses = field(default_factory=lambda: np.zeros((0, 3)))
    patterns: List[Tuple[float, led_tables.Pattern]] = field(default_factory=list)
    states: List[Tuple[float, str]] = field(default_factory=list)
    frames: List[Tuple[float, bytes]] = field(default_factory=list)
    world: Optional[World] = None
    config: RobotConfig = field(default_factory=RobotConfig)
    title: str = ""
    camera_topic: str = ""

    @property
    def span(self) -> Tuple[float, float]:
        """The first and last time anything was recorded, in seconds."""
        times = [
            float(value)
            for series in (self.truth_t, self.odometry_t)
            if len(series)
            for value in (series[0], series[-1])
        ]
        times += [t for t, _ in self.states] + [t for t, _ in self.frames]
        if not times:
            raise DuckielibError(
                "The recording has nothing to play: no poses, no states and no camera frames."
            )
        return min(times), max(times)

    def leds_at(self, t: float) -> Tuple[RGB, ...]:
        """The five LEDs' colours at ``t`` (blinking ones off in the second half of a period)."""
        return led_tables.colors_shown(self.patterns, t)

    def pattern_at(self, t: float) -> Optional[led_tables.Pattern]:
        """The LED pattern set at ``t``, or None before the first."""
        before = [pattern for since, pattern in self.patterns if since <= t]
        return before[-1] if before else None

    def state_at(self, t: float) -> str:
        """The name of the state announced last before ``t`` ("" before the first)."""
        before = [name for since, name in self.states if since <= t]
        return before[-1] if before else ""

    def frame_at(self, t: float) -> Optional[bytes]:
        """The camera's latest frame at ``t`` (JPEG bytes), or None before the first."""
        times = [since for since, _ in self.frames]
        index = int(np.searchsorted(times, t, side="right")) - 1
        return self.frames[index][1] if index >= 0 else None

    @classmethod
    def from_simulator(
        cls, sim: Any, odometry: Optional[object] = None, title: str = "the simulator's run"
    ) -> Recording:
        """The run the simulator recorded (its trace), with odometry's path when given.

        Args:
            sim: a :class:`~duckielib.sim.Simulator` or a
                :class:`~duckielib.sim.VirtualDuckiebot` (its ``sim``), created with
                ``trace_rate_hz > 0``.
            odometry: odometry's poses, shape (N, 3) (or (N, 2)), taken as evenly spread over
                the run; or ``(times, poses)``.
            title: what the run is.

        Raises:
            DuckielibError: if the simulator recorded nothing.
        """
        simulator: Simulator = getattr(sim, "sim", sim)
        trace = simulator.trace
        if len(trace) == 0:
            raise DuckielibError(
                "The simulator recorded no run: create it with trace_rate_hz > 0 and run it first."
            )
        times = np.asarray(trace.times, dtype=float)
        recording = cls(
            truth_t=times,
            truth=trace.poses(),
            patterns=list(trace.patterns),
            world=simulator.world,
            config=simulator.config,
            title=title,
        )
        if odometry is not None:
            recording.odometry_t, recording.odometry = _spread(odometry, times)
        return recording

    @classmethod
    def from_bag(
        cls,
        bag: Union[Bag, str, Path],
        camera_topic: Optional[str] = None,
        world: Optional[World] = None,
        title: Optional[str] = None,
    ) -> Recording:
        """What a bag shows: its poses, LED patterns, mission states and camera frames.

        The true poses are a ``.../ground_truth_pose`` topic (the simulator's), odometry's the
        first other ``duckietown_msgs/Pose2DStamped`` topic (``odometry_node/pose``, or a real
        robot's ``velocity_to_pose_node/pose``). The states are a ``.../state`` topic of
        ``std_msgs/String``. Times are the bag's record times, from its first message.

        Args:
            bag: the bag, or its path.
            camera_topic: the ``sensor_msgs/CompressedImage`` topic to show; by default the
                first whose name says it is annotated, else the first there is.
            world: the mat; by default the missions' 4 x 4 mat (without walls) when the bag has
                ground truth that stays on it, else tiles under the poses.
            title: what the run is (default: the bag's file name).

        Raises:
            BagError: if the bag cannot be read.
            DuckielibError: if the camera topic is not in the bag, or the bag holds nothing
                to play (no poses, states or frames).
        """
        from duckielib.bags import Bag, pose_tracks
        from duckielib.bags.behaviour import led_messages

        bag = bag if isinstance(bag, Bag) else Bag(bag)
        start = bag.start_ns / NS_PER_S
        recording = cls(title=title if title is not None else bag.path.name)
        tracks = pose_tracks(bag, "record")
        truth = [track for track in tracks if track.label.endswith("ground_truth_pose")]
        others = [track for track in tracks if not track.label.endswith("ground_truth_pose")]
        odometry = sorted(others, key=lambda track: "odometry" not in track.label)
        for name, chosen in (("truth", truth), ("odometry", odometry)):
            if chosen and len(chosen[0]):
                track = chosen[0]
                setattr(recording, f"{name}_t", track.t - start)
                setattr(recording, name, np.column_stack((track.x, track.y, track.theta)))
        for topic in bag.topics_of_type(_LED_TYPE):
            for t, message in led_messages(bag, topic):
                recording.patterns.append((t - start, _message_pattern(message)))
            break
        states = [topic for topic in bag.topics_of_type(_STRING_TYPE) if topic.endswith("/state")]
        if states:
            recording.states = [
                (item.time - start, item.message.data) for item in bag.read(states[0])
            ]
        camera_topic = image_topic(bag, camera_topic)
        if camera_topic:
            recording.camera_topic = camera_topic
            recording.frames = [
                (item.time - start, bytes(item.message.data)) for item in bag.read(camera_topic)
            ]
        recording.world = world if world is not None else _bag_world(recording.truth)
        recording.span  # noqa: B018 - says clearly when there is nothing to play
        return recording


def image_topic(bag: Bag, wanted: Optional[str] = None) -> str:
    """The bag's ``sensor_msgs/CompressedImage`` topic to show ("" if it has none).

    That is ``wanted``, or by default the first whose name says it is annotated, else the
    first there is.

    Raises:
        DuckielibError: if ``wanted`` is not an image topic of the bag (naming those there are).
    """
    images = bag.topics_of_type(_IMAGE_TYPE)
    if wanted is None:
        annotated = [topic for topic in images if "annotated" in topic]
        return (annotated or images or [""])[0]
    if wanted not in images:
        listed = ", ".join(images) or "none"
        raise DuckielibError(
            f"The bag has no image topic {wanted}; its CompressedImage topics: {listed}."
        )
    return wanted


def _spread(odometry: object, times: np.ndarray) -> Tuple[np.ndarray, Poses]:
    """Odometry's times and (N, 3) poses, from ``(times, poses)`` or poses alone."""
    if isinstance(odometry, tuple) and len(odometry) == 2:
        own_times, poses = np.asarray(odometry[0], dtype=float), np.asarray(odometry[1], float)
    else:
        poses = np.asarray(odometry, dtype=float)
        own_times = np.linspace(times[0], times[-1], len(poses)) if len(poses) else times[:0]
    if poses.ndim != 2 or poses.shape[1] not in (2, 3) or len(own_times) != len(poses):
        raise DuckielibError(
            f"Odometry's poses must have shape (N, 3) (x, y and theta) or (N, 2), one per time, "
            f"not {poses.shape}."
        )
    if poses.shape[1] == 2:
        poses = np.column_stack((poses, np.zeros(len(poses))))
    return own_times, poses


def _message_pattern(message: Any) -> led_tables.Pattern:
    """The pattern an LEDPattern message shows; all off if it shows nothing the LEDs can."""
    try:
        return led_tables.pattern_of_message(
            message.color_list,
            [(color.r, color.g, color.b) for color in message.rgb_vals],
            message.frequency,
            message.frequency_mask,
        )
    except DuckielibError:
        return led_tables.pattern_named(led_tables.OFF_PATTERN)


def _bag_world(truth: Poses) -> Optional[World]:
    """The missions' mat when the true poses stay on it, else None (tiles under the poses)."""
    mat = OPEN_MAT
    if len(truth) and all(mat.contains(float(x), float(y)) for x, y, _ in truth):
        return mat
    return None


class _Frame:
    """One figure whose moving parts are set to a time.

    The still parts (the mat, its axes, the legend and the titles) are drawn once; each frame
    then puts that picture back and draws only the moving parts over it, lowest first, as a
    whole drawing would (none of the still parts lies over a moving one): the same pixels, in
    a fraction of the time.
    """

    def __init__(self, recording: Recording) -> None:
        self.recording = recording
        self._canvas: Any = None
        self._still: Any = None
        camera = bool(recording.frames)
        # With the camera, the figure is wider and the mat and its panel keep their share:
        # figure fractions along x are divided by ``scale``.
        scale = _CAMERA_SCALE if camera else 1.0
        self.figure = NotebookFigure(
            figsize=(FRAME_WIDTH * scale / _DPI, FRAME_HEIGHT / _DPI), dpi=_DPI
        )
        # The mat on the left, as tall as the frame allows (room below for the x axis).
        mat = self.figure.add_axes((0.075 / scale, 0.1, 0.53 / scale, 0.885))
        self.mat = mat
        self._draw_mat(mat)
        truth = len(recording.truth) > 0
        (self.true_line,) = mat.plot(
            [], [], color=_TRUE_COLOR, linewidth=2.5, label="true path", zorder=3
        )
        (self.odometry_line,) = mat.plot(
            [],
            [],
            color=_ODOMETRY_COLOR,
            linewidth=2,
            linestyle="--",
            zorder=3,
            label="odometry\n(dashed robot: where it believes it is)"
            if truth
            else "odometry\n(no ground truth: the robot is\ndrawn where odometry puts it)",
        )
        if not truth:
            self.true_line.set_label("_nolegend_")
        self.ghost = RobotArtist(mat, recording.config, ghost=True, color=_ODOMETRY_COLOR)
        self.robot = RobotArtist(mat, recording.config)
        # The panel beside the mat: the time, the state, the LEDs, the run's title, the legend.
        left = _PANEL_LEFT / scale
        self.time_text = self.figure.text(
            left, 0.9, "", fontsize=15, family="monospace", va="center"
        )
        self.state_text = self.figure.text(
            left + 0.004 / scale,
            0.77,
            "",
            fontsize=15,
            weight="bold",
            va="center",
            bbox={"boxstyle": "round,pad=0.3", "facecolor": "white", "edgecolor": "#444444"},
        )
        self.led_swatches = self._draw_led_strip(left, scale)
        self.figure.text(left, 0.52, recording.title, fontsize=10, color="#555555", va="center")
        if len(recording.truth) or len(recording.odometry):
            mat.legend(
                loc="lower left",
                bbox_to_anchor=(left - 0.01 / scale, 0.1),
                bbox_transform=self.figure.transFigure,
                fontsize=9,
                frameon=False,
            )
        self.camera_image = None
        if camera:
            ax = self.figure.add_axes((1.0 / scale, 0.1, 0.72 / scale, 0.8))
            ax.set_title(f"camera: {recording.camera_topic}", fontsize=10)
            ax.axis("off")
            self.camera_image = ax.imshow(np.zeros((480, 640, 3), dtype=np.uint8))

    def _draw_mat(self, ax: Any) -> None:
        recording = self.recording
        if recording.world is not None:
            draw_mat(ax, recording.world)
            return
        poses = [p for p in (recording.truth, recording.odometry) if len(p)]
        xs = np.concatenate([p[:, 0] for p in poses]) if poses else np.zeros(1)
        ys = np.concatenate([p[:, 1] for p in poses]) if poses else np.zeros(1)
        x_span, y_span = tile_span(xs), tile_span(ys)
        # A square view, so that the frame keeps its size whatever the path.
        side = max(x_span[1] - x_span[0], y_span[1] - y_span[0])
        x_span = (x_span[0], x_span[0] + side)
        y_span = (y_span[0], y_span[0] + side)
        draw_tile_grid(ax, x_span, y_span, on_mat=True)
        ax.set_xlim(x_span[0] - 0.05, x_span[1] + 0.05)
        ax.set_ylim(y_span[0] - 0.05, y_span[1] + 0.05)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")

    def _draw_led_strip(self, left: float, scale: float) -> List[Any]:
        from matplotlib.patches import Ellipse

        width, height = self.figure.get_size_inches()
        self.figure.text(left, 0.64, "LEDs", fontsize=12, va="center")
        swatches = []
        for index in range(led_tables.LED_COUNT):
            # Round on screen: the figure is wider than tall, so the height is scaled up.
            swatch = Ellipse(
                (left + (0.1 + 0.052 * index) / scale, 0.64),
                0.044 / scale,
                0.044 / scale * width / height,
                transform=self.figure.transFigure,
                edgecolor="black",
                linewidth=1,
            )
            self.figure.add_artist(swatch)
            swatches.append(swatch)
        return swatches

    def show(self, t: float) -> List[Artist]:
        """Set every moving part to time ``t``; return them."""
        recording = self.recording
        colors = recording.leds_at(t)
        artists: List[Artist] = [self.time_text, self.state_text]
        truth = _until(recording.truth_t, recording.truth, t)
        odometry = _until(recording.odometry_t, recording.odometry, t)
        self.true_line.set_data(truth[:, 0], truth[:, 1])
        self.odometry_line.set_data(odometry[:, 0], odometry[:, 1])
        solid, ghost = (truth, odometry) if len(recording.truth) else (odometry, truth[:0])
        artists += [self.true_line, self.odometry_line]
        artists += self.robot.update(solid[-1] if len(solid) else None, colors)
        artists += self.ghost.update(ghost[-1] if len(ghost) else None, None)
        self.time_text.set_text(f"t = {t:6.1f} s")
        state = recording.state_at(t)
        self.state_text.set_text(f"state: {state}" if state else "state: (none announced)")
        for swatch, color in zip(self.led_swatches, colors):
            swatch.set_facecolor(color)
        artists += self.led_swatches
        if self.camera_image is not None:
            frame = recording.frame_at(t)
            if frame is not None:
                self.camera_image.set_data(_decode(frame))
            artists.append(self.camera_image)
        return artists

    def rgb(self, t: float) -> np.ndarray:
        """The frame at ``t`` as an RGB image, shape (H, W, 3), uint8."""
        moving = self.show(t)
        if self._still is None:
            self._draw_still(moving)
        self._canvas.restore_region(self._still)
        for artist in sorted(moving, key=lambda artist: artist.get_zorder()):
            self.figure.draw_artist(artist)
        # The red, green and blue planes gathered at once (a strided copy takes twice as long).
        return np.take(np.asarray(self._canvas.buffer_rgba()), (0, 1, 2), axis=2)

    def whole(self, t: float) -> np.ndarray:
        """The frame at ``t`` drawn whole, still parts included (what :meth:`rgb` must equal)."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        self.show(t)
        canvas = FigureCanvasAgg(self.figure)
        canvas.draw()
        self._canvas = self._still = None  # the figure has another canvas now
        return np.asarray(canvas.buffer_rgba())[:, :, :3].copy()

    def _draw_still(self, moving: List[Artist]) -> None:
        """Draw the figure without its moving parts and keep that picture."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        self._canvas = FigureCanvasAgg(self.figure)
        shown = [artist.get_visible() for artist in moving]
        for artist in moving:
            artist.set_visible(False)
        self._canvas.draw()
        self._still = self._canvas.copy_from_bbox(self.figure.bbox)
        for artist, visible in zip(moving, shown):
            artist.set_visible(visible)

    def png(self, t: float) -> bytes:
        """The frame at ``t`` as PNG bytes."""
        from PIL import Image

        buffer = io.BytesIO()
        Image.fromarray(self.rgb(t)).save(buffer, format="PNG", compress_level=1)
        return buffer.getvalue()


def _until(times: np.ndarray, poses: Poses, t: float) -> Poses:
    return poses[: int(np.searchsorted(times, t, side="right"))]


def _decode(jpeg: bytes) -> np.ndarray:
    from PIL import Image

    try:
        return np.asarray(Image.open(io.BytesIO(jpeg)).convert("RGB"))
    except (OSError, ValueError):  # a damaged frame: shown black rather than stopping the player
        return np.zeros((480, 640, 3), dtype=np.uint8)


class RunPlayer:
    """Play a recorded run: in a notebook with play, pause and a time slider, or to a file.

    Args:
        run: a :class:`Recording`, a bag (or its path), a simulator or a virtual Duckiebot.
        fps: frames per second when playing.
        speed: the run's seconds per second of playing (default: the whole run in about 30 s).
        odometry: with a simulator, odometry's poses to draw (see
            :meth:`Recording.from_simulator`).
        max_frames: the most frames (a long run is sampled more sparsely).

    In a notebook, the player shows itself when it is the cell's last value::

        RunPlayer("runs/latest/mission.bag")

    Raises:
        DuckielibError: if the run has nothing to play, or a rate is not a positive number.
    """

    def __init__(
        self,
        run: Any,
        fps: float = 5.0,
        speed: Optional[float] = None,
        odometry: Optional[object] = None,
        max_frames: int = 200,
    ) -> None:
        for name, value in (("fps", fps), ("speed", 1.0 if speed is None else speed)):
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise DuckielibError(f"RunPlayer needs a positive {name}, not {value!r}.")
        if isinstance(run, Recording):
            self.recording = run
        elif hasattr(run, "trace") or hasattr(getattr(run, "sim", None), "trace"):
            self.recording = Recording.from_simulator(run, odometry)
        else:
            self.recording = Recording.from_bag(run)
        first, last = self.recording.span
        duration = last - first
        step = (duration / 30.0 if speed is None else speed) / fps
        count = max(1, min(max_frames, math.ceil(duration / step - 1e-9) + 1 if step > 0 else 1))
        self.fps = float(fps)
        self.times = np.linspace(first, last, count) if count > 1 else np.array([last])
        self._frame = _Frame(self.recording)
        self._cache: Dict[int, bytes] = {}

    @classmethod
    def lasting(
        cls, recording: Recording, seconds: float = 12.0, max_frames: int = 100
    ) -> RunPlayer:
        """A player whose whole run lasts about ``seconds`` at 8 frames a second, for a file.

        A run shorter than ``seconds`` plays in real time, never slower.
        """
        first, last = recording.span
        return cls(
            recording, fps=8.0, speed=max(1.0, (last - first) / seconds), max_frames=max_frames
        )

    def __len__(self) -> int:
        return len(self.times)

    def frame(self, index: int) -> np.ndarray:
        """Frame number ``index`` as an RGB image, shape (H, W, 3), uint8."""
        return self._frame.rgb(float(self.times[index]))

    def png(self, index: int) -> bytes:
        """Frame number ``index`` as PNG bytes (kept, so that playing again is quick)."""
        if index not in self._cache:
            self._cache[index] = self._frame.png(float(self.times[index]))
        return self._cache[index]

    def caption(self, index: int) -> str:
        """What frame ``index`` shows, in words: its time, state and LED pattern."""
        t = float(self.times[index])
        state = self.recording.state_at(t) or "(none announced)"
        pattern = self.recording.pattern_at(t)
        lights = pattern.name if pattern is not None else "off"
        return f"t = {t:.1f} s · state: {state} · LEDs: {lights}"

    def widget(self) -> Any:
        """The player as an ipywidgets box: the picture, play/pause, a time slider, a caption."""
        return playing_widget(
            len(self.times), self.fps, lambda index: (self.png(index), "png"), self.caption
        )

    def _repr_mimebundle_(self, **kwargs: Any) -> Dict[str, Any]:
        bundle: Dict[str, Any] = self.widget()._repr_mimebundle_(**kwargs) or {}
        # Where no widget can show (a page made from the notebook), the last frame does.
        bundle["image/png"] = self.png(len(self.times) - 1)
        return bundle

    def animation(self) -> FuncAnimation:
        """The frames as a matplotlib animation, at the player's ``fps``."""
        from matplotlib import animation

        def draw(index: int) -> List[Artist]:
            return self._frame.show(float(self.times[index]))

        return animation.FuncAnimation(
            self._frame.figure, draw, frames=len(self.times), interval=1000.0 / self.fps, blit=False
        )

    def save(self, path: Union[str, Path]) -> Path:
        """Write the frames as an animated GIF or an MP4 video (at least 800 pixels wide).

        Raises:
            DuckielibError: if the suffix is neither .gif nor .mp4, the folder does not exist,
                an MP4 is asked for without ffmpeg, or the file cannot be written.
        """
        from duckielib.plots.files import (
            ANIMATION_FORMATS,
            checked_path,
            save_animation,
            save_gif_frames,
        )

        path = checked_path(path, "animation", ANIMATION_FORMATS)  # before any frame is drawn
        if path.suffix.lower() == ".mp4":
            return save_animation(self.animation(), path, fps=self.fps, dpi=_DPI)
        # The LEDs' colours exact in every frame, whatever the palette makes of the rest.
        shown = {
            color
            for _, pattern in self.recording.patterns
            for color in led_tables.pattern_colors(pattern)
        }
        frames = [self.frame(index) for index in range(len(self.times))]
        return save_gif_frames(frames, path, self.fps, sorted(shown))

    def __repr__(self) -> str:
        first, last = self.recording.span
        return (
            f"RunPlayer({self.recording.title!r}: {last - first:.1f} s in {len(self.times)} frames)"
        )


def playing_widget(
    count: int,
    fps: float,
    picture: Callable[[int], Tuple[bytes, str]],
    caption: Callable[[int], str],
) -> Any:
    """An ipywidgets box that plays ``count`` pictures: play/pause, a slider and a caption.

    The controls are above the picture, and the picture is shown at its own size (smaller in a
    narrower page), so that the play button and the whole picture fit on a laptop's screen.

    Args:
        count: how many pictures.
        fps: pictures per second when playing.
        picture: picture number ``index`` as (bytes, format: ``"png"`` or ``"jpeg"``).
        caption: what picture ``index`` shows, in words (HTML).
    """
    import ipywidgets as widgets

    last = count - 1
    data, kind = picture(0)
    width = _pixel_width(data)
    image = widgets.Image(
        value=data,
        format=kind,
        layout=widgets.Layout(
            width=f"{width}px" if width else "auto", max_width="100%", height="auto"
        ),
    )
    play = widgets.Play(min=0, max=last, step=1, interval=round(1000 / fps), description="Play")
    slider = widgets.IntSlider(min=0, max=last, readout=False, layout=widgets.Layout(width="45%"))
    text = widgets.HTML(value=caption(0))
    widgets.jslink((play, "value"), (slider, "value"))

    def show(change: Dict[str, Any]) -> None:
        index = int(change["new"])
        image.value, image.format = picture(index)
        text.value = caption(index)

    slider.observe(show, names="value")
    box = widgets.VBox([widgets.HBox([play, slider, text]), image])
    box.add_class("duckie-player")
    return box


def _pixel_width(data: bytes) -> int:
    """How many pixels wide a PNG or JPEG picture is (0 if it cannot be read)."""
    from PIL import Image

    try:
        with Image.open(io.BytesIO(data)) as picture:
            return int(picture.width)
    except (OSError, ValueError):
        return 0
