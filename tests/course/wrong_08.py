"""Deliberately wrong solutions of notebook 08_leds, one dict entry per mistake.

Each mistake is the reference node with one thing wrong, written as ``(old, new)`` edits of the
reference cell; the test cell ``test_<grade_id>`` must lose marks with it. None of them hangs: a
node that never stops is left waiting on the graph, and every check runs for a bounded simulated
time.
"""

WRONG = {
    "light_service_node": {
        "forwards unknown colours to the emitter without an error": (
            (
                (
                    "        if name not in COLORS:\n"
                    "            raise rospy.ServiceException(\n"
                    "                f\"unknown colour {name!r}: use one of {', '.join(COLORS)}\"\n"
                    "            )\n"
                ),
                "",
            ),
        ),
        "offers set_pattern instead of set_color": (
            (
                '    rospy.Service("~set_color", ChangePattern, on_set_color)\n',
                '    rospy.Service("~set_pattern", ChangePattern, on_set_color)\n',
            ),
        ),
        "ignores the shutdown topic": (
            (
                '        rospy.signal_shutdown("the shutdown topic asked to stop")\n',
                '        rospy.loginfo("asked to stop, but carrying on")\n',
            ),
        ),
        "calls the emitter by a wrong service name, without waiting": (
            ('    rospy.wait_for_service("led_emitter_node/set_pattern", timeout=10.0)\n', ""),
            (
                'ServiceProxy("led_emitter_node/set_pattern"',
                'ServiceProxy("led_emitter_node/set_color"',
            ),
        ),
        "lower-cases the colour before forwarding it": (
            (
                "        emitter(String(data=name))\n",
                "        emitter(String(data=name.lower()))\n",
            ),
        ),
        "the handler returns None": (("        return ChangePatternResponse()\n", ""),),
        "the error does not name the valid colours": (
            (
                "                f\"unknown colour {name!r}: use one of {', '.join(COLORS)}\"\n",
                '                f"unknown colour {name!r}"\n',
            ),
        ),
        "refuses with ValueError instead of rospy.ServiceException": (
            ("            raise rospy.ServiceException(\n", "            raise ValueError(\n"),
        ),
        "no rospy.spin(): the node ends at once": (("    rospy.spin()\n", ""),),
        "hard-codes the robot's name": (
            (
                'wait_for_service("led_emitter_node/set_pattern"',
                'wait_for_service("/duckiebot/led_emitter_node/set_pattern"',
            ),
            (
                'ServiceProxy("led_emitter_node/set_pattern"',
                'ServiceProxy("/duckiebot/led_emitter_node/set_pattern"',
            ),
        ),
        "listens to a private ~shutdown topic": (
            (
                '    rospy.Subscriber("shutdown", Empty, on_shutdown_topic, queue_size=1)\n',
                '    rospy.Subscriber("~shutdown", Empty, on_shutdown_topic, queue_size=1)\n',
            ),
        ),
        "withdraws the service on shutdown but keeps the node running": (
            (
                ("\n    def on_shutdown_topic(msg):\n"),
                (
                    "\n"
                    '    service = rospy.Service("~set_color", ChangePattern, on_set_color)\n'
                    "\n"
                    "    def on_shutdown_topic(msg):\n"
                ),
            ),
            (
                '        rospy.signal_shutdown("the shutdown topic asked to stop")\n',
                '        service.shutdown("asked to stop")\n',
            ),
            ('    rospy.Service("~set_color", ChangePattern, on_set_color)\n', ""),
        ),
        "accepts every pattern the emitter knows": (
            (
                "        if name not in COLORS:\n",
                '        if name not in COLORS and not name.startswith("CAR_"):\n',
            ),
        ),
    },
}
