"""Recording the graph to bags: what is recorded, when it reaches the disk, how it is closed."""

from __future__ import annotations

import io
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest
from bagtools import LEFT, RIGHT

from duckielib.bags import Bag, BagRecorder, read_topic, repair_bag
from duckielib.bags.records import scan
from duckielib.errors import BagError
from duckielib.messages import String
from duckielib.ros import Graph, rospy
from duckielib.ros.context import node_context
from duckielib.sim import VirtualDuckiebot

TRUTH = "/duckiebot/simulator_node/ground_truth_pose"


@pytest.fixture
def bot(monkeypatch):
    monkeypatch.delenv("VEHICLE_NAME", raising=False)
    bot = VirtualDuckiebot(graph=Graph(stdout=io.StringIO(), stderr=io.StringIO()))
    yield bot
    bot.shutdown()


def test_recording_chosen_topics(bot, tmp_path):
    path = tmp_path / "run.bag"
    with BagRecorder(path, [LEFT, RIGHT, TRUTH], graph=bot.graph) as recorder:
        assert recorder.active_path.exists()
        assert not path.exists()
        bot.run(2.0)
    assert path.exists()
    assert not recorder.active_path.exists()
    bag = Bag(path)
    assert sorted(bag.topics) == sorted([LEFT, RIGHT, TRUTH])
    assert bag.topics[LEFT].count in (60, 61)
    truth = read_topic(bag, TRUTH)
    assert truth.t[-1] == pytest.approx(2.0, abs=1 / 30)
    # Recorded at the moment it was published (time 0 is recorded as 1 ns, ROS's smallest).
    assert (truth.record_t - truth.t).max() <= 1e-9


def test_recording_everything_includes_topics_that_appear_later(bot, tmp_path):
    path = tmp_path / "all.bag"
    recorder = BagRecorder(path, graph=bot.graph)
    rosnode_names = list(bot.graph.nodes)
    assert any(name.startswith("/record_") for name in rosnode_names)
    bot.run(0.5)
    node = bot.graph.host_node("late")
    with node_context(node):
        chatter = rospy.Publisher("/chatter", String, queue_size=1)
    bot.run(0.2)
    chatter.publish(String("hello"))
    bot.run(0.2)
    recorder.close()
    bag = Bag(path)
    assert [item.message.data for item in bag.read("/chatter")] == ["hello"]
    assert "/duckiebot/camera_node/image/compressed" in bag.topics


def test_a_bag_is_closed_by_an_exception_and_by_shutdown(bot, tmp_path):
    first = tmp_path / "error.bag"
    with pytest.raises(RuntimeError), BagRecorder(first, [LEFT], graph=bot.graph):  # noqa: PT012
        bot.run(1.0)
        raise RuntimeError("the mission failed")
    assert Bag(first).topics[LEFT].count in (30, 31)
    second = tmp_path / "shutdown.bag"
    recorder = BagRecorder(second, [TRUTH], graph=bot.graph)
    bot.run(1.0)
    bot.shutdown()
    assert recorder.closed
    assert Bag(second).topics[TRUTH].count in (30, 31)


def test_refuses_to_overwrite(tmp_path):
    (tmp_path / "x.bag").write_bytes(b"")
    with pytest.raises(BagError, match="exists already"):
        BagRecorder(tmp_path / "x.bag", graph=Graph(echo_logs=False))


def test_messages_reach_the_disk_by_the_flush_interval(bot, tmp_path):
    eager = BagRecorder(tmp_path / "eager.bag", [LEFT], graph=bot.graph, flush_interval=0.0)
    lazy = BagRecorder(tmp_path / "lazy.bag", [LEFT], graph=bot.graph, flush_interval=3600.0)
    bot.run(1.0)
    assert len(scan(eager.active_path).messages) == eager.counts[LEFT] > 0
    assert len(scan(lazy.active_path).messages) == 0, "still in memory"
    lazy.flush()
    assert len(scan(lazy.active_path).messages) == lazy.counts[LEFT]


def test_an_idle_recording_still_reaches_the_disk(bot, tmp_path):
    recorder = BagRecorder(tmp_path / "idle.bag", [LEFT], graph=bot.graph, flush_interval=0.2)
    bot.run(1.0)  # a few milliseconds of wall time: no flush yet
    recorded = recorder.counts[LEFT]
    deadline = time.monotonic() + 5.0
    while len(scan(recorder.active_path).messages) < recorded and time.monotonic() < deadline:
        time.sleep(0.05)  # the graph is idle; the recorder's own thread flushes
    assert len(scan(recorder.active_path).messages) == recorded > 0
    recorder.close()


RECORDING = textwrap.dedent(
    """
    import sys
    from duckielib.bags import BagRecorder
    from duckielib.ros import Graph
    from duckielib.sim import VirtualDuckiebot

    bot = VirtualDuckiebot(graph=Graph(echo_logs=False))
    recorder = BagRecorder(sys.argv[1], graph=bot.graph,
                           topics=["{left}", "{right}", "{truth}"])
    if sys.argv[2] == "exit":
        bot.run(2.0)
        sys.exit(0)  # never closed by the code: closed when Python exits
    while True:
        bot.run(1.0)
        recorder.flush()
        print(sum(recorder.counts.values()), flush=True)
    """
).format(left=LEFT, right=RIGHT, truth=TRUTH)


def run_recording(path, mode):
    return subprocess.Popen(
        [sys.executable, "-c", RECORDING, str(path), mode],
        stdout=subprocess.PIPE,
        text=True,
    )


def test_a_recording_left_open_is_closed_when_python_exits(tmp_path):
    path = tmp_path / "exit.bag"
    process = run_recording(path, "exit")
    assert process.wait(timeout=120) == 0
    assert Bag(path).topics[LEFT].count in (60, 61)


def test_a_killed_recording_is_repaired_up_to_its_last_flush(tmp_path):
    path = tmp_path / "killed.bag"
    process = run_recording(path, "loop")
    flushed = [int(process.stdout.readline()) for _ in range(3)]
    os.kill(process.pid, signal.SIGKILL)
    process.wait(timeout=60)
    process.stdout.close()
    active = tmp_path / "killed.bag.active"
    assert active.exists()
    assert not path.exists()
    with pytest.raises(BagError, match="duckie bag repair"):
        Bag(active)
    report = repair_bag(active, tmp_path / "fixed.bag")
    assert report.messages >= flushed[-1] > flushed[0] > 0
    assert not report.was_indexed
    bag = Bag(tmp_path / "fixed.bag")
    assert bag.message_count == report.messages
    left = read_topic(bag, LEFT)
    assert (left["data"] == left["data"][0]).all(), "a robot standing still"


FULL_DISK = textwrap.dedent(
    """
    import resource, signal, sys
    from duckielib.bags import BagRecorder
    from duckielib.messages import String
    from duckielib.ros import Graph, rospy

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails instead
    resource.setrlimit(resource.RLIMIT_FSIZE, (100_000, 100_000))  # a disk that fills up
    graph = Graph(echo_logs=False)
    sent = []

    def talker():
        rospy.init_node("talker")
        publisher = rospy.Publisher("/chatter", String, queue_size=1)
        rate = rospy.Rate(10)
        while not rospy.is_shutdown():
            publisher.publish(String(data="x" * 10_000))
            sent.append(rospy.get_time())
            rate.sleep()

    graph.launch(talker)
    recorder = BagRecorder(sys.argv[1], ["/chatter"], graph=graph, flush_interval=0)
    graph.run(3.0)
    left = recorder.close()
    errors = [record.text for record in graph.log if record.level >= 8]
    print(len(sent), recorder.counts["/chatter"], left.name, graph.nodes["/talker"].is_shutdown)
    print(recorder.error)
    print(errors[0] if errors else "no error logged")
    """
)


def test_a_full_disk_stops_the_recording_not_the_publisher(tmp_path):
    path = tmp_path / "full.bag"
    done = subprocess.run(
        [sys.executable, "-c", FULL_DISK, str(path)],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    counts, error, logged = done.stdout.splitlines()
    sent, recorded, left, talker_stopped = counts.split()
    assert int(sent) == 31, "the talker kept publishing for its 3 s"
    assert 0 < int(recorded) < 10, "the recording stopped at the limit"
    assert talker_stopped == "False"
    assert left == "full.bag.active", "an unfinished bag keeps its .active name"
    assert not path.exists()
    assert "File too large" in error
    assert "Stopped recording full.bag" in logged
    assert "duckie bag repair" in logged
    report = repair_bag(tmp_path / "full.bag.active", tmp_path / "fixed.bag")
    assert report.messages == int(recorded)
    kept = Bag(tmp_path / "fixed.bag").read("/chatter")
    assert [message.message.data for message in kept] == ["x" * 10_000] * int(recorded)
