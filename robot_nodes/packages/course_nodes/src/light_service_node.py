#!/usr/bin/env python3
"""The light service node: your notebook 08 node, which sets the robot's LEDs on request.

A ROS service is a question with an answer: a node offers it under a name, another node calls
it and waits for the reply. Your ``light_service_node`` offers ``~set_color`` and, for each
request, asks the robot's LED emitter (``led_emitter_node/set_pattern``) to show that colour.
The mission node calls it at each change of state.

``roslaunch`` starts it (see ``launch/course.launch``); the code is
``duckielib.nodes.mains.light_service_main``, and your solution is the file ``DUCKIE_SOLUTION``
names.
"""

from duckielib.nodes.mains import light_service_main

if __name__ == "__main__":
    light_service_main()
