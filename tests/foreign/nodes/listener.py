#!/usr/bin/env python3
# ruff: noqa  (written in the style of code from elsewhere, on purpose)
# A listener as the rospy tutorials write one (our own code in their pattern).
import rospy
from std_msgs.msg import String


def callback(data):
    rospy.loginfo(rospy.get_caller_id() + " I heard %s", data.data)


def listener():
    rospy.init_node("listener", anonymous=True)
    rospy.Subscriber("chatter", String, callback)
    rospy.spin()


if __name__ == "__main__":
    listener()
