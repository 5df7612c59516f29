"""The virtual Duckiebot as a real ROS node, for running the course's nodes on a real roscore.

In a notebook the virtual Duckiebot lives on duckielib's in-process graph. Before a student
takes their nodes to a robot, they can run them exactly as on the robot, as separate
processes on a real ROS master, against this node: the same simulator and the same driver
code (:mod:`duckielib.sim.drivers`), here given the real rospy and genpy's message classes,
so ``rostopic echo``, ``rosservice call`` and ``rosbag record`` work on every topic.

The node owns the clock: it publishes ``/clock`` as the simulation advances (100 steps per
simulated second), and the other nodes run with ``use_sim_time`` (the launch file sets it).
``~rate`` is how fast simulated time runs against the wall clock (1.0: real time), at most:
when the machine is too busy to keep up, simulated time runs slower (as Gazebo's real-time
factor drops) rather than catching up in a burst, in which a node that answers a few
milliseconds late would see whole simulated seconds go by.

Private parameters: ``~noise`` (``ideal`` or ``realistic``), ``~seed``, ``~rate``, ``~mission``
(the start pose is that mission's), ``~mute_encoders_after`` (simulated seconds after which
the encoders stop publishing, to test what nodes do when a driver dies; default: never),
``~paused`` (true: the clock stays at 0 until a ``std_msgs/Empty`` arrives on ``~start``, as
Gazebo starts paused, so a ``rosbag record`` started alongside has connected to every node
before anything happens; default: false).

Laptop only: it needs the simulator (pymunk).
"""

from __future__ import annotations

import os
import threading
import time
from typing import Any, Callable, Dict, Optional

from duckielib.missions import mission_named
from duckielib.rostime import NS_PER_S
from duckielib.sim import drivers
from duckielib.sim.simulator import Simulator

__all__ = ["PHYSICS_STEP_S", "Pace", "VirtualDuckiebotNode", "main"]

#: Simulated seconds between two ``/clock`` messages (and physics updates).
PHYSICS_STEP_S = 0.01
_RATE_HZ = 30.0  # ground truth and camera
_MAX_LAG_S = 0.02  # wall seconds the clock may fall behind ~rate and still catch up


class _Locked:
    """The simulator, with every method call made under one lock.

    The drivers' callbacks run in rospy's threads while the main loop advances the physics.
    """

    def __init__(self, sim: Simulator, lock: threading.RLock) -> None:
        self._sim = sim
        self._lock = lock

    def __getattr__(self, name: str) -> Any:
        value = getattr(self._sim, name)
        if not callable(value):
            return value
        lock = self._lock

        def call(*args: Any, **kwargs: Any) -> Any:
            with lock:
                return value(*args, **kwargs)

        return call


class Pace:
    """Keeps simulated time at ``rate`` times the wall clock, or slower, never in bursts.

    When a step took longer than its share of wall time, the clock may catch up by at most
    ``max_lag`` wall seconds; beyond that, simulated time simply runs slower.

    Args:
        rate: simulated seconds per wall-clock second.
        max_lag: wall seconds the clock may fall behind and still catch up.
        clock: the wall clock, in seconds (``time.monotonic``).
        sleep: how to wait, in wall seconds (``time.sleep``).
        start: the simulated time now, in seconds.
    """

    def __init__(
        self,
        rate: float,
        max_lag: float = _MAX_LAG_S,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
        start: float = 0.0,
    ) -> None:
        self.rate = rate
        self.max_lag = max_lag
        self._clock = clock
        self._sleep = sleep
        self._origin = clock() - start / rate  # the wall time at which simulated time was 0

    def wait(self, t: float) -> None:
        """Wait until simulated time ``t`` (seconds) is due on the wall clock."""
        delay = self._origin + t / self.rate - self._clock()
        if delay > 0:
            self._sleep(delay)
        elif delay < -self.max_lag:
            self._origin -= delay + self.max_lag


class VirtualDuckiebotNode:
    """The simulator's drivers on a real ROS master, and the loop that advances them.

    Args:
        rospy: the real rospy, after ``init_node``.
        sim: the simulator.
        namespace: the robot's namespace, ``/VEH/``.
        rate: simulated seconds per wall-clock second.
        mute_encoders_after: stop publishing encoder ticks from this simulated time on.
        paused: keep the clock at 0 until a message arrives on ``~start``.
    """

    def __init__(
        self,
        rospy: Any,
        sim: Simulator,
        namespace: str,
        rate: float = 1.0,
        mute_encoders_after: Optional[float] = None,
        paused: bool = False,
    ) -> None:
        from rosgraph_msgs.msg import Clock
        from std_msgs.msg import Empty

        self.rospy = rospy
        self.sim = sim
        self.rate = rate
        self.mute_encoders_after = mute_encoders_after
        self._lock = threading.RLock()
        locked: Any = _Locked(sim, self._lock)
        veh = namespace
        self.drivers: Dict[str, Any] = {
            "wheels_driver_node": drivers.WheelsDriverNode(rospy, locked, veh),
            "left_wheel_encoder_node": drivers.WheelEncoderNode(rospy, locked, veh, "left"),
            "right_wheel_encoder_node": drivers.WheelEncoderNode(rospy, locked, veh, "right"),
            "kinematics_node": drivers.KinematicsNode(
                rospy, veh, sim.config, sim.noise.kinematics_gain
            ),
            "car_cmd_switch_node": drivers.CarCmdSwitchNode(rospy, veh),
            "led_emitter_node": drivers.LEDEmitterNode(rospy, locked, veh),
            "led_driver_node": drivers.LEDDriverNode(rospy, locked, veh),
            "camera_node": drivers.CameraNode(rospy, locked, veh),
            "simulator_node": drivers.GroundTruthNode(rospy, locked, veh),
        }
        self._clock = Clock
        self._clock_publisher = rospy.Publisher("/clock", Clock, queue_size=10)
        self._started = threading.Event()
        if not paused:
            self._started.set()
        self._start_subscriber = rospy.Subscriber(
            "~start", Empty, lambda _: self._started.set(), queue_size=1
        )

    def _publish_clock(self, t_ns: int) -> None:
        stamp = self.rospy.Time(t_ns // NS_PER_S, t_ns % NS_PER_S)
        self._clock_publisher.publish(self._clock(clock=stamp))

    def spin(self, until: Optional[Callable[[], bool]] = None) -> None:
        """Advance the simulation, publishing as the robot does, until rospy shuts down."""
        step_ns = round(PHYSICS_STEP_S * NS_PER_S)
        period_ns = round(NS_PER_S / _RATE_HZ)
        t_ns, next_frame_ns = 0, 0  # the first /clock is one step in: ROS reads 0 as "no time"
        if not self._started.is_set():
            self.rospy.loginfo(
                f"Paused: the clock starts when a std_msgs/Empty arrives on "
                f"{self._start_subscriber.name}."
            )
        while not self._started.wait(0.1):
            if self.rospy.is_shutdown() or (until is not None and until()):
                return
        pace = Pace(self.rate)
        while not self.rospy.is_shutdown() and not (until is not None and until()):
            t_ns += step_ns
            with self._lock:
                self.sim.run_until(t_ns / NS_PER_S)
                readings = self.sim.pop_encoder_readings()
            self._publish_clock(t_ns)
            muted = (
                self.mute_encoders_after is not None and t_ns >= self.mute_encoders_after * NS_PER_S
            )
            for reading in [] if muted else readings:
                self.drivers[f"{reading.wheel}_wheel_encoder_node"].publish(reading)
            if t_ns >= next_frame_ns:
                self.drivers["simulator_node"].publish(t_ns)
                self.drivers["camera_node"].publish(t_ns)
                next_frame_ns += period_ns
            pace.wait(t_ns / NS_PER_S)


def main() -> None:
    """``virtual_duckiebot_node.py``: start the virtual Duckiebot in the launch file's namespace."""
    import sys

    from duckielib.errors import DuckielibError
    from duckielib.ros.backend import use_debian_ros

    use_debian_ros()
    import rospy

    rospy.init_node("virtual_duckiebot")
    namespace = rospy.get_namespace()
    os.environ.setdefault("VEHICLE_NAME", namespace.strip("/") or "duckiebot")
    try:
        mission = mission_named(str(rospy.get_param("~mission", "square_then_circle")))
        sim = Simulator(
            seed=int(rospy.get_param("~seed", 0)),
            noise=str(rospy.get_param("~noise", "ideal")),
            start_pose=mission.start,
        )
        rate = float(rospy.get_param("~rate", 1.0))
        if not rate > 0:
            raise DuckielibError(f"~rate must be more than 0, not {rate}.")
    except DuckielibError as error:
        sys.stderr.write(f"virtual_duckiebot: {error}\n")
        sys.exit(1)
    mute = rospy.get_param("~mute_encoders_after", None)
    node = VirtualDuckiebotNode(
        rospy,
        sim,
        namespace,
        rate,
        None if mute in (None, "") else float(mute),
        paused=str(rospy.get_param("~paused", False)).lower() == "true",
    )
    rospy.loginfo(f"Virtual Duckiebot {namespace} running at {rate:g}x real time.")
    node.spin()
