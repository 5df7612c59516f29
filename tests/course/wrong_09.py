"""Deliberately wrong solutions of notebook 09_mission, one dict entry per mistake.

Each mistake is the reference node with one thing wrong, written as ``(old, new)`` edits of the
reference cell, so it fails for that mistake alone: the test drives the mission and checks the
states and colours, the stops, 'done', where the square and the return end, and the circle's
direction.
"""

WRONG = {
    "mission_node": {
        "LED colours never set (no call to the light service)": (
            ("        set_color(String(data=state.color))\n", ""),
        ),
        "every stop lasts 1 s instead of the state's time": (
            ("rospy.sleep(move.seconds)", "rospy.sleep(1.0)"),
        ),
        "Rotate moves ignored": (
            (
                "                goal = (x, y, (theta + move.angle) % (2 * math.pi))\n"
                "                turn_to(goal[2])\n",
                "                pass\n",
            ),
        ),
        "ReturnToStart does nothing": (
            (
                "                goal = tuple(mission.start)\n"
                "                go_to(goal)\n"
                "                turn_to(goal[2])\n",
                "                pass\n",
            ),
        ),
        "never publishes 'done'": (('    announce.publish(String(data="done"))\n', ""),),
        "arcs always counter-clockwise (the angle's sign ignored)": (
            (
                "        sign = 1.0 if angle > 0 else -1.0  "
                "# +1: curve left (counter-clockwise), -1: right\n",
                "        sign = 1.0\n",
            ),
        ),
    },
}
