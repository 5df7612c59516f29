"""Fixtures for tests against Debian's ROS 1 packages (marked ``ros``)."""

from __future__ import annotations

import importlib
import os
import shutil
import subprocess
import sys
import time
import xmlrpc.client
from pathlib import Path
from typing import Dict, Iterator, List

import pytest

from duckielib.ros.modules import _is_ours as is_ours
from duckielib.solution import export_solution, reference_solution_dir
from duckielib.tools.real_ros import free_port, stop_ros_tool

#: Where Debian installs rospy, genpy, rosbag and the message packages.
DEBIAN_DIST_PACKAGES = "/usr/lib/python3/dist-packages"
ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ROOT / "robot_nodes" / "packages"
#: The robot's namespace in these tests.
VEH = "/duckiebot/"
#: How fast the virtual Duckiebot runs against the wall clock in these tests.
RATE = 2.0
#: The node name of the tests' ``rosbag record`` (which adds a suffix of its own).
RECORDER = "test_recorder"


def _from_debian(module: object) -> bool:
    return (getattr(module, "__file__", None) or "").startswith(DEBIAN_DIST_PACKAGES)


@pytest.fixture(scope="module")
def ros_import():
    """Import a module of Debian's ROS 1 packages, or skip saying how to install them.

    The folder is appended at the end of ``sys.path`` so the project's own packages keep
    priority, as the ROS backend does. While the module's tests run, the course's own modules
    of the same names (``rospy``, ``std_msgs.msg``... which an earlier test in this process may
    have installed) step aside, so the name finds Debian's; a test that gets anything else fails
    saying so. Afterwards the path and every module loaded from it are removed again and the
    course's modules come back, so other tests never meet the real rospy by accident.
    """
    added = DEBIAN_DIST_PACKAGES not in sys.path
    if added:
        sys.path.append(DEBIAN_DIST_PACKAGES)
    aside = {  # the course's modules under ROS's names
        name: module
        for name, module in sys.modules.items()
        if name.partition(".")[0] != "duckielib" and is_ours(module)
    }
    for name in aside:
        del sys.modules[name]
    before = set(sys.modules)

    def load(name: str):
        try:
            module = importlib.import_module(name)
        except ImportError as error:
            pytest.skip(f"Debian's ROS 1 packages are not installed ({error}); run `make ros`.")
        if not _from_debian(module):
            pytest.fail(f"{name} came from {getattr(module, '__file__', None)}, not Debian's ROS.")
        return module

    yield load
    for name in set(sys.modules) - before:
        if _from_debian(sys.modules[name]):
            del sys.modules[name]
    sys.modules.update(aside)
    if added:
        sys.path.remove(DEBIAN_DIST_PACKAGES)


class Master:
    """A roscore on loopback and the environment the course's nodes need to use it."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.uri = f"http://127.0.0.1:{free_port()}"
        # In a process of its own: this one keeps Debian's packages off its path.
        messages = folder / "msgs"
        subprocess.run(
            [
                sys.executable,
                "-c",
                "import sys; from duckielib.ros.backend import generate_message_packages as make;"
                " make(sys.argv[1])",
                str(messages),
            ],
            check=True,
        )
        self.solution = folder / "solution.py"
        self.solution.write_text(export_solution(reference_solution_dir()).source)
        self.env: Dict[str, str] = dict(
            os.environ,
            ROS_MASTER_URI=self.uri,
            ROS_IP="127.0.0.1",
            ROS_HOME=str(folder / "ros"),
            ROS_LOG_DIR=str(folder / "ros" / "log"),
            ROS_PACKAGE_PATH=str(PACKAGES),
            PYTHONPATH=os.pathsep.join([str(ROOT), str(messages)]),
            PATH=os.pathsep.join([str(Path(sys.executable).parent), os.environ["PATH"]]),
            DUCKIE_SOLUTION=str(self.solution),
            VEHICLE_NAME=VEH.strip("/"),
            PYTHONUNBUFFERED="1",
        )
        port = self.uri.rsplit(":", 1)[1]
        self.core = self.start(["roscore", "-p", port], "roscore")
        self.api = xmlrpc.client.ServerProxy(self.uri)
        deadline = time.monotonic() + 30
        while True:
            try:
                self.api.getPid("/test")
                break
            except OSError:
                if time.monotonic() > deadline:
                    pytest.fail(f"roscore did not start; see {folder / 'roscore.log'}")
                time.sleep(0.2)
        # Record times are simulated times, as the nodes' own.
        self.api.setParam("/test", "/use_sim_time", True)

    def start(self, command: List[str], log: str) -> subprocess.Popen:
        out = (self.folder / f"{log}.log").open("w")
        return subprocess.Popen(
            command, env=self.env, stdout=out, stderr=subprocess.STDOUT, start_new_session=True
        )

    def subscribed(self, topic: str) -> bool:
        _, _, (_, subscribers, _) = self.api.getSystemState("/test")
        return any(name == topic and nodes for name, nodes in subscribers)

    def record(self, bag: Path, topics: List[str]) -> subprocess.Popen:
        """Start ``rosbag record`` of ``topics`` into ``bag``; return once it listens."""
        recorder = self.start(
            ["rosbag", "record", "-O", str(bag), *topics, f"__name:={RECORDER}"], bag.stem
        )
        deadline = time.monotonic() + 20
        while not all(self.subscribed(topic) for topic in topics):
            assert time.monotonic() < deadline, "rosbag record did not subscribe in 20 s"
            time.sleep(0.2)
        return recorder

    def connected(self, topic: str, subscriber: str = RECORDER) -> bool:
        """Whether ``topic`` has publishers and ``subscriber`` is connected to each of them.

        ``subscriber`` is the node's name as given with ``__name:=`` (rosbag and rostopic
        add a suffix to it).
        """
        _, _, (publishers, _, _) = self.api.getSystemState("/test")
        nodes = next((nodes for name, nodes in publishers if name == topic), [])
        for node in nodes:
            _, _, uri = self.api.lookupNode("/test", node)
            _, _, connections = xmlrpc.client.ServerProxy(uri).getBusInfo("/test")
            # Each: (id, the other end's node, direction, transport, topic, connected, ...)
            if not any(
                c[1].startswith(f"/{subscriber}") and c[2] == "o" and c[4] == topic
                for c in connections
            ):
                return False
        return bool(nodes)

    def start_clock(self, recorded: List[str], timeout: float = 60) -> None:
        """Start a paused virtual Duckiebot once the recorder hears every publisher of
        ``recorded`` and the clock, so the bag misses nothing of the first seconds.

        The recorder stamps each message with its own reading of ``/clock``: connected late
        to the clock, it would stamp the first second's messages with a later time. With no
        topics to record, there is no recorder to wait for.
        """
        deadline = time.monotonic() + timeout
        awaited = [*recorded, "/clock"] if recorded else []
        while not all(self.connected(topic) for topic in awaited):
            assert time.monotonic() < deadline, f"the recorder missed a topic of {recorded}"
            time.sleep(0.2)
        subprocess.run(
            ["rostopic", "pub", "--once", VEH + "virtual_duckiebot/start", "std_msgs/Empty"],
            env=self.env,
            check=True,
            capture_output=True,
            timeout=60,
        )

    rate = RATE
    stop = staticmethod(stop_ros_tool)

    @staticmethod
    def wait_for_bag(bag: Path, timeout: float = 20) -> Path:
        """Wait until a recorder has closed ``bag`` (rosbag renames NAME.bag.active to NAME.bag)."""
        deadline = time.monotonic() + timeout
        while not bag.exists() or bag.with_name(bag.name + ".active").exists():
            assert time.monotonic() < deadline, f"no closed bag {bag.name} after {timeout:g} s"
            time.sleep(0.1)
        return bag

    def log(self, name: str) -> str:
        return (self.folder / f"{name}.log").read_text(errors="replace")


@pytest.fixture(scope="module")
def master(tmp_path_factory) -> Iterator[Master]:
    missing = [tool for tool in ("roscore", "roslaunch", "rosbag") if shutil.which(tool) is None]
    if missing:
        pytest.skip(f"Debian's ROS 1 is not installed ({', '.join(missing)}); run `make ros`.")
    running = Master(tmp_path_factory.mktemp("ros"))
    yield running
    running.stop(running.core)
