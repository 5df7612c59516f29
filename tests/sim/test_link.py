"""The robot and the nodes apart: one clock over a socket, and nothing but topics and services.

The robot's side runs here on a real virtual Duckiebot; the nodes' side is either the real
nodes' process (``python -m duckielib.tools.apart``) or a hand-written peer in a thread that
sends what a hostile nodes' process could send.
"""

from __future__ import annotations

import socket
import struct
import threading
from pathlib import Path

import pytest

from duckielib.bags import Bag
from duckielib.messages import get_message_class, get_service_class
from duckielib.missions import mission_named
from duckielib.ros.graph import Graph
from duckielib.rostime import NS_PER_S
from duckielib.sim import VirtualDuckiebot
from duckielib.sim.link import LinkError, NodesStopped, RobotLink, receive, send
from duckielib.tools.apart import drive_apart, local_launcher, nodes_arguments, run_apart
from duckielib.tools.runner import RECORDED, drive_and_record

NAMESPACE = "/duckiebot/"
Pose2DStamped = get_message_class("duckietown_msgs/Pose2DStamped")
WheelsCmdStamped = get_message_class("duckietown_msgs/WheelsCmdStamped")


class Peer:
    """A nodes' side written by hand: answers each step as ``answer(header)`` says."""

    def __init__(self, sock, answer):
        self.sock = sock
        self.answer = answer
        self.hello = None
        self.steps = []
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        try:
            self.hello, _ = receive(self.sock, 10)
            send(self.sock, {"k": "ready"})
            while True:
                header, body = receive(self.sock, 10)
                self.steps.append(header)
                if header["k"] == "end":
                    send(self.sock, {"k": "bye", "pubs": [], "msgs": [], "log": []})
                    return
                reply, blobs = self.answer(header, body)
                if reply is None:
                    return
                self.sock.sendall(reply) if isinstance(reply, bytes) else send(
                    self.sock, reply, blobs
                )
        except (LinkError, OSError):
            return


def idle(**fields):
    return {"k": "idle", "next": None, "finished": False, "pubs": [], "subs": [], "msgs": [],
            **fields}  # fmt: skip


def robot_with(answer, seconds=1.0):
    """Start a robot's side against a :class:`Peer`; run ``seconds`` and end."""
    graph = Graph(echo_logs=False)
    bot = VirtualDuckiebot(graph=graph)
    here, there = socket.socketpair()
    link = RobotLink(here, bot, reply_timeout=10)
    peer = Peer(there, answer)
    link.start()
    return link, bot, peer


def test_the_nodes_are_offered_the_robots_topics_and_services_but_not_the_simulators():
    link, bot, peer = robot_with(lambda header, body: (idle(), []))
    link.advance(round(0.5 * NS_PER_S))
    assert link.end(True) is None
    topics = {topic for _, topic, _, _ in peer.hello["topics"]}
    services = {name for _, name, _ in peer.hello["services"]}
    assert NAMESPACE + "left_wheel_encoder_node/tick" in topics
    assert NAMESPACE + "camera_node/image/compressed" in topics
    assert NAMESPACE + "led_emitter_node/set_pattern" in services
    assert not [name for name in topics | services if "simulator_node" in name]
    assert NAMESPACE + "simulator_node/ground_truth_pose" in bot.graph.topics  # it is there
    assert peer.hello["params"]["duckiebot"]["kinematics_node"]["baseline"] == pytest.approx(0.1)


def test_what_the_nodes_publish_on_the_robots_outputs_stays_with_them():
    forged = Pose2DStamped(x=9.0, y=9.0, theta=1.0).to_bytes()
    ticks = NAMESPACE + "left_wheel_encoder_node/tick"
    truth = NAMESPACE + "simulator_node/ground_truth_pose"
    command = NAMESPACE + "wheels_driver_node/wheels_cmd"
    go = WheelsCmdStamped(vel_left=0.5, vel_right=0.5).to_bytes()
    sent = []

    def answer(header, body):
        if sent:
            return idle(), []
        sent.append(True)
        pubs = [
            ["/duckiebot/mission_node", truth, "duckietown_msgs/Pose2DStamped"],
            ["/duckiebot/mission_node", ticks, "duckietown_msgs/WheelEncoderStamped"],
            ["/duckiebot/mission_node", command, "duckietown_msgs/WheelsCmdStamped"],
        ]
        msgs = [[truth, len(forged)], [command, len(go)]]
        return idle(pubs=pubs, msgs=msgs), [forged, go]

    link, bot, _ = robot_with(answer)
    seen = []
    from duckielib.ros.context import node_context
    from duckielib.ros.rospy import Subscriber

    with node_context(bot.graph.host_node("watcher", NAMESPACE)):
        Subscriber(truth, Pose2DStamped, seen.append, queue_size=None)
    link.advance(round(1.0 * NS_PER_S))
    link.end(True)
    assert set(link.refused) == {truth, ticks}
    assert all(pose.x < 1.0 for pose in seen), "no forged pose reached the robot's graph"
    # The command topic is an input of the robot: its message drove the wheels.
    assert bot.sim.pose.y > 0.0 or bot.sim.pose.x > 0.0
    assert bot.sim.wheel_duties == (0.5, 0.5)


@pytest.mark.parametrize(
    ("frame", "said"),
    [
        (struct.pack("!II", 10, 0) + b"not json!!", "not JSON"),
        (struct.pack("!II", 2**30, 0), "over the limit"),
        (b"\x00\x00", "closed the link"),
        # Read without recursing: a JSON reader would stop on its recursion limit.
        (struct.pack("!II", 200_000, 0) + b"[" * 200_000, "nests more than 32 levels deep"),
    ],
)
def test_a_broken_frame_ends_the_run_with_a_sentence(frame, said):
    def answer(header, body):
        there.sendall(frame)
        there.shutdown(socket.SHUT_RDWR)  # and then it is gone
        return None, []

    graph = Graph(echo_logs=False)
    bot = VirtualDuckiebot(graph=graph)
    here, there = socket.socketpair()
    link = RobotLink(here, bot, reply_timeout=10)
    Peer(there, answer)
    link.start()
    with pytest.raises(LinkError, match=said):
        link.advance(round(1.0 * NS_PER_S))


def test_junk_bytes_on_an_accepted_topic_are_refused_before_any_node_reads_them():
    state = NAMESPACE + "mission_node/state"

    def answer(header, body):
        pubs = [["/duckiebot/mission_node", state, "std_msgs/String"]]
        return idle(pubs=pubs, msgs=[[state, 4]]), [b"\xff\xff\xff\x7f"]

    link, _, _ = robot_with(answer)
    with pytest.raises(LinkError, match="on /duckiebot/mission_node/state that is not a std_msgs"):
        link.advance(round(1.0 * NS_PER_S))


@pytest.mark.parametrize(
    ("reply", "said"),
    [
        (idle(next="soon"), "a time in the past"),
        (idle(pubs=[["/duckiebot/n", "no spaces allowed", "std_msgs/String"]]), "not a ROS name"),
        (idle(subs=[["a", "list"]]), "wrongly"),
        (idle(msgs=[["/duckiebot/x", 99]]), "sizes do not match"),
        ({"k": "call", "service": "/duckiebot/simulator_node/teleport"}, "does not offer"),
        ({"k": "shout"}, "'shout' where 'idle'"),
    ],
)
def test_what_a_hostile_nodes_side_says_is_checked(reply, said):
    link, _, _ = robot_with(lambda header, body: (reply, []))
    with pytest.raises(LinkError, match=said):
        link.advance(round(1.0 * NS_PER_S))


def test_a_service_call_reaches_the_robots_led_emitter_at_the_same_time():
    change_pattern = get_service_class("duckietown_msgs/ChangePattern")
    request = change_pattern._request_class(pattern_name=get_message_class("std_msgs/String")(
        data="GREEN"
    )).to_bytes()  # fmt: skip
    replies = []

    def answer(header, body):
        if not replies:
            send(peer_sock[0], {"k": "call", "service": NAMESPACE + "led_emitter_node/set_pattern"},
                 [request])  # fmt: skip
            replies.append(receive(peer_sock[0], 10)[0])
        return idle(), []

    peer_sock = []
    graph = Graph(echo_logs=False)
    bot = VirtualDuckiebot(graph=graph)
    here, there = socket.socketpair()
    peer_sock.append(there)
    link = RobotLink(here, bot, reply_timeout=10)
    Peer(there, answer)
    link.start()
    link.advance(round(0.5 * NS_PER_S))
    link.end(True)
    assert replies == [{"k": "reply", "ok": True}]
    assert bot.sim.led_pattern.name == "GREEN"


def test_a_nodes_side_that_stops_says_why():
    def answer(header, body):
        return {"k": "bye", "crash": ["solution", "Finish notebook 05."], "log": []}, []

    link, _, _ = robot_with(answer)
    with pytest.raises(NodesStopped, match="Finish notebook 05"):
        link.advance(round(1.0 * NS_PER_S))


def test_a_run_apart_records_what_one_process_records(tmp_path, monkeypatch):
    # The same nodes, the same seed: the robot's side and the nodes' process keep one clock,
    # so every recorded topic carries as many messages, and the robot ends where it ended.
    monkeypatch.setenv("VEHICLE_NAME", "duckiebot")
    chosen = mission_named("rotation")
    together = {"bag": tmp_path / "one.bag", "log": tmp_path / "one.txt"}
    apart = {"bag": tmp_path / "two.bag", "log": tmp_path / "two.txt"}
    from duckielib.ros.modules import modules_installed
    from duckielib.tools.runner import _solution

    with modules_installed(replace_real=True):
        parts = _solution(None)
        one = drive_and_record(parts, chosen, "realistic", 3, together, 240.0)
    arguments = nodes_arguments("rotation")
    start = lambda sock: local_launcher(None)(sock, arguments)  # noqa: E731
    two = drive_apart(start, chosen, "realistic", 3, apart, 240.0)
    assert one[3] is None
    assert two[3] is None
    assert one[1] == two[1], "the same simulated time"
    bags = [Bag(files["bag"]) for files in (together, apart)]
    assert set(bags[1].topics) == {NAMESPACE + name for name in RECORDED}
    assert set(bags[0].topics) == set(bags[1].topics)
    for topic in bags[0].topics:  # message for message: the same time, the same content
        one_side, other = bags[0].read(topic), bags[1].read(topic)
        assert len(one_side) == len(other) > 0, topic
        assert [(m.time_ns, m.message) for m in one_side] == [
            (m.time_ns, m.message) for m in other
        ], topic
    # Both sides' logs, in one file, in time order.
    text = apart["log"].read_text()
    assert "[/duckiebot/led_emitter_node]: Pattern changed to RED." in text
    assert "[/duckiebot/mission_node]: state clockwise" in text


FORKS_A_BUSY_CHILD = """

_mission_node = mission_node


def mission_node(mission):
    import os

    child = os.fork()
    if child == 0:
        while True:
            pass
    with open(os.environ["CHILD_FILE"], "w") as noted:
        noted.write(str(child))
    _mission_node(mission)
"""


def test_what_a_node_forked_ends_with_a_run_apart(tmp_path, monkeypatch):
    import time

    from duckielib.config import PROJECT_ROOT
    from duckielib.solution.export import export_solution

    solution = tmp_path / "solution.py"
    solution.write_text(export_solution(PROJECT_ROOT / "solutions").source + FORKS_A_BUSY_CHILD)
    monkeypatch.setenv("CHILD_FILE", str(tmp_path / "child"))
    run = run_apart(solution, mission="straight", out=tmp_path / "run", animation=False)
    assert run.report.finished
    child = int((tmp_path / "child").read_text())
    deadline = time.monotonic() + 5
    while _state(child) not in ("gone", "Z") and time.monotonic() < deadline:
        time.sleep(0.05)  # killed at the run's end; reaped by whoever adopted it
    assert _state(child) in ("gone", "Z"), f"the node's busy child {child} still runs"


def _state(pid):
    """A process's state letter (``Z``: ended, not yet reaped), or ``"gone"``."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return "gone"


def test_duckie_mission_apart_drives_the_reference_as_one_process_does(tmp_path):
    run = run_apart(mission="straight", out=tmp_path / "run", animation=False)
    assert run.report.finished
    assert run.summary["error"] is None
    assert run.summary["distance_to_start"] < 0.01
