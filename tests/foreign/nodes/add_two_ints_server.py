#!/usr/bin/env python3
# ruff: noqa  (written in the style of code from elsewhere, on purpose)
# A service server in the tutorials' pattern, with its package's own .srv beside it.
import rospy
from beginner_tutorials.srv import AddTwoInts, AddTwoIntsResponse


def handle_add_two_ints(req):
    return AddTwoIntsResponse(req.a + req.b)


def add_two_ints_server():
    rospy.init_node("add_two_ints_server")
    rospy.Service("add_two_ints", AddTwoInts, handle_add_two_ints)
    rospy.spin()


if __name__ == "__main__":
    add_two_ints_server()
