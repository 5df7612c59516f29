"""rospy's API on the in-process graph: plain rospy nodes, run on simulated time."""

from __future__ import annotations

import io
import time as wallclock

import pytest

from duckielib.messages import (
    ChangePattern,
    ChangePatternResponse,
    String,
    Twist2DStamped,
    WheelsCmdStamped,
)
from duckielib.ros import Graph, NodeCrashed, rospy
from duckielib.ros.context import node_context


@pytest.fixture(params=["greenlets", "threads"])
def graph(request):
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO(), threads=request.param == "threads")
    assert graph.threads == (request.param == "threads")
    yield graph
    graph.shutdown()


def texts(graph, level=None):
    return [record.text for record in graph.log if level is None or record.level == level]


# -- the examples every ROS tutorial starts with -------------------------------------------------
def talker():
    rospy.init_node("talker")
    pub = rospy.Publisher("chatter", String, queue_size=10)
    rate = rospy.Rate(10)
    count = 0
    while not rospy.is_shutdown():
        pub.publish(String(data=f"hello world {count}"))
        count += 1
        rate.sleep()


def listener(heard):
    rospy.init_node("listener", anonymous=True)

    def callback(message):
        heard.append((rospy.get_time(), rospy.get_name(), message.data))

    rospy.Subscriber("chatter", String, callback, queue_size=10)
    rospy.spin()


def test_chatter_talker_and_listener(graph):
    heard = []
    graph.launch(listener, heard)
    graph.launch(talker)
    graph.run(1.0)
    assert [data for _, _, data in heard] == [f"hello world {i}" for i in range(11)]
    assert [round(t, 9) for t, _, _ in heard] == [i / 10 for i in range(11)]
    assert {name for _, name, _ in heard} == {"/listener_1"}


def test_runs_much_faster_than_real_time_and_identically(graph):
    heard = []
    graph.launch(listener, heard)
    graph.launch(talker)
    start = wallclock.perf_counter()
    graph.run(60.0)
    elapsed = wallclock.perf_counter() - start
    assert len(heard) == 601
    assert elapsed < 30.0  # a generous bound: 60 simulated seconds take about 0.1 s here

    again = []
    other = Graph(stdout=io.StringIO())
    other.launch(listener, again)
    other.launch(talker)
    other.run(60.0)
    other.shutdown()
    assert again == heard


def test_node_in_callbacks_only(graph):
    ticks = []

    def ticker():
        rospy.init_node("ticker")
        rospy.Timer(rospy.Duration(0.25), lambda event: ticks.append(event.current_real.to_sec()))
        rospy.spin()

    graph.launch(ticker)
    graph.run(1.0)
    assert ticks == [0.25, 0.5, 0.75, 1.0]


def test_sleep_advances_simulated_time_exactly(graph):
    stamps = []

    def sleeper():
        rospy.init_node("sleeper")
        stamps.append(rospy.Time.now())
        rospy.sleep(5)
        stamps.append(rospy.Time.now())
        rospy.sleep(rospy.Duration(0.5))
        stamps.append(rospy.get_rostime())

    graph.launch(sleeper)
    graph.run(10.0)
    assert [stamp.to_sec() for stamp in stamps] == [0.0, 5.0, 5.5]
    assert isinstance(stamps[0], rospy.Time)
    assert graph.time == 10.0
    assert "/sleeper" not in graph.nodes  # its main function returned: the node exited


def test_rate_catches_up_when_the_loop_is_late(graph):
    wakes = []

    def slow_loop():
        rospy.init_node("slow")
        rate = rospy.Rate(10)
        for step in range(4):
            if step == 1:
                rospy.sleep(0.25)  # one late cycle
            rate.sleep()
            wakes.append(round(rospy.get_time(), 9))

    graph.launch(slow_loop)
    graph.run(2.0)
    # As rospy: the late cycle returns at once, the next catches up, then the 0.1 s grid resumes.
    assert wakes == [0.1, 0.35, 0.35, 0.4]


def test_foreground_node_drives_the_graph_with_sleep(graph):
    heard = []
    graph.launch(listener, heard)
    rospy.init_node("notebook")
    pub = rospy.Publisher("/chatter", String, queue_size=1)
    rospy.sleep(0.1)  # let the listener subscribe
    pub.publish("typed as the single field")
    rospy.sleep(1.0)
    assert heard == [(0.1, "/listener_1", "typed as the single field")]
    assert rospy.get_time() == pytest.approx(1.1)


# -- queues and latching ------------------------------------------------------------------------
def test_full_subscriber_queue_drops_the_oldest(graph):
    got = []

    def burst():
        rospy.init_node("burst")
        pub = rospy.Publisher("numbers", String, queue_size=10)
        rospy.sleep(0.1)
        for i in range(5):
            pub.publish(str(i))  # no sleep in between: the subscriber cannot keep up

    def slow_reader():
        rospy.init_node("reader")
        rospy.Subscriber("numbers", String, lambda m: got.append(m.data), queue_size=2)
        rospy.spin()

    graph.launch(slow_reader)
    graph.launch(burst)
    graph.run(1.0)
    assert got == ["3", "4"]


def test_latched_topic_reaches_late_subscribers(graph):
    got = {"latched": [], "plain": []}

    def announcer():
        rospy.init_node("announcer")
        rospy.Publisher("map", String, queue_size=1, latch=True).publish("the map")
        rospy.Publisher("news", String, queue_size=1).publish("old news")
        rospy.spin()

    def late():
        rospy.init_node("late")
        rospy.sleep(2.0)
        rospy.Subscriber("map", String, lambda m: got["latched"].append(m.data), queue_size=1)
        rospy.Subscriber("news", String, lambda m: got["plain"].append(m.data), queue_size=1)
        rospy.spin()

    graph.launch(announcer)
    graph.launch(late)
    graph.run(3.0)
    assert got == {"latched": ["the map"], "plain": []}


def test_anymsg_receives_any_topics_bytes_and_connection_header(graph):
    raw = []

    def recorder():
        rospy.init_node("recorder")
        rospy.Subscriber("chatter", rospy.AnyMsg, raw.append, queue_size=None)
        rospy.spin()

    def talker():
        rospy.init_node("talker")
        rospy.sleep(0.1)
        rospy.Publisher("chatter", String, queue_size=1).publish("hi")
        rospy.spin()

    graph.launch(recorder)
    graph.launch(talker)
    graph.run(1.0)
    assert graph.topics["/chatter"].type == "std_msgs/String", "the publisher gave the type"
    assert [message._buff for message in raw] == [String("hi").to_bytes()]
    header = raw[0]._connection_header
    assert header["type"] == "std_msgs/String"
    assert header["md5sum"] == String._md5sum
    assert header["callerid"] == "/talker"
    assert header["message_definition"] == String._full_text
    graph.shutdown()
    rospy.init_node("publisher_of_nothing")
    with pytest.raises(ValueError, match="concrete message class"):
        rospy.Publisher("chatter", rospy.AnyMsg, queue_size=1)


def test_messages_arrive_as_copies_with_header_seq(graph):
    got = []

    def sender():
        rospy.init_node("sender")
        pub = rospy.Publisher("cmd", Twist2DStamped, queue_size=5)
        message = Twist2DStamped(v=0.3, omega=0.0)
        rospy.sleep(0.1)
        pub.publish(message)
        message.v = 99.0  # changing it after publishing does not change what was sent
        pub.publish(v=0.1, omega=1.0)

    def receiver():
        rospy.init_node("receiver")
        rospy.Subscriber("cmd", Twist2DStamped, got.append, queue_size=5)
        rospy.spin()

    graph.launch(receiver)
    graph.launch(sender)
    graph.run(1.0)
    assert [m.header.seq for m in got] == [1, 2]
    assert got[0].v == pytest.approx(0.3)  # float32 on the wire, as on the robot
    assert got[1].omega == 1.0


# -- type errors --------------------------------------------------------------------------------
def test_publishing_another_message_type_fails_clearly(graph):
    rospy.init_node("typo")
    pub = rospy.Publisher(
        "/duckiebot/wheels_driver_node/wheels_cmd", WheelsCmdStamped, queue_size=1
    )
    with pytest.raises(
        TypeError,
        match=r"expected \[duckietown_msgs/WheelsCmdStamped\] but got "
        r"\[duckietown_msgs/Twist2DStamped\]",
    ):
        pub.publish(Twist2DStamped(v=0.2))
    with pytest.raises(
        rospy.ROSException,
        match=r"carries duckietown_msgs/WheelsCmdStamped .*"
        r"cannot subscribe to it with duckietown_msgs",
    ):
        rospy.Subscriber("/duckiebot/wheels_driver_node/wheels_cmd", Twist2DStamped)
    with pytest.raises(rospy.ROSSerializationException, match=r"vel_left must be a number"):
        pub.publish(vel_left="fast", vel_right=0.0)
    with pytest.raises(ValueError, match="needs a message class"):
        rospy.Publisher("x", "std_msgs/String", queue_size=1)


def test_missing_queue_size_gives_rospys_warning(graph):
    rospy.init_node("forgetful")
    rospy.Publisher("chatter", String)
    assert "explicit keyword argument 'queue_size'" in texts(graph, rospy.WARN)[0]


# -- services -----------------------------------------------------------------------------------
def light_server(log):
    rospy.init_node("light_server")

    def handle(request):
        log.append((rospy.get_name(), request.pattern_name.data))
        if request.pattern_name.data == "PURPLE":
            raise rospy.ServiceException("unknown colour PURPLE")
        if request.pattern_name.data == "CRASH":
            raise ValueError("bug in the handler")
        if request.pattern_name.data == "NONE":
            return None
        return ChangePatternResponse()

    rospy.Service("set_light", ChangePattern, handle)
    rospy.spin()


def test_service_server_and_client(graph):
    calls, results = [], []

    def client():
        rospy.init_node("client")
        rospy.wait_for_service("set_light", timeout=5)
        results.append(rospy.get_time())
        set_light = rospy.ServiceProxy("set_light", ChangePattern)
        results.append(type(set_light(String("RED"))).__name__)
        for name in ("PURPLE", "CRASH", "NONE"):
            try:
                set_light(pattern_name=String(name))
            except rospy.ServiceException as error:
                results.append(str(error))

    graph.launch(client)
    graph.run(1.0)  # the server starts a second later: the client waits for it
    graph.launch(light_server, calls)
    graph.run(1.0)
    assert results == [
        1.0,
        "ChangePatternResponse",
        "service cannot process request: unknown colour PURPLE",
        "error processing request: bug in the handler",
        "service cannot process request: service handler returned None",
    ]
    assert calls[0] == ("/light_server", "RED")
    assert any("Error processing request: bug in the handler" in text for text in texts(graph))


def test_wait_for_service_times_out(graph):
    outcome = []

    def impatient():
        rospy.init_node("impatient")
        try:
            rospy.wait_for_service("/nobody/offers/this", timeout=2.5)
        except rospy.ROSException as error:
            outcome.append((rospy.get_time(), str(error)))

    graph.launch(impatient)
    graph.run(5.0)
    assert outcome == [(2.5, "timeout exceeded while waiting for service /nobody/offers/this")]


def test_calling_a_missing_service(graph):
    rospy.init_node("caller")
    with pytest.raises(rospy.ServiceException, match=r"service \[/set_light\] unavailable"):
        rospy.ServiceProxy("set_light", ChangePattern)(String("RED"))


def test_a_service_call_blocks_the_caller(graph):
    times = []

    def slow_server():
        rospy.init_node("slow_server")

        def handle(request):
            rospy.sleep(2.0)
            return ChangePatternResponse()

        rospy.Service("slow", ChangePattern, handle)
        rospy.spin()

    def caller():
        rospy.init_node("caller")
        rospy.wait_for_service("slow")
        times.append(rospy.get_time())
        rospy.ServiceProxy("slow", ChangePattern)(String("RED"))
        times.append(rospy.get_time())

    graph.launch(slow_server)
    graph.launch(caller)
    graph.run(5.0)
    assert times == [0.0, 2.0]


# -- parameters ---------------------------------------------------------------------------------
def test_parameters(graph):
    seen = {}

    def configured():
        rospy.init_node("kinematics_node")
        seen["private"] = rospy.get_param("~gain")
        seen["relative"] = rospy.get_param("robot_type")
        seen["default"] = rospy.get_param("~trim", 0.0)
        seen["namespace"] = rospy.get_param("/duckiebot/kinematics_node")
        rospy.set_param("~baseline", 0.1)
        seen["search"] = rospy.search_param("robot_type")
        try:
            rospy.get_param("~missing")
        except KeyError as error:
            seen["missing"] = str(error)

    graph.set_param("/duckiebot/robot_type", "duckiebot")
    graph.launch(configured, namespace="/duckiebot", params={"gain": 1.0})
    graph.run(0.0)
    assert seen == {
        "private": 1.0,
        "relative": "duckiebot",
        "default": 0.0,
        "namespace": {"gain": 1.0},
        "search": "/duckiebot/robot_type",
        "missing": "'~missing'",
    }
    assert graph.param_names() == [
        "/duckiebot/kinematics_node/baseline",
        "/duckiebot/kinematics_node/gain",
        "/duckiebot/robot_type",
    ]
    graph.delete_param("/duckiebot/kinematics_node/gain")
    assert not graph.has_param("/duckiebot/kinematics_node/gain")
    with pytest.raises(KeyError):
        graph.delete_param("/nothing")


def test_cached_parameters_follow_every_change(graph):
    seen = []

    def driver():
        rospy.init_node("kinematics_node")
        rate = rospy.Rate(10)
        for _ in range(4):
            rospy.get_param_cached("~")["gain"] = -1.0  # the caller's copy: the parameter stays
            seen.append((rospy.get_param_cached("~"), rospy.get_param_cached("~trim", "unset")))
            rate.sleep()

    graph.launch(driver, namespace="/duckiebot", params={"gain": 1.0, "trim": 0.0})
    graph.run(0.05)
    graph.set_param("/duckiebot/kinematics_node/trim", -0.1)
    graph.run(0.1)
    graph.delete_param("/duckiebot/kinematics_node/trim")
    graph.run(0.1)
    graph.set_param("/duckiebot/kinematics_node", {"gain": 0.5})
    graph.run(0.1)
    assert seen == [
        ({"gain": 1.0, "trim": 0.0}, 0.0),
        ({"gain": 1.0, "trim": -0.1}, -0.1),
        ({"gain": 1.0}, "unset"),
        ({"gain": 0.5}, "unset"),
    ]
    rospy.init_node("notebook")
    with pytest.raises(KeyError, match="/missing"):
        rospy.get_param_cached("/missing")


# -- names --------------------------------------------------------------------------------------
def test_namespaces_and_remapping(graph):
    seen = {}

    def node():
        rospy.init_node("camera_node")
        seen["name"] = rospy.get_name()
        seen["namespace"] = rospy.get_namespace()
        seen["relative"] = rospy.Publisher("image/compressed", String, queue_size=1).name
        seen["private"] = rospy.resolve_name("~image")
        seen["remapped"] = rospy.Publisher("raw", String, queue_size=1).name

    graph.launch(node, namespace="duckiebot", remap={"raw": "/elsewhere"})
    graph.run(0.0)
    assert seen == {
        "name": "/duckiebot/camera_node",
        "namespace": "/duckiebot/",
        "relative": "/duckiebot/image/compressed",
        "private": "/duckiebot/camera_node/image",
        "remapped": "/elsewhere",
    }


def test_init_node_rules(graph):
    with pytest.raises(ValueError, match="base name without '/'"):
        rospy.init_node("duckiebot/talker")
    rospy.init_node("notebook")
    rospy.init_node("notebook")  # the same arguments again: fine, as in rospy
    with pytest.raises(rospy.ROSException, match="already been called with different"):
        rospy.init_node("other")


def test_a_new_node_with_the_same_name_replaces_the_old_one(graph):
    def named():
        rospy.init_node("driver")
        rospy.spin()

    graph.launch(named)
    graph.run(0.1)
    old = graph.nodes["/driver"]
    graph.launch(named)
    graph.run(0.1)
    assert old.is_shutdown
    assert old.shutdown_reason == "a new node registered with the same name"
    assert graph.nodes["/driver"] is not old


def test_calls_before_init_node_explain_what_to_do():
    Graph(stdout=io.StringIO())
    with pytest.raises(rospy.ROSInitException, match=r"call rospy.init_node\('name'\) first"):
        rospy.Time.now()
    # As in rospy, handles may be made first (the tutorials' talker does); they need the node
    # only to be used.
    pub = rospy.Publisher("chatter", String, queue_size=1)
    with pytest.raises(rospy.ROSInitException, match=r"publish\(\) on chatter needs a node"):
        pub.publish(String(data="too early"))


def test_handles_made_before_init_node_join_the_node(graph):
    heard = []
    pub = rospy.Publisher("chatter", String, queue_size=10)
    sub = rospy.Subscriber("chatter", String, heard.append)
    proxy = rospy.ServiceProxy("add", ChangePattern)
    rospy.init_node("early", anonymous=False)
    assert (pub.name, sub.name, proxy.name) == ("/chatter", "/chatter", "/add")
    pub.publish(String(data="now"))
    graph.run(0.0)
    assert [msg.data for msg in heard] == ["now"]
    assert graph.topics["/chatter"].publishers == [pub]


# -- shutdown -----------------------------------------------------------------------------------
def _motor_node():
    """Drive at 0.5 ten times a second; a shutdown hook sends the zero command."""
    rospy.init_node("motors")
    pub = rospy.Publisher("wheels_cmd", WheelsCmdStamped, queue_size=1)
    rospy.on_shutdown(lambda: pub.publish(WheelsCmdStamped(vel_left=0.0, vel_right=0.0)))
    rate = rospy.Rate(10)
    while not rospy.is_shutdown():
        pub.publish(WheelsCmdStamped(vel_left=0.5, vel_right=0.5))
        rate.sleep()


def test_shutdown_hooks_run_and_close_the_node(graph):
    stopped = []

    def watcher():
        rospy.init_node("watcher")
        rospy.Subscriber(
            "wheels_cmd",
            WheelsCmdStamped,
            lambda m: stopped.append((rospy.get_time(), m.vel_left)),
            queue_size=10,
        )
        rospy.spin()

    graph.launch(watcher)
    graph.launch(_motor_node)
    graph.run(0.25)
    graph.nodes["/motors"].shutdown("user pressed stop")
    graph.run(0.25)
    assert stopped[-1] == (0.25, 0.0)  # the hook's zero command arrived
    assert [value for _, value in stopped[:-1]] == [0.5, 0.5, 0.5]
    assert "/motors" not in graph.nodes
    assert "/wheels_cmd" in graph.topics  # the watcher still subscribes
    assert graph.topics["/wheels_cmd"].publishers == []


def test_graph_shutdown_delivers_what_launched_nodes_say_on_the_way_out(graph):
    heard = []
    with node_context(graph.host_node("wheels_driver")):  # a driver: callbacks only
        rospy.Subscriber(
            "wheels_cmd",
            WheelsCmdStamped,
            lambda m: heard.append((m.vel_left, rospy.is_shutdown())),
            queue_size=10,
        )

    graph.launch(_motor_node)
    graph.run(0.15)
    graph.shutdown()
    assert heard == [(0.5, False), (0.5, False), (0.0, False)], "the driver heard the zero"
    assert graph.nodes == {}
    assert all(actor.finished for actor in graph._actors)


def test_after_shutdown_a_publish_is_dropped_and_a_sleep_ends_the_loop(graph):
    # A publish is dropped quietly, as Debian's rospy does; a sleep raises, as rospy does on
    # simulated time, so a loop with no is_shutdown() check ends.
    heard = []
    listener = graph.host_node("listener")
    with node_context(listener):
        rospy.Subscriber("chatter", String, heard.append)
    rospy.init_node("short_lived")
    pub = rospy.Publisher("chatter", String, queue_size=1)
    rospy.signal_shutdown("done")
    assert rospy.is_shutdown()
    assert pub.publish("too late") is None
    with pytest.raises(rospy.ROSInterruptException):
        rospy.sleep(1.0)
    graph.run(0.0)
    assert heard == []
    assert graph.time == 0.0


def test_publish_to_an_unregistered_publisher_is_refused(graph):
    rospy.init_node("tidy")
    pub = rospy.Publisher("chatter", String, queue_size=1)
    pub.unregister()
    with pytest.raises(rospy.ROSException, match="unregistered"):
        pub.publish("after unregister")


def test_a_node_shut_down_while_it_sleeps_or_spins_wakes_at_once(graph):
    woke = {}

    def sleeper():
        rospy.init_node("sleeper")
        try:
            rospy.sleep(100)
        except rospy.ROSInterruptException:
            woke["sleeper"] = rospy.get_time()

    def spinner():
        rospy.init_node("spinner")
        rospy.Subscriber("stop", String, lambda m: rospy.signal_shutdown(m.data), queue_size=1)
        rospy.spin()
        woke["spinner"] = rospy.get_time()

    def stopper():
        rospy.init_node("stopper")
        pub = rospy.Publisher("stop", String, queue_size=1)
        rospy.sleep(2.0)
        pub.publish("asked to stop")
        rospy.spin()

    for node in (sleeper, spinner, stopper):
        graph.launch(node)
    graph.run(1.0)
    graph.nodes["/sleeper"].shutdown("stopped from outside")
    graph.run(5.0)
    assert woke == {"sleeper": 1.0, "spinner": 2.0}


def test_graph_shutdown_interrupts_sleeping_nodes(graph):
    outcome = []

    def sleeper():
        rospy.init_node("sleeper")
        try:
            rospy.sleep(100)
        except rospy.ROSInterruptException as error:
            outcome.append(str(error))

    graph.launch(sleeper)
    graph.run(1.0)
    graph.shutdown()
    assert outcome == ["ROS shutdown request"]
    assert all(actor.finished for actor in graph._actors)


def test_a_crashing_node_is_reported_and_the_others_go_on(graph):
    heard = []

    def crasher():
        rospy.init_node("crasher")
        rospy.sleep(0.5)
        raise ZeroDivisionError("oops")

    graph.launch(listener, heard)
    graph.launch(talker)
    graph.launch(crasher)
    with pytest.raises(NodeCrashed, match="Node /crasher stopped with ZeroDivisionError: oops"):
        graph.run(1.0)
    assert graph.time == 0.5
    assert any("ZeroDivisionError: oops" in text for text in texts(graph, rospy.ERROR))
    graph.run(0.5)
    assert len(heard) == 11


def test_a_failing_callback_is_logged_and_the_subscriber_goes_on(graph):
    got = []

    def fragile():
        rospy.init_node("fragile")

        def callback(message):
            if message.data.endswith("1"):
                raise RuntimeError("cannot handle 1")
            got.append(message.data)

        rospy.Subscriber("chatter", String, callback, queue_size=10)
        rospy.spin()

    graph.launch(fragile)
    graph.launch(talker)
    graph.run(0.3)
    assert got == ["hello world 0", "hello world 2", "hello world 3"]
    assert "bad callback on /chatter" in texts(graph, rospy.ERROR)[0]


def test_wait_for_message(graph):
    graph.launch(talker)
    rospy.init_node("notebook")
    rospy.sleep(0.05)
    message = rospy.wait_for_message("/chatter", String, timeout=1.0)
    assert message.data == "hello world 1"
    assert rospy.get_time() == pytest.approx(0.1)
    with pytest.raises(rospy.ROSException, match="timeout exceeded"):
        rospy.wait_for_message("/silence", String, timeout=0.5)


def test_logging_levels_and_output():
    out, err = io.StringIO(), io.StringIO()
    graph = Graph(stdout=out, stderr=err)
    rospy.init_node("talkative")
    rospy.loginfo("x is %d", 3)
    rospy.logwarn("careful")
    rospy.logdebug("hidden at INFO level")
    for _ in range(3):
        rospy.loginfo_once("only once")
    assert out.getvalue() == (
        "[INFO] [0.000] [/talkative]: x is 3\n[INFO] [0.000] [/talkative]: only once\n"
    )
    assert err.getvalue() == "[WARN] [0.000] [/talkative]: careful\n"
    graph.shutdown()


# -- how launched nodes take turns ----------------------------------------------------------------
def test_ctrl_c_in_a_nodes_code_stops_the_run_and_ends_only_that_node(graph):
    steps = []

    def impatient():
        rospy.init_node("impatient")
        rospy.sleep(1.0)
        raise KeyboardInterrupt  # as if Ctrl-C arrived while this node's code ran

    def steady():
        rospy.init_node("steady")
        rate = rospy.Rate(2)
        while not rospy.is_shutdown():
            steps.append(rospy.get_time())
            rate.sleep()

    graph.launch(impatient)
    graph.launch(steady)
    with pytest.raises(KeyboardInterrupt):
        graph.run(5.0)
    assert graph.time == 1.0
    assert "/impatient" not in graph.nodes
    graph.run(1.0)  # the other node carries on
    assert steps == [0.0, 0.5, 1.0, 1.5, 2.0]
    assert not any(record.level >= rospy.ERROR for record in graph.log)


def test_nodes_as_greenlets_are_driven_from_one_thread():
    import threading

    graph = Graph(stdout=io.StringIO())
    assert not graph.threads, "the course's environment has greenlet"

    def ticker():
        rospy.init_node("ticker")
        while not rospy.is_shutdown():
            rospy.sleep(1.0)

    graph.launch(ticker)
    graph.run(1.5)
    failed = []
    other = threading.Thread(target=lambda: _run_catching(graph, failed))
    other.start()
    other.join()
    assert failed == [
        "Node /ticker runs in the thread that first drove this graph; drive the graph from "
        "that thread (or create it with Graph(threads=True))."
    ]
    graph.shutdown()
    assert all(actor.finished for actor in graph._actors)


def _run_catching(graph, failed):
    try:
        graph.run(1.0)
    except rospy.ROSException as error:
        failed.append(str(error))


def test_a_graph_dropped_without_shutdown_leaves_its_nodes_parked():
    import gc

    from duckielib.ros import actors

    cleaned = []

    def tidy():
        rospy.init_node("tidy")
        try:
            rospy.spin()
        finally:
            cleaned.append("ran at collection")

    graph = Graph(stdout=io.StringIO())
    graph.launch(tidy)
    graph.run(0.1)
    parked = len(actors.parked)
    del graph
    gc.collect()
    assert cleaned == []
    assert len(actors.parked) == parked
