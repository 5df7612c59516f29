#!/usr/bin/env python3
# ruff: noqa  (written in the style of students' nodes, on purpose)
"""Records the left encoder's ticks for 2 s to the robot's /data, as students' nodes do."""

import os
import socket

import rosbag
import rospy
from duckietown_msgs.msg import WheelEncoderStamped

BAG_DIR = "/data/bags"

if __name__ == "__main__":
    rospy.init_node("tick_recorder")
    # On the robot, the container's host name is the robot's name.
    veh = socket.gethostname()
    rospy.loginfo("recording on %s (uname says %s)", veh, os.uname()[1])
    if not os.path.exists(BAG_DIR):
        os.makedirs(BAG_DIR)
    bag = rosbag.Bag(os.path.join(BAG_DIR, "ticks.bag"), "w")
    count = [0]

    def on_tick(msg):
        bag.write("left_ticks", msg)
        count[0] += 1

    rospy.Subscriber("left_wheel_encoder_node/tick", WheelEncoderStamped, on_tick)
    rospy.sleep(2.0)
    bag.close()
    with (
        open("/data/logs/ticks.txt", "w")
        if os.path.isdir("/data/logs")
        else open("/data/ticks.txt", "w")
    ) as out:
        out.write("%d ticks\n" % count[0])
    rospy.loginfo("recorded %d ticks", count[0])
