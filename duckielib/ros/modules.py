"""Make robot code's imports (``import rospy``, ``from std_msgs.msg import String``...) work.

The names served: ``rospy``, ``duckietown.dtros``, every message package of
:mod:`duckielib.messages`, and on the laptop the libraries registered in the entry point group
``duckielib.ros_libraries`` (``cv_bridge``, ``rosbag``, ``message_filters``, ``tf``,
``tf2_ros``: :mod:`duckielib.libraries`).

Code written for a Duckiebot imports rospy, the message packages and Duckietown's ``DTROS``
by their usual names. Once :mod:`duckielib.ros` is imported, those names resolve to the
in-process graph and the course's message classes wherever nothing else provides them: a
finder placed *last* on ``sys.meta_path`` serves them only when no real ROS installation on the
Python path does. So robot code runs unchanged in a notebook with no set-up call to forget, and
a real rospy (Debian's, a robot's) always wins.

:func:`install_modules` serves the names at once, and with ``replace_real=True`` even where a
real ROS is installed (the mission runner does this for the nodes it runs in-process).

A package of one's own works as on a robot too: its ``msg/*.msg`` and ``srv/*.srv`` files, in a
package folder on the Python path or in the current folder, import as ``<package>.msg`` and
``<package>.srv`` (see :class:`PackageDefinitions`).
"""

from __future__ import annotations

import contextlib
import importlib.abc
import importlib.machinery
import sys
import types
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Union

from duckielib import messages
from duckielib.ros import apriltags, dtros, rospy

__all__ = [
    "PackageDefinitions",
    "RobotImports",
    "install_modules",
    "modules_installed",
    "node_script",
    "provided_elsewhere",
    "uninstall_modules",
]


def _message_packages() -> List[str]:
    """The packages with definitions in :mod:`duckielib.messages`: std_msgs, geometry_msgs..."""
    names = [*messages.REGISTRY.messages, *messages.REGISTRY.services]
    return sorted({name.partition("/")[0] for name in names})


#: The message packages served: every package of the course's definitions.
_MESSAGE_PACKAGES = tuple(_message_packages())


def _aliases() -> Dict[str, Dict[str, types.ModuleType]]:
    """Top-level name -> {module name: module} for every name this installs."""
    duckietown = types.ModuleType("duckietown", "Duckietown's ROS library (in-process version).")
    duckietown.dtros = dtros  # type: ignore[attr-defined]
    duckietown._duckielib_alias = True  # type: ignore[attr-defined]
    found: Dict[str, Dict[str, types.ModuleType]] = {
        "rospy": {
            "rospy": rospy,
            **{f"rospy.{name}": module for name, module in rospy.SUBMODULES.items()},
        },
        "duckietown": {"duckietown": duckietown, "duckietown.dtros": dtros},
    }
    for package in _MESSAGE_PACKAGES:
        module = getattr(messages, package)
        found[package] = {package: module}
        for kind in ("msg", "srv"):
            if hasattr(module, kind):
                found[package][f"{package}.{kind}"] = getattr(module, kind)
    return found


#: The entry point group the libraries served besides rospy register in (pyproject.toml).
LIBRARIES_GROUP = "duckielib.ros_libraries"

_LIBRARIES: Dict[str, Dict[str, Any]] = {}


def _library_modules() -> Dict[str, Any]:
    """The ROS libraries served besides rospy (``cv_bridge``, ``rosbag``, ``tf``...).

    Import name -> the entry point that loads the module standing for it. The libraries live
    on the laptop and register themselves in the entry point group :data:`LIBRARIES_GROUP`
    of the installed course (``pyproject.toml``); this module never names them. On a robot,
    which has the real ones and whose copy of duckielib is not installed, there are none.
    """
    if "modules" not in _LIBRARIES:
        from importlib import metadata

        found: Any = metadata.entry_points()
        if hasattr(found, "select"):  # Python 3.10 and later
            entries = found.select(group=LIBRARIES_GROUP)
        else:  # Python 3.8 and 3.9: a dict of groups
            entries = found.get(LIBRARIES_GROUP, ())
        _LIBRARIES["modules"] = {entry.name: entry for entry in entries}
    return _LIBRARIES["modules"]


def _is_ours(module: object) -> bool:
    name = getattr(module, "__name__", "")
    return name.startswith("duckielib.") or getattr(module, "_duckielib_alias", False)


def install_modules(replace_real: bool = False) -> List[str]:
    """Serve robot code's imports from the in-process graph and the course's messages.

    After it, ``import rospy``, ``duckietown.dtros`` and the message packages (``std_msgs.msg``,
    ``geometry_msgs.msg``, ``duckietown_msgs.msg`` and ``.srv``, ``std_srvs.srv``... every
    package of :mod:`duckielib.messages`) resolve to duckielib.

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
            current is None and provided_elsewhere(top)
        )
        if real and not replace_real:
            continue
        for name, module in modules.items():
            sys.modules[name] = module
        installed.append(top)
    return installed


def provided_elsewhere(top: str) -> bool:
    """Whether a finder other than the course's own finds the top-level module ``top``."""
    for finder in sys.meta_path:
        if isinstance(finder, RobotImports) or not hasattr(finder, "find_spec"):
            continue
        if finder.find_spec(top, None) is not None:
            return True
    return False


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


class RobotImports(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """The last resort for robot code's imports: serves the in-process modules by their names.

    It sits at the end of ``sys.meta_path``, so Python asks it only after every other finder
    (the real rospy and message packages on the path among them) came back empty-handed.
    """

    def find_spec(
        self, fullname: str, path: Optional[Sequence[str]] = None, target: object = None
    ) -> Optional[importlib.machinery.ModuleSpec]:
        """A spec for a name the course serves (``rospy``, ``std_msgs.msg``...), else None."""
        top = fullname.partition(".")[0]
        if fullname in _library_modules():
            return importlib.machinery.ModuleSpec(fullname, self)
        if top not in _SERVED:
            # Last of all: a package of one's own in the current folder (its msg/ and srv/
            # folders are then served by PackageDefinitions).
            if "." in fullname or _real_rospy_in_use():
                return None
            folder = _cwd() / fullname
            if not _has_definitions(folder):
                return None
            spec = importlib.machinery.ModuleSpec(fullname, self, is_package=True)
            spec.submodule_search_locations = [str(folder)]
            return spec
        if fullname not in _SERVED[top]:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        """A placeholder module, replaced by :meth:`exec_module`."""
        # A placeholder: exec_module puts duckielib's own module in its place, so the module
        # (duckielib.ros.rospy, say) keeps its own name and spec.
        return types.ModuleType(spec.name)

    def exec_module(self, module: types.ModuleType) -> None:
        """Put duckielib's modules for the name's package into ``sys.modules``."""
        top = module.__name__.partition(".")[0]
        libraries = _library_modules()
        if module.__name__ in libraries:
            for name, entry in libraries.items():  # rosbag, and rosbag.bag with it
                same_top = name.partition(".")[0] == top
                if same_top and (name == module.__name__ or name not in sys.modules):
                    sys.modules[name] = entry.load()
            return
        if top not in _SERVED:
            return  # a package folder of one's own: its __path__ is all it needs
        for name, served in _aliases()[top].items():
            # Its package's other modules too, unless already imported (by a real ROS).
            if name == module.__name__ or name not in sys.modules:
                sys.modules[name] = served


class PackageDefinitions(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Serves the ``msg/`` and ``srv/`` folders of a package of one's own as its modules.

    When catkin builds a robot's workspace, it turns ``my_pkg/msg/Foo.msg`` into the module
    ``my_pkg.msg``; this does the same on import, for a package folder on the Python path or in
    the current folder, so ``from my_pkg.msg import Foo`` just works. The fields of the types
    may use those of the package itself and of every package the course defines.

    It stands before Python's own path finder, which would take such a folder for an empty
    namespace package, and steps aside for a folder with an ``__init__.py`` (a module catkin
    generated), for the course's own packages, and whenever a real rospy is in use.
    """

    def find_spec(
        self, fullname: str, path: Optional[Sequence[str]] = None, target: object = None
    ) -> Optional[importlib.machinery.ModuleSpec]:
        """A spec for ``<package>.msg`` or ``.srv`` of a folder with definitions, else None."""
        package, _, kind = fullname.partition(".")
        if kind not in ("msg", "srv") or package in _MESSAGE_PACKAGES or path is None:
            return None
        if _real_rospy_in_use():
            return None
        for entry in path:
            folder = Path(entry)
            if _has_definitions(folder, kind):
                return importlib.machinery.ModuleSpec(fullname, self, origin=str(folder / kind))
        return None

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        """A placeholder module, replaced by :meth:`exec_module`."""
        return types.ModuleType(spec.name)

    def exec_module(self, module: types.ModuleType) -> None:
        """Read the package's definitions and put its ``msg`` or ``srv`` module in place.

        Raises:
            MessageDefinitionError: if a definition is invalid or names an unknown type.
        """
        package, _, kind = module.__name__.partition(".")
        origin = module.__spec__.origin if module.__spec__ else None
        folder = Path(str(origin)).parent
        sys.modules[module.__name__] = getattr(messages.add_package(package, folder), kind)


def _has_definitions(folder: Path, kind: Optional[str] = None) -> bool:
    """Whether ``folder`` holds ``msg/*.msg`` or ``srv/*.srv`` files not built into a module."""
    for each in [kind] if kind else ["msg", "srv"]:
        found = folder / str(each)
        try:
            if (
                found.is_dir()
                and not (found / "__init__.py").exists()
                and not (folder / f"{each}.py").exists()
                and any(found.glob(f"*.{each}"))
            ):
                return True
        except OSError:  # unreadable, or not a folder name at all
            continue
    return False


def _cwd() -> Path:
    try:
        return Path.cwd()
    except OSError:  # the current folder was deleted
        return Path("/nonexistent")


def _real_rospy_in_use() -> bool:
    found = sys.modules.get("rospy")
    return found is not None and not _is_ours(found)


#: The names the finder serves: top-level name -> its module names.
_SERVED: Dict[str, List[str]] = {top: list(modules) for top, modules in _aliases().items()}


def _before_path_finder(kind: type) -> None:
    """Place a ``kind`` finder just before Python's path finder, unless one is placed."""
    finders = sys.meta_path
    if not any(isinstance(finder, kind) for finder in finders):
        where = next(
            (i for i, f in enumerate(finders) if f is importlib.machinery.PathFinder),
            len(finders),
        )
        finders.insert(where, kind())


def _register_finder() -> None:
    if not any(isinstance(finder, RobotImports) for finder in sys.meta_path):
        sys.meta_path.append(RobotImports())
    # Before Python's path finder: it would make a package folder a namespace package, and it
    # finds dt_apriltags, whose Detector the fix replaces the clean-up of.
    _before_path_finder(apriltags.AprilTagsFix)
    _before_path_finder(PackageDefinitions)
    apriltags.fix_loaded()


_register_finder()


#: The process's own command line, before any node script set its own.
_PROCESS_ARGV: Dict[str, List[str]] = {}


def node_script(path: Union[str, Path], *args: str) -> Callable[[], None]:
    """A node written as a script, ready to launch: ``graph.launch(node_script("talker.py"))``.

    The script runs as ``python talker.py ARGS`` would run it on a robot: as ``__main__``,
    with ``sys.argv`` its path and ``args`` while it starts, and its folder first on the
    import path (so a package of its own beside it imports). Its robot imports (``rospy``, the
    message packages, ``duckietown.dtros``) are the in-process graph's wherever no real ROS is
    on the path, as for any code; launch it inside ``modules_installed(replace_real=True)``
    to use them even there.

    Raises:
        FileNotFoundError: if there is no such file (when the node starts).
    """
    script = Path(path).resolve()

    def run_script() -> None:
        if not script.is_file():
            raise FileNotFoundError(f"There is no node script {script}.")
        folder = str(script.parent)
        if folder not in sys.path:
            sys.path.insert(0, folder)
        _PROCESS_ARGV.setdefault("argv", sys.argv)
        sys.argv = argv = [str(script), *args]
        # Run it as __main__ without taking sys.modules["__main__"] (runpy would, for as long
        # as the node lives, and a new process started meanwhile would run the script).
        namespace = {"__name__": "__main__", "__file__": str(script), "__builtins__": __builtins__}
        code = compile(script.read_text(encoding="utf-8"), str(script), "exec")
        try:
            exec(code, namespace)
        finally:
            if sys.argv is argv:  # no other script has started since
                sys.argv = _PROCESS_ARGV["argv"]

    run_script.__name__ = script.stem
    return run_script
