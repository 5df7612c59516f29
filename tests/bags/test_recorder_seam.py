"""The recorder's tie to rospy's Subscriber internals: the private names it relies on are there."""

from __future__ import annotations

import inspect
import io

from duckielib.bags.recorder import Tap
from duckielib.messages import String
from duckielib.ros import Graph, rospy
from duckielib.ros.context import node_context

WHERE = "the bag recorder and the live view (Tap in duckielib/bags/recorder.py)"


def _shape(signature):
    """Parameter names, kinds and annotations, the same whether annotations are strings."""

    def name(annotation):
        if annotation is inspect.Parameter.empty:
            return None
        return getattr(annotation, "__name__", annotation)

    parameters = [(p.name, p.kind, name(p.annotation)) for p in signature.parameters.values()]
    return parameters, name(signature.return_annotation)


def test_rospy_subscriber_has_the_enqueue_method_the_recorder_overrides():
    base = getattr(rospy.Subscriber, "_enqueue", None)
    assert callable(base), (
        f"duckielib.ros.rospy.Subscriber no longer has _enqueue(self, data: bytes), which {WHERE} "
        "overrides to take each message's bytes as published; give the recorder another way."
    )
    expected = (
        [
            ("self", inspect.Parameter.POSITIONAL_OR_KEYWORD, None),
            ("data", inspect.Parameter.POSITIONAL_OR_KEYWORD, "bytes"),
        ],
        "None",
    )
    found = _shape(inspect.signature(base))
    assert found == expected, (
        f"duckielib.ros.rospy.Subscriber._enqueue is now {inspect.signature(base)}, but {WHERE} "
        "overrides it as (self, data: bytes) -> None; make the two agree."
    )
    assert _shape(inspect.signature(Tap._enqueue)) == expected


def test_rospy_calls_enqueue_with_the_bytes_and_sets_record_first():
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    received = []

    class Probe(rospy.Subscriber):
        def _enqueue(self, data):
            received.append((data, self._record))

    try:
        with node_context(graph.host_node("talker")):
            latched = rospy.Publisher("/latched", String, latch=True, queue_size=1)
            latched.publish(String("kept"))
            live = rospy.Publisher("/live", String, queue_size=1)
        with node_context(graph.host_node("listener")):
            old = Probe("/latched", rospy.AnyMsg)
            assert received == [(String("kept").to_bytes(), old._record)], (
                f"rospy no longer gives a latched message to Subscriber._enqueue while "
                f"subscribing, with _record set, as {WHERE} expects."
            )
            received.clear()
            tap = Probe("/live", rospy.AnyMsg)
        live.publish(String("now"))
        assert received == [(String("now").to_bytes(), tap._record)], (
            f"rospy's publish() no longer calls Subscriber._enqueue with the message's bytes, "
            f"as {WHERE} expects."
        )
        record = tap._record
        assert record.name == "/live"
        assert record.connection_header()["type"] == "std_msgs/String"
        tap.unregister()
        assert tap._record is None, (
            f"Subscriber._record is no longer None once unsubscribed, as {WHERE} expects."
        )
    finally:
        graph.shutdown()


def test_a_tap_hands_each_message_bytes_and_topic_record_latched_first():
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    taken = []
    try:
        with node_context(graph.host_node("talker")):
            talker = rospy.Publisher("/chatter", String, latch=True, queue_size=1)
            talker.publish(String("first"))
        with node_context(graph.host_node("tap")):
            tap = Tap("/chatter", lambda record, data: taken.append((record.name, data)))
        talker.publish(String("second"))
        assert taken == [
            ("/chatter", String("first").to_bytes()),
            ("/chatter", String("second").to_bytes()),
        ]
        tap.unregister()
        talker.publish(String("third"))
        assert len(taken) == 2
    finally:
        graph.shutdown()
