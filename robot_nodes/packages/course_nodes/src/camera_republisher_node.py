#!/usr/bin/env python3
"""The camera republisher: the robot's camera frames, published again under this node.

It subscribes to the camera (``camera_node/image/compressed``, JPEG frames) and republishes
each frame on ``~image/compressed``, so a laptop can watch it (``rqt_image_view``) or record
it in a bag. The launch file starts it only with ``camera:=true`` (the default).

``roslaunch`` starts it (see ``launch/course.launch``); the code is
``duckielib.nodes.mains.camera_republisher_main``.
"""

from duckielib.nodes.mains import camera_republisher_main

if __name__ == "__main__":
    camera_republisher_main()
