"""ROS 1 in the notebook: rospy's API on an in-process graph that runs on simulated time.

A node written for a real Duckiebot runs here unchanged::

    from duckielib.ros import Graph, rospy

    graph = Graph()
    graph.launch(talker)     # talker() calls rospy.init_node(...) like any rospy node
    graph.launch(listener)
    graph.run(5.0)           # five simulated seconds, in a fraction of a real one

See :mod:`duckielib.ros.rospy` for the API and :mod:`duckielib.ros.graph` for how the graph
schedules nodes deterministically. The layers, each importing only those below it:

- :mod:`~duckielib.ros.names`, :mod:`~duckielib.ros.exceptions`, :mod:`~duckielib.ros.log`:
  ROS names, rospy's exceptions, log levels and lines;
- :mod:`~duckielib.ros.context`: which node is calling, per thread;
  :mod:`~duckielib.ros.params`: the parameter server;
- :mod:`~duckielib.ros.node`: a node and the topic and service records (it knows its graph
  only through the few things it asks of it);
- :mod:`~duckielib.ros.graph`: the master, its clock and scheduler;
- :mod:`~duckielib.ros.rospy` and :mod:`~duckielib.ros.introspect`: rospy's API and the
  ``rostopic``-like tools on top; :mod:`~duckielib.ros.rosgraph`: what ``rqt_graph`` shows,
  now or over the whole run.
"""

from __future__ import annotations

from duckielib.ros import rospy
from duckielib.ros.graph import Graph, NodeCrashed, default_graph
from duckielib.ros.introspect import rosmsg, rosnode, rosparam, rosservice, rossrv, rostopic
from duckielib.ros.log import LogRecord
from duckielib.ros.modules import install_modules, node_script, uninstall_modules
from duckielib.ros.rosgraph import GraphSnapshot, ros_graph

__all__ = [
    "Graph",
    "GraphSnapshot",
    "LogRecord",
    "NodeCrashed",
    "default_graph",
    "install_modules",
    "node_script",
    "rosmsg",
    "rosnode",
    "ros_graph",
    "rosparam",
    "rospy",
    "rosservice",
    "rossrv",
    "rostopic",
    "uninstall_modules",
]
