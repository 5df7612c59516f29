"""The in-process rospy offers what Debian's rospy offers, by the same names (``ros``)."""

from __future__ import annotations

import importlib

import pytest

pytestmark = pytest.mark.ros

#: What robot code reaches in rospy, at the top and in its modules.
USED = {
    "": [
        "Header",
        "get_published_topics",
        "remap_name",
        "logfatal_throttle",
        "logfatal_once",
        "logdebug_throttle_identical",
        "loginfo_throttle_identical",
        "logwarn_throttle_identical",
        "logerr_throttle_identical",
        "logfatal_throttle_identical",
    ],
    "rostime": ["Time", "Duration", "get_rostime", "get_time"],
    "names": ["ns_join", "resolve_name", "get_name", "get_namespace", "remap_name"],
    "exceptions": ["ROSException", "ROSInterruptException", "ROSInitException"],
    "msg": ["AnyMsg"],
    "timer": ["Rate", "Timer", "TimerEvent", "sleep"],
    "service": ["ServiceException"],
    "topics": ["Publisher", "Subscriber"],
    "client": ["init_node", "get_param", "spin"],
    "core": ["is_shutdown", "signal_shutdown", "is_shutdown_requested"],
}


@pytest.mark.parametrize("module", sorted(USED))
def test_each_name_robot_code_uses_is_in_both_rospys(ros_import, module):
    from duckielib.ros.modules import modules_installed

    real = ros_import("rospy" + (f".{module}" if module else ""))
    with modules_installed(replace_real=True):
        ours = importlib.import_module("rospy" + (f".{module}" if module else ""))
        assert ours.__name__.startswith(("rospy", "duckielib.ros.rospy"))
        for name in USED[module]:
            assert hasattr(real, name), f"Debian's rospy.{module} has no {name}"
            assert hasattr(ours, name), f"the in-process rospy.{module} has no {name}"
