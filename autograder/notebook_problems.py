"""What the run of a student's notebook says of it, in sentences for ``problems``.

Each sentence names the notebook, and the cells by their position and first line in the
notebook as the grader sent it to the sandbox (rebuilt on the release's instructor cells): cells
outside the tests that raised, tests that ran out of their time, cells that were slow, and a
full disk. Only the executed notebook's error outputs and the times its kernel recorded are
read from the run, as text.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, List, Optional

__all__ = [
    "cell_seconds",
    "cells_that_stopped",
    "disk_full",
    "raised_outside_tests",
    "slow_cells",
]


def _is_test(cell: Any) -> bool:
    """Whether ``cell`` is a test cell (code nbgrader grades that is not an answer)."""
    meta = cell.get("metadata", {}).get("nbgrader", {})
    return cell.cell_type == "code" and bool(meta.get("grade")) and not meta.get("solution")


def raised_outside_tests(
    assignment: str, sent: Any, executed: Any, cell_seconds: Optional[int] = None
) -> Optional[str]:
    """One sentence naming every cell outside the test cells that raised, or None if none did.

    Which cells are tests, where each cell is and what it says come from ``sent``: the notebook
    this process handed to the run, rebuilt on the release's instructor cells
    (:func:`autograder.tamper.repair`, then nbgrader's own restoring from the gradebook), so a
    student cannot turn a cell into a test or out of one. Only the error outputs are read from
    ``executed``, what came back from the run, and only as text. Cells that never ran because
    the kernel died (the ``NotRun`` error of
    :func:`autograder.sandbox.inside.notebook.mark_not_run`) are left out: the kernel's death is
    a problem of its own.

    Args:
        assignment: the assignment's name, which starts the sentence.
        sent: the notebook as sent to be run.
        executed: the same notebook as it came back, with its outputs.
        cell_seconds: the time limit of a cell, quoted for a cell that ran out of it.
    """
    from autograder.sandbox.inside.notebook import NOT_RUN
    from duckielib.tools.handin import raised_cells

    raised = [
        cell
        for cell in raised_cells(sent.cells, executed.cells, cell_seconds, skip=(NOT_RUN,))
        if not sent.cells[cell.number - 1].get("metadata", {}).get("nbgrader", {}).get("grade")
    ]
    if not raised:
        return None
    cells = "1 cell" if len(raised) == 1 else f"{len(raised)} cells"
    found = "; ".join(cell.describe() for cell in raised)
    return f"{assignment}: {cells} outside the tests raised: {found}"


def cells_that_stopped(name: str, sent: Any, executed: Any, cell_seconds: int) -> List[str]:
    """Sentences for the cells outside the tests that raised, and the tests that ran out of time."""
    from duckielib.tools.handin import raised_cells

    said = []
    raised = raised_outside_tests(name, sent, executed, cell_seconds)
    if raised is not None:
        said.append(raised)
    tests = {
        index
        for index, cell in enumerate(sent.cells)
        if cell.get("metadata", {}).get("nbgrader", {}).get("grade")
    }
    late = [
        cell
        for cell in raised_cells(sent.cells, executed.cells, cell_seconds)
        if cell.number - 1 in tests
        and cell.error.startswith(("CellTimeoutError", "KeyboardInterrupt"))
    ]
    if late:
        names = ", ".join(cell.grade_id or f"cell {cell.number}" for cell in late)
        said.append(
            f"{name}: {names} ran out of the {cell_seconds} s a cell may take and scored zero."
        )
    return said


def disk_full(folder: Path) -> Optional[str]:
    """How big ``folder``'s file system is, as a sentence's words, if it is full (or nearly)."""
    try:
        stats = os.statvfs(folder)
    except OSError:
        return None
    if stats.f_bavail * stats.f_frsize > 1024**2:
        return None
    return f"{stats.f_blocks * stats.f_frsize / 1e6:.0f} MB"


def cell_seconds(notebook: Any) -> float:
    """How long a run notebook's cells took, by the times its kernel recorded."""
    return sum(_seconds_of(cell) for cell in notebook.cells)


def _seconds_of(cell: Any) -> float:
    """How long one run cell took, by the times its kernel recorded (0 when it does not say)."""
    from datetime import datetime

    times = cell.get("metadata", {}).get("execution", {})
    try:
        start = datetime.fromisoformat(times["iopub.execute_input"].replace("Z", "+00:00"))
        end = datetime.fromisoformat(times["shell.execute_reply"].replace("Z", "+00:00"))
    except (KeyError, TypeError, ValueError, AttributeError):
        return 0.0
    return max(0.0, (end - start).total_seconds())


def slow_cells(name: str, sent: Any, executed: Any, seconds: int) -> List[str]:
    """One sentence naming the cells outside the tests that took more than ``seconds`` each.

    The times are the kernel's own; the cells are named by position and first line as the
    grader sent them (see :func:`raised_outside_tests`).
    """
    from duckielib.tools.handin import first_line

    slow = [
        (number, _seconds_of(cell))
        for number, cell in enumerate(executed.cells, start=1)
        if cell.cell_type == "code" and not _is_test(sent.cells[number - 1])
    ]
    slow = [(number, took) for number, took in slow if took > seconds]
    if not slow:
        return []
    total = sum(took for _, took in slow)
    shown = ", ".join(
        f"cell {number} ({first_line(sent.cells[number - 1].source)}): {took:.0f} s"
        for number, took in slow[:5]
    )
    more = f" and {len(slow) - 5} more" if len(slow) > 5 else ""
    if len(slow) == 1:
        return [f"{name}: 1 cell took over {seconds} s: {shown}."]
    return [
        f"{name}: {len(slow)} cells took over {seconds} s each, {total:.0f} s in all: "
        f"{shown}{more}."
    ]
