"""The camera on screen, as ``rqt_image_view`` shows it on a robot: :class:`ImageView`.

An image view shows a ``sensor_msgs/CompressedImage`` topic in a notebook:

- live, while the graph runs: ``ImageView(topic)`` subscribes to the topic and shows each new
  frame (at most ``max_rate`` pictures per second of real time; the latest one always when
  the view is closed, or at the end of a ``with`` block);
- from a bag: ``ImageView.from_bag(path, topic)`` plays the recorded frames with play, pause
  and a slider.

The JPEG bytes are shown as they are, without decoding: what is on screen is what a subscriber
receives. Like every module of :mod:`duckielib.plots`, it runs on the laptop only.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, Dict, List, Optional, Tuple, Union

from duckielib.errors import DuckielibError
from duckielib.plots.player import image_topic, playing_widget
from duckielib.rostime import NS_PER_S

if TYPE_CHECKING:
    from duckielib.bags.reader import Bag
    from duckielib.ros.graph import Graph

__all__ = ["ImageView"]

_IMAGE_TYPE = "sensor_msgs/CompressedImage"
#: What the view's own node is called (the graph drawing hides it, as it hides rostopic's).
VIEW_NODE = "rqt_image_view"


def _format(message: Any) -> str:
    """The picture format of a CompressedImage for the browser: "jpeg" or "png"."""
    return "png" if "png" in str(message.format).lower() else "jpeg"


class ImageView:
    """Show a compressed image topic in a notebook, live while the graph runs.

    Args:
        topic: the ``sensor_msgs/CompressedImage`` topic, for example
            ``"/duckiebot/camera_node/image/compressed"``.
        graph: the graph to subscribe on (default: the current one, the notebook's robot).
        max_rate: the most pictures shown per second of real time while the graph runs.

    Use it in a ``with`` block, so that it stops subscribing at the end (a camera renders
    only while someone subscribes)::

        with ImageView(topic) as view:
            display(view)
            bot.run(2.0)

    Raises:
        ROSException: if no node publishes or subscribes to ``topic``.
        DuckielibError: if the topic's type is not ``sensor_msgs/CompressedImage``.
    """

    def __init__(self, topic: str, graph: Optional[Graph] = None, max_rate: float = 15.0) -> None:
        import ipywidgets as widgets

        from duckielib.ros.context import node_context
        from duckielib.ros.graph import current_graph
        from duckielib.ros.introspect import tool_node, topic_record
        from duckielib.ros.rospy import Subscriber

        self.graph = graph if graph is not None else current_graph()
        record = topic_record(self.graph, topic)
        if record.type != _IMAGE_TYPE:
            raise DuckielibError(
                f"{record.name} carries {record.type}, not {_IMAGE_TYPE}: an image view shows "
                f"compressed images; try a topic ending in image/compressed."
            )
        self.topic = record.name
        self.count = 0
        self.latest: Optional[Any] = None
        self._shown: Optional[Any] = None
        self._gap = 1.0 / max_rate
        self._last_shown = -float("inf")
        self.image = widgets.Image(format="jpeg", layout=widgets.Layout(max_width="100%"))
        self.caption = widgets.HTML(value=f"{self.topic}: waiting for a frame")
        self.box = widgets.VBox([self.image, self.caption])
        self.box.add_class("duckie-image-view")
        self._node = tool_node(self.graph, VIEW_NODE)
        with node_context(self._node):
            self._subscriber = Subscriber(record.name, record.data_class, self._receive)

    def _receive(self, message: Any) -> None:
        self.latest = message
        self.count += 1
        now = time.monotonic()
        if now - self._last_shown >= self._gap:
            self._last_shown = now
            self.show_latest()

    def show_latest(self) -> None:
        """Show the latest frame received (if it is not shown yet)."""
        message = self.latest
        if message is None or message is self._shown:
            return
        self._shown = message
        self.image.format = _format(message)
        self.image.value = bytes(message.data)
        stamp = message.header.stamp.to_nsec() / NS_PER_S
        self.caption.value = (
            f"{self.topic}: frame {self.count}, stamped {stamp:.2f} s, {len(message.data)} bytes"
        )

    def close(self) -> None:
        """Show the latest frame and stop subscribing (the picture stays)."""
        self.show_latest()
        if not self._node.is_shutdown:
            self._node.shutdown("image view closed")

    def __enter__(self) -> ImageView:
        return self

    def __exit__(self, *exc_info: Any) -> None:
        self.close()

    def _repr_mimebundle_(self, **kwargs: Any) -> Dict[str, Any]:
        self.show_latest()
        return self.box._repr_mimebundle_(**kwargs) or {}

    def __repr__(self) -> str:
        return f"ImageView({self.topic!r}: {self.count} frames received)"

    @staticmethod
    def from_bag(bag: Union[Bag, str, Path], topic: Optional[str] = None, fps: float = 10.0) -> Any:
        """Play the frames a bag recorded on an image topic: play, pause and a slider.

        Args:
            bag: the bag, or its path.
            topic: the ``sensor_msgs/CompressedImage`` topic (default: the first whose name
                says it is annotated, else the first there is).
            fps: frames per second when playing.

        Returns:
            The ipywidgets box; a notebook shows it as the cell's last value.

        Raises:
            BagError: if the bag cannot be read.
            DuckielibError: if the bag has no such image topic, or no frame on it.
        """
        from duckielib.bags import Bag

        bag = bag if isinstance(bag, Bag) else Bag(bag)
        topic = image_topic(bag, topic)
        if not topic:
            raise DuckielibError("The bag has no image topic: it recorded no CompressedImage.")
        start = bag.start_ns / NS_PER_S
        frames: List[Tuple[float, bytes, str]] = [
            (item.time - start, bytes(item.message.data), _format(item.message))
            for item in bag.read(topic)
        ]
        if not frames:
            raise DuckielibError(f"The bag recorded no frame on {topic}.")

        def caption(index: int) -> str:
            t, data, _ = frames[index]
            return f"{topic}: frame {index + 1} of {len(frames)}, t = {t:.2f} s, {len(data)} bytes"

        return playing_widget(
            len(frames), fps, lambda index: (frames[index][1], frames[index][2]), caption
        )
