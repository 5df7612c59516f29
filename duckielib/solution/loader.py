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
import math
import os
import sys
import textwrap
import traceback
import types
from pathlib import Path
from typing import Any, Callable, Iterable, List, Mapping, Optional, Tuple, Union

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
    except SystemExit:
        sys.modules.pop(name, None)
        raise SolutionError(
            f"The solution from {filename} called sys.exit() or exit() while being imported: "
            "take that call out of the cells tagged 'export' (or put it inside a function), "
            "save, and try again."
        ) from None
    except Exception as error:
        sys.modules.pop(name, None)
        raise SolutionError(
            f"The solution from {filename} fails to import: {_raised(error)}."
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
    path: Union[str, os.PathLike[str], None] = None,
    required: Iterable[str] = ODOMETRY_PARTS,
    visible_tests: Optional[bool] = None,
) -> types.ModuleType:
    """Load a solution: an exported module, or a folder of notebooks exported on the fly.

    Args:
        path: a ``.py`` file made by ``duckie export`` (or written by hand with the contract's
            names), or a folder of notebooks; ``None`` for the reference solution.
        required: the parts the caller needs; each must be present, written and shaped as in
            :data:`CONTRACT`.
        visible_tests: for a folder of notebooks, whether the visible tests of the required
            parts, and of the parts they build on, must pass first (run from the folder's own
            notebooks, see :mod:`duckielib.solution.visible_tests`). None: when a notebook of
            that folder loads it, as ``load_solution("..", ...)`` does in a later notebook
            (the working folder is one of the folder's notebook folders), and only for the
            notebooks before that one.

    Returns:
        The solution as a module; its parts are attributes.

    Raises:
        SolutionError: if the solution cannot be read or imported, a required part is
            missing, unfinished or has other parameters, or fails a visible test of its
            notebook (the message names the notebook).
    """
    folder = reference_solution_dir() if path is None else Path(path)
    found: Optional[Mapping[str, str]] = None  # of a folder: each part's notebook
    if folder.is_dir():
        export = export_solution(folder, strict=False)
        for name in required:
            notebook = CONTRACT[name].notebook
            if name not in export.found and notebook in export.broken:
                raise SolutionError(export.broken[notebook])
        _refuse_unfinished(required, export.unfinished)
        module = _module_from_source(export.source, f"<solution exported from {folder}>")
        found = export.found
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
    if found is not None:
        loading_notebook = _loading_notebook(folder)
        if visible_tests or (visible_tests is None and loading_notebook is not None):
            _refuse_failing(folder, module, required, found, loading_notebook)
    return module


def _loading_notebook(folder: Path) -> Optional[str]:
    """The notebook of ``folder`` the process works in (``NN_name/NN_name.ipynb``), or None.

    A notebook's kernel works in the notebook's folder: a later notebook loading ``..``.
    """
    try:
        here = Path.cwd().resolve()
        if here.parent != folder.resolve() or not (here / f"{here.name}.ipynb").is_file():
            return None
    except OSError:
        return None
    return here.name


def _refuse_failing(
    folder: Path,
    module: types.ModuleType,
    required: Iterable[str],
    found: Mapping[str, str],
    loading_notebook: Optional[str],
) -> None:
    """Stop at the first required part (or part it builds on) failing a visible test."""
    # Only for a folder of notebooks: on the robot a solution is a file.
    from duckielib.solution.visible_tests import checking, first_failing_test

    if checking():
        return  # a load inside the tests being run: the outer load checks
    parts = {
        name: Path(found[name]).parent.name or CONTRACT[name].notebook
        for name in required
        if name in found
    }
    failed = first_failing_test(folder, module, parts, before=loading_notebook)
    if failed is not None:
        raise SolutionError(failed.sentence())


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

    A result that holds a number that is not finite (NaN or an infinity) is a failure too:
    a pose made of NaN would silently spoil every pose after it.

    Raises:
        SolutionError: naming the notebook to finish if the part is not implemented yet, or
            the call (its inputs) and what went wrong: the error it raised, or the
            non-finite result it returned.
    """
    part = CONTRACT[name.split(".", maxsplit=1)[0]]
    try:
        result = function(*args)
    except NotImplementedError:
        raise SolutionError(
            f"{finish_notebook(part)}: {name} is not implemented yet (run its cell after "
            "writing it)."
        ) from None
    except SystemExit:
        raise SolutionError(
            f"{_call(name, args)}, from notebook {part.notebook}, called sys.exit() or exit(): "
            "a function of the solution must return its result instead."
        ) from None
    except Exception as error:
        raise SolutionError(
            f"{_call(name, args)}, from notebook {part.notebook}, raised "
            f"{_raised(error, _where(name, function, error))}."
        ) from error
    if not _finite(result):
        raise SolutionError(
            f"{_call(name, args)}, from notebook {part.notebook}, returned {_shown(result)}: "
            "every number it returns must be finite, not NaN or infinite (look for a division "
            "by zero, or a NaN among the values it computes with)."
        )
    return result


def _finite(value: Any) -> bool:
    """Whether every number in ``value`` (a number, a sequence, a numpy array) is finite."""
    if value is None or isinstance(value, (int, str, bytes)):
        return True
    if isinstance(value, float):  # numpy's float64 too
        return math.isfinite(value)
    if isinstance(value, (tuple, list)):
        return all(map(_finite, value))
    if hasattr(value, "dtype") and hasattr(value, "tolist"):  # numpy arrays and scalars
        return _finite(value.tolist())
    return True


def _shown(value: Any) -> str:
    """``value`` as a student would write it: numpy's numbers and arrays as plain ones."""
    if hasattr(value, "dtype") and hasattr(value, "tolist"):
        value = value.tolist()
    if isinstance(value, list):
        return f"[{', '.join(map(_shown, value))}]"
    if isinstance(value, tuple):
        return f"({', '.join(map(_shown, value))}{',' if len(value) == 1 else ''})"
    return repr(float(value)) if isinstance(value, float) else repr(value)


def _call(name: str, args: Tuple[Any, ...]) -> str:
    """A call as code: ``estimate_pose(0.0318, 0.1, ...)``."""
    return f"{name}({', '.join(map(_shown, args))})"


def _raised(error: BaseException, where: str = "") -> str:
    """An error as a clause of a sentence, on one line: ``ZeroDivisionError in f: division``."""
    text = " ".join(str(error).split()).rstrip(".")
    return f"{type(error).__name__}{where}" + (f": {text}" if text else "")


def _where(name: str, function: Callable[..., Any], error: BaseException) -> str:
    """Where in the solution ``error`` was raised (`` in delta_phi``), if not in ``name``."""
    code = getattr(getattr(function, "__func__", function), "__code__", None)
    mine = [
        frame
        for frame in traceback.extract_tb(error.__traceback__)
        if code is not None and frame.filename == code.co_filename
    ]
    if not mine or mine[-1].name == name.rsplit(".", 1)[-1]:
        return ""
    return f" in {mine[-1].name}"


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
