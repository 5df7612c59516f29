"""Loading a solution: the module of a student's (or the reference) graded functions.

The functions a student writes in the notebooks are collected into one importable module, a
"solution". The library's runners load it and call its functions by the names and signatures
listed in :data:`CONTRACT`, the same names a student meets in the notebooks.
"""

from __future__ import annotations

import importlib.util
import inspect
import sys
import types
from pathlib import Path
from typing import Dict, Iterable, Tuple, Union

from duckielib.errors import DuckielibError

__all__ = ["CONTRACT", "SolutionError", "load_solution"]

#: The graded functions runners call, by name, with their parameters in order.
CONTRACT: Dict[str, Tuple[str, ...]] = {
    "delta_phi": ("ticks", "prev_ticks", "resolution"),
    "estimate_pose": (
        "R",
        "baseline",
        "x_prev",
        "y_prev",
        "theta_prev",
        "delta_phi_left",
        "delta_phi_right",
    ),
}


class SolutionError(DuckielibError):
    """A solution cannot be loaded or lacks a function (the message says what to finish)."""


def load_solution(
    path: Union[str, Path], required: Iterable[str] = ("delta_phi", "estimate_pose")
) -> types.ModuleType:
    """Import the solution module at ``path`` and check it has the ``required`` functions.

    Raises:
        SolutionError: if the file is missing, fails to import, or lacks a required function
            or has it with other parameters.
    """
    path = Path(path)
    if not path.is_file():
        raise SolutionError(f"There is no solution file {path}.")
    name = f"duckielib_solution_{abs(hash(str(path.resolve())))}"
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise SolutionError(f"{path} is not a Python module; a solution is a .py file.")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except Exception as error:
        sys.modules.pop(name, None)
        raise SolutionError(
            f"The solution {path} fails to import: {type(error).__name__}: {error}"
        ) from error
    for function_name in required:
        parameters = CONTRACT[function_name]
        function = getattr(module, function_name, None)
        signature = f"{function_name}({', '.join(parameters)})"
        if not callable(function):
            raise SolutionError(f"The solution {path} has no function {signature}.")
        try:
            found = tuple(inspect.signature(function).parameters)
        except (TypeError, ValueError):
            continue
        if len(found) != len(parameters):
            raise SolutionError(
                f"In {path}, {function_name} takes ({', '.join(found)}); "
                f"it must take {len(parameters)} parameters: {signature}."
            )
    return module
