"""ROS graph names and how rospy resolves them.

A name is *global* (``/duckiebot/wheels_driver_node/wheels_cmd``), *relative*
(``wheels_driver_node/wheels_cmd``, resolved in the node's namespace) or *private*
(``~tick``, resolved under the node's own name). Namespaces are written with a leading and a
trailing slash (``/duckiebot/``), as ``rospy.get_namespace()`` returns them.
"""

from __future__ import annotations

import re
from typing import Dict, Optional

__all__ = [
    "canonical",
    "is_legal_name",
    "is_legal_base_name",
    "namespace_of",
    "normalize_namespace",
    "resolve",
]

_LEGAL = re.compile(r"^[~/]?([A-Za-z][\w]*)?(/[A-Za-z][\w]*)*/?$")
_BASE = re.compile(r"^[A-Za-z][\w]*$")


def is_legal_name(name: str) -> bool:
    """True for a legal ROS name: letters, digits, ``_`` and ``/``; parts start with a letter."""
    return isinstance(name, str) and "//" not in name and bool(_LEGAL.match(name))


def is_legal_base_name(name: str) -> bool:
    """True for a single name part, such as a node name: ``talker``, ``odometry_node``."""
    return isinstance(name, str) and bool(_BASE.match(name))


def canonical(name: str) -> str:
    """Drop a trailing slash and repeated slashes (``/a//b/`` becomes ``/a/b``)."""
    parts = [part for part in name.split("/") if part]
    prefix = "/" if name.startswith("/") else ""
    return prefix + "/".join(parts) if parts else prefix


def normalize_namespace(namespace: Optional[str]) -> str:
    """A namespace with a leading and trailing slash: ``duckiebot`` becomes ``/duckiebot/``."""
    if not namespace:
        return "/"
    inner = canonical("/" + namespace.strip("/"))
    return inner + "/" if inner != "/" else "/"


def namespace_of(name: str) -> str:
    """The namespace a global name lives in: ``/duckiebot/talker`` gives ``/duckiebot/``."""
    return normalize_namespace(canonical(name).rsplit("/", 1)[0])


def resolve(
    name: str,
    namespace: str = "/",
    node_name: Optional[str] = None,
    remappings: Optional[Dict[str, str]] = None,
) -> str:
    """Resolve a name the way rospy does.

    Args:
        name: a global, relative or private name.
        namespace: the node's namespace, for relative names.
        node_name: the node's global name, for private names.
        remappings: resolved name -> resolved replacement (as ``roslaunch`` remaps).

    Returns:
        The global name, without a trailing slash.

    Raises:
        ValueError: for an illegal name, or a private name without a node.
    """
    if not is_legal_name(name):
        raise ValueError(
            f"{name!r} is not a legal ROS name: use letters, digits, '_' and '/', "
            "each part starting with a letter (for example 'wheels_driver_node/wheels_cmd')."
        )
    if name.startswith("/"):
        resolved = canonical(name)
    elif name.startswith("~"):
        if node_name is None:
            raise ValueError(
                f"The private name {name!r} needs a node: call rospy.init_node(...) first."
            )
        resolved = canonical(node_name + "/" + name[1:])
    else:
        resolved = canonical(normalize_namespace(namespace) + name)
    if remappings and resolved in remappings:
        return remappings[resolved]
    return resolved
