#!/usr/bin/env python3
"""Shows the camera's frames in a window and looks for AprilTags in them, as students'
nodes do (the mat has no tags: none is found)."""

import cv2
import numpy as np
import rospy
from dt_apriltags import Detector
from sensor_msgs.msg import CompressedImage

if __name__ == "__main__":
    rospy.init_node("camera_viewer")
    cv2.namedWindow("camera", cv2.WINDOW_AUTOSIZE)
    frames = [0]
    detector = Detector(families="tag36h11")
    tags = []

    def on_image(msg):
        image = cv2.imdecode(np.frombuffer(msg.data, np.uint8), cv2.IMREAD_COLOR)
        tags.extend(detector.detect(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)))
        cv2.imshow("camera", image)
        cv2.waitKey(1)
        frames[0] += 1

    rospy.Subscriber("camera_node/image/compressed", CompressedImage, on_image, queue_size=1)
    while not rospy.is_shutdown() and frames[0] < 5:
        rospy.sleep(0.1)
    cv2.destroyAllWindows()
    rospy.loginfo("showed %d frames, %d AprilTags in them", frames[0], len(tags))
