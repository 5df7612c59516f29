"""Fixtures for tests against Debian's ROS 1 packages (marked ``ros``)."""

from __future__ import annotations

import importlib
import sys

import pytest

#: Where Debian installs rospy, genpy, rosbag and the message packages.
DEBIAN_DIST_PACKAGES = "/usr/lib/python3/dist-packages"


@pytest.fixture(scope="session")
def ros_import():
    """Import a module of Debian's ROS 1 packages, or skip saying how to install them.

    The folder is appended at the end of ``sys.path`` so the project's own packages keep
    priority, as the ROS backend does.
    """
    if DEBIAN_DIST_PACKAGES not in sys.path:
        sys.path.append(DEBIAN_DIST_PACKAGES)

    def load(name: str):
        try:
            return importlib.import_module(name)
        except ImportError as error:
            pytest.skip(f"Debian's ROS 1 packages are not installed ({error}); run `make ros`.")

    return load
