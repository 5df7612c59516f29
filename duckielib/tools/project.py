"""A Duckietown project on the virtual Duckiebot, as ``dts devel run`` runs it on the robot.

A project in Duckietown's template layout holds catkin packages under ``packages/`` (each with
its ``package.xml``, node scripts, ``launch/`` files, its own ``msg/`` and ``srv/``, Python
packages under ``include/``) and ``launchers/*.sh``, the scripts ``dts devel run`` starts
(``default.sh`` unless another is named). :func:`run_project` reads what the launcher runs
(its ``roslaunch``, ``rosrun`` and ``python3`` lines), the launch files they name (arguments,
groups, nodes, parameters, ``rosparam``, remappings, includes and the ``$(...)``
substitutions), and starts every node, unchanged, on a :class:`~duckielib.sim.VirtualDuckiebot`
named ``VEHICLE_NAME``, its packages resolved as a catkin workspace resolves them
(:class:`Workspace`) from whatever folder the command runs in.

Laptop side; never deployed.
"""

from __future__ import annotations

import contextlib
import importlib.abc
import importlib.machinery
import importlib.util
import json
import os
import re
import shlex
import sys
import time
import traceback
import types
import xml.parsers.expat
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import yaml

from duckielib.errors import DuckielibError
from duckielib.tools.robot_env import node_clocks, robot_data, windows_saved

__all__ = [
    "NodeSpec",
    "ProjectError",
    "ProjectRun",
    "Workspace",
    "launched_nodes",
    "run_project",
]

PathLike = Union[str, "os.PathLike[str]"]

#: Launcher lines that only set the container up on the robot: nothing to run here.
_SET_UP = (
    "source",
    ".",
    "set",
    "dt-launchfile-init",
    "dt-launchfile-join",
    "echo",
    "sleep",
    "wait",
    "roscore",  # the virtual Duckiebot's graph is the master
)
#: The shell's own words: a launcher's ``if ... fi`` around lines runs the lines inside.
_SHELL = ("if", "then", "else", "elif", "fi", "do", "done", "for", "while", "until", "case", "esac")
#: Where a node script may sit in its package, searched first (rosrun searches them all).
_SCRIPT_FOLDERS = ("src", "scripts", "nodes", "bin", "")
#: Topics a run does not record: the camera's images (about 30 large messages a second).
_NOT_RECORDED = r".*/camera_node/image/compressed"


class ProjectError(DuckielibError):
    """A project, launcher or launch file that cannot be run, said in one sentence."""


@dataclass(frozen=True)
class Package:
    """One catkin package of a project.

    Attributes:
        name: the package's name, from its ``package.xml``.
        folder: the package's folder.
        python: the folders its Python packages are installed from (``include/`` in
            Duckietown's packages, or what its ``setup.py`` names), as catkin installs them.
    """

    name: str
    folder: Path
    python: Tuple[Path, ...]


class Workspace:
    """The catkin packages of a project, found from any folder inside it.

    Args:
        root: the project's folder (the one holding ``packages/``), or a package's.

    Raises:
        ProjectError: if the folder holds no package.
    """

    def __init__(self, root: PathLike) -> None:
        self.root = Path(root).resolve()
        search = self.root / "packages" if (self.root / "packages").is_dir() else self.root
        self.packages: Dict[str, Package] = {}
        for folder in _package_folders(search):
            name = _package_name(folder)
            if name not in self.packages:  # the first found wins, as in a catkin workspace
                self.packages[name] = Package(name, folder, _python_folders(folder))
        self.packages = dict(sorted(self.packages.items()))
        if not self.packages:
            raise ProjectError(
                f"{self.root} holds no catkin package (a folder with a package.xml): give the "
                "project's folder, the one with packages/ and launchers/ in it."
            )

    @classmethod
    def around(cls, path: PathLike) -> Workspace:
        """The workspace of the project that holds ``path`` (a file or folder inside it)."""
        start = Path(path).resolve()
        folder = start if start.is_dir() else start.parent
        for candidate in [folder, *folder.parents]:
            if (candidate / "packages").is_dir() or (candidate / "launchers").is_dir():
                return cls(candidate)
        for candidate in [folder, *folder.parents]:
            if (candidate / "package.xml").is_file():
                return cls(candidate.parent)
        raise ProjectError(
            f"{start} is not inside a Duckietown project: no folder above it holds packages/, "
            "launchers/ or a package.xml."
        )

    def find(self, name: str) -> Path:
        """A package's folder, as ``$(find name)`` and ``rospack find`` give it.

        Raises:
            ProjectError: if the project has no such package.
        """
        if name not in self.packages:
            raise ProjectError(
                f"The project has no package {name!r}; its packages are: "
                f"{', '.join(self.packages)}."
            )
        return self.packages[name].folder

    def executable(self, package: str, name: str) -> Path:
        """The node script ``name`` of a package, as ``rosrun package name`` finds it.

        Raises:
            ProjectError: if the package has no such file.
        """
        folder = self.find(package)
        for sub in _SCRIPT_FOLDERS:
            candidate = folder / sub / name
            if candidate.is_file():
                return candidate
        found = sorted(path for path in folder.rglob(name) if path.is_file())
        if not found:
            raise ProjectError(f"The package {package} has no node script {name}.")
        return found[0]

    @contextlib.contextmanager
    def importable(self) -> Iterator[None]:
        """While inside, the project's packages import by name, from any working folder.

        ``import my_package`` and ``from my_package.srv import MyService`` find the package's
        Python code and its own ``msg/`` and ``srv/`` (a sibling package's too), as catkin's
        devel space makes them importable on the robot.
        """
        added = [str(path) for package in self.packages.values() for path in package.python]
        added = [path for path in dict.fromkeys(added) if path not in sys.path]
        finder = _PackageFinder(self)
        sys.path[:0] = added
        sys.meta_path.insert(0, finder)
        try:
            yield
        finally:
            sys.meta_path.remove(finder)
            for path in added:
                with contextlib.suppress(ValueError):
                    sys.path.remove(path)
            for name in list(sys.modules):
                if name.partition(".")[0] in self.packages:
                    del sys.modules[name]


def _package_folders(search: Path) -> List[Path]:
    """The catkin packages under ``search``, found as catkin crawls for them.

    A folder with a ``package.xml`` is a package (nothing below it is searched); a folder with
    ``CATKIN_IGNORE`` is skipped.
    """
    found: List[Path] = []
    for folder, subfolders, files in os.walk(search):
        if "CATKIN_IGNORE" in files:
            subfolders.clear()
        elif "package.xml" in files:
            found.append(Path(folder))
            subfolders.clear()
        else:
            subfolders[:] = sorted(each for each in subfolders if not each.startswith("."))
    return found


def _package_name(folder: Path) -> str:
    """A package's name, from its ``package.xml`` (its folder's name if it says none)."""
    text = (folder / "package.xml").read_text(encoding="utf-8", errors="replace")
    match = re.search(r"<name>\s*([^<\s]+)\s*</name>", text)
    return match[1] if match else folder.name


def _python_folders(folder: Path) -> Tuple[Path, ...]:
    """The folders a catkin package's ``setup.py`` installs Python packages from."""
    setup = folder / "setup.py"
    named: List[str] = []
    if setup.is_file():
        text = setup.read_text(encoding="utf-8", errors="replace")
        named = re.findall(r"""package_dir\s*=\s*\{\s*['"]['"]\s*:\s*['"]([^'"]+)['"]""", text)
    candidates = [folder / each for each in named] or [folder / "include"]
    return tuple(path for path in candidates if path.is_dir())


class _PackageFinder(importlib.abc.MetaPathFinder):
    """Finds a workspace's packages by name: their Python code, ``msg/`` and ``srv/``."""

    def __init__(self, workspace: Workspace) -> None:
        self.workspace = workspace

    def find_spec(
        self, fullname: str, path: Optional[Sequence[str]] = None, target: object = None
    ) -> Optional[importlib.machinery.ModuleSpec]:
        package = self.workspace.packages.get(fullname)
        if package is None:
            return None
        code = [folder / fullname for folder in package.python if (folder / fullname).is_dir()]
        locations = [str(each) for each in code] + [str(package.folder)]
        init = next(
            (each / "__init__.py" for each in code if (each / "__init__.py").is_file()), None
        )
        if init is not None:
            return importlib.util.spec_from_file_location(
                fullname, init, submodule_search_locations=locations
            )
        spec = importlib.machinery.ModuleSpec(fullname, _EmptyPackage(), is_package=True)
        spec.submodule_search_locations = locations
        return spec


class _EmptyPackage(importlib.abc.Loader):
    """A package with no ``__init__.py``: its ``__path__`` is all it has."""

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        return types.ModuleType(spec.name)

    def exec_module(self, module: types.ModuleType) -> None:
        return None


@dataclass
class NodeSpec:
    """One node a launcher starts, as roslaunch would start it.

    Attributes:
        name: the node's name (roslaunch's ``name``; None keeps the one in ``init_node``).
        namespace: its namespace, for example ``/duckiebot``.
        package: its package.
        script: its node script.
        args: its command-line arguments.
        params: its private parameters (``~name``).
        remap: its remappings, ``{"from": "to"}``.
        required: whether the run ends when it ends (roslaunch's ``required``).
        where: the launch file and line (or launcher line) that starts it.
    """

    name: Optional[str]
    namespace: str
    package: str
    script: Path
    args: List[str] = field(default_factory=list)
    params: Dict[str, Any] = field(default_factory=dict)
    remap: Dict[str, str] = field(default_factory=dict)
    required: bool = False
    where: str = ""

    @property
    def label(self) -> str:
        """The node's name in its namespace, for the printout."""
        base = self.name or self.script.stem
        return self.namespace.rstrip("/") + "/" + base


@dataclass
class Launched:
    """What a launcher starts: its nodes, the global parameters, and notes on what was left."""

    nodes: List[NodeSpec] = field(default_factory=list)
    params: Dict[str, Any] = field(default_factory=dict)
    notes: List[str] = field(default_factory=list)


@dataclass
class _Element:
    tag: str
    attrs: Dict[str, str]
    line: int
    children: List[_Element] = field(default_factory=list)
    text: str = ""


def _parse_xml(path: Path) -> _Element:
    """A launch file's elements, each with its line (for the messages)."""
    parser = xml.parsers.expat.ParserCreate()
    root: List[_Element] = []
    stack: List[_Element] = []

    def start(tag: str, attrs: Dict[str, str]) -> None:
        element = _Element(tag, dict(attrs), parser.CurrentLineNumber)
        (stack[-1].children if stack else root).append(element)
        stack.append(element)

    def end(tag: str) -> None:
        stack.pop()

    def text(data: str) -> None:
        if stack:
            stack[-1].text += data

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = text
    try:
        parser.Parse(path.read_bytes(), True)
    except OSError as error:
        raise ProjectError(f"The launch file {path} cannot be read: {error.strerror}.") from None
    except xml.parsers.expat.ExpatError as error:
        raise ProjectError(
            f"The launch file {path} does not parse, line {error.lineno}: "
            f"{xml.parsers.expat.ErrorString(error.code)}."
        ) from None
    if not root or root[0].tag != "launch":
        raise ProjectError(f"The launch file {path} does not start with <launch>.")
    return root[0]


@dataclass
class _Scope:
    """Where a launch file's element is read: its file, arguments, namespace, remappings."""

    file: Path
    args: Dict[str, str]
    namespace: str
    remap: Dict[str, str]

    def where(self, element: _Element) -> str:
        return f"{self.file}, line {element.line}"


_SUBSTITUTION = re.compile(r"\$\((\w+)((?:\s+[^()\s]+)*)\s*\)")


def _substitute(text: str, scope: _Scope, element: _Element, workspace: Workspace) -> str:
    """``text`` with its ``$(find ...)``, ``$(arg ...)``, ``$(env ...)``... resolved."""

    def one(match: re.Match[str]) -> str:
        command, words = match[1], match[2].split()
        if command == "find" and len(words) == 1:
            return str(workspace.find(words[0]))
        if command == "arg" and len(words) == 1:
            if words[0] not in scope.args:
                raise ProjectError(
                    f"{scope.where(element)} uses $(arg {words[0]}), an argument that is not "
                    "declared (<arg name=...>) or was given no value."
                )
            return scope.args[words[0]]
        if command == "env" and len(words) == 1:
            if words[0] not in os.environ:
                raise ProjectError(
                    f"{scope.where(element)} uses $(env {words[0]}), which is not set; set it, "
                    f"or use $(optenv {words[0]} default)."
                )
            return os.environ[words[0]]
        if command == "optenv" and words:
            return os.environ.get(words[0], " ".join(words[1:]))
        if command == "dirname" and not words:
            return str(scope.file.parent)
        if command == "anon" and len(words) == 1:
            return f"{words[0]}_{os.getpid()}"
        raise ProjectError(
            f"{scope.where(element)} uses $({command}{match[2]}), which duckie run does not "
            "resolve; it resolves $(find), $(arg), $(env), $(optenv), $(dirname) and $(anon)."
        )

    return _SUBSTITUTION.sub(one, text)


def _value(text: str, kind: Optional[str], where: str) -> Any:
    """A ``<param>`` value as roslaunch types it (``type``, or guessed from the text)."""
    if kind in ("str", "string"):
        return text
    if kind == "yaml":
        return yaml.safe_load(text)
    try:
        if kind == "int" or (kind is None and re.fullmatch(r"[+-]?\d+", text.strip())):
            return int(text)
        if kind == "double" or (kind is None and _is_float(text)):
            return float(text)
    except ValueError:
        raise ProjectError(f"{where}: {text!r} is not a {kind}.") from None
    if kind == "bool" or (kind is None and text.strip().lower() in ("true", "false")):
        return text.strip().lower() in ("true", "1")
    return text


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _truthy(value: str, where: str) -> bool:
    value = value.strip().lower()
    if value in ("true", "1"):
        return True
    if value in ("false", "0"):
        return False
    raise ProjectError(f"{where}: if/unless take true or false, not {value!r}.")


def _joined(namespace: str, name: str) -> str:
    """A name resolved in a namespace (global names kept)."""
    if name.startswith("/"):
        return name
    return namespace.rstrip("/") + "/" + name


class _LaunchReader:
    """Reads launch files into a :class:`Launched`."""

    def __init__(self, workspace: Workspace) -> None:
        self.workspace = workspace
        self.launched = Launched()

    def read(self, path: Path, args: Dict[str, str], namespace: str = "/") -> None:
        """Read a launch file given ``roslaunch``'s ``name:=value`` arguments.

        As roslaunch does, the arguments of the command line are there for ``$(arg ...)``
        even where the file does not declare them.
        """
        root = _parse_xml(path)
        scope = _Scope(path, dict(args), namespace, {})
        self._children(root, scope, given=args)

    def _attr(self, element: _Element, scope: _Scope, name: str, default: Any = None) -> Any:
        if name not in element.attrs:
            return default
        return _substitute(element.attrs[name], scope, element, self.workspace)

    def _needed(self, element: _Element, scope: _Scope, name: str) -> str:
        value = self._attr(element, scope, name)
        if value is None:
            raise ProjectError(f"{scope.where(element)}: <{element.tag}> needs {name}=.")
        return str(value)

    def _included(self, element: _Element, scope: _Scope) -> bool:
        where = scope.where(element)
        if "if" in element.attrs and not _truthy(self._attr(element, scope, "if"), where):
            return False
        return not (
            "unless" in element.attrs and _truthy(self._attr(element, scope, "unless"), where)
        )

    def _children(self, parent: _Element, scope: _Scope, given: Dict[str, str]) -> None:
        for element in parent.children:
            if not self._included(element, scope):
                continue
            handler = getattr(self, f"_{element.tag}", None)
            if element.tag == "arg":
                self._arg(element, scope, given)
            elif handler is not None:
                handler(element, scope)
            else:
                self.launched.notes.append(
                    f"{scope.where(element)}: <{element.tag}> is left out (duckie run reads "
                    "arg, group, node, param, rosparam, remap and include)."
                )

    def _arg(self, element: _Element, scope: _Scope, given: Dict[str, str]) -> None:
        name = self._needed(element, scope, "name")
        if "value" in element.attrs:
            scope.args[name] = self._attr(element, scope, "value")
        elif name in given:
            scope.args[name] = given[name]
        elif "default" in element.attrs:
            scope.args[name] = self._attr(element, scope, "default")

    def _group(self, element: _Element, scope: _Scope) -> None:
        namespace = scope.namespace
        if "ns" in element.attrs:
            namespace = _joined(scope.namespace, self._attr(element, scope, "ns"))
        inner = _Scope(scope.file, scope.args, namespace, dict(scope.remap))
        self._children(element, inner, given={})

    def _remap(self, element: _Element, scope: _Scope) -> None:
        source = self._needed(element, scope, "from")
        scope.remap[source] = self._needed(element, scope, "to")

    def _param(
        self, element: _Element, scope: _Scope, private: Optional[Dict[str, Any]] = None
    ) -> None:
        name = self._needed(element, scope, "name")
        kind = self._attr(element, scope, "type")
        where = scope.where(element)
        if "value" in element.attrs:
            value = _value(self._attr(element, scope, "value"), kind, where)
        elif "textfile" in element.attrs:
            value = Path(self._attr(element, scope, "textfile")).read_text(encoding="utf-8")
        else:
            raise ProjectError(
                f"{where}: <param name={name!r}> needs value= or textfile= (duckie run does not "
                "run command=)."
            )
        self._set(name, value, scope, private)

    def _set(self, name: str, value: Any, scope: _Scope, private: Optional[Dict[str, Any]]) -> None:
        if private is not None and not name.startswith("/"):
            private[name.lstrip("~")] = value
        else:
            self.launched.params[_joined(scope.namespace, name.lstrip("~"))] = value

    def _rosparam(
        self, element: _Element, scope: _Scope, private: Optional[Dict[str, Any]] = None
    ) -> None:
        command = self._attr(element, scope, "command", "load")
        where = scope.where(element)
        if command != "load":
            self.launched.notes.append(f"{where}: <rosparam command={command!r}> is left out.")
            return
        if "file" in element.attrs:
            path = Path(self._attr(element, scope, "file"))
            try:
                text = path.read_text(encoding="utf-8")
            except OSError as error:
                raise ProjectError(f"{where}: cannot read {path}: {error.strerror}.") from None
        else:
            text = element.text
            if _truthy(self._attr(element, scope, "subst_value", "false"), where):
                text = _substitute(text, scope, element, self.workspace)
        try:
            loaded = yaml.safe_load(text)
        except yaml.YAMLError as error:
            raise ProjectError(f"{where}: the parameters are not YAML: {error}") from None
        if loaded is None:
            return
        ns = self._attr(element, scope, "ns", "")
        param = self._attr(element, scope, "param", "")
        base = "/".join(part for part in (ns, param) if part)
        if not isinstance(loaded, dict) or param:
            self._set(base or "value", loaded, scope, private)
            return
        for key, value in loaded.items():
            self._set(f"{base}/{key}" if base else str(key), value, scope, private)

    def _node(self, element: _Element, scope: _Scope) -> None:
        package = self._needed(element, scope, "pkg")
        kind = self._needed(element, scope, "type")
        where = scope.where(element)
        if package not in self.workspace.packages:
            self.launched.notes.append(
                f"{where}: node {kind} of package {package} is not in this project and is left "
                "out (the virtual Duckiebot runs the robot's own drivers itself)."
            )
            return
        namespace = scope.namespace
        if "ns" in element.attrs:
            namespace = _joined(namespace, self._attr(element, scope, "ns"))
        spec = NodeSpec(
            name=self._attr(element, scope, "name"),
            namespace=namespace,
            package=package,
            script=self.workspace.executable(package, kind),
            args=shlex.split(self._attr(element, scope, "args", "")),
            remap=dict(scope.remap),
            required=_truthy(self._attr(element, scope, "required", "false"), where),
            where=where,
        )
        inner = _Scope(scope.file, scope.args, namespace, spec.remap)
        for child in element.children:
            if not self._included(child, inner):
                continue
            if child.tag == "param":
                self._param(child, inner, spec.params)
            elif child.tag == "rosparam":
                self._rosparam(child, inner, spec.params)
            elif child.tag == "remap":
                self._remap(child, inner)
            else:
                self.launched.notes.append(
                    f"{inner.where(child)}: <{child.tag}> in a node is left out."
                )
        self.launched.nodes.append(spec)

    def _include(self, element: _Element, scope: _Scope) -> None:
        path = Path(self._needed(element, scope, "file"))
        namespace = scope.namespace
        if "ns" in element.attrs:
            namespace = _joined(namespace, self._attr(element, scope, "ns"))
        given = dict(scope.args) if "pass_all_args" in element.attrs else {}
        for child in element.children:
            if child.tag == "arg" and self._included(child, scope):
                given[self._needed(child, scope, "name")] = self._needed(child, scope, "value")
        root = _parse_xml(path)
        inner = _Scope(path, {}, namespace, dict(scope.remap))
        self._children(root, inner, given=given)


def _launch_file(workspace: Workspace, words: List[str], where: str) -> Tuple[Path, List[str]]:
    """The launch file of a ``roslaunch`` command line, and the rest of its words."""
    if words and words[0].endswith((".launch", ".xml")):
        return Path(words[0]), words[1:]
    if len(words) >= 2:
        folder = workspace.find(words[0])
        found = sorted(folder.rglob(words[1]))
        if not found:
            raise ProjectError(f"{where}: the package {words[0]} has no launch file {words[1]}.")
        return found[0], words[2:]
    raise ProjectError(f"{where}: roslaunch needs a package and a launch file.")


def _assignments(words: List[str], where: str) -> Tuple[Dict[str, str], List[str]]:
    """``name:=value`` words apart from the others."""
    given, rest = {}, []
    for word in words:
        name, sep, value = word.partition(":=")
        if sep:
            given[name] = value
        else:
            rest.append(word)
    return given, rest


def launched_nodes(path: PathLike, launcher: str = "default") -> Tuple[Workspace, Launched]:
    """What ``duckie run PATH`` would start: the project's workspace and its nodes.

    Args:
        path: a project folder (its ``launchers/<launcher>.sh`` is read), a launch file or a
            node script inside a project.
        launcher: the launcher's name, without ``.sh``.

    Raises:
        ProjectError: with the file and line, for what cannot be run.
    """
    target = Path(path)
    if not target.exists():
        raise ProjectError(f"There is no file or folder {target}.")
    workspace = Workspace.around(target)
    reader = _LaunchReader(workspace)
    if target.is_file() and target.suffix in (".launch", ".xml"):
        reader.read(target.resolve(), {})
    elif target.is_file():
        reader.launched.nodes.append(_script_node(workspace, target.resolve(), [], str(target)))
    else:
        _read_launcher(workspace, reader, launcher)
    if not reader.launched.nodes:
        raise ProjectError(f"{path} starts no node of the project.")
    return workspace, reader.launched


def _script_node(workspace: Workspace, script: Path, args: List[str], where: str) -> NodeSpec:
    package = next(
        (name for name, package in workspace.packages.items() if package.folder in script.parents),
        "",
    )
    return NodeSpec(None, "/", package, script, args, where=where)


def _read_launcher(workspace: Workspace, reader: _LaunchReader, launcher: str) -> None:
    folder = workspace.root / "launchers"
    path = folder / f"{launcher}.sh"
    if not path.is_file():
        there = sorted(each.stem for each in folder.glob("*.sh")) if folder.is_dir() else []
        raise ProjectError(
            f"The project {workspace.root} has no launcher {launcher!r}"
            + (f"; its launchers are: {', '.join(there)}." if there else " (no launchers/).")
        )
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        where = f"{path}, line {number}"
        words = _launcher_words(line, where)
        if not words or words[0] in _SET_UP + _SHELL or words[0].startswith("#!"):
            continue
        if words[0] == "export" or re.fullmatch(r"\w+=.*", words[0]):
            for word in words[1:] if words[0] == "export" else words:
                name, _, value = word.partition("=")
                os.environ[name] = value
            continue
        _launcher_line(workspace, reader, words, where)


def _launcher_words(line: str, where: str) -> List[str]:
    """A launcher line's words, its variables expanded, without ``dt-exec`` or a final ``&``."""
    try:
        words = shlex.split(line, comments=True)
    except ValueError as error:
        raise ProjectError(f"{where}: {error}.") from None
    words = [os.path.expandvars(word) if "$" in word else word for word in words]
    if words and words[0] == "dt-exec":
        words = words[1:]
    while words and words[-1] in ("&", ";"):
        words = words[:-1]
    return words


def _launcher_line(
    workspace: Workspace, reader: _LaunchReader, words: List[str], where: str
) -> None:
    """Read what one launcher line starts: a roslaunch, a rosrun or a python3 script."""
    command, rest = words[0], words[1:]
    if command == "roslaunch":
        rest = [word for word in rest if not word.startswith("--")]
        launch, rest = _launch_file(workspace, rest, where)
        given, _ = _assignments(rest, where)
        reader.read(launch.resolve(), given)
    elif command == "rosrun" and len(rest) >= 2:
        script = workspace.executable(rest[0], rest[1])
        reader.launched.nodes.append(_script_node(workspace, script, rest[2:], where))
    elif command in ("python", "python3") and rest and not rest[0].startswith("-"):
        script = (workspace.root / rest[0]).resolve()
        if not script.is_file():
            raise ProjectError(f"{where}: there is no script {rest[0]} in the project.")
        reader.launched.nodes.append(_script_node(workspace, script, rest[1:], where))
    else:
        raise ProjectError(
            f"{where} runs {command!r}, which duckie run cannot run here: it runs "
            "roslaunch, rosrun and python3 lines."
        )


@dataclass
class ProjectRun:
    """What a run of a project did.

    Attributes:
        folder: the run's folder (``run.bag``, ``log.txt``, ``summary.json``).
        nodes: each node's name and how it ended (``"running"`` when the run ended first).
        topics: messages recorded, by topic.
        notes: what the launch files held that the run left out.
        simulated: simulated seconds.
        wall: wall-clock seconds.
    """

    folder: Path
    nodes: Dict[str, str]
    topics: Dict[str, int]
    notes: List[str]
    simulated: float
    wall: float

    @property
    def files(self) -> Dict[str, Path]:
        """The run's files, by kind."""
        return {
            "bag": self.folder / "run.bag",
            "log": self.folder / "log.txt",
            "summary": self.folder / "summary.json",
        }

    def text(self) -> str:
        """What ``duckie run`` prints: the nodes, the topics they published, the files."""
        lines = [f"ran {len(self.nodes)} node(s) for {self.simulated:.1f} s (simulated):"]
        width = max(len(name) for name in self.nodes)
        lines += [f"  {name:<{width}}  {how}" for name, how in self.nodes.items()]
        lines.append("recorded:")
        width = max((len(topic) for topic in self.topics), default=0)
        lines += [f"  {topic:<{width}}  {count}" for topic, count in self.topics.items()]
        lines += [f"note: {note}" for note in self.notes]
        data = sorted(path for path in (self.folder / "data").rglob("*") if path.is_file())
        if data:
            lines.append(
                f"the nodes wrote {len(data)} file(s) to the robot's /data: they are in "
                f"{self.folder / 'data'}"
            )
        lines.append(f"wrote run.bag, log.txt, summary.json in {self.folder}")
        return "\n".join(lines)

    def summary(self) -> Dict[str, Any]:
        """The run as JSON-ready data."""
        return {
            "nodes": self.nodes,
            "topics": self.topics,
            "notes": self.notes,
            "simulated_s": round(self.simulated, 3),
            "wall_s": round(self.wall, 3),
        }


def _node_main(spec: NodeSpec, run: Any, ended: Dict[str, str]) -> Any:
    """A node's main code that notes in ``ended`` whether it ended or failed."""

    def node_main() -> None:
        try:
            run()
            ended[spec.label] = "ended"
        except BaseException:
            ended[spec.label] = "failed"
            raise

    node_main.__name__ = run.__name__
    return node_main


def _how_it_ended(how: Optional[str], spec: NodeSpec, simulated: float, seconds: float) -> str:
    if how == "ended":
        return "ended" + (" (required: the run ended with it)" if spec.required else "")
    if how == "failed":
        return "failed (its traceback is in log.txt)"
    if simulated >= seconds - 1e-6:
        return f"still running after {seconds:g} s, stopped"
    return "running, stopped when the run ended"


def run_project(
    path: PathLike,
    launcher: str = "default",
    noise: Any = "ideal",
    seed: int = 0,
    seconds: float = 30.0,
    out: PathLike = "runs/project",
) -> ProjectRun:
    """Run a Duckietown project's nodes on the virtual Duckiebot for ``seconds``.

    The run's bag (every topic but the camera's images), ``log.txt`` and ``summary.json`` are
    written in ``out``; what the nodes write to the robot's ``/data`` lands in ``out/data``,
    and the frames they show with ``cv2.imshow`` in ``out/windows`` (:mod:`.robot_env`). It
    ends after ``seconds`` of simulated time, or when a ``required`` node ends, or when every
    node has ended; the wheels are stopped in every case.

    Raises:
        ProjectError: for a project, launcher or launch file that cannot be run (the file and
            line said), or a node that fails when it starts.
    """
    from duckielib.bags import BagRecorder
    from duckielib.ros import Graph, node_script
    from duckielib.ros.graph import NodeCrashed
    from duckielib.ros.modules import modules_installed
    from duckielib.sim import VirtualDuckiebot
    from duckielib.sim.world import OPEN_MAT

    os.environ.setdefault("VEHICLE_NAME", "duckiebot")
    workspace, launched = launched_nodes(path, launcher)
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    files = {"bag": folder / "run.bag", "log": folder / "log.txt"}
    for each in files.values():
        each.unlink(missing_ok=True)
    graph = Graph(echo_logs=False)
    bot = VirtualDuckiebot(seed=seed, noise=noise, graph=graph, world=OPEN_MAT)
    for name, value in launched.params.items():
        graph.set_param(name, value)
    ended: Dict[str, str] = {}
    wall = time.perf_counter()
    path_before = list(sys.path)  # node scripts put their folders first, as on the robot
    notes = list(launched.notes)
    with contextlib.ExitStack() as robot:
        robot.enter_context(workspace.importable())
        robot.enter_context(modules_installed(replace_real=True))
        robot.enter_context(robot_data(folder / "data"))
        robot.enter_context(node_clocks(workspace.root, lambda: graph.time))
        robot.enter_context(windows_saved(folder / "windows", notes))
        for spec in launched.nodes:
            bot.launch(
                _node_main(spec, node_script(spec.script, *spec.args), ended),
                name=spec.name,
                namespace=spec.namespace,
                remap=spec.remap or None,
                params=spec.params or None,
            )
        recorder = BagRecorder(files["bag"], graph=graph, exclude=_NOT_RECORDED)
        required = [spec.label for spec in launched.nodes if spec.required]

        def over() -> bool:
            if any(label in ended for label in required):
                return True
            return len(ended) == len(launched.nodes)

        crash: Optional[BaseException] = None
        try:
            bot.run_until(over, seconds)
        except NodeCrashed as error:
            crash = error
        finally:
            at_end = dict(ended)
            bot.shutdown()
            recorder.close()
            files["log"].write_text(
                "\n".join(repr(record) for record in graph.log) + "\n", encoding="utf-8"
            )
            sys.path[:] = path_before
    run = ProjectRun(
        folder=folder,
        nodes={
            spec.label: _how_it_ended(at_end.get(spec.label), spec, bot.time, seconds)
            for spec in launched.nodes
        },
        topics=dict(sorted(recorder.counts.items())),
        notes=notes,
        simulated=bot.time,
        wall=time.perf_counter() - wall,
    )
    (folder / "summary.json").write_text(json.dumps(run.summary(), indent=2) + "\n")
    if crash is not None:
        raise ProjectError(
            f"{_crash_said(crash, workspace)} The run's bag and log are in {folder}."
        )
    return run


def _crash_said(crash: BaseException, workspace: Workspace) -> str:
    """A node's crash in a sentence, at the project's own line that raised."""
    cause = crash.__cause__ or crash
    node = str(getattr(crash, "node", "")).rsplit("/", 1)[-1] or "a node"
    frames = [
        frame
        for frame in traceback.extract_tb(cause.__traceback__)
        if workspace.root in Path(frame.filename).resolve().parents
    ]
    at = ""
    if frames:
        frame = frames[-1]
        at = f" at {Path(frame.filename).relative_to(workspace.root)}, line {frame.lineno}"
    said = f"The node {node} stopped with {type(cause).__name__}{at}: {cause}."
    if isinstance(cause, ModuleNotFoundError) and cause.name:
        said += " " + _install_hint(cause.name.partition(".")[0], workspace)
    return said


def _install_hint(module: str, workspace: Workspace) -> str:
    """How to get a module a node imports: from the project's ``dependencies-py3.txt``."""
    listed = workspace.root / "dependencies-py3.txt"
    wanted = re.sub(r"[-_.]+", "_", module).lower()
    if listed.is_file():
        for line in listed.read_text(encoding="utf-8", errors="replace").splitlines():
            requirement = line.split("#", 1)[0].strip()
            name = re.split(r"[\s<>=!~;\[]", requirement, maxsplit=1)[0]
            if name and re.sub(r"[-_.]+", "_", name).lower() == wanted:
                return (
                    f"The project lists {requirement} in dependencies-py3.txt, which dts devel "
                    f"build installs on the robot: install it here too, with "
                    f"'.venv/bin/pip install {requirement}'."
                )
    apt = workspace.root / "dependencies-apt.txt"
    if apt.is_file():
        ros_name = "-" + module.replace("_", "-").lower()
        for line in apt.read_text(encoding="utf-8", errors="replace").splitlines():
            package = line.split("#", 1)[0].strip()
            if package.startswith("ros-") and package.endswith(ros_name):
                return (
                    f"The project installs it on the robot from dependencies-apt.txt "
                    f"({package}), a ROS package the virtual Duckiebot does not serve: copy "
                    "what the node needs of it into the project, or run this node on the robot."
                )
    return (
        f"If {module} is a library your robot's image installs, install it here too "
        "(.venv/bin/pip install ...)."
    )
