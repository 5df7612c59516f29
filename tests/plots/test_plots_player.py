"""The run player and the image view: what a student watches a run and the camera with."""

from __future__ import annotations

import math

import numpy as np
import pytest

from duckielib import rostime
from duckielib.bags import Bag, BagRecorder, BagWriter, sample_bag
from duckielib.errors import DuckielibError
from duckielib.leds import pattern_colors, pattern_named
from duckielib.messages import Pose2DStamped, String
from duckielib.missions import SQUARE_THEN_CIRCLE
from duckielib.plots import ImageView, Recording, RunPlayer
from duckielib.plots.player import _DPI
from duckielib.sim import VirtualDuckiebot

CHASSIS = np.array([0xF2, 0xC2, 0x00])


def pixels_near(image: np.ndarray, rgb, tolerance: int = 20) -> int:
    """How many pixels of ``image`` are within ``tolerance`` of ``rgb`` in every channel."""
    difference = np.abs(image[:, :, :3].astype(int) - np.asarray(rgb, dtype=int))
    return int(np.all(difference <= tolerance, axis=2).sum())


def mat_and_panel(frame: np.ndarray):
    """A frame's mat (left) and the panel beside it (time, state, LED swatches, legend)."""
    edge = int(0.6 * frame.shape[1])
    return frame[:, :edge], frame[:, edge:]


def led_rgb(name: str) -> np.ndarray:
    """The colour the first LED of pattern ``name`` shows, 0 to 255."""
    return np.round(np.asarray(pattern_colors(pattern_named(name))[0]) * 255).astype(int)


@pytest.fixture(scope="module")
def mission_player():
    return RunPlayer(sample_bag("square_then_circle_realistic"))


def test_a_mission_bag_gives_poses_states_and_lights_on_one_clock(mission_player):
    recording = mission_player.recording
    bag = Bag(sample_bag("square_then_circle_realistic"))
    assert len(recording.truth) == bag.topics["/duckiebot/simulator_node/ground_truth_pose"].count
    assert len(recording.odometry) == bag.topics["/duckiebot/odometry_node/pose"].count
    names = [name for _, name in recording.states]
    assert names == [state.name for state in SQUARE_THEN_CIRCLE.states] + ["done"]
    assert len(recording.patterns) == 8
    # The realistic robot drifts off the mat's edge (the missions' mat lies on an open floor):
    # the player draws tiles under the poses instead.
    assert recording.world is None
    first, last = recording.span
    assert first == pytest.approx(0.0, abs=0.05)
    assert last == pytest.approx(bag.duration, abs=0.05)
    # The first square leg shows its state's colour half-way through.
    start, end = recording.states[1][0], recording.states[2][0]
    middle = (start + end) / 2
    assert recording.state_at(middle) == "square"
    assert recording.pattern_at(middle).name == SQUARE_THEN_CIRCLE.states[1].color
    assert recording.frames == []


def test_a_frame_shows_the_robot_its_led_colour_and_its_state(mission_player):
    recording = mission_player.recording
    start, end = recording.states[1][0], recording.states[2][0]
    index = int(np.argmin(np.abs(mission_player.times - (start + end) / 2)))
    frame = mission_player.frame(index)
    assert frame.shape == (460, 800, 3)  # wider than tall: it fits a laptop's screen
    color = SQUARE_THEN_CIRCLE.states[1].color
    # Five LED swatches beside the mat and five LEDs on the robot, in the state's colour.
    mat, panel = mat_and_panel(frame)
    assert pixels_near(panel, led_rgb(color)) > 2000
    assert pixels_near(mat, led_rgb(color)) > 10
    # The yellow chassis, to scale (the view spans the path, a little more than the mat).
    assert pixels_near(mat, CHASSIS, tolerance=8) > 250
    caption = mission_player.caption(index)
    assert f"state: square · LEDs: {color}" in caption
    assert mission_player.png(index)[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_robot_moves_from_frame_to_frame_and_the_paths_grow(mission_player):
    first, last = mission_player.frame(0), mission_player.frame(len(mission_player) - 1)
    assert not np.array_equal(first, last)
    true_path = (0x1F, 0x9B, 0xFF)
    assert pixels_near(first, true_path, 10) < pixels_near(last, true_path, 10)


def test_the_player_shows_itself_in_a_notebook_as_a_widget_with_a_picture(mission_player):
    bundle = mission_player._repr_mimebundle_()
    assert "application/vnd.jupyter.widget-view+json" in bundle
    assert bundle["image/png"][:4] == b"\x89PNG"
    box = mission_player.widget()
    # On a laptop's screen (1366 by 768: about 650 pixels of page, 530 of them the notebook's)
    # the play button and the whole picture show together: the controls come first, above a
    # picture shown at its own size, 460 pixels tall.
    controls, image = box.children
    play, slider, caption = controls.children
    assert mission_player._frame.figure.get_size_inches() * _DPI == pytest.approx((800, 460))
    assert (image.layout.width, image.layout.max_width) == ("800px", "100%")
    assert (play.max, slider.max) == (len(mission_player) - 1, len(mission_player) - 1)
    before = image.value
    slider.value = len(mission_player) // 2  # what moving the slider (or playing) does
    assert image.value != before
    assert "state: " in caption.value
    assert caption.value != mission_player.caption(0)


def test_a_simulator_run_plays_with_its_lights_and_an_odometry_ghost():
    bot = VirtualDuckiebot(seed=1)
    bot.run(0.1)  # the LED emitter shows its start pattern first
    bot.sim.set_led_pattern("RED")
    bot.sim.set_wheel_duties(0.4, 0.5)
    bot.run(2.0)
    poses = bot.sim.trace.poses() + np.array([0.05, 0.0, 0.0])  # odometry 5 cm off
    player = RunPlayer(bot, odometry=poses)
    frame = player.frame(len(player) - 1)
    assert pixels_near(mat_and_panel(frame)[1], led_rgb("RED")) > 2000
    assert "state: (none announced) · LEDs: RED" in player.caption(len(player) - 1)
    ghost = (0xFF, 0x9D, 0x2E)
    assert pixels_near(frame, ghost, 10) > 100


def test_a_bag_with_the_camera_shows_its_latest_frame_beside_the_mat(tmp_path):
    bot = VirtualDuckiebot(seed=0)
    topics = [
        bot.namespace + name
        for name in ("camera_node/image/compressed", "simulator_node/ground_truth_pose")
    ]
    with BagRecorder(tmp_path / "camera.bag", topics, graph=bot.graph):
        bot.run(0.5)
    player = RunPlayer(tmp_path / "camera.bag")
    assert player.recording.camera_topic == topics[0]
    assert len(player.recording.frames) >= 14
    frame = player.frame(len(player) - 1)
    assert frame.shape[1] >= 1400  # the mat's 800 pixels and the camera beside it
    camera_side = frame[:, 850:]
    assert camera_side.std() > 20  # a picture, not a blank panel


def test_frames_drawn_over_the_still_mat_are_the_whole_drawings_pixel_for_pixel(
    mission_player, tmp_path
):
    # The still parts are drawn once and each frame only draws what moves over them: the
    # pictures must be exactly those of drawing everything, in any order of times, with the
    # camera beside the mat and with a robot hidden before its first pose.
    bot = VirtualDuckiebot(seed=0)
    topics = [
        bot.namespace + name
        for name in ("camera_node/image/compressed", "simulator_node/ground_truth_pose")
    ]
    bot.run(0.2)
    with BagRecorder(tmp_path / "camera.bag", topics, graph=bot.graph):
        bot.sim.set_wheel_duties(0.4, 0.5)
        bot.run(0.5)
    for player in (mission_player, RunPlayer(tmp_path / "camera.bag")):
        last = len(player) - 1
        for index in (last // 2, 0, last, last // 3):
            fast = player.frame(index)
            whole = player._frame.whole(float(player.times[index]))
            assert fast.shape == whole.shape
            assert np.array_equal(fast, whole), f"frame {index}: {(fast != whole).sum()} values"
    hidden = mission_player._frame.rgb(mission_player.times[0] - 5.0)  # before any pose
    assert np.array_equal(hidden, mission_player._frame.whole(mission_player.times[0] - 5.0))
    assert pixels_near(hidden, CHASSIS, tolerance=8) == 0


def test_a_bag_with_nothing_to_play_or_without_the_camera_asked_for_says_so(tmp_path):
    path = tmp_path / "chatter.bag"
    with BagWriter(path) as writer:
        writer.write("/chatter", String(data="hello"), 1_000_000_000)
    with pytest.raises(DuckielibError, match="nothing to play"):
        RunPlayer(path)
    with pytest.raises(DuckielibError, match=r"no image topic /nope.*none"):
        Recording.from_bag(sample_bag(), camera_topic="/nope")
    with pytest.raises(DuckielibError, match="positive fps"):
        RunPlayer(sample_bag(), fps=0)


def test_the_player_saves_a_gif_at_least_800_pixels_wide(tmp_path):
    from PIL import Image

    bot = VirtualDuckiebot(seed=0)
    bot.run(0.1)
    bot.sim.set_led_pattern("GREEN")
    bot.sim.set_wheel_duties(0.5, 0.5)
    bot.run(1.0)
    path = RunPlayer(bot, speed=0.5).save(tmp_path / "run.gif")
    with Image.open(path) as gif:
        assert gif.size[0] >= 800
        assert gif.n_frames == 12  # 1.1 s at 0.5 s per second and 5 frames per second
    with pytest.raises(DuckielibError, match=r"\.gif or \.mp4"):
        RunPlayer(bot).save(tmp_path / "run.avi")


def test_the_image_view_shows_a_topic_live_and_stops_subscribing_when_closed():
    bot = VirtualDuckiebot(seed=0)
    topic = bot.namespace + "camera_node/image/compressed"
    with ImageView(topic, graph=bot.graph) as view:
        assert view.image.value == b""
        bot.run(1.0)
    assert view.count == 31  # at 0 s, 1/30 s, ..., 1 s
    assert view.image.value == bytes(view.latest.data)  # the last frame, shown when closed
    assert view.image.value[:2] == b"\xff\xd8"  # a JPEG, shown as it arrived
    assert "frame 31, stamped 1.00 s" in view.caption.value
    assert bot.graph.topics[topic].subscribers == []  # the camera may stop rendering
    with pytest.raises(DuckielibError, match="not sensor_msgs/CompressedImage"):
        ImageView(bot.namespace + "left_wheel_encoder_node/tick", graph=bot.graph)


def test_the_image_view_plays_a_bags_frames(tmp_path):
    bot = VirtualDuckiebot(seed=0)
    topic = bot.namespace + "camera_node/image/compressed"
    with BagRecorder(tmp_path / "camera.bag", [topic], graph=bot.graph):
        bot.run(0.5)
    box = ImageView.from_bag(tmp_path / "camera.bag")
    (play, slider, caption), image = box.children[0].children, box.children[1]
    frames = Bag(tmp_path / "camera.bag").read(topic)
    assert play.max == len(frames) - 1
    slider.value = 3
    assert image.value == bytes(frames[3].message.data)
    assert f"frame 4 of {len(frames)}" in caption.value
    with pytest.raises(DuckielibError, match="no image topic"):
        ImageView.from_bag(sample_bag())


def test_a_real_robots_odometry_bag_plays_with_the_robot_where_odometry_puts_it(tmp_path):
    # A real Duckiebot has no ground truth: its bag holds the robot's own pose estimate, which
    # starts at (0, 0) and may go negative.
    path = tmp_path / "real.bag"
    with BagWriter(path) as writer:
        for k in range(60):
            t = k / 10
            pose = Pose2DStamped(x=-0.3 * t, y=0.1 * t, theta=math.pi)
            pose.header.stamp = rostime.Time.from_sec(1_700_000_000 + t)
            writer.write("/db21/velocity_to_pose_node/pose", pose, int((1_700_000_000 + t) * 1e9))
    player = RunPlayer(path)
    recording = player.recording
    assert len(recording.truth) == 0
    assert len(recording.odometry) == 60
    assert recording.world is None  # tiles under the path, no walls
    assert recording.span == pytest.approx((0.0, 5.9))
    frame = player.frame(len(player) - 1)
    assert pixels_near(frame, CHASSIS, tolerance=8) > 500  # the robot, drawn at odometry's pose
    assert "state: (none announced) · LEDs: off" in player.caption(0)


def test_the_image_views_own_node_is_left_out_of_the_graph_drawing():
    from duckielib.ros import ros_graph

    bot = VirtualDuckiebot(seed=0)
    before = ros_graph(bot.graph)
    with ImageView(bot.namespace + "camera_node/image/compressed", graph=bot.graph):
        bot.run(0.1)
        during = ros_graph(bot.graph)
    assert during.nodes == before.nodes
    assert [name for name in during.hidden if name.startswith("/rqt_image_view_")]
