"""The laptop's tools: the ``duckie`` command and what it runs.

- :mod:`~duckielib.tools.cli`: the ``duckie`` command (instructors' commands come from the
  ``duckie.commands`` entry points that other packages register);
- :mod:`~duckielib.tools.runner`: a mission on the simulator, from a solution to a bag;
- :mod:`~duckielib.tools.handin`: a student's checks before handing in;
- :mod:`~duckielib.tools.deploy`: the robot project's image, with the robot's modules;
- :mod:`~duckielib.tools.real_ros`: the mission on a real ROS master (roscore, roslaunch,
  rosbag record);
- :mod:`~duckielib.tools.bench`: the benchmarks ``duckie bench`` runs.

Laptop only: these import the simulator, rosbags and matplotlib.
"""
