#!/usr/bin/env python3
# ruff: noqa  (written in the style of code from elsewhere, on purpose)
# Reads the headers of the connection each message came on, then calls a service with a
# header of its own (our own code in that pattern).
import rospy
from std_msgs.msg import String
from std_srvs.srv import Trigger


def heard(msg):
    header = msg._connection_header
    rospy.loginfo(
        "status %s from %s as %s of fleet %s (latching %s)",
        msg.data,
        header["callerid"],
        header["robot_role"],
        header["fleet"],
        header["latching"],
    )
    rospy.wait_for_service("who_asks")
    ask = rospy.ServiceProxy("who_asks", Trigger, headers={"token": "abc123"})
    answer = ask()
    rospy.loginfo(
        "service says: %s (answered by %s)", answer.message, answer._connection_header["callerid"]
    )
    rospy.signal_shutdown("done")


if __name__ == "__main__":
    rospy.init_node("tagged_listener")
    rospy.Subscriber("status", String, heard, queue_size=1)
    rospy.spin()
