#!/usr/bin/env python3
"""The virtual Duckiebot on a real ROS master: laptop only, never on the robot.

It runs the course's simulator and the robot's driver nodes (wheels, encoders, LEDs, camera)
under ``/ROBOT/``, with the same topics, services and parameters as a real Duckiebot, and
publishes the simulated time on ``/clock`` (the launch file sets ``/use_sim_time``). The
course's nodes then run against it exactly as they do on the robot.

It needs the laptop's Python environment (the simulator uses pymunk), which the robot's image
does not have. Private parameters (set by ``launch/virtual_duckiebot.launch``): ``~noise``
(``ideal`` or ``realistic``), ``~seed``, ``~rate`` (the real-time factor) and ``~mission``
(where the robot starts).

The code is ``duckielib.sim.ros_node.main``.
"""

from duckielib.sim.ros_node import main

if __name__ == "__main__":
    main()
