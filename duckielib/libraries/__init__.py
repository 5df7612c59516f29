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

They are served by name only where no real one is installed. Each registers the names it
stands for in the entry point group ``duckielib.ros_libraries`` of ``pyproject.toml``, which
:mod:`duckielib.ros.modules` reads: the robot's code never names this laptop package.
Importing this package imports none of them (nor OpenCV).

Laptop side; never deployed.
"""
