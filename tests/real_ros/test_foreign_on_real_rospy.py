"""Foreign nodes do under Debian's rospy, on a real roscore, what they do on the virtual graph.

The same scripts run in-process in ``tests/foreign/test_foreign_nodes.py``; here they run as
a robot runs them, with the real rospy, so what the in-process rospy gives them is checked
against what rospy really gives.
"""

from __future__ import annotations

from pathlib import Path

import pytest

pytestmark = pytest.mark.ros

NODES = Path(__file__).resolve().parents[1] / "foreign" / "nodes"
#: Debian's Python, which finds Debian's rospy (the course's environment does not).
DEBIAN_PYTHON = "/usr/bin/python3"


def test_custom_connection_headers_reach_subscribers_and_services(master):
    talker = master.start([DEBIAN_PYTHON, str(NODES / "tagged_talker.py")], "tagged_talker")
    try:
        listener = master.start(
            [DEBIAN_PYTHON, str(NODES / "tagged_listener.py")], "tagged_listener"
        )
        assert listener.wait(timeout=60) == 0, master.log("tagged_listener")
    finally:
        master.stop(talker)
    log = master.log("tagged_listener")
    assert "status ready from /tagged_talker as leader of fleet 7 (latching 1)" in log
    assert "service says: /tagged_listener with token abc123 (answered by /tagged_talker)" in log
