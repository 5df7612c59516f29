"""The mission on a real ROS master: roscore, roslaunch and rosbag record, as in a terminal.

The last notebook runs the robot project's nodes the way the robot does, on a real ROS 1
master (Debian's packages, installed with ``make ros``), against the virtual Duckiebot node,
which publishes ``/clock`` so that every node runs on simulated time. What a person would type
in four terminals, :func:`mission_on_real_ros` does in order:

1. ``roscore -p PORT`` (a free port, so that no other master is disturbed);
2. ``rosbag record -O BAG topics...`` once ``/use_sim_time`` is set;
3. ``roslaunch course_nodes simulation.launch veh:=VEH rate:=RATE camera:=false``;
4. ``rostopic list``, ``rostopic echo`` and ``rosservice list`` while the mission drives.

Each tool ends as Ctrl-C ends it (SIGINT to its process group), harder only if it does not
listen. Nothing is left running, however the run ends.

Laptop side; never deployed.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
import xmlrpc.client
from pathlib import Path
from typing import Any, Dict, List, Sequence

__all__ = [
    "free_port",
    "mission_on_real_ros",
    "recorded_topics",
    "run_tool",
    "start_ros_tool",
    "stop_ros_tool",
]

#: How long the master, the recorder and the mission node may take to come up, in s.
STARTUP_S = 30.0


def recorded_topics(veh: str) -> List[str]:
    """The topics the mission's bag records: poses (odometry, truth), states and LEDs."""
    return [
        f"/{veh}/odometry_node/pose",
        f"/{veh}/simulator_node/ground_truth_pose",
        f"/{veh}/mission_node/state",
        f"/{veh}/led_emitter_node/led_pattern",
    ]


def free_port() -> int:
    """A TCP port nobody listens on, for the ROS master."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def start_ros_tool(command: Sequence[str], env: Dict[str, str], log: Path) -> subprocess.Popen:
    """Start a ROS tool in its own process group, its output into the file ``log``."""
    with Path(log).open("w") as output:
        return subprocess.Popen(
            list(command), env=env, stdout=output, stderr=subprocess.STDOUT, start_new_session=True
        )


def stop_ros_tool(process: subprocess.Popen, timeout: float = 20.0) -> None:
    """End a process as Ctrl-C does (then harder if it does not listen)."""
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGINT)
        try:
            process.wait(timeout)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()


def run_tool(command: Sequence[str], env: Dict[str, str]) -> None:
    """Run a ROS command-line tool as in a terminal; print what it prints."""
    print("$ " + " ".join(command))
    done = subprocess.run(
        list(command), env=env, capture_output=True, text=True, timeout=30, check=False
    )
    print((done.stdout + done.stderr).strip())


def _show_ros_tools(env: Dict[str, str], veh: str) -> None:
    """What rostopic and rosservice show while the mission drives."""
    run_tool(["rostopic", "list"], env)
    run_tool(["rostopic", "echo", "-n", "1", f"/{veh}/mission_node/state"], env)
    run_tool(["rostopic", "echo", "-n", "1", f"/{veh}/odometry_node/pose"], env)
    run_tool(["rosservice", "list"], env)


def _ros_env(prepared: Any, folder: Path, port: int, veh: str) -> Dict[str, str]:
    """The environment of every ROS tool: the master, the deployed packages, the solution."""
    return dict(
        os.environ,
        ROS_MASTER_URI=f"http://127.0.0.1:{port}",
        ROS_IP="127.0.0.1",
        ROS_HOME=str(folder / "ros"),
        ROS_PACKAGE_PATH=str(prepared.deploy.parent / "packages"),
        PYTHONPATH=os.pathsep.join([str(prepared.deploy), str(prepared.deploy / "msgs")]),
        DUCKIE_SOLUTION=str(prepared.solution),
        PATH=os.pathsep.join([str(Path(sys.executable).parent), os.environ["PATH"]]),
        VEHICLE_NAME=veh,
        PYTHONUNBUFFERED="1",
    )


def _wait_for(ready: Any, what: str, timeout: float = STARTUP_S) -> None:
    """Wait until ``ready()`` is true, or raise RuntimeError saying ``what`` did not happen."""
    deadline = time.monotonic() + timeout
    while not ready():
        if time.monotonic() > deadline:
            raise RuntimeError(f"{what} in {timeout:.0f} s")
        time.sleep(0.2)


def _master_up(master: Any) -> bool:
    try:
        master.getPid("/notebook")
    except OSError:
        return False
    return True


def mission_on_real_ros(
    prepared: Any,
    folder: Path,
    bag: Path,
    veh: str = "duckiebot",
    rate: float = 4.0,
    timeout: float = 120.0,
) -> str:
    """The mission through roslaunch on a real roscore, recorded by rosbag record.

    Args:
        prepared: the robot project prepared for the student's solution
            (:func:`duckielib.tools.deploy.prepare`).
        folder: a folder for the tools' logs and ``ROS_HOME``.
        bag: where ``rosbag record`` writes the bag.
        veh: the virtual robot's name on the master.
        rate: how fast the simulated clock runs, simulated s per wall-clock s.
        timeout: the longest the mission may take, wall-clock s.

    Returns:
        The roslaunch log's text.

    Raises:
        RuntimeError: if roscore or rosbag record did not start in time.
    """
    port = free_port()
    env = _ros_env(prepared, folder, port, veh)
    master: Any = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
    recorded = recorded_topics(veh)
    processes = [start_ros_tool(["roscore", "-p", str(port)], env, folder / "roscore.log")]
    try:
        _wait_for(lambda: _master_up(master), "roscore did not start")
        # The recorder must follow the simulated clock too: set it before it starts.
        master.setParam("/notebook", "/use_sim_time", True)
        recorder = start_ros_tool(
            ["rosbag", "record", "-O", str(bag), *recorded], env, folder / "rosbag.log"
        )
        processes.append(recorder)

        def subscribed(topic: str) -> bool:
            _, _, (_, subscribers, _) = master.getSystemState("/notebook")
            return any(name == topic and nodes for name, nodes in subscribers)

        _wait_for(
            lambda: all(subscribed(topic) for topic in recorded),
            "rosbag record did not subscribe",
        )
        command = ["roslaunch", "course_nodes", "simulation.launch", f"veh:={veh}"]
        command += [f"rate:={rate}", "camera:=false"]
        launch = start_ros_tool(command, env, folder / "roslaunch.log")
        processes.append(launch)
        # Once the mission node is up, what the ROS tools show while it drives.
        deadline = time.monotonic() + STARTUP_S
        while launch.poll() is None and time.monotonic() < deadline:
            _, _, published = master.getPublishedTopics("/notebook", "")
            if any(name == f"/{veh}/mission_node/state" for name, _ in published):
                break
            time.sleep(0.5)
        _show_ros_tools(env, veh)
        try:
            launch.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            print(f"The mission did not end in {timeout:.0f} s: stopping it.")
        stop_ros_tool(launch)
        stop_ros_tool(recorder)  # rosbag record closes the bag on Ctrl-C
        deadline = time.monotonic() + 20
        while not bag.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
    finally:
        for process in reversed(processes):
            stop_ros_tool(process)
    return (folder / "roslaunch.log").read_text(errors="replace")
