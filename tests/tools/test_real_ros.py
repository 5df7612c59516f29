"""The real-ROS mission's helpers that need no ROS: ports, topics, tools ended as by Ctrl-C."""

from __future__ import annotations

import os
import socket
import sys

from duckielib.tools import real_ros


def test_the_recorded_topics_are_under_the_robots_name():
    topics = real_ros.recorded_topics("bot7")
    assert topics[0] == "/bot7/odometry_node/pose"
    assert "/bot7/mission_node/state" in topics
    assert len(topics) == 4


def test_a_free_port_can_be_listened_on():
    port = real_ros.free_port()
    with socket.socket() as server:
        server.bind(("127.0.0.1", port))
    assert 1024 <= port <= 65535


def test_a_tool_started_in_its_group_ends_on_ctrl_c_and_writes_its_log(tmp_path):
    script = "import time; print('up', flush=True); time.sleep(60)"
    log = tmp_path / "tool.log"
    process = real_ros.start_ros_tool([sys.executable, "-c", script], dict(os.environ), log)
    assert os.getpgid(process.pid) == process.pid  # its own group, as a terminal's
    while "up" not in log.read_text():
        pass
    real_ros.stop_ros_tool(process, timeout=10)
    assert process.returncode not in (None, 0)
    real_ros.stop_ros_tool(process)  # a second stop does nothing


def test_run_tool_prints_the_command_and_what_it_printed(capsys):
    real_ros.run_tool([sys.executable, "-c", "print('hello')"], dict(os.environ))
    assert capsys.readouterr().out == f"$ {sys.executable} -c print('hello')\nhello\n"
