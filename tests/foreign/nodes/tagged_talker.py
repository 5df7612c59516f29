#!/usr/bin/env python3
# ruff: noqa  (written in the style of code from elsewhere, on purpose)
# A node that tags its connections with headers of its own, as some multi-robot code does
# (our own code in that pattern): its topic's subscribers and its service read them.
import rospy
from std_msgs.msg import String
from std_srvs.srv import Trigger, TriggerResponse


def who_asks(req):
    header = req._connection_header
    return TriggerResponse(
        success=True, message="%s with token %s" % (header["callerid"], header.get("token", "-"))
    )


if __name__ == "__main__":
    rospy.init_node("tagged_talker")
    pub = rospy.Publisher(
        "status", String, queue_size=1, latch=True, headers={"robot_role": "leader", "fleet": "7"}
    )
    rospy.Service("who_asks", Trigger, who_asks)
    pub.publish("ready")
    rospy.spin()
