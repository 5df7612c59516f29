"""Repair a submitted notebook against the release before nbgrader grades it.

Plain ``nbgrader autograde`` (0.9) restores the instructor's cells it finds by ``grade_id``
(source of locked cells, points, cell type, kernelspec) but fails the whole notebook, or
scores a test zero without running it, when a student's notebook is damaged: a duplicated or
renamed grade id fails it, a deleted test cell or one stripped of its metadata scores zero, a
test cell moved above its answer fails with a NameError, an invalid cell id or unreadable JSON
fails it. :func:`repair` rebuilds the notebook on the release's instructor cells so every
test runs on the student's answers, and says in one sentence per problem what it found.
"""

from __future__ import annotations

import copy
import re
from pathlib import Path
from typing import Dict, List, Optional, Tuple

import nbformat
from nbformat import NotebookNode
from nbformat.v4.nbbase import random_cell_id

__all__ = ["repair"]

_VALID_ID = re.compile(r"^[a-zA-Z0-9-_]{1,64}$")
_ROLES = ("grade", "solution", "locked", "task")


#: The most cells a handed-in notebook may have (the course's have about 80 each): a notebook
#: of 100,000 cells would hold its grading for minutes before any cell ran.
CELL_LIMIT = 2000


def repair(submitted: Path, release: Path) -> Tuple[NotebookNode, List[str]]:
    """A notebook nbgrader can grade fairly, built from ``submitted`` and the release's cells.

    Instructor cells (test, answer, read-only and task cells) are matched by ``grade_id``, or
    by cell id when the student changed or removed their nbgrader metadata; they get the
    release's metadata back, and locked ones their released source. Missing instructor cells
    are put back after the cell that precedes them in the release, an answer cell as released
    (so it scores as unanswered); copies of an instructor cell after the first are dropped (an
    answer's copies stay as ordinary cells); unknown grade ids become ordinary cells; a test cell
    moved above the cell it follows in the release is put back after it. The student's own
    cells keep their order. Kernelspec and language_info are the release's.

    Args:
        submitted: the student's notebook (any nbformat version, possibly not a notebook at all).
        release: the release notebook of the same assignment (``course/NN/NN.ipynb``).

    Returns:
        The notebook to grade, and one sentence per problem found, each starting with the
        assignment's name; a notebook that cannot be read is replaced by the release notebook.
    """
    original = nbformat.read(release, as_version=4)
    name = Path(release).stem
    try:
        text = Path(submitted).read_text(encoding="utf-8")
        if not text.strip():
            raise ValueError("the file is empty")
        notebook = nbformat.reader.reads(text)
        version = notebook.get("nbformat")
        if version not in (3, 4):
            raise ValueError("it is JSON but not a notebook of nbformat 3 or 4")
        cells = notebook.get("cells", notebook.get("worksheets", [{}])[0].get("cells", []))
        if len(cells) > CELL_LIMIT:
            raise ValueError(
                f"it has {len(cells)} cells, more than the {CELL_LIMIT} the grader takes"
            )
        notebook = nbformat.convert(notebook, 4)
        repaired, problems = _Repair(name, original).run(notebook)
        nbformat.validate(repaired)
    except Exception as error:  # any damage: grade the release in its place
        return copy.deepcopy(original), [
            f"{name}: not a readable notebook ({_reason(error)}); the release notebook was "
            "graded in its place, so it scores zero."
        ]
    if version != 4:
        problems.insert(
            0, f"{name}: the notebook was in nbformat {version}; it was converted to 4 and graded."
        )
    return repaired, problems


def _reason(error: Exception) -> str:
    if isinstance(error, nbformat.reader.NotJSONError):
        return "it is not JSON"
    if isinstance(error, UnicodeDecodeError):
        return "it is not UTF-8 text"
    lines = str(getattr(error, "message", error)).strip().splitlines() or [type(error).__name__]
    return lines[0][:1].lower() + lines[0][1:120]


def _grade_id(cell: NotebookNode) -> Optional[str]:
    return cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")


def _kind(cell: NotebookNode) -> str:
    roles = cell.metadata.nbgrader
    if roles.get("solution"):
        return "answer cell"
    if roles.get("grade"):
        return "test cell"
    return "task cell" if roles.get("task") else "read-only cell"


class _Repair:
    """One repair: the release's instructor cells and the problems found so far."""

    def __init__(self, name: str, release: NotebookNode) -> None:
        self.name = name
        self.release = release
        self.owned: Dict[str, NotebookNode] = {
            gid: cell for cell in release.cells if (gid := _grade_id(cell))
        }
        self.by_cell_id = {cell.get("id"): gid for gid, cell in self.owned.items()}
        self.problems: List[str] = []

    def say(self, cell: NotebookNode, what: str) -> None:
        self.problems.append(f"{self.name}: the {_kind(cell)} {_grade_id(cell)} {what}.")

    def run(self, notebook: NotebookNode) -> Tuple[NotebookNode, List[str]]:
        self._fix_ids(notebook.cells)
        present = {_grade_id(cell) for cell in notebook.cells} & set(self.owned)
        cells: List[NotebookNode] = []
        copies: Dict[str, int] = {}
        for cell in notebook.cells:
            gid = _grade_id(cell)
            if gid not in self.owned:
                claimed = self.by_cell_id.get(cell.get("id"))
                if claimed is not None and claimed not in present:
                    present.add(claimed)
                    self._say_renamed(self.owned[claimed], gid)
                    gid = claimed
                elif cell.get("metadata", {}).pop("nbgrader", None) and gid is not None:
                    self.problems.append(
                        f"{self.name}: a cell had the unknown grade id {gid!r}; "
                        "it was graded as an ordinary cell."
                    )
            if gid in copies:
                copies[gid] += 1
                if self.owned[gid].metadata.nbgrader.get("solution"):
                    cell.metadata.pop("nbgrader", None)
                    cells.append(cell)
            elif gid in self.owned:
                copies[gid] = 1
                cells.append(self._restore(cell, self.owned[gid]))
            else:
                cells.append(cell)
        for gid, count in copies.items():
            if count > 1:
                answer = self.owned[gid].metadata.nbgrader.get("solution")
                kept = "the others stay as ordinary cells" if answer else "only the first was kept"
                self.say(self.owned[gid], f"appeared {count} times; {kept}")
        self._place(cells)
        for cell in cells:
            if cell.cell_type == "code":
                cell.outputs, cell.execution_count = [], None
        self._fix_ids(cells, quiet=True)
        metadata = copy.deepcopy(notebook.metadata)
        self._fix_kernel(metadata)
        return nbformat.v4.new_notebook(cells=cells, metadata=metadata), self.problems

    def _say_renamed(self, original: NotebookNode, gid: Optional[str]) -> None:
        if gid is None:
            self.say(original, "had lost its nbgrader metadata; it was restored and graded")
        else:
            self.say(original, f"had its grade id changed to {gid!r}; it was restored and graded")

    def _restore(self, cell: NotebookNode, original: NotebookNode) -> NotebookNode:
        """The release's cell, with the student's source in an answer cell."""
        theirs = cell.get("metadata", {}).get("nbgrader", {})
        roles = original.metadata.nbgrader
        if theirs and roles.get("grade") and theirs.get("points") != roles.get("points"):
            self.say(
                original,
                f"claimed {theirs.get('points')} points; it was graded out of {roles['points']}",
            )
        elif theirs and any(bool(theirs.get(role)) != bool(roles.get(role)) for role in _ROLES):
            self.say(original, "had its nbgrader metadata changed; the released one was used")
        restored = copy.deepcopy(original)
        if not roles.get("locked"):
            restored.source = cell.get("source", "")
            if "attachments" in cell:
                restored.attachments = cell.attachments
        elif (cell.get("source"), cell.get("cell_type")) != (original.source, original.cell_type):
            self.say(original, "was edited; the original was put back and graded")
        return restored

    def _place(self, cells: List[NotebookNode]) -> None:
        """Put missing instructor cells back, and tests moved above their predecessor."""
        keys = [_grade_id(cell) or cell.get("id") for cell in cells]
        order = [_grade_id(cell) or cell.get("id") for cell in self.release.cells]
        for index, gid in enumerate(order):
            if gid not in self.owned:
                continue
            original = self.owned[gid]
            roles = original.metadata.nbgrader
            anchor = next((keys.index(key) for key in reversed(order[:index]) if key in keys), -1)
            if gid in keys:
                here = keys.index(gid)
                if here > anchor or not roles.get("grade") or roles.get("solution"):
                    continue
                cell, _ = cells.pop(here), keys.pop(here)
                anchor -= 1
                self.say(original, "was moved above the cell it follows; it was put back after it")
            else:
                cell = copy.deepcopy(original)
                self.say(
                    original,
                    "was deleted; the released cell was put back, so it scores as unanswered"
                    if roles.get("solution")
                    else "was deleted; it was put back and graded",
                )
            cells.insert(anchor + 1, cell)
            keys.insert(anchor + 1, gid)

    def _fix_ids(self, cells: List[NotebookNode], quiet: bool = False) -> None:
        """Give a new id to every cell whose id is missing, not valid or already taken."""
        seen, bad = set(), 0
        for cell in cells:
            cell_id = cell.get("id")
            if not isinstance(cell_id, str) or not _VALID_ID.match(cell_id) or cell_id in seen:
                bad += cell_id is not None
                cell_id = cell["id"] = random_cell_id()
            seen.add(cell_id)
        if bad and not quiet:
            self.problems.append(
                f"{self.name}: {bad} cell id(s) were not valid or not unique; new ones were given."
            )

    def _fix_kernel(self, metadata: NotebookNode) -> None:
        spec = self.release.metadata.get("kernelspec", {})
        language = self.release.metadata.get("language_info", {})
        theirs = (metadata.get("kernelspec") or {}).get("name")
        their_language = (metadata.get("language_info") or {}).get("name")
        if their_language not in (None, language.get("name")):
            asked = f"the kernel {theirs!r} in {their_language!r}"
        elif theirs != spec.get("name"):
            asked = f"the kernel {theirs!r}" if theirs else "no kernel"
        else:
            asked = ""
        if asked:
            self.problems.append(
                f"{self.name}: the notebook asked for {asked}; it was graded with "
                f"{spec.get('name')} as released."
            )
        metadata["kernelspec"] = copy.deepcopy(spec)
        metadata["language_info"] = copy.deepcopy(language)
