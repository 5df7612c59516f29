"""Watch the virtual Duckiebot live in Foxglove or Lichtblick, as one watches a real robot.

In a notebook::

    bot = VirtualDuckiebot()
    view = bot.live()        # serves ws://127.0.0.1:8765
    bot.launch(my_node)
    bot.run(30)              # 30 simulated seconds, now at the wall clock's pace
    view.close()

In Foxglove or Lichtblick, open a connection ("Foxglove WebSocket") to the address printed.
The view is a server of the Foxglove WebSocket protocol (the Foxglove SDK), on this computer
only (127.0.0.1). It serves, as ``foxglove_bridge`` serves a real ROS 1 robot:

- every topic of the graph, with ROS 1 bytes and definitions (``ros1`` encoding), from its
  first publisher's first message: its channel is advertised as the publisher is created,
  and a topic that starts while a viewer watches is held back, from its first message, until
  a viewer subscribes to it (for at most two wall seconds), so a viewer that subscribes to
  it as it is advertised has it whole, however short it is (``foxglove_bridge`` sends only
  what is published after the subscription arrives);
- the camera's images, which the camera renders only while a viewer shows them;
- a latched topic's last message when a viewer subscribes to it and no viewer has had it
  yet, as ROS gives it to a new subscriber;
- each 2D pose (``duckietown_msgs/Pose2DStamped``) as a frame on ``/tf`` and a
  ``geometry_msgs/PoseStamped`` on ``TOPIC_3d`` (:mod:`duckielib.bags.viewers`), which a 3D
  panel draws: the true pose and the odometry's side by side;
- the simulated time, as the protocol's time messages (viewers follow it) and on ``/clock``
  (``rosgraph_msgs/Clock``), as the clock moves, at most 100 times per simulated second.

While the view is open, the simulated time keeps pace with the wall clock (``rate`` 1; 2 runs
twice as fast), so there is something to watch: the graph waits between its events.

Laptop side; never deployed.
"""

from __future__ import annotations

import itertools
import math
import socket
import threading
import time
from typing import Any, Dict, List, Optional, Set, Tuple

import foxglove
from foxglove import _foxglove_py as _foxglove
from foxglove.websocket import ServerListener

from duckielib.bags.recorder import Tap
from duckielib.bags.viewers import POSE_2D, ViewerPoses, pose_3d_topic
from duckielib.errors import ConfigError
from duckielib.messages import get_message_class
from duckielib.ros.context import node_context
from duckielib.ros.graph import Graph
from duckielib.rostime import NS_PER_S, Time
from duckielib.sim.ros_node import Pace

__all__ = ["DEFAULT_PORT", "LiveView"]

#: The port Foxglove and Lichtblick suggest for a WebSocket connection.
DEFAULT_PORT = 8765

#: Topics rendered only for a viewer that shows them.
IMAGE_TYPES = ("sensor_msgs/CompressedImage", "sensor_msgs/Image")

#: How often, in simulated nanoseconds, the view looks for new topics and viewers' images.
_DISCOVERY_PERIOD_NS = 100_000_000

#: How often, in simulated nanoseconds, the time is sent (and published on /clock).
_TIME_PERIOD_NS = 10_000_000

#: Wall seconds a viewer's panels have to subscribe after its first subscription.
_SETTLE_S = 1.0

#: Wall seconds a topic that starts while a viewer watches is held back, from its advertisement,
#: for a viewer to subscribe to it; its messages until then reach the first that does.
_HOLD_S = 2.0

#: Messages the server holds for a viewer that falls behind, per unit of rate, and at most.
#: The SDK drops a viewer's oldest message when its queue is full (1,024 by default); a run
#: at 50 x the wall clock's pace sends about 10,000 messages a second, so a viewer's
#: process paused for a tenth of a second would otherwise lose some.
_BACKLOG_PER_RATE = 1024
_BACKLOG_MAX = 16384

#: Wall seconds a viewer has to receive the last messages before the server stops.
_LAST_MESSAGES_S = 0.25

_numbers = itertools.count(1)


class _Viewers(ServerListener):
    """The Foxglove server's listener: which topics viewers subscribe to, and whether any.

    The server calls it from its own threads once a subscription is in place (the channel
    has the viewer as a sink); :meth:`wait_for` waits for the subscriptions it is told of.
    """

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.changed = threading.Condition(self.lock)  # a viewer subscribed
        self.subscriptions: Dict[str, int] = {}  # by topic
        self.new: List[str] = []  # topics subscribed to since the graph last looked
        self.subscribed = threading.Event()

    def on_subscribe(self, client: Any, channel: Any) -> None:
        with self.changed:
            self.subscriptions[channel.topic] = self.subscriptions.get(channel.topic, 0) + 1
            self.new.append(channel.topic)
            self.changed.notify_all()
        self.subscribed.set()

    def take_new(self) -> List[str]:
        with self.lock:
            new, self.new = self.new, []
        return new

    def on_unsubscribe(self, client: Any, channel: Any) -> None:
        with self.lock:
            self.subscriptions[channel.topic] = max(0, self.subscriptions.get(channel.topic, 0) - 1)

    def watching(self, topic: str) -> bool:
        with self.lock:
            return self.subscriptions.get(topic, 0) > 0

    def watching_any(self) -> bool:
        """Whether a viewer subscribes to a topic now."""
        with self.lock:
            return any(count > 0 for count in self.subscriptions.values())

    def wait_for(self, topics: List[str], timeout: float) -> None:
        """Wait (wall seconds, at most ``timeout``) until a viewer subscribes to each topic."""
        with self.changed:
            self.changed.wait_for(
                lambda: all(self.subscriptions.get(topic, 0) > 0 for topic in topics),
                max(0.0, timeout),
            )


class LiveView:
    """Serve a graph's topics to Foxglove and Lichtblick over WebSocket, as it runs.

    Args:
        graph: the graph to serve (a :class:`~duckielib.sim.VirtualDuckiebot`'s ``graph``).
        port: the port to serve on (default 8765); 0 picks a free one.
        rate: simulated seconds per wall-clock second while the view is open.
        host: the address to serve on; the default, 127.0.0.1, is this computer only.
        name: the server's name, shown by the viewer.

    Attributes:
        url: the address to open in the viewer, ``ws://127.0.0.1:8765``.
        topics: the topics served, with their types.

    Raises:
        ConfigError: if the port is taken or the rate is not above 0.
    """

    def __init__(
        self,
        graph: Graph,
        port: int = DEFAULT_PORT,
        rate: float = 1.0,
        host: str = "127.0.0.1",
        name: str = "virtual Duckiebot",
    ) -> None:
        if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not rate > 0:
            raise ConfigError(f"The live view's rate must be a number above 0, not {rate!r}.")
        self.graph = graph
        self.rate = float(rate)
        self.closed = False
        # The SDK's server runs in threads of its own (Rust); its log lines (a viewer that
        # disconnects, say) would call into Python's logging from them at any moment. The
        # viewer says what went wrong on its side; the view's own errors are sentences here.
        _foxglove.disable_logging()
        self._context = foxglove.Context()
        self._viewers = _Viewers()
        try:
            self._server = foxglove.start_server(
                name=name,
                host=host,
                port=port,
                capabilities=[foxglove.Capability.Time],
                server_listener=self._viewers,
                context=self._context,
                message_backlog_size=min(
                    _BACKLOG_MAX, _BACKLOG_PER_RATE * max(1, math.ceil(self.rate))
                ),
            )
        except RuntimeError as error:
            reason = str(error).split(": ", 1)[-1]
            raise ConfigError(
                f"The live view cannot serve on {host}:{port} ({reason}). Another program, or "
                "an earlier live view still open, may use that port: close it, or choose "
                "another port (--port on the command line)."
            ) from None
        self._host = host
        self._port = self._server.port  # the server says 0 once it is stopped
        self.url = f"ws://{host}:{self._port}"
        self.topics: Dict[str, str] = {}
        self._channels: Dict[str, Any] = {}
        self._taps: Dict[str, Tap] = {}
        self._unseen: Set[str] = set()  # topics whose last message reached no viewer
        # Topics that started while a viewer watched, no viewer subscribed to yet: until when
        # (wall clock) they are held back, and their messages (bytes, time) until then.
        self._held: Dict[str, Tuple[float, List[Tuple[bytes, int]]]] = {}
        self._poses = ViewerPoses()
        self._clock = get_message_class("rosgraph_msgs/Clock")
        self._clock_channel = self._channel("/clock", self._clock)
        self._next_time_ns = graph.now_ns
        self._pace = Pace(self.rate, start=graph.time)
        self._node = graph.host_node(f"live_view_{next(_numbers)}")
        self._node.shutdown_hooks.append(self.close)
        graph.add_clock_listener(self._keep_pace)
        graph.topic_watchers.append(self._watch)
        self._discover()

    def __enter__(self) -> LiveView:
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self.closed else f"{len(self.topics)} topics, rate {self.rate:g}"
        return f"<LiveView {self.url} ({state})>"

    def wait_for_viewer(self, timeout: Optional[float] = None) -> bool:
        """Wait (wall-clock seconds, None: as long as it takes) until a viewer subscribes.

        It returns a second after the viewer's first subscription, so that the others it
        makes as its panels open land too.

        Returns:
            Whether a viewer subscribed to a topic.
        """
        if not self._viewers.subscribed.wait(timeout):
            return False
        time.sleep(_SETTLE_S)
        return True

    # Channels and taps.

    def _channel(self, topic: str, data_class: Any) -> Any:
        channel = self._channels.get(topic)
        if channel is None:
            schema = foxglove.Schema(
                name=data_class._type, encoding="ros1msg", data=data_class._full_text.encode()
            )
            channel = foxglove.Channel(
                topic,
                schema=schema,
                message_encoding="ros1",
                context=self._context,
                metadata={"md5sum": data_class._md5sum},
            )
            self._channels[topic] = channel
            self.topics[topic] = data_class._type
            if self._viewers.watching_any():  # a viewer may subscribe to it as it learns of it
                self._held[topic] = (time.monotonic() + _HOLD_S, [])
        return channel

    def _serve(self, topic: str) -> None:
        """Serve ``topic`` if it has a publisher; tap an image topic only while it is shown."""
        record = self.graph.topics.get(topic)
        if self.closed or record is None or not record.publishers:
            return
        self._channel(topic, record.data_class)
        if record.type == POSE_2D:
            self._channel("/tf", get_message_class("tf2_msgs/TFMessage"))
            self._channel(pose_3d_topic(topic), get_message_class("geometry_msgs/PoseStamped"))
        wanted = record.type not in IMAGE_TYPES or self._viewers.watching(topic)
        tapped = topic in self._taps
        if wanted and not tapped:
            with node_context(self._node):
                self._taps[topic] = Tap(topic, self._deliver)
        elif tapped and not wanted:
            self._taps.pop(topic).unregister()

    def _watch(self, handle: Any, publishes: bool) -> None:
        """The graph's topic watcher: a new publisher's topic is served from its first message."""
        if publishes:
            self._serve(handle.name)

    def _discover(self) -> None:
        """Look at every topic again (viewers start and stop showing images); say latched ones."""
        if self.closed:
            return
        for topic in list(self.graph.topics):
            self._serve(topic)
        for topic in self._viewers.take_new():  # a latched message no viewer has seen yet
            record = self.graph.topics.get(topic)
            if topic in self._unseen and record is not None and record.latched:
                self._unseen.discard(topic)
                for data in list(record.latched.values()):
                    self._channels[topic].log(data, log_time=self.graph.now_ns)
        self.graph.schedule(self.graph.now_ns + _DISCOVERY_PERIOD_NS, self._discover)

    def _deliver(self, record: Any, data: bytes) -> None:
        """Send one message as published, and its viewer's forms."""
        now = self.graph.now_ns
        if self._send(record.name, data, now):
            self._unseen.discard(record.name)
        else:
            self._unseen.add(record.name)
        if record.data_class._type == POSE_2D:
            for made in self._poses.messages(record.name, POSE_2D, data, now):
                self._send(made.topic, made.data, now)

    def _send(self, topic: str, data: bytes, t_ns: int) -> bool:
        """Send one message on ``topic``'s channel, or hold it back for a viewer to come.

        Returns:
            Whether a viewer has it, or will once it subscribes.
        """
        if topic in self._held:
            self._release(time.monotonic())
        held = self._held.get(topic)
        if held is not None:
            held[1].append((data, t_ns))
            return True
        channel = self._channels[topic]
        if channel.has_sinks():
            channel.log(data, log_time=t_ns)
            return True
        return False

    def _release(self, now: float) -> None:
        """Send what is held back to the topics a viewer subscribed to; drop it past its time.

        Args:
            now: the wall clock (``time.monotonic``).
        """
        for topic, (until, messages) in list(self._held.items()):
            channel = self._channels[topic]
            if channel.has_sinks():
                del self._held[topic]
                for data, t_ns in messages:
                    channel.log(data, log_time=t_ns)
            elif now >= until:
                del self._held[topic]
                if messages and topic in self.graph.topics:
                    self._unseen.add(topic)  # a latched one still reaches a later viewer

    # Time.

    def _keep_pace(self, t_ns: int) -> None:
        """Before the clock moves to ``t_ns``: wait for it on the wall clock; say the time."""
        if self._held:
            self._release(time.monotonic())
        self._pace.wait(t_ns / NS_PER_S)
        if t_ns >= self._next_time_ns:
            self._server.broadcast_time(t_ns)
            stamp = Time(t_ns // NS_PER_S, t_ns % NS_PER_S)
            self._clock_channel.log(self._clock(clock=stamp).to_bytes(), log_time=t_ns)
            self._next_time_ns = t_ns + _TIME_PERIOD_NS

    def close(self) -> None:
        """Stop serving; the graph runs at full speed again. Closing twice does nothing.

        A viewer gets a quarter of a second to receive the last messages first, and what is
        held back of a topic that started in the last two seconds waits for a viewer to
        subscribe to it for the rest of those two seconds.
        """
        if self.closed:
            return
        self.closed = True
        self.graph.remove_clock_listener(self._keep_pace)
        if self._watch in self.graph.topic_watchers:
            self.graph.topic_watchers.remove(self._watch)
        for tap in self._taps.values():
            tap.unregister()
        self._taps.clear()
        waiting = [topic for topic, (_, messages) in self._held.items() if messages]
        if waiting:  # a short topic's viewer may still be subscribing to it
            until = max(self._held[topic][0] for topic in waiting)
            self._viewers.wait_for(waiting, until - time.monotonic())
        self._release(math.inf)
        if self._viewers.subscribed.is_set():
            time.sleep(_LAST_MESSAGES_S)  # what is still queued for a viewer reaches it
        self._server.stop()  # it closes viewers' connections; its threads close the port after
        _wait_until_free(self._host, self._port)
        for channel in self._channels.values():
            channel.close()
        if not self._node.is_shutdown:
            self._node.shutdown("the live view was closed")


def _wait_until_free(host: str, port: int, timeout: float = 2.0) -> None:
    """Wait (at most ``timeout`` wall seconds) until a server can listen on the port again.

    The SDK's server closes its listening socket from its own threads, a moment after its
    ``stop()`` returns (and its ``port`` is 0 from then on). Waiting here, a view opened on the
    same port right after (the next ``duckie ... --live``, a notebook cell run again) finds it
    free. The probe listens as the server does: SO_REUSEADDR, bind, listen; so a viewer's
    connection not closed yet (the server's end in FIN-WAIT) keeps neither from the port.
    """
    try:
        family = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0][0]
    except OSError:
        return
    deadline = time.monotonic() + timeout
    while True:
        with socket.socket(family, socket.SOCK_STREAM) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            try:
                probe.bind((host, port))
                probe.listen()
                return
            except OSError:
                if time.monotonic() > deadline:
                    return
        time.sleep(0.005)
