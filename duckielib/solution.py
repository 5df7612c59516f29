"""The student contract: the graded functions, their export into a solution, and loading it.

A student writes the graded functions and classes in the notebooks. The cells that define them
carry the tag ``export``; :func:`export_solution` collects those cells from a folder of
notebooks into the text of one Python module, a *solution*. The library's runners, the
autograder and the robot nodes load a solution with :func:`load_solution` and call its parts
by the names and parameters of :data:`CONTRACT`, the names the student met in the notebooks.
The reference solution is the export of the instructors' ``solutions/``; a student's is the
export of their copy of ``course/``.

This module imports only the standard library: it runs on the robot (Python 3.8).
"""

from __future__ import annotations

import ast
import inspect
import json
import linecache
import sys
import textwrap
import types
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, List, Mapping, Tuple, Union

from duckielib.errors import DuckielibError

__all__ = [
    "CONTRACT",
    "EXPORT_TAG",
    "Export",
    "Part",
    "SolutionError",
    "call_part",
    "check_part",
    "check_saved",
    "export_solution",
    "load_solution",
    "reference_solution_dir",
]

#: The cell tag that marks a cell for export.
EXPORT_TAG = "export"

#: The modules an exported solution imports for its parts (and nothing else).
PRELUDE = "import math\n\nimport numpy as np\n"


@dataclass(frozen=True)
class Part:
    """One graded function or class of the contract.

    Attributes:
        name: its name, as in the notebook.
        notebook: the notebook (its assignment folder) where the student writes it.
        parameters: the parameter names, in order (for a class, those of ``__init__``).
        summary: what it computes, with units.
        methods: for a class, its methods' names and parameters (without ``self``).
    """

    name: str
    notebook: str
    parameters: Tuple[str, ...]
    summary: str
    methods: Tuple[Tuple[str, Tuple[str, ...]], ...] = ()

    @property
    def is_class(self) -> bool:
        """Whether the part is a class."""
        return bool(self.methods)

    @property
    def signature(self) -> str:
        """The part as the notebook shows it, for example ``delta_phi(ticks, ...)``."""
        text = f"{'class ' if self.is_class else ''}{self.name}({', '.join(self.parameters)})"
        for method, parameters in self.methods:
            text += f" with {method}({', '.join(parameters)})"
        return text


def _parts(*parts: Part) -> Dict[str, Part]:
    return {part.name: part for part in parts}


#: Every part of a solution, by name, in the order of the course.
CONTRACT: Dict[str, Part] = _parts(
    Part(
        "robot_topic",
        "02_ros_concepts",
        ("relative_name",),
        "the absolute name /VEHICLE_NAME/relative_name of one of the robot's topics",
    ),
    Part("wrap_angle", "03_frames", ("theta",), "theta in radians, wrapped into [0, 2 pi)"),
    Part(
        "rotation_matrix",
        "03_frames",
        ("theta",),
        "the 2x2 matrix that rotates a vector by theta radians counter-clockwise",
    ),
    Part(
        "world_from_robot",
        "03_frames",
        ("robot_pose", "point"),
        "a point (x, y) of the robot's frame in the world frame, shape (2,), metres",
    ),
    Part(
        "world_from_start",
        "03_frames",
        ("pose", "start"),
        "a pose (x, y, theta) of the start frame as a world pose, theta in [0, 2 pi)",
    ),
    Part(
        "forward_kinematics",
        "04_kinematics",
        ("omega_left", "omega_right", "R", "baseline"),
        "wheel speeds (rad/s) to (v in m/s, omega in rad/s)",
    ),
    Part(
        "inverse_kinematics",
        "04_kinematics",
        ("v", "omega", "R", "baseline"),
        "(v in m/s, omega in rad/s) to wheel speeds (omega_left, omega_right) in rad/s",
    ),
    Part(
        "duty_cycles",
        "04_kinematics",
        ("v", "omega", "R", "baseline", "gain", "trim", "k", "limit"),
        "(v, omega) to the wheels' duty cycles (u_left, u_right), as the kinematics node does",
    ),
    Part(
        "delta_phi",
        "05_odometry",
        ("ticks", "prev_ticks", "resolution"),
        "(change of wheel angle in radians, ticks to keep)",
    ),
    Part(
        "estimate_pose",
        "05_odometry",
        ("R", "baseline", "x_prev", "y_prev", "theta_prev", "delta_phi_left", "delta_phi_right"),
        "the next pose (x, y, theta), metres and radians, theta in [0, 2 pi)",
    ),
    Part(
        "WheelPairing",
        "05_odometry",
        ("resolution",),
        "pairs the two wheels' readings into (delta_phi_left, delta_phi_right) updates",
        methods=(("add", ("wheel", "ticks")),),
    ),
    Part(
        "angle_error",
        "06_driving",
        ("target", "theta"),
        "the signed turn from heading theta to heading target, radians in [-pi, pi)",
    ),
    Part(
        "distance_along",
        "06_driving",
        ("start", "pose"),
        "how far pose is from start along start's heading, in metres (negative: behind)",
    ),
    Part(
        "AngleTracker",
        "06_driving",
        ("theta0",),
        "the total angle turned since heading theta0, in radians, across the wrap at 2 pi",
        methods=(("update", ("theta",)),),
    ),
    Part(
        "PID",
        "07_control",
        ("kp", "ki", "kd", "limit"),
        "a discrete PID controller with an output limit and anti-windup",
        methods=(("update", ("error", "dt")), ("reset", ())),
    ),
    Part(
        "go_to_point",
        "07_control",
        ("pose", "target", "v_max", "k_omega"),
        "the command (v in m/s, omega in rad/s) that drives from pose towards a point",
    ),
    Part(
        "light_service_node",
        "08_leds",
        (),
        "a node offering ~set_color (ChangePattern) that sets the LEDs through the emitter",
    ),
    Part(
        "mission_node",
        "09_mission",
        ("mission",),
        "a node that carries out a mission state by state, each with its LED colour",
    ),
)

#: The parts the odometry runners need.
ODOMETRY_PARTS = ("delta_phi", "estimate_pose", "WheelPairing")

#: What a mission needs: the odometry, the driving and control parts, and the two nodes.
MISSION_PARTS = (
    *ODOMETRY_PARTS,
    "angle_error",
    "distance_along",
    "AngleTracker",
    "PID",
    "go_to_point",
    "light_service_node",
    "mission_node",
)


class SolutionError(DuckielibError):
    """A solution cannot be exported or loaded, lacks a part, or a part fails.

    The message names the notebook to finish or fix.
    """


def _finish(part: Part) -> str:
    return f"Finish notebook {part.notebook}"


# --- Export -------------------------------------------------------------------------------


@dataclass
class Export:
    """The result of :func:`export_solution`.

    Attributes:
        source: the text of the solution module.
        found: the notebook each contract part was exported from, by part name.
        missing: the contract parts no exported cell defines, by name.
        unfinished: the parts defined but not written yet (their body still raises
            ``NotImplementedError``).
        problems: sentences about parts whose parameters differ from the contract.
        notebooks: the notebooks read, relative to the exported folder.
        broken: sentences about exported cells that are not valid Python (left out), by
            notebook.
    """

    source: str
    found: Dict[str, str] = field(default_factory=dict)
    missing: List[str] = field(default_factory=list)
    unfinished: List[str] = field(default_factory=list)
    problems: List[str] = field(default_factory=list)
    notebooks: List[str] = field(default_factory=list)
    broken: Dict[str, str] = field(default_factory=dict)

    @property
    def complete(self) -> bool:
        """Whether every part of the contract is present, written and well-formed."""
        return not (self.missing or self.unfinished or self.problems)

    def report(self) -> str:
        """What is done and what is left, by notebook, in a few lines."""
        done = len(CONTRACT) - len(self.missing) - len(self.unfinished)
        lines = [f"{done} of {len(CONTRACT)} graded parts exported."]
        todo: Dict[str, Dict[str, List[str]]] = {}
        for name in self.unfinished:
            todo.setdefault(CONTRACT[name].notebook, {}).setdefault("write", []).append(name)
        for name in self.missing:
            todo.setdefault(CONTRACT[name].notebook, {}).setdefault("define", []).append(name)
        for notebook in sorted(todo):
            steps = []
            if "write" in todo[notebook]:
                steps.append(f"write {', '.join(todo[notebook]['write'])}")
            if "define" in todo[notebook]:
                steps.append(
                    f"define {', '.join(todo[notebook]['define'])} in a cell tagged {EXPORT_TAG!r}"
                )
            lines.append(f"Finish notebook {notebook}: {'; '.join(steps)}.")
        lines.extend(self.problems)
        return "\n".join(lines)


def _notebooks(folder: Path) -> List[Path]:
    found = sorted(
        path
        for path in folder.rglob("*.ipynb")
        if ".ipynb_checkpoints" not in path.parts
        and not path.name.startswith(".")
        and path.is_file()  # not a FIFO or a device, which would block or never end
    )
    if not found:
        raise SolutionError(
            f"{folder} holds no notebook (.ipynb): export the folder with your course notebooks."
        )
    return found


def _exported_cells(path: Path) -> List[str]:
    try:
        notebook = json.loads(path.read_text(encoding="utf-8"))
        cells = notebook["cells"]
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise SolutionError(f"{path} is not a readable notebook ({error}).") from None
    sources = []
    for cell in cells:
        if cell.get("cell_type") != "code":
            continue
        if EXPORT_TAG not in cell.get("metadata", {}).get("tags", []):
            continue
        source = cell.get("source", "")
        sources.append("".join(source) if isinstance(source, list) else source)
    return sources


def _kept(node: ast.stmt) -> bool:
    """Whether a top-level statement of an exported cell belongs in the solution."""
    if isinstance(node, (ast.Import, ast.ImportFrom, ast.FunctionDef, ast.ClassDef)):
        return True
    targets: List[ast.expr] = []
    if isinstance(node, ast.Assign):
        targets = node.targets
    elif isinstance(node, ast.AnnAssign):
        targets = [node.target]
    return bool(targets) and all(
        isinstance(target, ast.Name) and target.id.isupper() for target in targets
    )


def _unwritten(body: List[ast.stmt]) -> bool:
    """Whether a body is only a docstring, comments and ``raise NotImplementedError``."""
    statements = [
        node
        for node in body
        if not (isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant))
        and not isinstance(node, ast.Pass)
    ]
    if len(statements) != 1 or not isinstance(statements[0], ast.Raise):
        return False
    raised = statements[0].exc
    if isinstance(raised, ast.Call):
        raised = raised.func
    return isinstance(raised, ast.Name) and raised.id == "NotImplementedError"


def _parameters(function: ast.FunctionDef, drop_self: bool) -> Tuple[str, ...]:
    names = [argument.arg for argument in function.args.posonlyargs + function.args.args]
    return tuple(names[1:] if drop_self and names else names)


def _check_definition(part: Part, node: ast.stmt, notebook: str) -> Tuple[bool, List[str]]:
    """Whether a definition is unwritten, and what differs from the contract."""
    problems = []
    if part.is_class:
        if not isinstance(node, ast.ClassDef):
            return False, [f"In notebook {notebook}, {part.name} must be a class."]
        if _unwritten(node.body):
            return True, []
        methods = {item.name: item for item in node.body if isinstance(item, ast.FunctionDef)}
        init = methods.get("__init__")
        found = _parameters(init, True) if init is not None else ()
        if init is not None and found != part.parameters:
            problems.append(
                f"In notebook {notebook}, {part.name}.__init__ takes ({', '.join(found)}); "
                f"the course's version takes ({', '.join(part.parameters)})."
            )
        unwritten = False
        for name, parameters in part.methods:
            method = methods.get(name)
            if method is None:
                problems.append(f"In notebook {notebook}, {part.name} has no method {name}.")
                continue
            unwritten = unwritten or _unwritten(method.body)
            found = _parameters(method, True)
            if found != parameters:
                problems.append(
                    f"In notebook {notebook}, {part.name}.{name} takes ({', '.join(found)}); "
                    f"the course's version takes ({', '.join(parameters)})."
                )
        return unwritten or (init is not None and _unwritten(init.body)), problems
    if not isinstance(node, ast.FunctionDef):
        return False, [f"In notebook {notebook}, {part.name} must be a function (def)."]
    found = _parameters(node, False)
    if found != part.parameters:
        problems.append(
            f"In notebook {notebook}, {part.name} takes ({', '.join(found)}); "
            f"the course's version takes ({', '.join(part.parameters)})."
        )
    return _unwritten(node.body), problems


def _label(path: Path, folder: Path) -> str:
    return path.relative_to(folder).as_posix()


def export_solution(folder: Union[str, Path], strict: bool = True) -> Export:
    """Collect the cells tagged ``export`` of a folder's notebooks into one solution module.

    Notebooks are read in path order (``01_...`` first), so a later notebook can use what an
    earlier one defined. Of each exported cell only imports, ``def``, ``class`` and UPPER_CASE
    constants are kept: calls and prints made while exploring stay in the notebook.

    Args:
        folder: a folder of notebooks, at any depth: a student's ``course/``, one assignment
            folder, or the instructors' ``solutions/``.
        strict: whether an exported cell that is not valid Python stops the export; if not,
            the cell is left out and named in ``broken`` (a half-typed cell in a later
            notebook then does not keep an earlier notebook from loading its parts).

    Returns:
        The module's text and what is missing, unfinished or malformed, by notebook.

    Raises:
        SolutionError: if the folder has no notebook, a notebook cannot be read, or an
            exported cell is not valid Python (the message names the notebook and line).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise SolutionError(f"There is no folder {folder}; give the folder of your notebooks.")
    export = Export(
        source=(
            f'"""A Duckiebot course solution, exported from {folder.name}/ by duckie export.\n\n'
            'Do not edit this file: change the notebooks and export again.\n"""\n\n' + PRELUDE
        )
    )
    definitions: Dict[str, Tuple[str, ast.stmt]] = {}
    for path in _notebooks(folder):
        label = _label(path, folder)
        export.notebooks.append(label)
        for index, cell in enumerate(_exported_cells(path), start=1):
            try:
                tree = ast.parse(cell)
            except SyntaxError as error:
                sentence = (
                    f"In notebook {label}, exported cell {index} is not valid Python "
                    f"(line {error.lineno}: {error.msg}); fix it and export again."
                )
                if strict:
                    raise SolutionError(sentence) from None
                export.broken.setdefault(path.stem, sentence)
                continue
            lines = cell.splitlines()
            kept = []
            for node in tree.body:
                if not _kept(node):
                    continue
                first = min([node.lineno] + [d.lineno for d in _decorators(node)])
                kept.append("\n".join(lines[first - 1 : node.end_lineno]))
                if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and node.name in CONTRACT:
                    definitions[node.name] = (label, node)
            if kept:
                export.source += f"\n\n# From {label}, exported cell {index}.\n"
                export.source += "\n\n".join(kept) + "\n"
    for name, part in CONTRACT.items():
        if name not in definitions:
            export.missing.append(name)
            continue
        label, node = definitions[name]
        export.found[name] = label
        unwritten, problems = _check_definition(part, node, label)
        if unwritten:
            export.unfinished.append(name)
        export.problems.extend(problems)
    return export


def _decorators(node: ast.stmt) -> List[ast.expr]:
    return list(getattr(node, "decorator_list", []))


# --- Loading ------------------------------------------------------------------------------


def reference_solution_dir() -> Path:
    """The instructors' ``solutions/`` folder beside this library, whose export is the reference.

    Raises:
        SolutionError: if this installation has no ``solutions/`` folder (students' copies
            do not): then give a solution explicitly.
    """
    from duckielib.config import PROJECT_ROOT

    folder = PROJECT_ROOT / "solutions"
    if not any(folder.glob("*/*.ipynb")):
        raise SolutionError(
            "The course's reference solution is not part of this installation; give your own "
            "with --solution (your course/ folder or a file made by duckie export)."
        )
    return folder


def _module_from_source(source: str, filename: str) -> types.ModuleType:
    name = f"duckielib_solution_{abs(hash(filename))}"
    module = types.ModuleType(name)
    module.__file__ = filename
    # Registering the text lets tracebacks show the student's lines.
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    sys.modules[name] = module
    # Node parts import rospy and the message packages, as on the robot; in-process they are
    # served by duckielib's graph (a real ROS installation on the path is used instead), for
    # this import only.
    from duckielib.ros.modules import modules_installed

    try:
        with modules_installed():
            exec(compile(source, filename, "exec"), module.__dict__)
    except Exception as error:
        sys.modules.pop(name, None)
        raise SolutionError(
            f"The solution from {filename} fails to import: {type(error).__name__}: {error}"
        ) from error
    return module


def _refuse_unfinished(required: Iterable[str], unfinished: Iterable[str]) -> None:
    """Stop at the first required part still unwritten, naming its notebook."""
    waiting_parts = [name for name in CONTRACT if name in set(unfinished) & set(required)]
    if waiting_parts:
        first = CONTRACT[waiting_parts[0]]
        waiting = [name for name in waiting_parts if CONTRACT[name].notebook == first.notebook]
        raise SolutionError(
            f"{_finish(first)}: write {', '.join(waiting)} (their cells still raise "
            "NotImplementedError), save the notebook, and try again."
        )


def _unfinished_in_module(source: str) -> List[str]:
    """The contract parts a solution module defines but leaves unwritten.

    The last definition of a name counts, as when the module runs.
    """
    try:
        tree = ast.parse(source)
    except SyntaxError:
        return []  # the import says what is wrong, with the line
    definitions = {
        node.name: node
        for node in tree.body
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and node.name in CONTRACT
    }
    return [
        name
        for name, node in definitions.items()
        if _check_definition(CONTRACT[name], node, CONTRACT[name].notebook)[0]
    ]


def load_solution(
    path: Union[str, Path, None] = None, required: Iterable[str] = ODOMETRY_PARTS
) -> types.ModuleType:
    """Load a solution: an exported module, or a folder of notebooks exported on the fly.

    Args:
        path: a ``.py`` file made by ``duckie export`` (or written by hand with the contract's
            names), or a folder of notebooks; ``None`` for the reference solution.
        required: the parts the caller needs; each must be present, written and shaped as in
            :data:`CONTRACT`.

    Returns:
        The solution as a module; its parts are attributes.

    Raises:
        SolutionError: if the solution cannot be read or imported, or a required part is
            missing, unfinished or has other parameters (the message names the notebook).
    """
    folder = reference_solution_dir() if path is None else Path(path)
    if folder.is_dir():
        export = export_solution(folder, strict=False)
        for name in required:
            notebook = CONTRACT[name].notebook
            if name not in export.found and notebook in export.broken:
                raise SolutionError(export.broken[notebook])
        _refuse_unfinished(required, export.unfinished)
        module = _module_from_source(export.source, f"<solution exported from {folder}>")
    elif folder.is_file():
        if folder.suffix == ".ipynb":
            raise SolutionError(
                f"{folder} is one notebook; give the folder that holds your notebooks."
            )
        source = folder.read_text(encoding="utf-8")
        _refuse_unfinished(required, _unfinished_in_module(source))
        module = _module_from_source(source, str(folder))
    else:
        raise SolutionError(f"There is no solution file or folder {folder}.")
    for name in required:
        check_part(module, name, where=str(folder))
    return module


def check_part(solution: Any, name: str, where: str = "the solution") -> Any:
    """Return part ``name`` of a solution after checking it is there and shaped as agreed.

    Args:
        solution: a module, a mapping such as a notebook's ``globals()``, or any object with
            the parts as attributes.
        name: the part's name in :data:`CONTRACT`.
        where: how to name the solution in messages.

    Raises:
        SolutionError: if the part is missing, not callable, or has other parameters.
    """
    part = CONTRACT[name]
    value = solution.get(name) if isinstance(solution, Mapping) else getattr(solution, name, None)
    if value is None or not callable(value):
        raise SolutionError(
            f"{_finish(part)}: {where} has no {part.signature} (define it in a cell tagged "
            f"{EXPORT_TAG!r} and run that cell, or export again)."
        )
    checks: List[Tuple[str, Callable[..., Any], Tuple[str, ...], bool]] = []
    if part.is_class:
        checks.append((f"{name}.__init__", value.__init__, part.parameters, True))
        for method, parameters in part.methods:
            function = getattr(value, method, None)
            if function is None:
                raise SolutionError(f"{_finish(part)}: {name} has no method {method}.")
            checks.append((f"{name}.{method}", function, parameters, True))
    else:
        checks.append((name, value, part.parameters, False))
    for label, function, parameters, is_method in checks:
        try:
            found = tuple(inspect.signature(function).parameters)
        except (TypeError, ValueError):
            continue
        if is_method and found[:1] == ("self",):
            found = found[1:]
        if found != parameters and not (label.endswith("__init__") and found == ("args", "kwargs")):
            raise SolutionError(
                f"{_finish(part)}: {label} takes ({', '.join(found)}); "
                f"it must take ({', '.join(parameters)})."
            )
    return value


def call_part(name: str, function: Callable[..., Any], *args: Any) -> Any:
    """Call a solution's part, turning its failures into a :class:`SolutionError`.

    Raises:
        SolutionError: naming the notebook to finish if the part is not implemented yet, or
            the call and the error if it fails.
    """
    part = CONTRACT[name.split(".", maxsplit=1)[0]]
    try:
        return function(*args)
    except NotImplementedError:
        raise SolutionError(
            f"{_finish(part)}: {name} is not implemented yet (run its cell after writing it)."
        ) from None
    except Exception as error:
        arguments = ", ".join(repr(argument) for argument in args)
        raise SolutionError(
            f"{name}({arguments}), from notebook {part.notebook}, raised "
            f"{type(error).__name__}: {error}"
        ) from error


def _definition_ast(source: str, name: str) -> Any:
    """The last top-level ``def``/``class`` called ``name`` in ``source``, as an AST dump."""
    found = None
    for node in ast.parse(textwrap.dedent(source)).body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and node.name == name:
            found = ast.dump(node)
    return found


def check_saved(solution: Any, *defined_here: Any) -> None:
    """Check that parts a notebook defines are the ones its saved file gives the solution.

    Tests that run a student's nodes load the solution from the saved notebooks, exactly as
    ``duckie mission`` and the robot do. A part edited in the notebook but not saved yet would
    then be tested in its old version: this says so instead. Formatting and comments do not
    count, only the code.

    Args:
        solution: the loaded solution (:func:`load_solution`).
        defined_here: the functions or classes as the notebook defines them now.

    Raises:
        SolutionError: naming the first part whose saved version differs.
    """
    for mine in defined_here:
        name = getattr(mine, "__name__", "")
        part = CONTRACT.get(name)
        saved = getattr(solution, name, None)
        if part is None or saved is None:
            continue
        try:
            here = _definition_ast(inspect.getsource(mine), name)
            there = _definition_ast(inspect.getsource(saved), name)
        except (OSError, TypeError, SyntaxError):
            continue  # not defined in a cell (or not found): nothing to compare
        if here != there:
            raise SolutionError(
                f"{name} in this notebook differs from the one saved in notebook "
                f"{part.notebook}: save the notebook (Ctrl+S) and run this cell again. Tests, "
                "duckie mission and the robot all run your saved notebooks."
            )
