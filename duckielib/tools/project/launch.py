"""What a project's launcher starts: its lines and launch files read into nodes.

Laptop side; never deployed.
"""

# Over 600 lines: one reader turns a launcher's shell lines and roslaunch's XML (substitutions,
# scopes, includes) into the same node specs, as roslaunch reads them.

from __future__ import annotations

import os
import re
import shlex
import xml.parsers.expat
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import yaml

from duckielib.tools.project.shell import expand
from duckielib.tools.project.workspace import PathLike, ProjectError, Workspace

__all__ = ["Launched", "NodeSpec", "launched_nodes"]

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
        stage: when it starts: 0 at once; 1 once the launcher's first command that runs in
            the foreground (no ``dt-exec``, no ``&``) has ended, and so on, as bash runs them.
        foreground: whether its launcher line runs in the foreground (bash waits for it).
        launcher: the launcher that starts it ("" for a launch file or script run alone).
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
    stage: int = 0
    foreground: bool = False
    launcher: str = ""

    @property
    def label(self) -> str:
        """The node's name in its namespace, for the printout."""
        base = self.name or self.script.stem
        return self.namespace.rstrip("/") + "/" + base


@dataclass
class Launched:
    """What a launcher starts: its nodes, the global parameters, and notes on what was left.

    ``environment`` holds what the launcher exports for the nodes (``export NAME=value``).
    """

    nodes: List[NodeSpec] = field(default_factory=list)
    params: Dict[str, Any] = field(default_factory=dict)
    notes: List[str] = field(default_factory=list)
    environment: Dict[str, str] = field(default_factory=dict)


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
    #: The environment roslaunch runs in: the laptop's, with what the launcher exports.
    env: Dict[str, str] = field(default_factory=lambda: dict(os.environ))

    def where(self, element: _Element) -> str:
        return f"{self.file}, line {element.line}"


_SUBSTITUTION = re.compile(r"\$\((\w+)((?:\s+[^()\s]+)*)\s*\)")


#: What ``$(eval ...)`` may call of Python's builtins, as roslaunch allows.
_EVAL_BUILTINS = {"list": list, "dict": dict, "map": map, "str": str, "float": float, "int": int}


def _auto(text: str) -> Any:
    """An argument's value in ``$(eval)``, typed as roslaunch types it: number, bool or string."""
    try:
        if "." in text:
            return float(text)
        if "_" not in text:
            return int(text)
    except ValueError:
        pass
    if text.lower() in ("true", "false"):
        return text.lower() == "true"
    return text


def _evaluate(expression: str, scope: _Scope, element: _Element, workspace: Workspace) -> str:
    """``$(eval EXPRESSION)`` as roslaunch evaluates it: Python, with the arguments as names.

    As in roslaunch, an argument's value is typed (``"0.6"`` is 0.6, ``"false"`` is False),
    by its name and by ``arg('name')`` alike.
    """

    def arg(name: str) -> Any:
        return _auto(_substitute(f"$(arg {name})", scope, element, workspace))

    names: Dict[str, Any] = {
        **{name: _auto(value) for name, value in scope.args.items()},
        "arg": arg,
        "find": lambda package: str(workspace.find(package)),
        "env": lambda name: _substitute(f"$(env {name})", scope, element, workspace),
        "optenv": lambda name, default="": scope.env.get(name, default),
        "dirname": lambda: str(scope.file.parent),
        "anon": lambda name: f"{name}_{os.getpid()}",
        "true": True,
        "false": False,
    }
    try:
        value = eval(expression, {"__builtins__": _EVAL_BUILTINS}, names)
    except ProjectError:
        raise
    except Exception as error:
        raise ProjectError(
            f"{scope.where(element)}: $(eval {expression}) fails: {type(error).__name__}: {error}."
        ) from None
    return str(value)


def _substitute(text: str, scope: _Scope, element: _Element, workspace: Workspace) -> str:
    """``text`` with its ``$(find ...)``, ``$(arg ...)``, ``$(env ...)``... resolved.

    ``$(eval ...)`` is a Python expression; as in roslaunch it must be the whole value.
    """
    stripped = text.strip()
    if stripped.startswith("$(eval ") and stripped.endswith(")"):
        return _evaluate(stripped[len("$(eval ") : -1], scope, element, workspace)

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
            if words[0] not in scope.env:
                raise ProjectError(
                    f"{scope.where(element)} uses $(env {words[0]}), which is not set; set it, "
                    f"or use $(optenv {words[0]} default)."
                )
            return scope.env[words[0]]
        if command == "optenv" and words:
            return scope.env.get(words[0], " ".join(words[1:]))
        if command == "dirname" and not words:
            return str(scope.file.parent)
        if command == "anon" and len(words) == 1:
            return f"{words[0]}_{os.getpid()}"
        raise ProjectError(
            f"{scope.where(element)} uses $({command}{match[2]}), which duckie run does not "
            "resolve; it resolves $(find), $(arg), $(env), $(optenv), $(dirname), $(anon) and "
            "$(eval) (as the whole value)."
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

    def __init__(self, workspace: Workspace, launched: Optional[Launched] = None) -> None:
        self.workspace = workspace
        self.launched = Launched() if launched is None else launched
        #: The launcher's variables (the laptop's environment, then what its lines set).
        self.variables: Dict[str, str] = dict(os.environ)
        #: The environment of what the launcher starts: the laptop's and what it exports.
        self.environment: Dict[str, str] = dict(os.environ)
        for names in (self.variables, self.environment):
            names.setdefault("VEHICLE_NAME", "duckiebot")  # as Duckietown's environment sets it

    def read(self, path: Path, args: Dict[str, str], namespace: str = "/") -> None:
        """Read a launch file given ``roslaunch``'s ``name:=value`` arguments.

        As roslaunch does, the arguments of the command line are there for ``$(arg ...)``
        even where the file does not declare them.
        """
        root = _parse_xml(path)
        scope = _Scope(path, dict(args), namespace, {}, self.environment)
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
        inner = _Scope(scope.file, scope.args, namespace, dict(scope.remap), scope.env)
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
            why = (
                "duckie run records every topic itself, into run.bag"
                if package == "rosbag"
                else "the virtual Duckiebot runs the robot's own drivers itself"
            )
            self.launched.notes.append(
                f"{where}: node {kind} of package {package} is not in this project and is left "
                f"out ({why})."
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
        inner = _Scope(scope.file, scope.args, namespace, spec.remap, scope.env)
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
        inner = _Scope(path, {}, namespace, dict(scope.remap), scope.env)
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


def _assignments(words: List[str], where: str) -> Dict[str, str]:
    """The ``name:=value`` words of a roslaunch command line, by name.

    Raises:
        ProjectError: for a word that is none, as roslaunch stops at it.
    """
    found: Dict[str, str] = {}
    for word in words:
        name, sep, value = word.partition(":=")
        if not sep:
            raise ProjectError(
                f"{where}: roslaunch takes its arguments as name:=value after the package and "
                f"the launch file, and {word!r} is none (roslaunch would look for a file of "
                "that name and stop)."
            )
        found[name] = value
    return found


def launched_nodes(
    path: PathLike, launcher: Union[str, Sequence[str]] = "default"
) -> Tuple[Workspace, Launched]:
    """What ``duckie run PATH`` would start: the project's workspace and its nodes.

    Args:
        path: a project folder (its ``launchers/<launcher>.sh`` is read), a launch file or a
            node script inside a project.
        launcher: the launcher's name, without ``.sh``; or several, run together as
            ``dts devel run`` runs each in a container of its own (each with its own
            variables, its nodes on the one robot).

    Raises:
        ProjectError: with the file and line, for what cannot be run.
    """
    target = Path(path)
    if not target.exists():
        raise ProjectError(f"There is no file or folder {target}.")
    workspace = Workspace.around(target)
    launched = Launched()
    if target.is_file() and target.suffix in (".launch", ".xml"):
        reader = _LaunchReader(workspace, launched)
        reader.read(target.resolve(), {})
    elif target.is_file():
        launched.nodes.append(_script_node(workspace, target.resolve(), [], str(target)))
    else:
        for name in [launcher] if isinstance(launcher, str) else launcher:
            _read_launcher(workspace, _LaunchReader(workspace, launched), name)
    if not launched.nodes:
        left = "".join(f" {note[0].upper()}{note[1:]}" for note in launched.notes)
        raise ProjectError(f"{path} starts no node of the project.{left}")
    return workspace, launched


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
    stage = 0
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        where = f"{path}, line {number}"
        words, background = _launcher_words(line, where, reader.variables)
        if not words or words[0] in _SET_UP + _SHELL or words[0].startswith("#!"):
            continue
        if words[0] == "export" or re.fullmatch(r"\w+=.*", words[0]):
            for word in words[1:] if words[0] == "export" else words:
                name, _, value = word.partition("=")
                reader.variables[name] = value
                if words[0] == "export" or name in reader.environment:
                    reader.environment[name] = reader.launched.environment[name] = value
            continue
        before = len(reader.launched.nodes)
        _launcher_line(workspace, reader, words, where)
        started = reader.launched.nodes[before:]
        for spec in started:
            spec.launcher, spec.stage, spec.foreground = launcher, stage, not background
        if started and not background:
            stage += 1  # bash runs the next line once this one has ended


def _launcher_words(line: str, where: str, variables: Dict[str, str]) -> Tuple[List[str], bool]:
    """A launcher line's words, variables expanded, without ``dt-exec`` or a final ``&``.

    Also whether the line runs in the background (``dt-exec`` or ``&``), as bash reads it.
    """
    try:
        words = shlex.split(line, comments=True)
    except ValueError as error:
        raise ProjectError(f"{where}: {error}.") from None
    words = [expand(word, variables, missing="") if "$" in word else word for word in words]
    background = bool(words) and words[0] == "dt-exec"
    if background:
        words = words[1:]
    while words and words[-1] in ("&", ";"):
        background = background or words[-1] == "&"
        words = words[:-1]
    return words, background


def _launcher_line(
    workspace: Workspace, reader: _LaunchReader, words: List[str], where: str
) -> None:
    """Read what one launcher line starts: a roslaunch, a rosrun or a python3 script."""
    command, rest = words[0], words[1:]
    if command == "roslaunch":
        rest = [word for word in rest if not word.startswith("--")]
        launch, rest = _launch_file(workspace, rest, where)
        reader.read(launch.resolve(), _assignments(rest, where))
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
