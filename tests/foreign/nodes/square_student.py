#!/usr/bin/env python3
# ruff: noqa  (written in the style of code from elsewhere, on purpose)
# An exercise node written the way students of the course write them (our own code in their
# pattern): a DTROS class, wheel commands straight to the driver, LED patterns published on the
# emitter's topic, "stop" states with time.sleep, and loops that poll the encoders without
# sleeping.
import math
import os
import time

import rospy
from duckietown.dtros import DTROS, NodeType
from duckietown_msgs.msg import LEDPattern, WheelEncoderStamped, WheelsCmdStamped
from std_msgs.msg import ColorRGBA

R = 0.0318
BASELINE = 0.1
TICKS = 135
SIDE = 0.4
SPEED = 0.3


class SquareNode(DTROS):
    def __init__(self, node_name):
        super().__init__(node_name=node_name, node_type=NodeType.GENERIC)
        veh = os.environ["VEHICLE_NAME"]
        self.pub_wheels = rospy.Publisher(
            f"/{veh}/wheels_driver_node/wheels_cmd", WheelsCmdStamped, queue_size=1
        )
        self.pub_leds = rospy.Publisher(
            f"/{veh}/led_emitter_node/led_pattern", LEDPattern, queue_size=1
        )
        self.ticks = {"left": None, "right": None}
        for wheel in ("left", "right"):
            rospy.Subscriber(
                f"/{veh}/{wheel}_wheel_encoder_node/tick",
                WheelEncoderStamped,
                self.cb_ticks,
                callback_args=wheel,
            )
        rospy.on_shutdown(self.stop)

    def cb_ticks(self, msg, wheel):
        self.ticks[wheel] = msg.data

    def wheels(self, left, right):
        self.pub_wheels.publish(WheelsCmdStamped(vel_left=left, vel_right=right))

    def stop(self):
        self.wheels(0.0, 0.0)

    def lights(self, r, g, b):
        color = ColorRGBA(r=r, g=g, b=b, a=1.0)
        self.pub_leds.publish(LEDPattern(rgb_vals=[color] * 5))

    def distance(self, start, wheel):
        return 2 * math.pi * R * (self.ticks[wheel] - start[wheel]) / TICKS

    def forward(self, metres):
        start = dict(self.ticks)
        while self.distance(start, "left") + self.distance(start, "right") < 2 * metres:
            self.wheels(SPEED, SPEED)
        self.stop()

    def turn_left(self, radians):
        start = dict(self.ticks)
        while (self.distance(start, "right") - self.distance(start, "left")) / BASELINE < radians:
            self.wheels(-SPEED, SPEED)
        self.stop()

    def run(self):
        while None in self.ticks.values():
            time.sleep(0.1)
        for _ in range(4):
            self.lights(1.0, 0.0, 0.0)
            time.sleep(1)
            self.lights(0.0, 1.0, 0.0)
            self.forward(SIDE)
            self.turn_left(math.pi / 2)
        self.lights(0.0, 0.0, 1.0)
        self.stop()


if __name__ == "__main__":
    node = SquareNode(node_name="square_student_node")
    node.run()
    rospy.signal_shutdown("done")
