#!/usr/bin/env python3
"""Answers how long a side of each shape is, from its ~side parameter."""

import rospy
from motion_msgs.srv import SideLength, SideLengthResponse


def answer(request):
    rospy.loginfo("side of a %s asked", request.shape)
    return SideLengthResponse(length=rospy.get_param("~side", 0.5))


if __name__ == "__main__":
    rospy.init_node("side_server")
    rospy.Service("~side_length", SideLength, answer)
    rospy.spin()
