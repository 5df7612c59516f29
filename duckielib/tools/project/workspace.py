"""A Duckietown project's catkin packages, and their imports by name from any folder.

Laptop side; never deployed.
"""

from __future__ import annotations

import contextlib
import importlib.abc
import importlib.machinery
import importlib.util
import os
import re
import sys
import types
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, Iterator, List, Optional, Sequence, Tuple, Union

from duckielib.errors import DuckielibError

__all__ = ["Package", "PathLike", "ProjectError", "Workspace"]

PathLike = Union[str, "os.PathLike[str]"]

#: Where a node script may sit in its package, searched first (rosrun searches them all).
_SCRIPT_FOLDERS = ("src", "scripts", "nodes", "bin", "")


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
            described = self.root / ".dtproject"
            kind = described.read_text(errors="replace") if described.is_file() else ""
            if "template-basic" in kind:
                raise ProjectError(
                    f"{self.root} is a Duckietown template-basic project: plain Python, with no "
                    "ROS nodes (no catkin package with a package.xml), so there is nothing for "
                    "duckie run to start on the virtual Duckiebot; run its code with python3."
                )
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
