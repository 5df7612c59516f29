#!/usr/bin/env python3
"""The mission node: your notebook 09 node, which drives the mission state by state.

It reads the pose from the odometry node, sends speed commands to the robot
(``car_cmd_switch_node/cmd``) and calls the light service at each state. A safety guard stops
the wheels however the node ends (finished, Ctrl-C, an error in your code, silent encoders).
The launch file marks it ``required``: when the mission ends, every node of the launch ends.

Private parameters (set by ``launch/course.launch``): ``~mission`` (``square_then_circle``,
``d_shape``, ``straight`` or ``rotation``) and ``~stop_color`` (the LED colour of the stops,
``RED`` by default); the launch file also passes them as ``--mission`` and ``--stop-color``.

``roslaunch`` starts it; the code is ``duckielib.nodes.mains.mission_main``, and your solution is
the file ``DUCKIE_SOLUTION`` names.
"""

from duckielib.nodes.mains import mission_main

if __name__ == "__main__":
    mission_main()
