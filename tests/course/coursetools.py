"""Helpers for the course gates: the notebooks' cells by kind, and the wrong solutions."""

from __future__ import annotations

import functools
import json
import re
import shutil
from pathlib import Path

from autograder.course import ROOT, assignments

SOLUTIONS = ROOT / "solutions"
COURSE = ROOT / "course"
NAMES = assignments(SOLUTIONS)

SOLUTION_REGION = re.compile(r"### BEGIN SOLUTION\n(.*?)### END SOLUTION", re.S)
HIDDEN_REGION = re.compile(r"### BEGIN HIDDEN TESTS\n(.*?)### END HIDDEN TESTS", re.S)


def notebook_path(folder: Path, name: str) -> Path:
    return folder / name / f"{name}.ipynb"


def load(path: Path) -> dict:
    return json.loads(path.read_text(encoding="utf-8"))


def source(cell: dict) -> str:
    text = cell.get("source", "")
    return "".join(text) if isinstance(text, list) else text


def nbgrader(cell: dict) -> dict:
    return cell.get("metadata", {}).get("nbgrader", {})


def graded_cells(notebook: dict) -> dict:
    """The cells students write, by grade_id."""
    return {
        nbgrader(cell)["grade_id"]: cell
        for cell in notebook["cells"]
        if nbgrader(cell).get("solution") and not nbgrader(cell).get("grade")
    }


def checking_cells(notebook: dict) -> dict:
    """The autograded test cells, by grade_id."""
    return {
        nbgrader(cell)["grade_id"]: cell
        for cell in notebook["cells"]
        if nbgrader(cell).get("grade") and not nbgrader(cell).get("solution")
    }


def answer_cells(notebook: dict) -> dict:
    """The answers in words a person grades (markdown cells), by grade_id."""
    return {
        nbgrader(cell)["grade_id"]: cell
        for cell in notebook["cells"]
        if nbgrader(cell).get("grade") and nbgrader(cell).get("solution")
    }


def answer_keys() -> set:
    """Every answer in words of the course, as ``(notebook, grade_id)``."""
    return {(name, grade_id) for name in NAMES for grade_id in answer_cells(load_solution_nb(name))}


def wrong_solutions() -> dict:
    """Every deliberately wrong solution: ``(notebook, grade_id, mistake) -> cell source``."""
    owners: dict = {}
    for name in NAMES:
        for grade_id in graded_cells(load_solution_nb(name)):
            owners.setdefault(grade_id, []).append(name)
    found = {}
    for path in sorted(Path(__file__).parent.glob("wrong_*.py")):
        namespace: dict = {}
        exec(compile(path.read_text(encoding="utf-8"), str(path), "exec"), namespace)
        for grade_id, mistakes in namespace["WRONG"].items():
            owner = owners.get(grade_id, [])
            assert len(owner) == 1, f"{path.name}: {grade_id} is graded in {owner or 'no'} notebook"
            for mistake, cell in mistakes.items():
                found[(owner[0], grade_id, mistake)] = (
                    cell
                    if isinstance(cell, str)
                    else edited_reference(owner[0], grade_id, cell, f"{path.name}: {mistake}")
                )
    return found


def edited_reference(name: str, grade_id: str, edits, label: str) -> str:
    """The reference source of a graded cell with ``(old, new)`` edits, each found once."""
    text = source(graded_cells(load_solution_nb(name))[grade_id])
    for old, new in edits:
        assert text.count(old) == 1, f"{label}: {old!r} is not in the reference exactly once"
        text = text.replace(old, new)
    return text


@functools.lru_cache(maxsize=None)
def load_solution_nb(name: str) -> dict:
    """A notebook of solutions/, read once (callers must not change it)."""
    return load(notebook_path(SOLUTIONS, name))


MARKERS = ("### BEGIN SOLUTION", "### END SOLUTION")


def as_student(text: str) -> str:
    """The reference code of a graded cell as a student would type it (no region markers)."""
    return "\n".join(line for line in text.splitlines() if line.strip() not in MARKERS) + "\n"


def reference_answers() -> dict:
    """Every graded cell's reference code, as a student would type it: ``{(name, id): text}``."""
    return {
        (name, grade_id): as_student(source(cell))
        for name in NAMES
        for grade_id, cell in graded_cells(load_solution_nb(name)).items()
    }


def student_copy(folder, replacements):
    """A copy of course/ in ``folder`` with graded cells replaced: ``{(name, grade_id): text}``."""
    shutil.copytree(COURSE, folder)
    for name in NAMES:
        path = notebook_path(folder, name)
        notebook = load(path)
        for cell in notebook["cells"]:
            grade_id = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")
            if (name, grade_id) in replacements:
                cell["source"] = replacements[(name, grade_id)]
        path.write_text(json.dumps(notebook, indent=1) + "\n", encoding="utf-8")
    return folder


def too_early(run) -> str | None:
    """Why Run All of an untouched released notebook stops before its first exercise, or None.

    It may stop only at the first exercise: its own cell, the first test cell after it, or a
    cell between the two that says in one sentence what to finish first (a ``SolutionError``
    starting "Finish", or "Fix notebook" for an earlier notebook's function that fails its
    visible test). A notebook without exercises must run to the end.
    """
    stop = run.stops_at
    if run.stopped is not None:
        return f"{run.name}: {run.stopped}"
    if stop is None:
        return None
    if not run.exercises:
        return f"{run.name} has no exercise, yet Run All stops at {stop.describe()}"
    first, number = next(iter(run.exercises.items()))
    if stop.number < number:
        return (
            f"{run.name}: Run All stops at {stop.describe()}, before the first exercise "
            f"({first}, cell {number}): what comes before it must run without it"
        )
    if stop.kind in ("exercise", "test") or stop.error.startswith(
        ("SolutionError: Finish", "SolutionError: Fix notebook")
    ):
        return None
    return (
        f"{run.name}: Run All stops at {stop.describe()}, after the first exercise ({first}) "
        "but without saying which exercise to finish first"
    )
