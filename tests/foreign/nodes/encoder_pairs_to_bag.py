#!/usr/bin/env python3
# ruff: noqa  (written in the style of code from elsewhere, on purpose)
# A dead-reckoning-style node (our own code in the pattern of Duckietown's): the two encoders
# paired by message_filters, each pair written to a bag with rosbag's Python API.
import os
import sys

import message_filters
import rosbag
import rospy
from duckietown_msgs.msg import WheelEncoderStamped


class EncoderPairs:
    def __init__(self, bag_path):
        veh = os.environ["VEHICLE_NAME"]
        self.bag = rosbag.Bag(bag_path, "w")
        left = message_filters.Subscriber(
            f"/{veh}/left_wheel_encoder_node/tick", WheelEncoderStamped
        )
        right = message_filters.Subscriber(
            f"/{veh}/right_wheel_encoder_node/tick", WheelEncoderStamped
        )
        self.ts = message_filters.ApproximateTimeSynchronizer([left, right], 10, 1.0 / 30.0)
        self.ts.registerCallback(self.cb_pair)
        rospy.on_shutdown(self.bag.close)

    def cb_pair(self, left, right):
        self.bag.write("left", left, left.header.stamp)
        self.bag.write("right", right, right.header.stamp)


if __name__ == "__main__":
    rospy.init_node("encoder_pairs")
    EncoderPairs(sys.argv[1])
    rospy.spin()
