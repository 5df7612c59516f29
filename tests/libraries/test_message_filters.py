"""message_filters on the in-process graph: the synchronizers' rules, and a dead-reckoning node.

The rules are checked with scripted publishers on the graph, against this module and, where
Debian's ROS packages are installed, against the real ``message_filters`` running on the same
in-process rospy: both must pair the same messages.
"""

from __future__ import annotations

import importlib.util
import io
import math
import sys
import types
from pathlib import Path

import pytest

from duckielib.libraries import message_filters
from duckielib.messages import String, WheelEncoderStamped, WheelsCmdStamped
from duckielib.ros import Graph, rospy
from duckielib.ros.log import ERROR, WARN
from duckielib.sim import VirtualDuckiebot

DEBIAN_MESSAGE_FILTERS = Path("/usr/lib/python3/dist-packages/message_filters/__init__.py")
TOPICS = ("/a", "/b")
MS = 1_000_000


def debian_message_filters(monkeypatch):
    """Debian's message_filters, importing the in-process rospy as its ``rospy``."""
    if not DEBIAN_MESSAGE_FILTERS.exists():
        pytest.skip("Debian's message_filters is not installed; run `make ros`.")
    shim = types.ModuleType("rospy")
    shim.__dict__.update({name: getattr(rospy, name) for name in rospy.__all__})
    shim.rostime = types.SimpleNamespace(is_wallclock=lambda: False)  # simulated time
    monkeypatch.setitem(sys.modules, "rospy", shim)
    spec = importlib.util.spec_from_file_location("debian_message_filters", DEBIAN_MESSAGE_FILTERS)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(params=["ours", pytest.param("debian", marks=pytest.mark.ros)])
def filters(request, monkeypatch):
    if request.param == "debian":
        return debian_message_filters(monkeypatch)
    return message_filters


@pytest.fixture
def graph():
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    yield graph
    graph.shutdown()


def synchronized(graph, filters, build, events, data_class=WheelEncoderStamped):
    """Run ``events`` through a synchronizer on the graph; the stamps (ms) it paired.

    Args:
        filters: the message_filters module to use.
        build: makes the synchronizer from the two subscribers.
        events: ``(input 0 or 1, stamp in ms)``, published in order 10 ms apart, or
            ``(input, None)`` for a message without a header.
    """
    matched = []

    def sync_node():
        rospy.init_node("sync")
        subscribers = [filters.Subscriber(t, data_class) for t in TOPICS]
        synchronizer = build(subscribers)

        def on_set(*messages):
            matched.append(
                tuple(
                    m.header.stamp.to_nsec() // MS if hasattr(m, "header") else m.data
                    for m in messages
                )
            )

        synchronizer.registerCallback(on_set)
        rospy.spin()

    def driver():
        rospy.init_node("driver")
        publishers = [rospy.Publisher(t, data_class, queue_size=10) for t in TOPICS]
        rospy.sleep(0.01)
        for index, (which, stamp_ms) in enumerate(events):
            if stamp_ms is None:
                publishers[which].publish(data_class(data=f"{which}@{rospy.get_time():.2f}"))
            else:
                msg = data_class(data=index)
                msg.header.stamp = rospy.Time(0, stamp_ms * MS)
                publishers[which].publish(msg)
            rospy.sleep(0.01)

    graph.launch(sync_node)
    graph.launch(driver)
    graph.run(0.02 + 0.01 * len(events))
    assert [r.text for r in graph.log if r.level == ERROR] == []
    return matched


@pytest.fixture
def run(graph, filters):
    return lambda build, events, **options: synchronized(graph, filters, build, events, **options)


def test_time_synchronizer_pairs_equal_stamps_oldest_first(run, filters):
    events = [
        (0, 1000),
        (1, 2000),
        (0, 2000),  # pairs with b@2000 at once; a@1000 waits
        (1, 1000),  # pairs with a@1000
        (0, 3000),
        (0, 4000),
        (0, 5000),  # a keeps 2 stamps: 3000 is dropped
        (1, 3000),  # no pair any more
        (1, 5000),
        (1, 4000),
    ]
    matched = run(lambda subs: filters.TimeSynchronizer(subs, 2), events)
    assert matched == [(2000, 2000), (1000, 1000), (5000, 5000), (4000, 4000)]


def test_time_synchronizer_calls_back_for_every_completed_stamp_in_order(run, filters):
    events = [(0, 3000), (0, 1000), (0, 2000), (1, 3000), (1, 2000), (1, 1000)]
    matched = run(lambda subs: filters.TimeSynchronizer(subs, 5), events)
    assert matched == [(3000, 3000), (2000, 2000), (1000, 1000)]
    # b@3000 completes only 3000; a set is passed on as soon as it is complete.


def test_approximate_synchronizer_rules(run, filters):
    events = [
        (0, 1000),
        (1, 1050),  # 50 ms apart, slop 100 ms: a pair
        (0, 2000),
        (1, 2100),  # exactly the slop apart: not a pair (the spread must be below it)
        (1, 2020),  # pairs with a@2000; b@2100 waits
        (0, 3000),
        (0, 3040),
        (1, 3030),  # both a's are near: the closest, a@3040, is taken
        (1, 5000),
        (1, 5100),
        (1, 5200),  # b keeps 3 stamps: b@2100 is dropped
        (0, 2150),  # would have paired with b@2100
        (0, 5190),  # b@5200 is closest
    ]
    matched = run(lambda subs: filters.ApproximateTimeSynchronizer(subs, 3, 0.1), events)
    assert matched == [(1000, 1050), (2000, 2020), (3040, 3030), (5190, 5200)]


def test_approximate_synchronizer_with_a_larger_queue_keeps_the_old_stamp(run, filters):
    events = [(0, 2000), (1, 2100), (1, 5000), (1, 5100), (1, 5200), (0, 2150)]
    matched = run(lambda subs: filters.ApproximateTimeSynchronizer(subs, 10, 0.1), events)
    assert matched == [(2150, 2100)]


def test_headerless_messages_need_allow_headerless(run, filters, graph):
    events = [(0, None), (1, None), (0, None), (1, None)]
    matched = run(
        lambda subs: filters.ApproximateTimeSynchronizer(subs, 5, 0.015, allow_headerless=True),
        events,
        data_class=String,
    )
    # Stamped on arrival, 10 ms apart: a@0.01 + b@0.02, a@0.03 + b@0.04.
    assert matched == [("0@0.01", "1@0.02"), ("0@0.03", "1@0.04")]


def test_headerless_messages_are_dropped_with_a_warning(graph, filters):
    matched = synchronized(
        graph,
        filters,
        lambda subs: filters.ApproximateTimeSynchronizer(subs, 5, 1.0),
        [(0, None), (1, None)],
        data_class=String,
    )
    assert matched == []
    warnings = [r.text for r in graph.log if r.level == WARN]
    assert len(warnings) == 2
    assert all("allow_headerless" in text for text in warnings)


def test_cache_keeps_the_newest_messages_for_queries(graph, filters):
    found = {}

    def node():
        rospy.init_node("cached")
        cache = filters.Cache(filters.Subscriber("/a", WheelEncoderStamped), cache_size=3)
        passed = []
        cache.registerCallback(passed.append)
        rospy.sleep(0.1)

        def stamp(ms):
            return rospy.Time(0, ms * MS)

        found["passed"] = [m.data for m in passed]
        found["interval"] = [m.data for m in cache.getInterval(stamp(2000), stamp(3000))]
        found["after"] = cache.getElemAfterTime(stamp(2500)).data
        found["before"] = cache.getElemBeforeTime(stamp(2500))
        found["before_kept"] = cache.getElemBeforeTime(stamp(4500)).data
        found["none_after"] = cache.getElemAfterTime(stamp(9000))
        found["oldest"] = cache.getOldestTime().to_nsec() // MS
        found["latest"] = cache.getLatestTime().to_nsec() // MS
        found["last"] = cache.getLast().data

    def driver():
        rospy.init_node("driver")
        pub = rospy.Publisher("/a", WheelEncoderStamped, queue_size=10)
        rospy.sleep(0.01)
        for index in range(5):
            msg = WheelEncoderStamped(data=index)
            msg.header.stamp = rospy.Time(0, (index + 1) * 1000 * MS)
            pub.publish(msg)
            rospy.sleep(0.01)

    graph.launch(node)
    graph.launch(driver)
    graph.run(0.2)
    # Stamps 3000, 4000 and 5000 are kept (data 2, 3 and 4).
    assert found == {
        "passed": [0, 1, 2, 3, 4],
        "interval": [2],
        "after": 2,
        "before": None,
        "before_kept": 3,
        "none_after": None,
        "oldest": 3000,
        "latest": 5000,
        "last": 4,
    }


def test_subscriber_acts_as_rospys(graph):
    done = []

    def node():
        rospy.init_node("subscribing")
        sub = message_filters.Subscriber("~ticks", WheelEncoderStamped, queue_size=3)
        assert sub.getTopic() == "~ticks"
        assert sub.resolved_name == "/subscribing/ticks"
        assert sub.registerCallback(print) == 0
        assert sub.registerCallback(print, "extra") == 1
        sub.unregister()
        with pytest.raises(TypeError, match="registerCallback"):
            message_filters.Subscriber("/a", String, print)
        with pytest.raises(TypeError, match="registerCallback"):
            message_filters.Subscriber("/a", String, callback=print)
        done.append(True)

    graph.launch(node)
    graph.run(0.01)
    assert done == [True]
    record = graph.topics.get("/subscribing/ticks")
    assert record is None or record.subscribers == []


# -- a dead-reckoning node, as Duckietown's ------------------------------------------------------
class DeadReckoningNode:
    """Integrates the wheel encoders' ticks, the two wheels' readings paired by stamp."""

    def __init__(self):
        import message_filters as filters

        rospy.init_node("deadreckoning_node")
        self.radius, self.baseline = 0.0318, 0.1
        self.x = self.y = self.theta = 0.0
        self.last = None
        self.pairs = []
        self.sub_left = filters.Subscriber("left_wheel_encoder_node/tick", WheelEncoderStamped)
        self.sub_right = filters.Subscriber("right_wheel_encoder_node/tick", WheelEncoderStamped)
        self.ts = filters.ApproximateTimeSynchronizer([self.sub_left, self.sub_right], 10, 0.5)
        self.ts.registerCallback(self.cb_ts_encoders)

    def cb_ts_encoders(self, left, right):
        self.pairs.append((left.header.stamp.to_sec(), right.header.stamp.to_sec()))
        ticks = (left.data, right.data)
        if self.last is not None:
            d_left, d_right = (
                2 * math.pi * self.radius * (now - before) / left.resolution
                for now, before in zip(ticks, self.last)
            )
            distance, turn = (d_left + d_right) / 2, (d_right - d_left) / self.baseline
            self.x += distance * math.cos(self.theta + turn / 2)
            self.y += distance * math.sin(self.theta + turn / 2)
            self.theta += turn
        self.last = ticks


def test_a_dead_reckoning_node_gets_matched_encoder_pairs(monkeypatch):
    monkeypatch.setitem(sys.modules, "message_filters", message_filters)
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    bot = VirtualDuckiebot(seed=3, graph=graph)
    nodes = []

    def main():
        nodes.append(DeadReckoningNode())
        wheels = rospy.Publisher("wheels_driver_node/wheels_cmd", WheelsCmdStamped, queue_size=1)
        while not rospy.is_shutdown():
            wheels.publish(WheelsCmdStamped(vel_left=0.5, vel_right=0.5))
            rospy.sleep(0.1)

    start = bot.sim.pose[:2]
    bot.launch(main)
    bot.run(2.0)
    x_true, y_true, _ = bot.sim.pose
    bot.shutdown()
    assert [r.text for r in graph.log if r.level == ERROR] == []
    (node,) = nodes
    # About 30 readings a second per wheel: nearly every one is paired, none twice.
    assert len(node.pairs) >= 55
    lefts, rights = zip(*node.pairs)
    assert list(lefts) == sorted(set(lefts))
    assert list(rights) == sorted(set(rights))
    assert max(abs(left - right) for left, right in node.pairs) < 1 / 30
    travelled = math.hypot(node.x, node.y)
    assert travelled > 0.1
    assert travelled == pytest.approx(math.dist((x_true, y_true), start), rel=0.1)
