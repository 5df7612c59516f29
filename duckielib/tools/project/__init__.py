"""A Duckietown project on the virtual Duckiebot, as ``dts devel run`` runs it on the robot.

A project in Duckietown's template layout holds catkin packages under ``packages/`` (each with
its ``package.xml``, node scripts, ``launch/`` files, its own ``msg/`` and ``srv/``, Python
packages under ``include/``) and ``launchers/*.sh``, the scripts ``dts devel run`` starts
(``default.sh`` unless another is named). :func:`run_project` reads what the launcher runs
(its ``roslaunch``, ``rosrun`` and ``python3`` lines), the launch files they name (arguments,
groups, nodes, parameters, ``rosparam``, remappings, includes and the ``$(...)``
substitutions), and starts every node, unchanged, on a :class:`~duckielib.sim.VirtualDuckiebot`
named ``VEHICLE_NAME``, its packages resolved as a catkin workspace resolves them
(:class:`Workspace`) from whatever folder the command runs in.

It is split as the work is: :mod:`.workspace` (the packages and their imports),
:mod:`.launch` (launchers and launch files read into nodes) and :mod:`.run` (the run).

Laptop side; never deployed.
"""

from __future__ import annotations

from duckielib.tools.project.launch import Launched, NodeSpec, launched_nodes
from duckielib.tools.project.run import ProjectRun, run_project
from duckielib.tools.project.workspace import Package, ProjectError, Workspace

__all__ = [
    "Launched",
    "NodeSpec",
    "Package",
    "ProjectError",
    "ProjectRun",
    "Workspace",
    "launched_nodes",
    "run_project",
]
