"""Real ROS 1 next to the in-process graph: finding it, and giving it the course's messages.

The course's nodes are written once, against the rospy API (DESIGN.md, principle 1). In a
notebook they get duckielib's in-process rospy; on a laptop with Debian's ROS 1 packages, and
on the robot, they get the real one. Three things make the second case work:

- :func:`use_debian_ros` puts Debian's packages (rospy, genpy, std_msgs...) at the *end* of
  ``sys.path``, so the project's own packages keep priority.
- :func:`generate_message_packages` writes ``duckietown_msgs`` (and ``std_srvs``) as genuine
  genpy packages, generated from the course's own ``.msg``/``.srv`` text, so that real rospy,
  ``rostopic echo``, ``rosservice call`` and ``rosbag record`` all know the robot's types.
  A Duckiebot has its own ``duckietown_msgs`` already; the md5 sums are the same.
- :func:`message_classes` gives a node the message classes that belong to the rospy it runs
  on, so driver code never needs to know which rospy it has.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
import types
from pathlib import Path
from typing import Any, Dict, List, Union

from duckielib import messages

__all__ = [
    "DEBIAN_DIST_PACKAGES",
    "GENERATED_PACKAGES",
    "generate_message_packages",
    "is_in_process",
    "message_classes",
    "use_debian_ros",
]

#: Where Debian installs rospy, genpy, rosbag and the standard message packages.
DEBIAN_DIST_PACKAGES = "/usr/lib/python3/dist-packages"

#: The message packages Debian does not ship, generated from the course's definitions.
GENERATED_PACKAGES = ("duckietown_msgs", "std_srvs")

_DEFINITIONS = Path(messages.__file__).parent / "definitions"


def use_debian_ros() -> bool:
    """Make Debian's ROS 1 packages importable, after everything else on the path.

    Returns:
        Whether rospy can now be imported.
    """
    if Path(DEBIAN_DIST_PACKAGES).is_dir() and DEBIAN_DIST_PACKAGES not in sys.path:
        sys.path.append(DEBIAN_DIST_PACKAGES)
    return importlib.util.find_spec("rospy") is not None


def is_in_process(rospy: Any) -> bool:
    """Whether ``rospy`` is duckielib's in-process rospy (not a real one)."""
    return getattr(rospy, "__name__", "") == "duckielib.ros.rospy"


class _RealMessages(types.SimpleNamespace):
    """The real message classes, by the names :mod:`duckielib.messages` gives them."""

    def __getattr__(self, name: str) -> Any:
        ours = getattr(messages, name, None)
        module_name = getattr(ours, "__module__", "")
        if not module_name.startswith("duckielib.messages."):
            raise AttributeError(f"there is no message class {name!r}")
        # duckielib.messages.duckietown_msgs.msg -> duckietown_msgs.msg
        module = importlib.import_module(module_name[len("duckielib.messages.") :])
        found = getattr(module, name)
        setattr(self, name, found)
        return found


_REAL = _RealMessages()


def message_classes(rospy: Any) -> Any:
    """The message and service classes that go with ``rospy``, as attributes by type name.

    With the in-process rospy these are :mod:`duckielib.messages`; with a real rospy, the
    classes of the installed packages (``duckietown_msgs.msg.WheelsCmdStamped``...).
    """
    return messages if is_in_process(rospy) else _REAL


def generate_message_packages(folder: Union[str, Path]) -> Path:
    """Write genpy's Python packages for :data:`GENERATED_PACKAGES` into ``folder``.

    Put ``folder`` on ``sys.path`` (or ``PYTHONPATH``) and ``import duckietown_msgs.msg``
    works for real rospy and the ROS command-line tools. Needs Debian's genpy and genmsg.

    Returns:
        ``folder``, as a Path.
    """
    use_debian_ros()
    import genmsg
    import genmsg.msg_loader
    import genpy.generator

    folder = Path(folder)
    context = genmsg.MsgContext.create_default()
    search_path: Dict[str, List[str]] = {
        package.name: [str(package / "msg")] for package in _DEFINITIONS.iterdir()
    }
    for package in GENERATED_PACKAGES:
        root = folder / package
        root.mkdir(parents=True, exist_ok=True)
        (root / "__init__.py").write_text("", encoding="utf-8")
        for kind in ("msg", "srv"):
            sources = sorted((_DEFINITIONS / package / kind).glob(f"*.{kind}"))
            if not sources:
                continue
            (root / kind).mkdir(exist_ok=True)
            for source in sources:
                full_name = f"{package}/{source.stem}"
                if kind == "msg":
                    spec = genmsg.msg_loader.load_msg_from_file(context, str(source), full_name)
                    genmsg.msg_loader.load_depends(context, spec, search_path)
                    lines = genpy.generator.msg_generator(context, spec, search_path)
                else:
                    spec = genmsg.msg_loader.load_srv_from_file(context, str(source), full_name)
                    genmsg.msg_loader.load_depends(context, spec, search_path)
                    lines = genpy.generator.srv_generator(context, spec, search_path)
                text = "\n".join(lines) + "\n"
                (root / kind / f"_{source.stem}.py").write_text(text, encoding="utf-8")
            imports = "".join(f"from ._{source.stem} import *\n" for source in sources)
            (root / kind / "__init__.py").write_text(imports, encoding="utf-8")
    return folder
