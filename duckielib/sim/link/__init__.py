"""The virtual Duckiebot and the nodes that drive it, in two processes joined by one socket.

On a real Duckiebot, a student's nodes reach the robot only through topics and services: they
cannot move the robot's body, read where it really is, or rewrite what the encoders count.
In one process they could (the simulator is an object away), so for grading, and with
``duckie mission --apart`` and :class:`~duckielib.tools.apart.ApartDuckiebot`, the two sides
run apart, each on a graph of its own:

- the **robot's side** (:class:`RobotLink`): the simulator, the robot's driver nodes and the
  bag recorder, in the process that starts the other;
- the **nodes' side** (:class:`NodesLink`): the student's nodes, in a process of their own (in
  the grader's sandbox when grading).

The two graphs keep one simulated clock. The robot's side leads: it runs everything due on
its graph up to a time ``t``, hands the nodes' side the messages its nodes subscribed to and
the time ``t``, and waits while that side runs everything due there; the answer carries what
the nodes published, any new subscriptions, and when the nodes' side next has something to do.
The clock then moves to whichever side has the earlier next thing. Nothing runs on one side
while the other works, so the run unfolds as on one graph.

What crosses, and how it is checked on the robot's side:

- The robot's topics and services are offered to the nodes (the nodes' graph shows them as
  the robot's nodes' own), except the simulator's (``simulator_node/...``): no real robot has
  them. A topic's messages are sent over only once a node subscribes to it.
- What the nodes publish reaches the robot's graph as messages of the robot's known types,
  read by the types' own strict ROS 1 decoders, and is recorded from there. The robot's own
  outputs (encoder ticks, the executed wheel commands, the LED pattern it shows, the camera)
  are the robot's alone: the nodes' messages on those topics stay on the nodes' side.
- A node's service call to the robot is answered by the robot's service, at the same
  simulated time; the robot's graph lists the nodes' nodes and services as a master would, and
  a call of one of their services there is answered by the node.
- The robot's graph gathers the nodes' log lines, as ``/rosout`` does.
- Parameters: the nodes' side starts with a copy of the robot's.

Every frame is a length-prefixed JSON header followed by the messages' bytes; sizes are
bounded on both ends.
"""

from duckielib.sim.link.nodes import NodesLink
from duckielib.sim.link.robot import RobotLink
from duckielib.sim.link.wire import (
    HEADER_LIMIT,
    MESSAGE_LIMIT,
    LinkError,
    NodesStopped,
    OutOfWallTime,
    receive,
    send,
)

__all__ = [
    "HEADER_LIMIT",
    "LinkError",
    "MESSAGE_LIMIT",
    "NodesLink",
    "NodesStopped",
    "OutOfWallTime",
    "RobotLink",
    "receive",
    "send",
]
