"""The two rules judged on the reading (:mod:`autograder.rules.reading`) of a notebook.

No answer taken from the course's library, and no call doing the exercise (:data:`FORBIDDEN`):
what an answer reaches, judged into a sentence for the student (:func:`broken_rules`).
"""

from __future__ import annotations

import ast
import functools
import importlib.util
import sys
from dataclasses import dataclass
from typing import Any, Dict, List, Mapping, Optional, Sequence, Set, Tuple

from autograder.rules.reading import (
    _MODULES,
    _NESTED,
    _bound,
    _course_sources,
    _Found,
    _is_answer,
    _matches,
    _Notebook,
    _parse,
    _reach,
    _rebinding,
    _source,
)

__all__ = ["FORBIDDEN", "Forbidden", "broken_rules", "graded_names"]


@dataclass(frozen=True)
class Forbidden:
    """The libraries an exercise's answer may not use, because one call would do the exercise.

    Attributes:
        paths: dotted names; a reference to one of them or to anything inside it breaks the
            rule. ``"numpy:unwrap"`` is numpy's ``unwrap`` wherever numpy keeps it.
        instead: what to write instead, in the student's words.
    """

    paths: Tuple[str, ...]
    instead: str


_TRANSFORMS = ("tf", "tf2_ros", "scipy.spatial.transform", "matplotlib.transforms")

#: assignment -> graded name -> what its answer may not use. The notebook says so in one
#: sentence next to the exercise.
FORBIDDEN: Dict[str, Dict[str, Forbidden]] = {
    "02_ros_concepts": {
        "bgr_from_jpeg": Forbidden(
            ("cv2", "cv_bridge", "duckietown_utils"),
            "decode the bytes with Pillow and reverse the channels with numpy",
        ),
        "grey_bgr": Forbidden(
            ("cv2", "cv_bridge", "duckietown_utils", "PIL"), "weigh the three channels with numpy"
        ),
    },
    "03_frames": {
        "rotation_matrix": Forbidden(_TRANSFORMS, "build the matrix with math.cos and math.sin"),
        "world_from_robot": Forbidden(_TRANSFORMS, "rotate and translate with numpy yourself"),
        "world_from_start": Forbidden(_TRANSFORMS, "use your world_from_robot and wrap_angle"),
    },
    "10_bag_analysis": {
        "unwrap_heading": Forbidden(
            ("numpy:unwrap",), "add up the steps yourself with np.diff and np.cumsum"
        ),
    },
}

#: Where the ROS libraries duckielib serves register (pyproject.toml). duckielib.ros.modules
#: reads it too, but importing that would serve rospy in the grader's own process.
_LIBRARIES_GROUP = "duckielib.ros_libraries"
#: Modules of duckielib that hold no computation, only descriptions: the missions, which
#: exported cells may import (solutions/README.md).
_WHOLE = ("duckielib.missions",)
#: A student's own earlier answers, as the later notebooks load them.
_SOLUTION_LOADERS = ("duckielib.solution.load_solution", "duckielib.solution.loader.load_solution")

# The rules broken, the most telling first: a graded name's sentence names its first.
_FORBIDDEN, _SIMULATOR, _PRIVATE, _DYNAMIC, _UNREADABLE, _LIBRARY, _KEPT = range(7)


def broken_rules(
    submitted_cells: Sequence[Mapping[str, Any]],
    course_cells: Sequence[Mapping[str, Any]],
    assignment: str,
) -> Dict[str, str]:
    """The graded names of a submitted notebook whose code breaks a rule, each with a sentence.

    Args:
        submitted_cells: the cells of the student's notebook (nbformat cells or plain dicts),
            the cells they added included.
        course_cells: the cells of the course's source notebook of the same assignment
            (``solutions/NAME/NAME.ipynb``); its answer cells are those whose
            ``metadata.nbgrader.solution`` is true, and the names they define (functions,
            classes, constants) are the graded names.
        assignment: the assignment's name, for example ``"03_frames"``.

    Returns:
        ``{graded name: sentence}`` for each graded name whose code breaks a rule, in the order
        the course defines them; empty when every answer keeps the rules. The sentence is for
        the student: what the answer uses, and what to do instead.
    """
    graded = list(graded_names(course_cells))
    trusted = _course_sources(course_cells)
    course = _Notebook(course_cells, trusted)
    allowed = _Allowed()
    for name in graded:
        for found in _reach(course, name):
            allowed.add(found)
    notebook = _Notebook(submitted_cells, trusted)
    broken: Dict[str, str] = {}
    for name in graded:
        verdicts = [_judge(name, found, assignment, allowed) for found in _reach(notebook, name)]
        kind, sentence = min(verdicts, key=lambda verdict: verdict[0], default=(_KEPT, ""))
        if kind != _KEPT:
            broken[name] = sentence
    rebinding = _rebinding(notebook, set(graded))
    if rebinding is not None:
        where, construct = rebinding
        for name in graded:
            broken.setdefault(
                name,
                f"{name} could be changed by {where}, which uses {construct}: the grader cannot "
                f"read what that defines, so define {name} with a plain def and take "
                f"{construct} out."
                if construct != _NESTED
                else f"{name} could be changed by {where}, whose code is nested too deeply for "
                "the grader to read: write that cell more plainly.",
            )
    return {name: broken[name] for name in graded if name in broken}


def graded_names(course_cells: Sequence[Mapping[str, Any]]) -> Dict[str, str]:
    """The names the course's answer cells define, each with its answer cell's ``grade_id``.

    Args:
        course_cells: the cells of a source notebook of the course (``solutions/``).

    Returns:
        ``{name: grade_id}`` in the notebook's order: the functions, classes and constants of
        every answer cell (``{"SWEEP_SPEEDS": "sweep_speeds", "CONTROL_HZ": "mission_node",
        "mission_node": "mission_node", ...}``), the keys :func:`broken_rules` reports by.
    """
    names: Dict[str, str] = {}
    for cell in course_cells:
        tree = _parse(_source(cell)) if _is_answer(cell) else None
        grade_id = str(((cell.get("metadata") or {}).get("nbgrader") or {}).get("grade_id"))
        for statement in tree.body if tree is not None else ():
            if not isinstance(statement, (ast.Import, ast.ImportFrom)):
                for name in _bound(statement):
                    names.setdefault(name, grade_id)
    return names


# Judging what an answer reaches.


@functools.lru_cache(maxsize=1)
def _served() -> Tuple[Set[str], Set[str], Set[str]]:
    """The ROS names duckielib serves: libraries, message packages, message type names."""
    from importlib import metadata

    from duckielib import messages

    entries = metadata.entry_points(group=_LIBRARIES_GROUP)
    libraries = {entry.name.split(".")[0] for entry in entries} | {"rospy", "duckietown"}
    names = [*messages.REGISTRY.messages, *messages.REGISTRY.services]
    packages = {name.partition("/")[0] for name in names}
    types = {name.partition("/")[2] for name in names}
    types |= {f"{name}{part}" for name in types for part in ("Request", "Response")}
    return libraries, packages, types


def _family(path: str) -> Tuple[Optional[str], str]:
    """Which part of duckielib ``path`` is (None: none), and the name a student knows it by.

    The parts: ``"duckielib"`` itself, each ROS library it serves (``"rospy"``, ``"tf"``...)
    and ``"messages"``, the message types of every package.
    """
    libraries, packages, types = _served()
    parts = path.split(".")
    if parts[:3] == ["duckielib", "ros", "rospy"]:
        parts = parts[2:]
    elif parts[:3] == ["duckielib", "ros", "dtros"]:
        parts = ["duckietown", *parts[2:]]
    elif parts[:2] == ["duckielib", "libraries"] and parts[2:3] and parts[2] in libraries:
        parts = parts[2:]
    elif parts[:2] == ["duckielib", "messages"] and parts[2:3] and parts[2] in packages | types:
        parts = parts[2:] if parts[2] in packages else parts
        return "messages", ".".join(parts)
    canonical = ".".join(parts)
    if parts[0] in packages:
        return "messages", canonical
    return (parts[0] if parts[0] in libraries or parts[0] == "duckielib" else None), canonical


def _related(path: str, allowed: str) -> bool:
    if path == allowed or path.startswith(allowed + ".") or allowed.startswith(path + "."):
        return True
    # A package's name for what one of its modules defines: duckielib.bags.Bag allows
    # duckielib.bags.reader.Bag (and its methods).
    package, _, name = allowed.rpartition(".")
    inner = path[len(package) + 1 :].split(".") if path.startswith(package + ".") else []
    return name in inner[1:]


class _Allowed:
    """The parts of duckielib the course's own answers of one notebook use.

    A name of duckielib is allowed with what is inside it (``duckielib.bags.Bag`` and its
    methods); a ROS library or the message types as a whole. :data:`_WHOLE` modules are
    allowed whole once the answers use a part of them.
    """

    def __init__(self) -> None:
        self.paths: List[str] = list(_SOLUTION_LOADERS)
        self.families: Set[str] = set()

    def add(self, found: _Found) -> None:
        """Allow what the course's answer code (not its other cells) reaches."""
        family, path = _family(found.what) if found.kind == "path" else (None, "")
        if found.trusted or family is None or _simulator(path) or _private(path):
            return
        if family == "duckielib":
            self.paths.append(next((m for m in _WHOLE if _matches(path, m)), path))
        else:
            self.families.add(family)

    def allows(self, family: str, path: str) -> bool:
        if family == "duckielib":
            return any(_related(path, allowed) for allowed in self.paths)
        return family in self.families


def _simulator(path: str) -> bool:
    return _matches(path, "duckielib.sim")


def _private(path: str) -> bool:
    return any(part.startswith("_") and not part.endswith("__") for part in path.split(".")[1:])


@functools.lru_cache(maxsize=None)
def _installed(top: str) -> bool:
    """Whether ``top`` is a module of the course's Python (the standard library included)."""
    if top == "autograder":  # the grader's own code: never a student's
        return False
    if top in sys.stdlib_module_names or top in _served()[0] | _served()[1]:
        return True
    try:
        return importlib.util.find_spec(top) is not None
    except (ImportError, ValueError):
        return False


def _judge(name: str, found: _Found, assignment: str, allowed: _Allowed) -> Tuple[int, str]:
    """The rule ``found`` breaks, if any, and the sentence that tells the student.

    Returns:
        ``(kind, sentence)``; kind is ``_KEPT`` (and the sentence empty) when no rule is broken.
    """
    number = assignment.split("_", maxsplit=1)[0]
    uses = f"{name} uses {found.what}" if found.kind == "dynamic" else ""
    family, path = _family(found.what) if found.kind == "path" else (None, "")
    uses = uses or f"{name} uses {path}"
    uses += f" (through {', '.join(found.via)})" if found.via else ""
    why = "notebook 01 says why"
    yourself = f"write the computation yourself ({why})"
    names = "Python, numpy and what the exercise names"
    rule = FORBIDDEN.get(assignment, {}).get(name)
    dynamic = next((key for key in _MODULES if _matches(path, key)), None)
    if found.kind == "dynamic":
        kind, text = _DYNAMIC, f"which the grader cannot follow: {found.instead}"
    elif rule is not None and any(_matches(path, pattern) for pattern in rule.paths):
        says = f"notebook {number} says so above the exercise"
        kind, text = _FORBIDDEN, f"which would do this exercise for you: {rule.instead} ({says})"
    elif family == "duckielib" and _simulator(path):
        kind, text = _SIMULATOR, f"a part of the simulator: {yourself}"
    elif family is not None and _private(path):
        kind, text = _PRIVATE, f"a private part of the course's library: {yourself}"
    elif dynamic is not None:
        kind, text = _DYNAMIC, f"which the grader cannot follow: {_MODULES[dynamic]}"
    elif not _installed(path.split(".")[0]):
        kind, text = (
            _UNREADABLE,
            "from a module the grader cannot read: put its code in your notebook",
        )
    elif family is not None and not allowed.allows(family, path):
        kind = _LIBRARY
        text = f"which notebook {number}'s answers do not use: write it with {names} ({why})"
    else:
        return _KEPT, ""
    if found.trusted and kind not in (_FORBIDDEN, _SIMULATOR, _PRIVATE, _DYNAMIC):
        return _KEPT, ""  # the course's cells may use the library: the data they hold is yours
    return kind, f"{uses}, {text}."
