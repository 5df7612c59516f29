"""The virtual Duckiebot: the simulator, its driver nodes and a ROS graph, in one line.

In a notebook::

    from duckielib.sim import VirtualDuckiebot

    bot = VirtualDuckiebot()          # world, robot, graph and drivers, all running
    bot.launch(my_node)               # run a node written with rospy, in /duckiebot/
    bot.run(5.0)                      # five simulated seconds
    bot.sim.pose                      # where the robot really is

The robot lives under ``/VEH/`` (VEH is ``$VEHICLE_NAME``, or ``duckiebot``) with exactly the
topics, services and parameters of a real Duckiebot (see :mod:`duckielib.sim.drivers`). The
graph's clock is the simulator's: the physics advances whenever the graph's time does, encoder
samples are published at their own times, and everything is deterministic for a seed.
"""

from __future__ import annotations

import os
from typing import Any, Callable, Dict, List, Optional, Union

from duckielib.errors import ConfigError
from duckielib.ros import names, rospy
from duckielib.ros.context import node_context
from duckielib.ros.graph import Graph
from duckielib.rostime import NS_PER_S
from duckielib.sim import drivers
from duckielib.sim.encoders import EncoderReading
from duckielib.sim.noise import NoiseProfile
from duckielib.sim.simulator import Simulator

__all__ = ["VirtualDuckiebot", "DEFAULT_NAME"]

#: The robot's name when ``VEHICLE_NAME`` is not set.
DEFAULT_NAME = "duckiebot"

#: How often the camera and the ground truth publish, in Hz.
CAMERA_RATE_HZ = 30.0
GROUND_TRUTH_RATE_HZ = 30.0


class VirtualDuckiebot:
    """A simulated Duckiebot whose drivers run as ROS nodes on an in-process graph.

    Args:
        name: the robot's name, its namespace; default ``$VEHICLE_NAME`` or ``duckiebot``. It
            is also stored in ``VEHICLE_NAME``, as on the robot, so nodes can read it there.
        seed: seed of the simulator's random choices (same seed and nodes, same run).
        noise: the simulator's noise profile, ``"ideal"``, ``"realistic"`` or a
            :class:`~duckielib.sim.NoiseProfile`.
        graph: the graph to run on (default: a new one, which becomes the default graph that
            ``rospy.init_node`` in the notebook joins).
        sim: a simulator to use instead of creating one (``seed``, ``noise`` and
            ``sim_options`` then do not apply).
        **sim_options: more :class:`~duckielib.sim.Simulator` arguments (``start_pose``, ...).

    Attributes:
        sim: the :class:`~duckielib.sim.Simulator`: ground truth, LEDs, plots.
        graph: the :class:`~duckielib.ros.Graph` the drivers and your nodes run on.
        namespace: ``/VEH/``.
        nodes: the driver objects by node name.

    Raises:
        ConfigError: if ``name`` is not a legal ROS name.
    """

    def __init__(
        self,
        name: Optional[str] = None,
        seed: int = 0,
        noise: Union[str, NoiseProfile] = "ideal",
        graph: Optional[Graph] = None,
        sim: Optional[Simulator] = None,
        **sim_options: Any,
    ) -> None:
        name = name or os.environ.get("VEHICLE_NAME") or DEFAULT_NAME
        if not names.is_legal_base_name(name):
            raise ConfigError(
                f"{name!r} cannot be a robot's name: use letters, digits and '_', "
                "starting with a letter (for example 'duckiebot')."
            )
        self.name = name
        os.environ["VEHICLE_NAME"] = name
        self.namespace = f"/{name}/"
        self.graph = Graph() if graph is None else graph
        self.sim = Simulator(seed=seed, noise=noise, **sim_options) if sim is None else sim
        # The graph's time of the simulator's time 0, in nanoseconds.
        self._offset_ns = self.graph.now_ns - round(self.sim.time * NS_PER_S)
        self._pending: List[EncoderReading] = []
        self.graph.add_clock_listener(self._advance_physics)
        self.nodes: Dict[str, Any] = {}
        self._hosts: Dict[str, Any] = {}
        self._start_drivers()

    # Setup.

    def _host(self, node_name: str, make: Callable[[], Any]) -> Any:
        node = self.graph.host_node(node_name, self.namespace)
        with node_context(node):
            driver = make()
        self.nodes[node_name] = driver
        self._hosts[node_name] = node
        return driver

    def _running(self, node_name: str) -> bool:
        return not self._hosts[node_name].is_shutdown

    def _start_drivers(self) -> None:
        sim, veh = self.sim, self.namespace
        self._host("wheels_driver_node", lambda: drivers.WheelsDriverNode(rospy, sim, veh))

        def encoder(wheel: str) -> Callable[[], drivers.WheelEncoderNode]:
            return lambda: drivers.WheelEncoderNode(rospy, sim, veh, wheel)

        encoders = {
            wheel: self._host(f"{wheel}_wheel_encoder_node", encoder(wheel))
            for wheel in ("left", "right")
        }
        self._host(
            "kinematics_node",
            lambda: drivers.KinematicsNode(rospy, veh, sim.config, sim.noise.kinematics_gain),
        )
        self._host("car_cmd_switch_node", lambda: drivers.CarCmdSwitchNode(rospy, veh))
        self._host("led_emitter_node", lambda: drivers.LEDEmitterNode(rospy, sim, veh))
        self._host("led_driver_node", lambda: drivers.LEDDriverNode(rospy, sim, veh))
        camera = self._host("camera_node", lambda: drivers.CameraNode(rospy, sim, veh))
        truth = self._host("simulator_node", lambda: drivers.GroundTruthNode(rospy, sim, veh))
        self._encoders = encoders
        self._schedule_encoders()
        self._every(CAMERA_RATE_HZ, "camera_node", camera.publish)
        self._every(GROUND_TRUTH_RATE_HZ, "simulator_node", truth.publish)

    # Time.

    def _advance_physics(self, t_ns: int) -> None:
        self.sim.run_until((t_ns - self._offset_ns) / NS_PER_S)

    def _schedule_encoders(self) -> None:
        upcoming = self.sim.next_encoder_time
        if self._pending:
            upcoming = min(upcoming, self._pending[0].time)
        # A sample is published at its own time, to the nanosecond; never twice at one time.
        t_ns = max(self._offset_ns + round(upcoming * NS_PER_S), self.graph.now_ns + 1)
        self.graph.schedule(t_ns, self._publish_encoders)

    def _publish_encoders(self) -> None:
        if self.graph.is_shutdown:
            return
        self._pending.extend(self.sim.pop_encoder_readings())
        for reading in _due_readings(self._pending, self.graph.now_ns - self._offset_ns):
            if self._running(f"{reading.wheel}_wheel_encoder_node"):
                self._encoders[reading.wheel].publish(reading)
        self._schedule_encoders()

    def _every(self, rate_hz: float, node_name: str, publish: Callable[[int], Any]) -> None:
        start = self.graph.now_ns
        count = [0]

        def fire() -> None:
            if not self._running(node_name):
                return
            publish(self.graph.now_ns - self._offset_ns)
            count[0] += 1
            self.graph.schedule(start + round(count[0] * NS_PER_S / rate_hz), fire)

        self.graph.schedule(start, fire)

    # Use.

    @property
    def driver_nodes(self) -> Dict[str, Any]:
        """The robot's own nodes (its drivers), by base name: what a real robot runs."""
        return dict(self._hosts)

    @property
    def time(self) -> float:
        """The simulated time, in seconds."""
        return self.graph.time

    def launch(
        self,
        target: Callable[..., Any],
        *args: Any,
        name: Optional[str] = None,
        namespace: Optional[str] = None,
        remap: Optional[Dict[str, str]] = None,
        params: Optional[Dict[str, Any]] = None,
        **kwargs: Any,
    ) -> None:
        """Run ``target(*args, **kwargs)``, a node's main code written with rospy, on the robot.

        As in the robot's launch file, the node runs in the robot's namespace unless another
        is given, so relative names such as ``"wheels_driver_node/wheels_cmd"`` resolve under
        ``/VEH/``. It starts when the robot next runs.
        """
        self.graph.launch(
            target,
            *args,
            name=name,
            namespace=self.namespace if namespace is None else namespace,
            remap=remap,
            params=params,
            **kwargs,
        )

    def run(self, duration: float) -> None:
        """Advance the robot, its drivers and every node by ``duration`` simulated seconds."""
        self.graph.run(duration)

    def run_until(self, condition: Callable[[], bool], timeout: float) -> bool:
        """Advance until ``condition()`` is true or ``timeout`` simulated seconds have passed.

        Returns:
            Whether the condition became true.
        """
        return self.graph.run_until(condition, timeout)

    def live(self, port: int = 8765, rate: float = 1.0) -> Any:
        """Watch the robot live in Foxglove or Lichtblick; the address to open is printed.

        The view serves every topic, the camera, each pose as a frame a 3D panel draws, and
        the simulated time (see :mod:`duckielib.sim.live`). While it is open, ``run()`` keeps
        pace with the wall clock (``rate`` 2: twice as fast). Close it with ``close()``.

        Args:
            port: the port to serve on, on this computer only (127.0.0.1).
            rate: simulated seconds per wall-clock second.

        Returns:
            The :class:`~duckielib.sim.live.LiveView`.

        Raises:
            ConfigError: if the port is taken or the rate is not above 0.
        """
        from duckielib.sim.live import LiveView

        view = LiveView(self.graph, port=port, rate=rate, name=f"virtual Duckiebot {self.name}")
        print(
            f"Live view at {view.url}: in Foxglove or Lichtblick, open a connection, choose "
            "Foxglove WebSocket and give this address."
        )
        return view

    def shutdown(self) -> None:
        """Stop every node: the wheels stop and the LEDs go off, as when the robot shuts down."""
        self.graph.shutdown("the virtual Duckiebot was shut down")

    def __repr__(self) -> str:
        x, y, theta = self.sim.pose
        return (
            f"<VirtualDuckiebot {self.name!r} at t={self.time:.3f} s: "
            f"x={x:.3f} m, y={y:.3f} m, theta={theta:.3f} rad>"
        )


def _due_readings(pending: List[EncoderReading], t_ns: int) -> List[EncoderReading]:
    """Remove and return the readings of ``pending`` (time-ordered) due at or before ``t_ns``."""
    count = 0
    while count < len(pending) and round(pending[count].time * NS_PER_S) <= t_ns:
        count += 1
    due = pending[:count]
    del pending[:count]
    return due
