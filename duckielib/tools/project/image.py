"""What a project's ``Dockerfile`` gives its nodes: the image's environment, on the laptop.

``dts devel build`` builds the project's image from its ``Dockerfile``, and every node of
``dts devel run`` starts with the variables its ``ENV`` lines set: a path to a file the image
copied in (``COPY ./deploy /code/course`` then ``ENV DUCKIE_SOLUTION=/code/course/solution.py``),
a mode switch, a ``PYTHONPATH``. ``duckie run`` reads those lines and sets the same variables,
with each path inside the image turned back into the project's own file that ``COPY`` put
there. A variable whose value depends on the base image (``${CATKIN_WS_DIR}``), or names an
image path no ``COPY`` of the project fills, is left unset: the laptop has no such path.

Laptop side; never deployed.
"""

from __future__ import annotations

import contextlib
import os
import re
import shlex
import sys
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Dict, Iterator, List, Optional, Tuple

from duckielib.tools.project.shell import Unresolved, expand

__all__ = ["ImageEnvironment", "image_environment"]


@dataclass
class ImageEnvironment:
    """The variables a project's image sets for its nodes, mapped to the laptop.

    Attributes:
        variables: what to set, by name (paths are the project's files).
        python_path: the project's folders the image puts on ``PYTHONPATH``.
        notes: what the run should say about them (a path the project does not hold yet).
    """

    variables: Dict[str, str] = field(default_factory=dict)
    python_path: List[Path] = field(default_factory=list)
    notes: List[str] = field(default_factory=list)

    @contextlib.contextmanager
    def applied(self) -> Iterator[None]:
        """Set the variables (those the user has not set) and the Python path, then restore."""
        added = {name: value for name, value in self.variables.items() if name not in os.environ}
        path_before = list(sys.path)
        os.environ.update(added)
        sys.path.extend(str(folder) for folder in self.python_path if str(folder) not in sys.path)
        try:
            yield
        finally:
            for name in added:
                os.environ.pop(name, None)
            sys.path[:] = path_before


def _instructions(text: str) -> Iterator[Tuple[str, str]]:
    """A Dockerfile's instructions, ``(KEYWORD, arguments)``, continuation lines joined."""
    logical = ""
    for line in text.splitlines():
        stripped = line.strip()
        if not logical and (not stripped or stripped.startswith("#")):
            continue
        if stripped.startswith("#"):
            continue  # a comment inside a continued instruction
        if stripped.endswith("\\"):
            logical += stripped[:-1] + " "
            continue
        logical += stripped
        keyword, _, arguments = logical.partition(" ")
        yield keyword.upper(), arguments.strip()
        logical = ""


def _pairs(arguments: str) -> List[Tuple[str, str]]:
    """``NAME=value`` pairs of an ``ENV`` or ``ARG`` line (``ENV NAME value`` too)."""
    try:
        words = shlex.split(arguments, posix=True)
    except ValueError:
        return []
    if words and "=" not in words[0]:
        return [(words[0], " ".join(words[1:]))]
    return [tuple(word.split("=", 1)) for word in words if "=" in word]  # type: ignore[misc]


def _copied(arguments: str, known: Dict[str, str], root: Path) -> Optional[Tuple[str, Path]]:
    """``(image path, project path)`` of a ``COPY``/``ADD`` of one of the project's folders."""
    try:
        words = [word for word in shlex.split(arguments) if not word.startswith("--")]
        if len(words) != 2:
            return None
        source, target = words[0], expand(words[1], known)
    except (ValueError, Unresolved):
        return None
    source = re.sub(r"/\.?$", "", source).removeprefix("./") or "."
    if not target.startswith("/") or "$" in source or "*" in source:
        return None
    return str(PurePosixPath(target)), (root / source).resolve()


def _mapped(value: str, copies: List[Tuple[str, Path]]) -> Optional[str]:
    """``value`` with each image path (``:``-separated) turned into the project's path."""
    parts = []
    for part in value.split(":"):
        if not part.startswith("/"):
            parts.append(part)
            continue
        for image, project in sorted(copies, key=lambda copy: -len(copy[0])):
            if part == image or part.startswith(image + "/"):
                parts.append(str(project / part[len(image) :].lstrip("/")))
                break
        else:
            return None  # a path of the base image: the laptop has nothing there
    return ":".join(parts)


def image_environment(root: Path) -> ImageEnvironment:
    """The ``ENV`` of ``root/Dockerfile``, mapped to the project (empty without a Dockerfile)."""
    found = ImageEnvironment()
    dockerfile = root / "Dockerfile"
    if not dockerfile.is_file():
        return found
    known: Dict[str, str] = {}
    copies: List[Tuple[str, Path]] = []
    for keyword, arguments in _instructions(dockerfile.read_text(errors="replace")):
        if keyword == "ARG":
            for name, default in _pairs(arguments):
                if name in known:
                    continue
                with contextlib.suppress(Unresolved):  # else the base image's: unknown here
                    known[name] = expand(default, known)
        elif keyword in ("COPY", "ADD"):
            copy = _copied(arguments, known, root)
            if copy is not None:
                copies.append(copy)
        elif keyword == "ENV":
            for name, raw in _pairs(arguments):
                try:
                    value = expand(raw, known)
                except Unresolved:
                    known.pop(name, None)
                    continue
                known[name] = value
                _note_variable(found, name, value, copies, root)
    return found


def _note_variable(
    found: ImageEnvironment, name: str, value: str, copies: List[Tuple[str, Path]], root: Path
) -> None:
    mapped = _mapped(value, copies)
    if mapped is None:
        found.variables.pop(name, None)
        return
    if name == "PYTHONPATH":
        found.python_path = [Path(part) for part in mapped.split(":") if part]
        return
    found.variables[name] = mapped
    if mapped != value and not Path(mapped).exists():
        where = os.path.relpath(mapped, root)
        found.notes.append(
            f"the Dockerfile sets {name}={value}, the project's {where} in the image, which "
            "does not exist yet."
        )
