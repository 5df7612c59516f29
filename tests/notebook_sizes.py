"""How much code the notebooks give: given code cells, their lines, the cells over the limit.

Run it from the repository's root to see the released course, or name another folder::

    .venv/bin/python tests/notebook_sizes.py
    .venv/bin/python tests/notebook_sizes.py solutions

A given code cell is one a student does not write: a code cell with no nbgrader solution or
grade metadata (the exercises and their tests are the student's and the grader's). Given code
should read as the experiment, not as its plumbing: a cell longer than :data:`CELL_LINES`
belongs in the library, behind a function whose name says what it does. A cell's lines are
counted as the notebook shows them, blank lines included. The tests
(``tests/course/test_course_structure.py``) use :func:`sizes` to keep every given cell short.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import List, Tuple

ROOT = Path(__file__).resolve().parents[1]
#: The house's limit for a given code cell, in lines.
CELL_LINES = 40


@dataclass
class NotebookSize:
    """One notebook's given code: its name, and each given cell's number and lines.

    Attributes:
        name: the notebook's file name without ``.ipynb``.
        cells: ``(number, lines)`` of each given code cell; cells are numbered from 1 over
            all the notebook's cells, markdown included, as JupyterLab shows them.
    """

    name: str
    cells: List[Tuple[int, int]] = field(default_factory=list)

    @property
    def lines(self) -> int:
        """The given code's lines in all."""
        return sum(count for _, count in self.cells)

    def over(self, limit: int = CELL_LINES) -> List[Tuple[int, int]]:
        """The given cells longer than ``limit`` lines, as ``(number, lines)``."""
        return [(number, count) for number, count in self.cells if count > limit]


def is_given(cell: dict) -> bool:
    """Whether ``cell`` is code a student is given: a code cell nbgrader neither grades nor
    asks the student to write."""
    marks = cell.get("metadata", {}).get("nbgrader", {})
    return cell.get("cell_type") == "code" and not (marks.get("solution") or marks.get("grade"))


def cell_lines(cell: dict) -> int:
    """A cell's lines as the notebook shows them (a trailing line break opens no line)."""
    text = cell.get("source", "")
    text = "".join(text) if isinstance(text, list) else text
    return len(text.splitlines())


def notebook_size(path: Path) -> NotebookSize:
    """The given code cells of the notebook at ``path``."""
    notebook = json.loads(path.read_text(encoding="utf-8"))
    size = NotebookSize(path.stem)
    for number, cell in enumerate(notebook.get("cells", []), start=1):
        if is_given(cell):
            size.cells.append((number, cell_lines(cell)))
    return size


def sizes(folder: Path) -> List[NotebookSize]:
    """Every notebook under ``folder`` (checkpoints left out), in order of name."""
    paths = sorted(folder.rglob("*.ipynb"), key=lambda path: path.name)
    return [notebook_size(path) for path in paths if ".ipynb_checkpoints" not in path.parts]


def report(found: List[NotebookSize], limit: int = CELL_LINES) -> str:
    """Per notebook and in all: given cells, given lines, and the cells over ``limit`` lines."""
    lines = [f"{'notebook':24s} {'cells':>6s} {'lines':>6s} {'over ' + str(limit):>8s}"]
    for size in found:
        over = size.over(limit)
        lines.append(f"{size.name:24s} {len(size.cells):6d} {size.lines:6d} {len(over):8d}")
        lines += [f"  cell {number:3d}: {count:4d} lines" for number, count in over]
    cells = sum(len(size.cells) for size in found)
    given = sum(size.lines for size in found)
    over = sum(len(size.over(limit)) for size in found)
    lines.append(f"{'total':24s} {cells:6d} {given:6d} {over:8d}")
    largest = max((count for size in found for _, count in size.cells), default=0)
    lines.append(f"largest given cell: {largest} lines")
    return "\n".join(lines)


def main(argv: List[str]) -> int:
    """Print the report for the folder named in ``argv`` (``course`` by default)."""
    folder = Path(argv[0]) if argv else ROOT / "course"
    if not folder.is_dir():
        sys.stderr.write(f"{folder} is not a folder: name a folder of notebooks.\n")
        return 2
    sys.stdout.write(report(sizes(folder)) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
