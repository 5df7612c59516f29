"""In-process versions of the ROS libraries robot code imports besides rospy.

A Duckiebot's nodes import more than rospy: ``cv_bridge`` to turn camera messages into
OpenCV images, ``rosbag`` to write and read bags, ``message_filters`` to pair messages of
several topics by their stamps. The robot has the real ones; this laptop has none of them
(OpenCV itself, ``cv2``, comes from the ``opencv-python-headless`` package). The modules here
behave as the real ones on the in-process graph, so such nodes run unchanged in a notebook or
in ``duckie mission``:

- :mod:`~duckielib.libraries.cv_bridge`: ``CvBridge`` and ``CvBridgeError`` (vision_opencv).
- :mod:`~duckielib.libraries.rosbag`: ``Bag`` and its exceptions, on :mod:`duckielib.bags`.
- :mod:`~duckielib.libraries.message_filters`: ``Subscriber``, ``Cache``,
  ``TimeSynchronizer`` and ``ApproximateTimeSynchronizer`` on the in-process rospy.
- :mod:`~duckielib.libraries.tf2_ros`: ``TransformBroadcaster``,
  ``StaticTransformBroadcaster``, ``Buffer``, ``TransformListener`` and tf2's exceptions:
  coordinate frames on ``/tf`` and ``/tf_static``.
- :mod:`~duckielib.libraries.tf`: ROS 1's older ``tf`` (``TransformBroadcaster``,
  ``TransformListener``) on tf2_ros, and ``tf.transformations`` (quaternions, Euler angles,
  matrices).
- :mod:`~duckielib.libraries.duckietown_utils`: the helpers of Duckietown's library that nodes
  use most (the robot's name, YAML files, camera messages and JPEG bytes to pixels).

They are served by name only where no real one is installed: :data:`MODULES` says which
module stands for which name. Importing this package imports none of them (nor OpenCV).

Laptop side; never deployed.
"""

from __future__ import annotations

from typing import Dict

__all__ = ["MODULES"]

#: Modules of Duckietown's library that nodes import helpers from (``duckietown_utils.jpg``):
#: :mod:`.duckietown_utils` stands for each.
DUCKIETOWN_UTILS_MODULES = (
    "jpg",
    "yaml_wrap",
    "image_conversions",
    "file_utils",
    "exceptions",
    "exception_utils",
)

#: The names robot code imports, each with the module of this package that stands for it.
#: A dotted name is a submodule robot code also imports (``from rosbag.bag import Bag``):
#: the same module as its package's, or one its package's module holds as an attribute
#: (``tf.transformations``).
MODULES: Dict[str, str] = {
    "cv_bridge": "duckielib.libraries.cv_bridge",
    "cv_bridge.core": "duckielib.libraries.cv_bridge",
    "rosbag": "duckielib.libraries.rosbag",
    "rosbag.bag": "duckielib.libraries.rosbag",
    "message_filters": "duckielib.libraries.message_filters",
    "tf": "duckielib.libraries.tf",
    "tf.transformations": "duckielib.libraries.tf.transformations",
    "tf2_ros": "duckielib.libraries.tf2_ros",
    "duckietown_utils": "duckielib.libraries.duckietown_utils",
    # The library's own modules, where nodes import its helpers from (one module here).
    **{
        f"duckietown_utils.{name}": "duckielib.libraries.duckietown_utils"
        for name in DUCKIETOWN_UTILS_MODULES
    },
}
