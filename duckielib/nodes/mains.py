"""The course's nodes on a real ROS master: what ``robot_nodes``' executables run.

On a Duckiebot (and on a laptop with Debian's ROS 1 and the virtual Duckiebot), each node is
its own process, started by ``roslaunch`` in the robot's namespace. The functions here are
those processes' mains. Each takes the real rospy, loads the solution named by the
``DUCKIE_SOLUTION`` environment variable (the robot's image sets it to the student's exported
``solution.py``), and runs the very node code the notebooks run on the in-process graph:

- :func:`odometry_main`: the library's odometry node, driven by the student's functions;
- :func:`light_service_main`: the student's light service node (notebook 08);
- :func:`mission_main`: the student's mission node (notebook 09), inside a
  :class:`~duckielib.nodes.safety.SafetyGuard` that stops the wheels however the mission ends;
- :func:`camera_republisher_main`: the camera's images, republished for the laptop.

A problem with the solution (missing, unfinished) ends the node at once with one sentence on
stderr and exit status 1, before the robot moves; so does the first failure of the solution's
odometry functions (an error, or a NaN) while the robot drives.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any, Iterable, List, Optional

from duckielib.errors import DuckielibError
from duckielib.missions import MISSIONS, mission_named

__all__ = [
    "SOLUTION_ENV",
    "camera_republisher_main",
    "light_service_main",
    "mission_main",
    "odometry_main",
]

#: The environment variable that names the solution the nodes run (a ``.py`` file or a folder
#: of notebooks).
SOLUTION_ENV = "DUCKIE_SOLUTION"


def _fail(node: str, text: str) -> None:
    sys.stderr.write(f"{node}: {text}\n")
    sys.exit(1)


def _real_rospy(node: str) -> Any:
    """Import the real rospy (Debian's on a laptop, Noetic's on the robot).

    Under ``duckie run``, which runs the project's nodes on the virtual Duckiebot, the node's
    code runs on the in-process graph, whose rospy it takes, as every other node there does.
    """
    from duckielib.ros.backend import is_in_process, use_debian_ros
    from duckielib.ros.context import calling_actor
    from duckielib.ros.modules import provided_elsewhere

    installed = sys.modules.get("rospy")
    if calling_actor() is not None and installed is not None and is_in_process(installed):
        return installed
    use_debian_ros()
    if "rospy" not in sys.modules and not provided_elsewhere("rospy"):
        _fail(node, "rospy is not installed here; on a laptop, install ROS 1 with `make ros`.")
    import rospy

    if is_in_process(rospy):
        _fail(node, "this node needs a real ROS master; in a notebook, use VirtualDuckiebot.")
    return rospy


def _solution(node: str, parts: Iterable[str]) -> Any:
    """The solution named by ``DUCKIE_SOLUTION``, with ``parts`` checked."""
    from duckielib.solution import load_solution

    path = os.environ.get(SOLUTION_ENV)
    if not path:
        _fail(
            node,
            f"set {SOLUTION_ENV} to your exported solution.py (`duckie robot prepare` writes it).",
        )
    try:
        return load_solution(path, required=list(parts))
    except DuckielibError as error:
        _fail(node, str(error))
    return None  # not reached: _fail exits


def _arguments(rospy: Any, argv: Optional[List[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description="The course's mission node.")
    parser.add_argument("--mission", default="square_then_circle", choices=sorted(MISSIONS))
    parser.add_argument("--stop-color", default=None)
    args = rospy.myargv(argv=sys.argv if argv is None else argv)[1:]
    return parser.parse_args(args)


def odometry_main(argv: Optional[List[str]] = None) -> None:
    """Dead reckoning with the student's functions: ticks in, ``~pose`` out (until shutdown)."""
    from duckielib.nodes import odometry_node
    from duckielib.solution import ODOMETRY_PARTS

    rospy = _real_rospy("odometry_node")
    solution = _solution("odometry_node", ODOMETRY_PARTS)
    mission = mission_named(_arguments(rospy, argv).mission)
    try:
        odometry_node(rospy, solution, mission.start)
    except DuckielibError as error:  # the solution's odometry failed: the node stopped
        _fail("odometry_node", str(error))


def light_service_main() -> None:
    """The student's light service node: ``~set_color`` until a message on ``shutdown``."""
    _real_rospy("light_service_node")  # the solution imports it by name
    solution = _solution("light_service_node", ["light_service_node"])
    solution.light_service_node()


def mission_main(argv: Optional[List[str]] = None) -> None:
    """The student's mission node, with the wheels guarded (``--mission``, ``--stop-color``).

    Exit status 0 when the mission announced its end, 1 when it failed.
    """
    from duckielib.nodes.safety import SafetyGuard, guarded_init
    from duckielib.solution import MISSION_PARTS

    rospy = _real_rospy("mission_node")
    arguments = _arguments(rospy, argv)
    solution = _solution("mission_node", MISSION_PARTS)
    mission = mission_named(arguments.mission)
    if arguments.stop_color:
        mission = mission.with_stop_color(arguments.stop_color)
    guards: List[SafetyGuard] = []
    warm: List[Any] = []

    def on_init() -> None:
        guards.append(SafetyGuard(rospy))
        warm.append(_connect_listeners(rospy, "~state"))
        _wait_for_clock(rospy)

    restore = guarded_init(rospy, on_init)
    try:
        solution.mission_node(mission)
    except rospy.ROSInterruptException:
        pass  # shut down (Ctrl-C, roslaunch ending): the guard's shutdown hook stopped the wheels
    except Exception as error:
        for guard in guards:
            guard.stop(f"the mission raised {type(error).__name__}: {error}")
        _fail("mission_node", f"the mission stopped with {type(error).__name__}: {error}")
    finally:
        restore()
    for guard in guards:
        if guard.callback_error is None:
            guard.stop("the mission finished")
        guard.close()  # after a callback's exception, the guard has stopped the wheels
        if guard.callback_error is not None:
            _fail("mission_node", f"a callback raised {guard.callback_error}")


def _wait_for_clock(rospy: Any) -> None:
    """On simulated time, wait for the simulator's first ``/clock`` before the mission starts.

    Until then ROS time reads 0 and does not move: a mission that began then would time its
    first stop from a clock that is not running yet. On a robot (wall-clock time) this returns
    at once.
    """
    import time

    while rospy.get_rostime().is_zero() and not rospy.is_shutdown():
        time.sleep(0.01)


def _connect_listeners(rospy: Any, topic: str, timeout: float = 3.0) -> Any:
    """Connect ``topic``'s publisher to its subscribers before the node's own code publishes.

    A message published before a subscriber's connection is up reaches it late (latched) or
    never. The mission's first state announcement matters (a recorder times the first stop
    from it), so the publisher is created here, right after ``init_node``, and given up to
    ``timeout`` seconds (wall clock) to connect to every subscriber the master knows; the
    node's own publisher on the same topic then shares the connections, as rospy does.

    Returns:
        The publisher (keep it: the connections live as long as a publisher does).
    """
    import time

    from std_msgs.msg import String

    from duckielib.ros.backend import is_in_process

    publisher = rospy.Publisher(topic, String, queue_size=10)
    if is_in_process(rospy):
        return publisher  # on the in-process graph (duckie run), subscribers connect at once
    import rosgraph

    name = publisher.resolved_name
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not rospy.is_shutdown():
        try:
            _, subscribed, _ = rosgraph.Master(rospy.get_name()).getSystemState()
        except Exception:  # the master is busy or gone: nothing to wait for
            return publisher
        wanted = sum(len(nodes) for found, nodes in subscribed if found == name)
        if publisher.get_num_connections() >= wanted:
            break
        time.sleep(0.05)
    return publisher


def camera_republisher_main() -> None:
    """Republish the camera's JPEG frames on ``~image/compressed`` (for the laptop)."""
    from duckielib.nodes import camera_republisher_node

    rospy = _real_rospy("camera_republisher_node")
    camera_republisher_node(rospy)
