"""Getting the robot's image ready: the course library and a solution, into ``robot_nodes/``.

``robot_nodes/`` is a Duckietown project (template-ros, distro daffy) that ``dts devel build``
turns into an image for the robot. Its nodes are thin: the code they run is duckielib's and
the student's. :func:`prepare` (``duckie robot prepare``, ``make robot``) writes both into the
project's ``deploy/`` folder, which the image copies to ``/code/course``::

    deploy/duckielib/   the robot-deployable modules: all of duckielib but its laptop
                        packages (LAPTOP_PACKAGES); Python 3.8, standard library and numpy
    deploy/solution.py  the solution the nodes run (the image's DUCKIE_SOLUTION names it)
    deploy/msgs/        genpy's duckietown_msgs and std_srvs, for running the nodes on this
                        laptop against a real ROS master (left out of the image: the robot has
                        its own); written only where Debian's genpy is installed

The solution is checked before anything is written: it must load with every part the robot
runs (:data:`~duckielib.solution.MISSION_PARTS`) and parse as Python 3.8, the robot's Python.
The old ``deploy/`` is replaced only once the new one is complete.

Laptop side; never deployed.
"""

from __future__ import annotations

import ast
import importlib.util
import shutil
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import List, Optional, Union

from duckielib.config import PROJECT_ROOT
from duckielib.errors import DuckielibError
from duckielib.solution import (
    CONTRACT,
    MISSION_PARTS,
    SolutionError,
    export_solution,
    load_solution,
    reference_solution_dir,
)

__all__ = [
    "GENERATED",
    "LAPTOP_PACKAGES",
    "PROJECT",
    "ROBOT_PYTHON",
    "ROOT",
    "Prepared",
    "prepare",
    "robot_module_files",
]

#: The course's repository: the folder that holds ``duckielib/`` and ``pyproject.toml``.
ROOT = PROJECT_ROOT

#: The packages of ``duckielib/`` that stay on the laptop: the simulator (pymunk), bags
#: (rosbags), plots (matplotlib), the tools (the ``duckie`` command and what it runs),
#: JupyterLab's settings and the in-process ROS libraries (cv_bridge, rosbag,
#: message_filters, tf, tf2_ros: the robot has the real ones). Everything else in ``duckielib/`` is
#: deployed to the robot, so it must run on Python 3.8 with the standard library and numpy
#: only (the tests check it).
LAPTOP_PACKAGES = ("bags", "lab", "libraries", "plots", "sim", "tools")

#: The Duckietown project for the robot.
PROJECT = ROOT / "robot_nodes"

#: The folders of a project that :func:`prepare` writes: the deployed files, and the new and
#: the old ones while it swaps them.
GENERATED = ("deploy", "deploy.tmp", "deploy.old")

#: The Python the robot runs (ROS Noetic on Ubuntu 20.04).
ROBOT_PYTHON = (3, 8)

#: Files that files and folders of the robot-module list contribute besides ``.py`` files.
_TYPED_MARKER = "py.typed"
_DEFINITIONS = "definitions"


@dataclass
class Prepared:
    """What :func:`prepare` wrote.

    Attributes:
        deploy: the project's ``deploy/`` folder.
        solution: ``deploy/solution.py``.
        source: where the solution came from, in words (``"course/"``, ``"the reference
            solution"``...).
        library: the library files copied, relative to ``deploy/``.
        messages: ``deploy/msgs/``, or ``None`` if they were not generated.
        notes: sentences about what was skipped or left out.
    """

    deploy: Path
    solution: Path
    source: str
    library: List[Path] = field(default_factory=list)
    messages: Optional[Path] = None
    notes: List[str] = field(default_factory=list)

    def text(self) -> str:
        """What was written, and the commands that take it to the robot."""
        project = _shown(self.deploy.parent)
        lines = [
            f"Wrote {_shown(self.deploy)}/:",
            f"  duckielib/    the course library, {len(self.library)} files",
            f"  solution.py   {self.source}",
        ]
        if self.messages is not None:
            lines.append("  msgs/         duckietown_msgs and std_srvs for ROS on this laptop")
        lines.extend(f"note: {note}" for note in self.notes)
        lines += [
            "Next, with your robot's name for ROBOT:",
            f"  cd {project}",
            "  dts devel build -f -H ROBOT    # build the image on the robot",
            "  dts devel run -H ROBOT         # square then circle (-L d-shape for the D;",
            "                                 #   -L straight, -L rotation: the two tasks)",
        ]
        return "\n".join(lines)


def _shown(path: Path) -> str:
    """``path`` relative to the working folder when it is inside it, else absolute."""
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve())) or "."
    except ValueError:
        return str(path)


def _deployed(path: Path) -> bool:
    if "__pycache__" in path.parts or not path.is_file():
        return False
    return path.suffix == ".py" or path.name == _TYPED_MARKER or _DEFINITIONS in path.parts


def robot_module_files() -> List[Path]:
    """The files of the robot-deployable modules, relative to the repository.

    They are every ``.py`` file of ``duckielib/`` outside :data:`LAPTOP_PACKAGES`, the message
    definitions' text files, and ``duckielib/py.typed``.
    """
    library = ROOT / "duckielib"
    files = [
        path
        for path in library.rglob("*")
        if _deployed(path) and path.relative_to(library).parts[0] not in LAPTOP_PACKAGES
    ]
    return sorted(path.relative_to(ROOT) for path in files)


def _solution_source(solution: Union[str, Path, None]) -> tuple[str, str]:
    """The text of the solution to deploy, and where it came from, after checking it loads.

    Raises:
        SolutionError: if the solution cannot be loaded with every part the robot runs.
    """
    folder = reference_solution_dir() if solution is None else Path(solution)
    # load_solution names the notebook to finish when a part is missing or unfinished.
    load_solution(folder, required=MISSION_PARTS)
    if folder.is_dir():
        # What load_solution just checked: the same export, broken cells left out.
        export = export_solution(folder, strict=False)
        done = len(export.found) - len(export.unfinished)
        source = (
            "the reference solution (the export of solutions/)"
            if solution is None
            else f"exported from {folder}/"
        )
        return export.source, f"{source}, {done} of {len(CONTRACT)} graded parts"
    return folder.read_text(encoding="utf-8"), f"a copy of {folder}"


def _check_robot_python(source: str, where: str) -> None:
    version = ".".join(str(number) for number in ROBOT_PYTHON)
    try:
        ast.parse(source, filename=where, feature_version=ROBOT_PYTHON)
    except SyntaxError as error:
        raise SolutionError(
            f"The solution from {where} uses Python newer than {version} (line {error.lineno}: "
            f"{error.msg}), which the robot cannot run; rewrite that line for Python {version}."
        ) from None


def _copy_library(deploy: Path) -> List[Path]:
    copied = []
    for relative in robot_module_files():
        target = deploy / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / relative, target)
        copied.append(relative)
    return copied


def _message_packages(folder: Path) -> Optional[str]:
    """Generate genpy's message packages into ``folder``; a note if that is not possible.

    Debian's ROS packages are importable only while they are generated: the path and the
    modules loaded from there are as before afterwards, so that a notebook (or a later
    ``duckie run``) that prepared a robot project still meets the course's own rospy.
    """
    from duckielib.ros import backend

    path_before, modules_before = list(sys.path), set(sys.modules)
    try:
        if not (backend.use_debian_ros() and importlib.util.find_spec("genpy") is not None):
            return (
                "Debian's genpy is not installed, so deploy/msgs/ was not written: it is "
                "needed only to run the nodes on this laptop (install ROS 1 with `make ros`)."
            )
        backend.generate_message_packages(folder)
        return None
    finally:
        sys.path[:] = path_before
        for name in set(sys.modules) - modules_before:
            where = str(getattr(sys.modules[name], "__file__", None) or "")
            if where.startswith(backend.DEBIAN_DIST_PACKAGES):
                del sys.modules[name]


def _swap(new: Path, deploy: Path) -> None:
    """Put ``new`` in the place of ``deploy``; the old one is removed only after the swap."""
    old = deploy.with_name(GENERATED[2])
    if old.exists():
        shutil.rmtree(old)
    if deploy.exists():
        deploy.replace(old)
    new.replace(deploy)
    if old.exists():
        shutil.rmtree(old)


def prepare(
    solution: Union[str, Path, None] = None,
    project: Union[str, Path, None] = None,
    quiet: bool = False,
) -> Prepared:
    """Write the course library and a solution into a robot project's ``deploy/`` folder.

    Args:
        solution: a folder of notebooks (a student's ``course/``), a ``.py`` file made by
            ``duckie export``, or ``None`` for the course's reference solution.
        project: the Duckietown project (default: the repository's ``robot_nodes/``).
        quiet: whether to keep from printing what was written and the next commands.

    Returns:
        What was written.

    Raises:
        SolutionError: if the solution lacks a part the robot runs, has one unfinished, or
            uses syntax newer than Python 3.8 (nothing is written then).
        DuckielibError: if ``project`` is not a Duckietown project.
    """
    project = PROJECT if project is None else Path(project)
    if not ((project / ".dtproject").is_file() and (project / "Dockerfile").is_file()):
        raise DuckielibError(
            f"{project} is not a Duckietown project (it needs .dtproject and a Dockerfile); "
            "give the course's robot_nodes/ folder."
        )
    source, origin = _solution_source(solution)
    _check_robot_python(source, "the reference solution" if solution is None else str(solution))

    deploy, new = project / GENERATED[0], project / GENERATED[1]
    if new.exists():
        shutil.rmtree(new)
    try:
        new.mkdir()
        library = _copy_library(new)
        (new / "solution.py").write_text(source, encoding="utf-8")
        note = _message_packages(new / "msgs")
    except BaseException:
        shutil.rmtree(new, ignore_errors=True)
        raise
    _swap(new, deploy)
    prepared = Prepared(
        deploy=deploy,
        solution=deploy / "solution.py",
        source=origin,
        library=library,
        messages=None if note else deploy / "msgs",
        notes=[note] if note else [],
    )
    if not quiet:
        print(prepared.text())
    return prepared
