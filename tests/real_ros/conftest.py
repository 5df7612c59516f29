"""Fixtures for tests against Debian's ROS 1 packages (marked ``ros``)."""

from __future__ import annotations

import importlib
import sys

import pytest

#: Where Debian installs rospy, genpy, rosbag and the message packages.
DEBIAN_DIST_PACKAGES = "/usr/lib/python3/dist-packages"


@pytest.fixture(scope="module")
def ros_import():
    """Import a module of Debian's ROS 1 packages, or skip saying how to install them.

    The folder is appended at the end of ``sys.path`` so the project's own packages keep
    priority, as the ROS backend does. Afterwards the path and every module loaded from it
    are removed again, so other tests never meet the real rospy by accident.
    """
    added = DEBIAN_DIST_PACKAGES not in sys.path
    if added:
        sys.path.append(DEBIAN_DIST_PACKAGES)
    before = set(sys.modules)

    def load(name: str):
        try:
            return importlib.import_module(name)
        except ImportError as error:
            pytest.skip(f"Debian's ROS 1 packages are not installed ({error}); run `make ros`.")

    yield load
    for name in set(sys.modules) - before:
        if (getattr(sys.modules[name], "__file__", None) or "").startswith(DEBIAN_DIST_PACKAGES):
            del sys.modules[name]
    if added:
        sys.path.remove(DEBIAN_DIST_PACKAGES)
