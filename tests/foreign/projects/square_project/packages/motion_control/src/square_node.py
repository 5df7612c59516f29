#!/usr/bin/env python3
"""Drives one side of the square: asks the side server how long, then drives it."""

import rospy
from duckietown_msgs.msg import Twist2DStamped
from motion_control.timing import side_seconds
from motion_msgs.msg import Progress
from motion_msgs.srv import SideLength


class SquareDriver:
    def __init__(self):
        rospy.init_node("square_node")
        self.speed = rospy.get_param("~speed")
        self.gains = rospy.get_param("~gains")
        rospy.wait_for_service("side_server/side_length", timeout=5.0)
        ask = rospy.ServiceProxy("side_server/side_length", SideLength)
        self.length = ask("square").length
        self.cmd = rospy.Publisher("car_cmd", Twist2DStamped, queue_size=1)
        self.progress = rospy.Publisher("~progress", Progress, queue_size=10)

    def drive(self):
        seconds = side_seconds(self.length, self.speed)
        rate = rospy.Rate(10)
        start = rospy.get_time()
        while not rospy.is_shutdown() and rospy.get_time() - start < seconds:
            self.cmd.publish(Twist2DStamped(v=self.speed, omega=0.0))
            self.progress.publish(Progress(done=(rospy.get_time() - start) / seconds))
            rate.sleep()
        self.cmd.publish(Twist2DStamped(v=0.0, omega=0.0))
        rospy.sleep(self.gains["settle"])
        rospy.loginfo("drove %.2f m at %.1f m/s", self.length, self.speed)


if __name__ == "__main__":
    SquareDriver().drive()
