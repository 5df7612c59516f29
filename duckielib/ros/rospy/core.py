"""What the parts of rospy share: waiting as a node, and the cost of never waiting.

A node's main code that never waits is charged :data:`CALL_COST_NS` of simulated time for each
rospy call that reads the clock, checks for shutdown or publishes, and waits once it owes a
millisecond (see the package's docstring). Handles made before ``init_node`` wait here for
the node.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

from typing import Callable, Optional

from duckielib.ros.context import (
    calling_actor,
    current_node,
    node_stack,
    refuse_library_thread,
    waiting_for_init,
)
from duckielib.ros.exceptions import (
    ROSInitException,
)
from duckielib.ros.node import Node

#: Simulated time that one rospy call costs the main code of a node that never waits, in ns.
CALL_COST_NS = 100_000
#: A node that never waits waits once it owes this much simulated time, in ns.
_MAX_DEBT_NS = 1_000_000


def _block(
    node: Node, deadline_ns: Optional[int], predicate: Callable[[], bool], polled: bool = True
) -> bool:
    """Wait as ``node`` (see :meth:`Graph.block`); a node that waits owes no compute time."""
    node.compute_debt_ns = 0
    return node.graph.block(deadline_ns, predicate, polled=polled)


def _spend(node: Node) -> None:
    """Charge ``node``'s main code for one rospy call; make it wait once it owes 1 ms.

    Callbacks, and code that runs while the graph delivers events in this thread, are not
    charged: only code that could otherwise hold the clock still for ever.
    """
    if not node.has_main_code or node.is_shutdown or node_stack():
        return
    if calling_actor() is None:
        if node.graph.driving_here():
            return
        refuse_library_thread()
    node.compute_debt_ns += CALL_COST_NS
    if node.compute_debt_ns >= _MAX_DEBT_NS:
        owed = node.compute_debt_ns
        _block(node, node.graph.now_ns + owed, lambda: node.is_shutdown, polled=False)


def _attach_waiting(node: Node) -> None:
    waiting = waiting_for_init()
    while waiting:
        waiting.pop(0)(node)


def _node_or_later(attach: Callable[[Node], None]) -> None:
    """Run ``attach(node)`` now, or once the calling code has called ``init_node``.

    rospy allows publishers, subscribers and service proxies made before ``init_node``.
    """
    try:
        node = current_node()
    except ROSInitException:
        waiting_for_init().append(attach)
    else:
        attach(node)
