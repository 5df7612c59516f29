#!/usr/bin/env python3
# ruff: noqa  (written in the style of code from elsewhere, on purpose)
# A Duckietown-style camera node (our own code in their pattern): DTROS, cv_bridge and OpenCV.
import os

import cv2
import rospy
from cv_bridge import CvBridge
from duckietown.dtros import DTROS, NodeType, TopicType
from sensor_msgs.msg import CompressedImage


class CameraAnnotatorNode(DTROS):
    def __init__(self, node_name):
        super(CameraAnnotatorNode, self).__init__(
            node_name=node_name, node_type=NodeType.PERCEPTION
        )
        self._vehicle_name = os.environ["VEHICLE_NAME"]
        self._bridge = CvBridge()
        self.sub = rospy.Subscriber(
            f"/{self._vehicle_name}/camera_node/image/compressed",
            CompressedImage,
            self.callback,
            queue_size=1,
        )
        self.pub = rospy.Publisher(
            "~image/compressed",
            CompressedImage,
            queue_size=1,
            dt_topic_type=TopicType.VISUALIZATION,
        )

    def callback(self, msg):
        image = self._bridge.compressed_imgmsg_to_cv2(msg)
        cv2.rectangle(image, (270, 190), (370, 290), (0, 0, 255), -1)
        out = self._bridge.cv2_to_compressed_imgmsg(image, dst_format="png")
        out.header = msg.header
        self.pub.publish(out)


if __name__ == "__main__":
    node = CameraAnnotatorNode(node_name="camera_annotator_node")
    rospy.spin()
