"""The parameter server: a tree of named values, as ``rosparam`` shows it.

Parameters are global names (``/duckiebot/kinematics_node/gain``); a namespace reads as a
dict of what it holds, and setting a dict sets a whole namespace. Values are copied in and
out, so a node that changes a value it read changes nothing on the server.

Pure: standard library only, Python 3.8 (deployed to the robot).
"""

from __future__ import annotations

from typing import Any, Dict, List, Tuple

from duckielib.ros.exceptions import ROSException

__all__ = ["ParameterServer", "copy_tree"]


def copy_tree(value: Any) -> Any:
    """A copy of a parameter's value, down to its nested dicts and lists."""
    if isinstance(value, dict):
        return {key: copy_tree(item) for key, item in value.items()}
    if isinstance(value, list):
        return [copy_tree(item) for item in value]
    return value


class ParameterServer:
    """The parameters of a graph, by global name."""

    def __init__(self) -> None:
        self.params: Dict[str, Any] = {}
        #: Values read by ``rospy.get_param_cached``, by (node, name); emptied on any change.
        self.param_cache: Dict[Tuple[str, str], Any] = {}

    def set_param(self, name: str, value: Any) -> None:
        """Set a parameter by global name; a dict value sets a whole namespace."""
        self.param_cache.clear()
        parts = [part for part in name.split("/") if part]
        if not parts:
            if not isinstance(value, dict):
                raise ROSException("Only a dictionary can be set as the root parameter '/'.")
            self.params = copy_tree(value)
            return
        tree = self.params
        for part in parts[:-1]:
            child = tree.get(part)
            if not isinstance(child, dict):
                child = tree[part] = {}
            tree = child
        tree[parts[-1]] = copy_tree(value)

    def get_param(self, name: str) -> Any:
        """Get a parameter by global name (a namespace gives a dict).

        Raises:
            KeyError: if it is not set, as rospy does.
        """
        tree: Any = self.params
        for part in [part for part in name.split("/") if part]:
            if not isinstance(tree, dict) or part not in tree:
                raise KeyError(name)
            tree = tree[part]
        return copy_tree(tree)

    def has_param(self, name: str) -> bool:
        """Whether a parameter (or namespace) is set."""
        try:
            self.get_param(name)
        except KeyError:
            return False
        return True

    def delete_param(self, name: str) -> None:
        """Delete a parameter or namespace.

        Raises:
            KeyError: if it is not set.
        """
        self.param_cache.clear()
        parts = [part for part in name.split("/") if part]
        tree: Any = self.params
        for part in parts[:-1]:
            if not isinstance(tree, dict) or part not in tree:
                raise KeyError(name)
            tree = tree[part]
        if not parts or not isinstance(tree, dict) or parts[-1] not in tree:
            raise KeyError(name)
        del tree[parts[-1]]

    def param_names(self) -> List[str]:
        """Every parameter's global name, sorted (``rosparam list``)."""
        found: List[str] = []

        def walk(prefix: str, tree: Dict[str, Any]) -> None:
            for key, value in tree.items():
                if isinstance(value, dict) and value:
                    walk(f"{prefix}/{key}", value)
                else:
                    found.append(f"{prefix}/{key}")

        walk("", self.params)
        return sorted(found)
