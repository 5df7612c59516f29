#!/usr/bin/env python3
# ruff: noqa  (written in the style of code from elsewhere, on purpose)
# A service client in the tutorials' pattern: the numbers come from the command line.
import sys

import rospy
from beginner_tutorials.srv import AddTwoInts


def add_two_ints_client(x, y):
    rospy.wait_for_service("add_two_ints")
    try:
        add_two_ints = rospy.ServiceProxy("add_two_ints", AddTwoInts)
        return add_two_ints(x, y).sum
    except rospy.ServiceException as e:
        print("Service call failed: %s" % e)


if __name__ == "__main__":
    rospy.init_node("add_two_ints_client")
    if len(sys.argv) == 3:
        x, y = int(sys.argv[1]), int(sys.argv[2])
    else:
        print("usage: %s x y" % sys.argv[0])
        sys.exit(1)
    rospy.loginfo("%s + %s = %s", x, y, add_two_ints_client(x, y))
