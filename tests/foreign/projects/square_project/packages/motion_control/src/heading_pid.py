#!/usr/bin/env python3
"""Turns on the spot with a PD controller whose dt comes from time.time()."""

import time

import rospy
from duckietown_msgs.msg import Twist2DStamped

if __name__ == "__main__":
    rospy.init_node("heading_pid")
    pub = rospy.Publisher("car_cmd_switch_node/cmd", Twist2DStamped, queue_size=1)
    rate = rospy.Rate(10)
    last = time.time()
    started = time.perf_counter()
    steps = []
    for _ in range(20):
        rate.sleep()
        now = time.time()
        steps.append(now - last)
        last = now
        pub.publish(Twist2DStamped(v=0.0, omega=1.0))
    pub.publish(Twist2DStamped(v=0.0, omega=0.0))
    rospy.loginfo(
        "mean dt %.3f s over %d steps, %.2f s in all",
        sum(steps) / len(steps),
        len(steps),
        time.perf_counter() - started,
    )
