"""Loading a solution and calling its parts, with a sentence for each way it can be wrong.

The library's runners, the autograder and the robot nodes load a solution (a file made by
``duckie export``, or a folder of notebooks, exported on the way) with :func:`load_solution`,
check a part with :func:`check_part` and call it with :func:`call_part`. In a notebook,
:func:`check_saved` tells a student whose saved notebook differs from the cell they ran.

This module imports only the standard library: it runs on the robot (Python 3.8).
"""

from __future__ import annotations

import ast
import inspect
import linecache
import os
import sys
import textwrap
import types
from pathlib import Path
from typing import Any, Callable, Iterable, List, Mapping, Tuple, Union

from duckielib.solution.contract import (
    CONTRACT,
    EXPORT_TAG,
    ODOMETRY_PARTS,
    SolutionError,
    finish_notebook,
)
from duckielib.solution.export import check_definition, export_solution

__all__ = ["call_part", "check_part", "check_saved", "load_solution", "reference_solution_dir"]


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
            f"{finish_notebook(first)}: write {', '.join(waiting)} (their cells still raise "
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
        if check_definition(CONTRACT[name], node, CONTRACT[name].notebook)[0]
    ]


def load_solution(
    path: Union[str, os.PathLike[str], None] = None, required: Iterable[str] = ODOMETRY_PARTS
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
            f"{finish_notebook(part)}: {where} has no {part.signature} (define it in a cell tagged "
            f"{EXPORT_TAG!r} and run that cell, or export again)."
        )
    checks: List[Tuple[str, Callable[..., Any], Tuple[str, ...], bool]] = []
    if part.is_class:
        checks.append((f"{name}.__init__", value.__init__, part.parameters, True))
        for method, parameters in part.methods:
            function = getattr(value, method, None)
            if function is None:
                raise SolutionError(f"{finish_notebook(part)}: {name} has no method {method}.")
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
                f"{finish_notebook(part)}: {label} takes ({', '.join(found)}); "
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
            f"{finish_notebook(part)}: {name} is not implemented yet (run its cell after "
            "writing it)."
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
