"""Make robot code's imports (``import rospy``, ``from std_msgs.msg import String``...) work.

Code written for a Duckiebot imports rospy, the message packages and Duckietown's ``DTROS``
by their usual names. :func:`install_modules` points those names at the in-process graph and
the course's message classes, so that code runs unchanged in a notebook. A real ROS
installation on the Python path is never shadowed unless ``replace_real=True`` is given.
"""

from __future__ import annotations

import contextlib
import importlib.util
import sys
import types
from typing import Dict, Iterator, List

from duckielib import messages
from duckielib.ros import dtros, rospy

__all__ = ["install_modules", "modules_installed", "uninstall_modules"]

_MESSAGE_PACKAGES = ("std_msgs", "sensor_msgs", "duckietown_msgs", "std_srvs")


def _aliases() -> Dict[str, Dict[str, types.ModuleType]]:
    """Top-level name -> {module name: module} for every name this installs."""
    duckietown = types.ModuleType("duckietown", "Duckietown's ROS library (in-process version).")
    duckietown.dtros = dtros  # type: ignore[attr-defined]
    found: Dict[str, Dict[str, types.ModuleType]] = {
        "rospy": {"rospy": rospy},
        "duckietown": {"duckietown": duckietown, "duckietown.dtros": dtros},
    }
    for package in _MESSAGE_PACKAGES:
        module = getattr(messages, package)
        found[package] = {package: module}
        for kind in ("msg", "srv"):
            if hasattr(module, kind):
                found[package][f"{package}.{kind}"] = getattr(module, kind)
    return found


def _is_ours(module: object) -> bool:
    name = getattr(module, "__name__", "")
    return name.startswith("duckielib.") or getattr(module, "_duckielib_alias", False)


def install_modules(replace_real: bool = False) -> List[str]:
    """Serve robot code's imports from the in-process graph and the course's messages.

    After it, ``import rospy``, ``std_msgs.msg``, ``sensor_msgs.msg``, ``duckietown_msgs.msg``
    and ``.srv``, ``std_srvs.srv`` and ``duckietown.dtros`` resolve to duckielib.

    Args:
        replace_real: also replace a real ROS installation found on the Python path.

    Returns:
        The top-level names now served by duckielib (a name a real installation provides is
        left out unless ``replace_real`` is true).
    """
    installed = []
    for top, modules in _aliases().items():
        current = sys.modules.get(top)
        real = (current is not None and not _is_ours(current)) or (
            current is None and importlib.util.find_spec(top) is not None
        )
        if real and not replace_real:
            continue
        for name, module in modules.items():
            if name == "duckietown":
                module._duckielib_alias = True  # type: ignore[attr-defined]
            sys.modules[name] = module
        installed.append(top)
    return installed


def uninstall_modules() -> None:
    """Undo :func:`install_modules` (modules already imported keep what they imported)."""
    for modules in _aliases().values():
        for name in modules:
            if name in sys.modules and _is_ours(sys.modules[name]):
                del sys.modules[name]


@contextlib.contextmanager
def modules_installed(replace_real: bool = False) -> Iterator[List[str]]:
    """:func:`install_modules` for the duration of a ``with`` block, then exactly as before.

    Code imported inside the block keeps the modules it imported; the rest of the process
    (a real ROS installation, another test) sees ``sys.modules`` as it was.

    Args:
        replace_real: serve the in-process modules even where a real ROS is importable (for
            code that runs on the in-process graph whatever else is installed).
    """
    names = [name for modules in _aliases().values() for name in modules]
    before = {name: sys.modules.get(name) for name in names}
    try:
        yield install_modules(replace_real)
    finally:
        for name, module in before.items():
            if module is None:
                sys.modules.pop(name, None)
            else:
                sys.modules[name] = module
