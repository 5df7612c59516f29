"""The student's solution: the graded functions, their export from the notebooks, and loading them.

A student writes the graded functions and classes in the notebooks, in cells tagged
``export``. :func:`export_solution` collects those cells into one Python module, a *solution*;
the library's runners, the autograder and the robot nodes load it with :func:`load_solution`
and call its parts by the names and parameters of :data:`CONTRACT`.

- :mod:`~duckielib.solution.contract`: the parts, their notebooks and parameters.
- :mod:`~duckielib.solution.export`: from notebooks to a solution's text.
- :mod:`~duckielib.solution.loader`: from a solution to a module, and calling its parts.

This package imports only the standard library: it runs on the robot (Python 3.8).
"""

from duckielib.solution.contract import (
    CONTRACT,
    EXPORT_TAG,
    MISSION_PARTS,
    ODOMETRY_PARTS,
    Part,
    SolutionError,
)
from duckielib.solution.export import Export, export_solution
from duckielib.solution.loader import (
    call_part,
    check_part,
    check_saved,
    load_solution,
    reference_solution_dir,
)

__all__ = [
    "CONTRACT",
    "EXPORT_TAG",
    "MISSION_PARTS",
    "ODOMETRY_PARTS",
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
