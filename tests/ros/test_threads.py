"""Threads a node's code starts, and code that never waits, on the in-process graph.

Real rospy runs a node's threads beside its main code; here they run as the node, on the
graph's baton and simulated time. A node's code that holds the baton too long on the wall
clock is stopped with a sentence, instead of freezing the graph for ever.
"""

from __future__ import annotations

import concurrent.futures
import io
import threading
import time

import pytest

from duckielib.messages import String
from duckielib.ros import Graph, NodeCrashed, rospy
from duckielib.ros.log import ERROR


def quiet_graph(**options):
    return Graph(stdout=io.StringIO(), stderr=io.StringIO(), **options)


def ticker(heard, daemon=False, count=4):
    """A node whose loop runs in a thread it starts; its main code returns at once."""

    def main():
        rospy.init_node("ticker")
        pub = rospy.Publisher("chatter", String, queue_size=10)

        def loop():
            rate = rospy.Rate(2)
            for n in range(count):
                pub.publish(String(data=f"{n}@{rospy.get_time():.2f}"))
                rate.sleep()

        threading.Thread(target=loop, daemon=daemon).start()

    def listener():
        rospy.init_node("listener")
        rospy.Subscriber("chatter", String, lambda message: heard.append(message.data))
        rospy.spin()

    return main, listener


@pytest.mark.parametrize("threads", [False, True], ids=["greenlets", "threads"])
def test_a_thread_a_node_starts_runs_as_the_node_on_simulated_time(threads):
    heard = []
    graph = quiet_graph(threads=threads)
    main, listener = ticker(heard)
    graph.launch(listener)
    graph.launch(main)
    graph.run(1.2)
    assert heard == ["0@0.00", "1@0.50", "2@1.00"]
    # The node's main code has returned, but a thread it started (not a daemon) still runs:
    # the node lives on, as its process would on a robot.
    assert "/ticker" in graph.nodes
    graph.run(2.0)
    assert heard == ["0@0.00", "1@0.50", "2@1.00", "3@1.50"]
    assert "/ticker" not in graph.nodes  # the thread ended, so did the node
    graph.shutdown()
    assert not [line for line in graph.log if line.level >= ERROR]


def test_a_daemon_thread_ends_with_its_node():
    heard = []
    graph = quiet_graph()
    main, listener = ticker(heard, daemon=True)
    graph.launch(listener)
    graph.launch(main)
    graph.run(2.0)
    # The main code returned at once, which ended the node before its daemon thread ran, as
    # a process ends without waiting for its daemon threads.
    assert heard == []
    assert "/ticker" not in graph.nodes
    graph.shutdown()


def test_runs_with_threads_are_the_same_every_time():
    runs = []
    for _ in range(3):
        heard = []
        graph = quiet_graph()
        main, listener = ticker(heard, count=6)
        graph.launch(listener)
        graph.launch(main)
        graph.run(5.0)
        graph.shutdown()
        runs.append(heard)
    assert runs[0] == runs[1] == runs[2]
    assert len(runs[0]) == 6


def test_join_timer_and_time_sleep_wait_simulated_time():
    seen = {}
    graph = quiet_graph()

    def main():
        rospy.init_node("joiner")
        worker = threading.Thread(target=lambda: (time.sleep(2.0), seen.update(work=1)))
        worker.start()
        fired = threading.Timer(1.5, lambda: seen.update(timer=rospy.get_time()))
        cancelled = threading.Timer(1.0, lambda: seen.update(cancelled=True))
        fired.start()
        cancelled.start()
        cancelled.cancel()
        worker.join()
        seen["joined"] = rospy.get_time()
        worker.join(timeout=5.0)  # an ended thread: returns at once
        seen["again"] = rospy.get_time()

    graph.launch(main)
    started = time.monotonic()
    graph.run(10.0)
    assert time.monotonic() - started < 1.0  # simulated seconds, not wall ones
    assert seen == {"timer": 1.5, "work": 1, "joined": 2.0, "again": 2.0}
    graph.shutdown()


def test_a_thread_started_by_a_callback_runs_as_the_callbacks_node():
    seen = []
    graph = quiet_graph()

    def worker(stamp):
        rospy.sleep(0.25)
        seen.append((rospy.get_name(), stamp, rospy.get_time()))

    def node():
        rospy.init_node("reactor")
        rospy.Subscriber(
            "go",
            String,
            lambda message: threading.Thread(target=worker, args=(message.data,)).start(),
        )
        rospy.spin()

    def sender():
        rospy.init_node("sender")
        pub = rospy.Publisher("go", String, queue_size=10, latch=False)
        rospy.sleep(1.0)
        pub.publish(String(data="first"))
        rospy.sleep(1.0)
        pub.publish(String(data="second"))

    graph.launch(node)
    graph.launch(sender)
    graph.run(3.0)
    assert seen == [("/reactor", "first", 1.25), ("/reactor", "second", 2.25)]
    graph.shutdown()


def test_an_exception_in_a_thread_is_logged_and_the_node_goes_on():
    graph = quiet_graph()
    beats = []

    def main():
        rospy.init_node("sturdy")

        def broken():
            rospy.sleep(0.5)
            raise ValueError("the sensor said no")

        threading.Thread(target=broken, name="reader").start()
        rate = rospy.Rate(1)
        while not rospy.is_shutdown():
            beats.append(rospy.get_time())
            rate.sleep()

    graph.launch(main)
    graph.run(3.0)
    errors = [line for line in graph.log if line.level == ERROR]
    assert len(errors) == 1
    assert errors[0].node == "/sturdy"
    assert errors[0].time == 0.5
    assert "thread reader stopped" in errors[0].text
    assert "ValueError: the sensor said no" in errors[0].text
    assert beats == [0.0, 1.0, 2.0, 3.0]
    graph.shutdown()


def test_threads_of_libraries_are_left_alone():
    graph = quiet_graph()
    answers = []

    def main():
        rospy.init_node("pooled")
        with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
            answers.extend(pool.map(lambda n: n * n, range(5)))
        answers.append(rospy.get_time())

    graph.launch(main)
    graph.run(1.0)
    assert answers == [0, 1, 4, 9, 16, 0.0]
    graph.shutdown()


def test_rospy_in_a_thread_pools_worker_says_what_to_start_instead():
    graph = quiet_graph()
    outcomes = []

    def main():
        rospy.init_node("pooled")
        pub = rospy.Publisher("chatter", String, queue_size=1)
        with concurrent.futures.ThreadPoolExecutor(max_workers=1) as pool:
            for call in (rospy.get_time, lambda: pub.publish(String(data="x"))):
                try:
                    pool.submit(call).result()
                except rospy.ROSException as error:
                    outcomes.append(str(error))

    graph.launch(main)
    graph.run(1.0)
    assert len(outcomes) == 2
    for outcome in outcomes:
        assert outcome.startswith(
            "rospy was called from a thread that a library started for node /pooled"
        )
        assert "threading.Thread(target=your_function)" in outcome
    graph.shutdown()


def test_a_loop_that_never_waits_is_stopped_with_a_sentence():
    graph = quiet_graph(stall_limit=0.5)

    def main():
        rospy.init_node("poller")
        flag = []
        rospy.Subscriber("chatter", String, flag.append)
        while True:  # waits for a callback without ever calling rospy
            try:
                if flag:
                    break
            except Exception:  # does not swallow the graph's stop
                continue

    graph.launch(main)
    started = time.monotonic()
    with pytest.raises(NodeCrashed) as caught:
        graph.run(5.0)
    assert time.monotonic() - started < 5.0
    message = str(caught.value)
    assert message.startswith(
        "Node /poller stopped: its code ran for 0.5 s of real time without calling rospy"
    )
    assert message.endswith("Wait inside the loop with rospy.sleep() or rate.sleep().")
    assert [line.node for line in graph.log if line.level == ERROR] == ["/poller"]
    # The graph goes on without it.
    graph.run(1.0)
    assert graph.time == 1.0
    graph.shutdown()


def test_a_callback_that_never_returns_is_stopped_with_a_sentence():
    # A callback runs between the graph's events: while it computes, no time passes and no
    # message arrives. One that never returns is stopped, and the run with it, saying which.
    graph = quiet_graph(stall_limit=0.5)
    seen = []

    def talker():
        rospy.init_node("talker")
        publisher = rospy.Publisher("chatter", String, queue_size=1)
        rospy.sleep(0.5)
        publisher.publish(String(data="first"))
        rospy.sleep(1.0)

    def listener():
        rospy.init_node("listener")

        def busy(message):
            seen.append(message.data)
            while True:
                pass

        rospy.Subscriber("chatter", String, busy)
        rospy.spin()

    graph.launch(talker)
    graph.launch(listener)
    started = time.monotonic()
    with pytest.raises(NodeCrashed) as caught:
        graph.run(5.0)
    assert time.monotonic() - started < 5.0
    assert seen == ["first"]
    assert str(caught.value).startswith(
        "Node /listener stopped: its callback on /chatter ran for 0.5 s of real time without "
        "calling rospy"
    )
    assert [line.node for line in graph.log if line.level == ERROR] == ["/listener"]
    graph.shutdown()


def test_code_that_waits_is_never_stopped_however_long_it_runs():
    graph = quiet_graph(stall_limit=0.3)

    def main():
        rospy.init_node("patient")
        for _ in range(8):  # 0.8 s of real work in all, but it waits between steps
            time.monotonic()
            end = time.monotonic() + 0.1
            while time.monotonic() < end:
                pass
            rospy.sleep(1.0)

    graph.launch(main)
    graph.run(10.0)
    assert not [line for line in graph.log if line.level == ERROR]
    graph.shutdown()
