"""The live view: a viewer speaking the Foxglove WebSocket protocol watches the virtual robot.

The client here speaks the protocol as Foxglove and Lichtblick do (its published spec: JSON
control messages, binary message data and time, little-endian), over a real WebSocket on
loopback, and decodes what it receives with rosbags from the schemas the server advertised:
nothing of the course's own message code reads the bytes.
"""

from __future__ import annotations

import io
import json
import math
import re
import signal
import socket
import struct
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

import pytest
import websocket
from PIL import Image

from duckielib.bags import Bag
from duckielib.errors import ConfigError
from duckielib.messages import String, WheelsCmdStamped
from duckielib.ros import rospy
from duckielib.ros.context import node_context
from duckielib.ros.graph import Graph
from duckielib.sim import VirtualDuckiebot
from duckielib.sim.live import LiveView

#: What Foxglove and Lichtblick offer in the handshake; the server picks the one it speaks.
SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"]
DUCKIE = str(Path(sys.executable).with_name("duckie"))


class Viewer:
    """A viewer's end of the Foxglove WebSocket protocol."""

    def __init__(self, url: str) -> None:
        self.ws = websocket.create_connection(url, subprotocols=SUBPROTOCOLS, timeout=10)
        self.info = json.loads(self.ws.recv())
        assert self.info["op"] == "serverInfo"
        self.channels: dict[int, dict] = {}
        self.by_topic: dict[str, dict] = {}
        self.subscriptions: dict[int, int] = {}  # subscription id -> channel id
        self.received: dict[str, list] = defaultdict(list)  # topic -> [(time, payload)]
        self.times: list[int] = []
        self.closed = False
        self._decoders: dict[int, object] = {}

    def pump(self, quiet: float = 0.3, subscribe_new: bool = False) -> None:
        """Take what the server sends until it has been quiet for ``quiet`` s (or closes).

        With ``subscribe_new``, subscribe to each channel as it is advertised.
        """
        self.ws.settimeout(quiet)
        try:
            while True:
                opcode, data = self.ws.recv_data()
                if opcode == websocket.ABNF.OPCODE_CLOSE:
                    self.closed = True
                    return
                if opcode == websocket.ABNF.OPCODE_TEXT:
                    message = json.loads(data)
                    new = message.get("channels", []) if message["op"] == "advertise" else []
                    for channel in new:
                        self.channels[channel["id"]] = channel
                        self.by_topic[channel["topic"]] = channel
                    if new and subscribe_new:
                        self.subscribe([channel["topic"] for channel in new])
                elif data[0] == 1:  # message data
                    subscription, stamp = struct.unpack_from("<IQ", data, 1)
                    topic = self.channels[self.subscriptions[subscription]]["topic"]
                    self.received[topic].append((stamp, bytes(data[13:])))
                elif data[0] == 2:  # time
                    self.times.append(struct.unpack_from("<Q", data, 1)[0])
        except (websocket.WebSocketTimeoutException, websocket.WebSocketConnectionClosedException):
            self.closed = self.closed or not self.ws.connected

    def subscribe(self, topics) -> None:
        asked = []
        for topic in topics:
            number = len(self.subscriptions)
            self.subscriptions[number] = self.by_topic[topic]["id"]
            asked.append({"id": number, "channelId": self.by_topic[topic]["id"]})
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": asked}))

    def unsubscribe(self, topic: str) -> None:
        ids = [n for n, c in self.subscriptions.items() if c == self.by_topic[topic]["id"]]
        self.ws.send(json.dumps({"op": "unsubscribe", "subscriptionIds": ids}))

    def decoded(self, topic: str) -> list:
        """The messages received on ``topic``, decoded by rosbags from the advertised schema."""
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore

        channel = self.by_topic[topic]
        assert (channel["encoding"], channel["schemaEncoding"]) == ("ros1", "ros1msg")
        if channel["id"] not in self._decoders:
            store = get_typestore(Stores.EMPTY)
            store.register(get_types_from_msg(channel["schema"], channel["schemaName"]))
            name = channel["schemaName"].replace("/", "/msg/", 1)
            self._decoders[channel["id"]] = lambda data: store.deserialize_ros1(data, name)
        decode = self._decoders[channel["id"]]
        return [(stamp, decode(payload)) for stamp, payload in self.received[topic]]


def ns(stamp) -> int:
    return stamp.sec * 10**9 + stamp.nanosec


def drive_in_a_curve():
    rospy.init_node("driver")
    wheels = rospy.Publisher("wheels_driver_node/wheels_cmd", WheelsCmdStamped, queue_size=1)
    while not rospy.is_shutdown():
        wheels.publish(WheelsCmdStamped(vel_left=0.3, vel_right=0.6))
        rospy.sleep(0.1)


@pytest.fixture
def bot():
    robot = VirtualDuckiebot(graph=Graph(echo_logs=False))
    yield robot
    robot.shutdown()


def test_a_viewer_sees_every_topic_the_poses_as_frames_the_camera_and_the_time(bot, capsys):
    bot.launch(drive_in_a_curve, name="driver")
    view = bot.live(port=0, rate=20)
    assert capsys.readouterr().out.startswith(f"Live view at {view.url}: in Foxglove or ")
    viewer = Viewer(view.url)
    assert "time" in viewer.info["capabilities"]
    viewer.pump()
    published = {t for t, record in bot.graph.topics.items() if record.publishers}
    truth = "/duckiebot/simulator_node/ground_truth_pose"
    camera = "/duckiebot/camera_node/image/compressed"
    assert set(viewer.by_topic) == published | {"/tf", "/clock", truth + "_3d"}
    for topic in published:  # each with its ROS 1 type and full definition
        channel, record = viewer.by_topic[topic], bot.graph.topics[topic]
        assert channel["schemaName"] == record.type
        assert channel["schema"] == record.data_class._full_text
    viewer.subscribe([truth, truth + "_3d", "/tf", camera, "/clock"])
    assert view.wait_for_viewer(timeout=10)
    wall = time.monotonic()
    bot.run(1.0)
    wall = time.monotonic() - wall
    viewer.pump()

    # The poses: the truth as published, as a frame on /tf and as a PoseStamped.
    poses = viewer.decoded(truth)
    frames = [(t, tf.transforms[0]) for t, tf in viewer.decoded("/tf")]
    stamped = viewer.decoded(truth + "_3d")
    assert len(poses) == len(frames) == len(stamped) == 31  # 30 Hz, 0 s to 1 s
    x, y, theta = bot.sim.pose
    last = poses[-1][1]
    assert (last.x, last.y, last.theta) == pytest.approx((x, y, theta), abs=1e-3)
    assert math.hypot(last.x - poses[0][1].x, last.y - poses[0][1].y) > 0.1  # it drove
    for (t, pose), (t_tf, frame), (t_3d, pose_3d) in zip(poses, frames, stamped):
        assert t == t_tf == t_3d == ns(pose.header.stamp) == ns(frame.header.stamp)
        assert (frame.header.frame_id, frame.child_frame_id) == ("world", truth.strip("/"))
        assert (frame.transform.translation.x, frame.transform.translation.y) == (pose.x, pose.y)
        q = frame.transform.rotation
        assert math.isclose(2 * math.atan2(q.z, q.w), pose.theta, abs_tol=1e-12)
        assert (pose_3d.pose.position.x, pose_3d.pose.orientation.z) == (pose.x, q.z)

    # The camera, rendered once a viewer shows it (the view looks every 0.1 s).
    images = viewer.decoded(camera)
    assert 25 <= len(images) <= 28
    stamp, image = images[-1]
    assert image.format == "jpeg"
    assert stamp == ns(image.header.stamp) == 10**9
    assert Image.open(io.BytesIO(bytes(image.data))).size == (640, 480)

    # The time: the protocol's time messages and /clock, up to the end, never backwards.
    assert viewer.times == sorted(viewer.times)
    assert viewer.times[-1] == 10**9
    clocks = [ns(message.clock) for _, message in viewer.decoded("/clock")]
    assert clocks == viewer.times
    assert len(clocks) >= 30

    # The pace: 1 simulated second at 20 x the wall clock's takes at least 0.05 s.
    assert wall >= 0.045
    view.close()
    assert bot.graph._clock_listeners == [bot._advance_physics]
    port = int(view.url.rsplit(":", 1)[1])
    # The port is free again at once, though the viewer has not closed its connection.
    with LiveView(bot.graph, port=port) as again:
        assert again.url == view.url


def test_images_are_rendered_only_while_shown_and_latched_messages_reach_a_late_viewer(bot):
    with node_context(bot.graph.host_node("greeter")):
        greeting = rospy.Publisher("/greeting", String, queue_size=1, latch=True)
        greeting.publish(String("hello"))
    camera = "/duckiebot/camera_node/image/compressed"
    with LiveView(bot.graph, port=0, rate=100) as view:
        viewer = Viewer(view.url)
        viewer.pump()

        def tapped():
            return sum(type(s).__name__ == "Tap" for s in bot.graph.topics[camera].subscribers)

        bot.run(0.2)
        assert tapped() == 0
        viewer.subscribe([camera, "/greeting"])
        viewer.pump()
        bot.run(0.2)
        assert tapped() == 1
        viewer.unsubscribe(camera)
        viewer.pump()
        bot.run(0.2)
        assert tapped() == 0
        viewer.pump()
        assert [m.data for _, m in viewer.decoded("/greeting")] == ["hello"]
        assert 0 < len(viewer.received[camera]) <= 7
    assert view.closed
    assert tapped() == 0


def test_a_topic_that_starts_while_a_viewer_watches_reaches_it_whole_however_late_it_subscribes(
    bot,
):
    # The viewer subscribes to the new topic only once the run has published all of it: what
    # was held back for it arrives then, in order, with the times it was published at.
    with LiveView(bot.graph, port=0, rate=100) as view:
        viewer = Viewer(view.url)
        viewer.pump()
        viewer.subscribe(["/clock"])
        assert view.wait_for_viewer(timeout=10)
        with node_context(bot.graph.host_node("counter")):
            counter = rospy.Publisher("/count", String, queue_size=10)
        for number in range(5):
            counter.publish(String(str(number)))
            bot.run(0.05)
        viewer.pump()
        assert "/count" in viewer.by_topic
        assert viewer.received["/count"] == []
        viewer.subscribe(["/count"])
    # Closing waited for the subscription, then sent what was held back.
    while not viewer.closed:
        viewer.pump()
    messages = viewer.decoded("/count")
    assert [message.data for _, message in messages] == ["0", "1", "2", "3", "4"]
    assert [t for t, _ in messages] == [round(n * 0.05 * 10**9) for n in range(5)]


def test_a_taken_port_and_a_bad_rate_are_said(bot):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(ConfigError, match=f"cannot serve on 127.0.0.1:{port} .*another port"):
            LiveView(bot.graph, port=port)
    for rate in (0, -1.0, math.nan, True):
        with pytest.raises(ConfigError, match="rate must be a number above 0"):
            LiveView(bot.graph, port=0, rate=rate)
    assert bot.graph._clock_listeners == [bot._advance_physics]


def start_live_mission(
    out: Path, *command: str, rate: str = "50"
) -> tuple[subprocess.Popen, str, str]:
    """``duckie mission --live`` (or ``command --live``), the address it serves at, and what
    it says waits for the viewer.

    Its stderr goes to ``err.txt`` beside ``out``: a pipe nobody reads could fill and stop it.
    """
    command = command or ("mission", "--mission", "straight", "--no-animation", "--no-figure")
    with (out.parent / "err.txt").open("w") as err:
        process = subprocess.Popen(
            [DUCKIE, *command, "--live", "--port", "0", "--rate", rate, "--out", str(out)],
            stdout=subprocess.PIPE,
            stderr=err,
            text=True,
        )
    url = None
    for line in process.stdout:  # up to the line that says what waits for the viewer
        found = re.search(r"ws://127\.0\.0\.1:\d+", line)
        url = found.group(0) if found else url
        if url and "when a viewer subscribes to a topic (Ctrl-C to stop)." in line:
            return process, url, line.split(" when ")[0]
    process.kill()
    pytest.fail(f"{command[0]} --live said no address: {(out.parent / 'err.txt').read_text()}")


def test_duckie_mission_live_waits_for_a_viewer_and_serves_the_whole_run(tmp_path):
    process, url, waiting = start_live_mission(tmp_path / "run")
    assert waiting == "The mission starts"
    try:
        viewer = Viewer(url)
        viewer.pump()
        time.sleep(1.0)
        assert process.poll() is None  # waiting for the viewer: nothing ran
        truth = "/duckiebot/simulator_node/ground_truth_pose"
        viewer.subscribe([truth, "/tf", "/duckiebot/left_wheel_encoder_node/tick"])
        while not viewer.closed:
            viewer.pump(quiet=30)
        out, _ = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 0, (tmp_path / "err.txt").read_text()
    assert "A viewer is watching: driving at 50 x the wall clock's pace." in out
    bag = Bag(tmp_path / "run" / "mission.bag")
    received = viewer.decoded(truth)
    recorded = [data for _, _, data in bag.raw_messages([truth])]
    payloads = {payload for _, payload in viewer.received[truth]}
    lost = [number for number, data in enumerate(recorded) if data not in payloads]
    assert not lost, f"the viewer missed these of the {len(recorded)} poses: {lost}"
    assert len(received) == bag.topics[truth].count > 300
    assert received[0][0] <= 10**6  # from the start
    assert [payload for _, payload in viewer.received[truth]] == [
        data for _, _, data in bag.raw_messages([truth])
    ]
    children = [tf.transforms[0].child_frame_id for _, tf in viewer.decoded("/tf")]
    assert children.count(truth.strip("/")) == len(received)
    assert (
        children.count("duckiebot/odometry_node/pose")
        == bag.topics["/duckiebot/odometry_node/pose"].count
    )
    assert len(viewer.received["/duckiebot/left_wheel_encoder_node/tick"]) == (
        bag.topics["/duckiebot/left_wheel_encoder_node/tick"].count
    )


def test_ctrl_c_while_waiting_for_a_viewer_ends_the_mission_as_interrupted(tmp_path):
    process, _, _ = start_live_mission(tmp_path / "run")
    try:
        time.sleep(0.5)
        process.send_signal(signal.SIGINT)
        process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 130
    assert (tmp_path / "err.txt").read_text().strip() == "duckie: interrupted."
    bag = Bag(tmp_path / "run" / "mission.bag")  # closed whole: its index lists every chunk
    assert list(bag.topics) == ["/duckiebot/led_emitter_node/led_pattern"]  # nothing drove


def test_duckie_run_live_serves_a_projects_nodes_with_the_projects_own_messages(tmp_path):
    project = Path(__file__).resolve().parents[1] / "foreign" / "projects" / "square_project"
    command = ("run", str(project), "--seconds", "20")
    process, url, waiting = start_live_mission(tmp_path / "run", *command, rate="5")
    assert waiting == "The nodes start"
    try:
        viewer = Viewer(url)
        while not viewer.closed:  # each channel subscribed to as it is advertised, to the end
            viewer.pump(quiet=30, subscribe_new=True)
        out, _ = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 0, (tmp_path / "err.txt").read_text()
    assert "A viewer is watching: driving at 5 x the wall clock's pace." in out
    progress = "/duckiebot/square_driver/progress"
    assert viewer.by_topic[progress]["schemaName"] == "motion_msgs/Progress"
    # A topic that starts during the run (here for 0.6 wall seconds) is advertised as its
    # publisher is created and held back until the viewer's subscription arrives (within two
    # wall seconds): the viewer has it whole, from its first message, however short it is.
    received = [data for _, data in viewer.received[progress]]
    recorded = [data for _, _, data in Bag(tmp_path / "run" / "run.bag").raw_messages([progress])]
    assert len(recorded) >= 10
    assert len(received) == len(recorded), (
        f"the viewer received {len(received)} of the {len(recorded)} messages recorded"
    )
    assert received == recorded
    done = [message.done for _, message in viewer.decoded(progress)]
    assert done == sorted(done)
    assert done[-1] == pytest.approx(1.0, abs=0.05)
    truth = viewer.decoded("/duckiebot/simulator_node/ground_truth_pose")
    assert math.hypot(truth[-1][1].x - truth[0][1].x, truth[-1][1].y - truth[0][1].y) > 0.3
