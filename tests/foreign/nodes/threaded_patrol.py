#!/usr/bin/env python3
# ruff: noqa  (written in the style of code from elsewhere, on purpose)
# A node written the way many Duckietown and student nodes are (our own code in their
# pattern): the control loop runs in a thread the node starts, beside rospy.spin() in the main
# thread; a threading.Timer blinks the LEDs; a callback flips a flag the loop reads; the
# shutdown hook joins the loop's thread; the robot's name comes from duckietown_utils.
import threading
import time

import duckietown_utils as dtu
import rospy
from duckietown.dtros import DTROS, NodeType
from duckietown_msgs.msg import LEDPattern, WheelEncoderStamped, WheelsCmdStamped
from std_msgs.msg import ColorRGBA


class PatrolNode(DTROS):
    def __init__(self, node_name):
        super().__init__(node_name=node_name, node_type=NodeType.CONTROL)
        veh = dtu.get_current_robot_name()
        self.pub = rospy.Publisher(
            f"/{veh}/wheels_driver_node/wheels_cmd", WheelsCmdStamped, queue_size=1
        )
        self.leds = rospy.Publisher(
            f"/{veh}/led_emitter_node/led_pattern", LEDPattern, queue_size=1
        )
        self.lock = threading.Lock()
        self.left_ticks = None
        self.running = True
        rospy.Subscriber(f"/{veh}/left_wheel_encoder_node/tick", WheelEncoderStamped, self.cb)
        self.worker = threading.Thread(target=self.loop)
        self.worker.start()
        self.blink = threading.Timer(2.0, self.lights)
        self.blink.start()
        rospy.on_shutdown(self.on_stop)

    def cb(self, msg):
        with self.lock:
            self.left_ticks = msg.data

    def lights(self):
        white = ColorRGBA(r=1.0, g=1.0, b=1.0, a=1.0)
        self.leds.publish(LEDPattern(rgb_vals=[white] * 5))
        rospy.loginfo("lights on at %.2f", rospy.get_time())

    def loop(self):
        rate = rospy.Rate(20)
        start = rospy.get_time()
        while self.running and not rospy.is_shutdown():
            with self.lock:
                ticks = self.left_ticks
            if rospy.get_time() - start < 3.0:
                self.pub.publish(WheelsCmdStamped(vel_left=0.4, vel_right=0.4))
            else:
                self.pub.publish(WheelsCmdStamped(vel_left=0.0, vel_right=0.0))
                rospy.loginfo("stopped after %d ticks", ticks)
                break
            rate.sleep()
        time.sleep(0.5)
        rospy.signal_shutdown("patrol done")

    def on_stop(self):
        self.running = False
        if threading.current_thread() is not self.worker:
            self.worker.join(timeout=1.0)
        self.pub.publish(WheelsCmdStamped(vel_left=0.0, vel_right=0.0))


if __name__ == "__main__":
    node = PatrolNode(node_name="patrol_node")
    rospy.spin()
