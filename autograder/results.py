"""What grading one student gives, and how it is kept: as plain data, written whole or not at all.

A student's result travels from the process that graded them (perhaps on another machine of
a cluster) to the one writer of the class's results as JSON (:func:`to_data`,
:func:`from_data`), and is kept in ``results/STUDENT.json`` as soon as it arrives, written
atomically (:func:`write_atomic`): a crash or Ctrl-C never leaves half a file, and the next
``duckie grade`` reads it back instead of grading that student again.
"""

from __future__ import annotations

import base64
import dataclasses
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

from autograder.driving import Driving, driving_score

__all__ = ["StudentResult", "from_data", "not_graded", "to_data", "write_atomic"]


def not_graded(why: str) -> str:
    """The sentence of a student whose grading stopped on the grader's side (no grade given)."""
    return f"Not graded: {why}; run duckie grade again to grade this student."


@dataclass
class StudentResult:
    """What grading one student gave.

    Attributes:
        student: the student's id: their folder's name, or for a name nbgrader or a file system
            cannot take (spaces at its ends, brackets, a new line, 250 characters), a plain
            form of it with a hash (:func:`autograder.grade.student_id`).
        cells: ``(assignment, grade_id) -> (score, max_score)``.
        problems: one sentence each: what went wrong while grading (not failed tests).
        messages: ``(assignment, grade_id) -> message`` of each failed test.
        missions: each mission's driving score, by mission name (empty when the missions
            were not driven); :attr:`driving_score` is their mean.
        seconds: wall-clock seconds spent on this student.
        complete: False when the grading itself stopped (a crash, the grader's time limit):
            the next ``duckie grade`` grades this student again.
        to_grade: the graded cells that wait for a person (an answer in words): no automatic
            score, and none given yet in nbgrader's Formgrader. They count 0 until graded.
        comments: ``(assignment, cell) -> text``: what a person wrote in nbgrader's
            Formgrader about a cell (an answer in words, or the code of a graded cell), read
            from the gradebook at every run.
        name: the folder's name as written, when the id differs from it (:attr:`shown`).
        timings: where the unit's time went, in seconds: ``notebooks`` (the sandboxed runs,
            kernels' starts included), ``cells`` (the cells themselves), ``nbgrader`` (its
            converters and gradebook), ``driving`` (export and mission), ``unit`` (all);
            ``notebook:NAME``, each notebook's sandboxed run. Besides times: ``calls`` (the
            tests' calls to the student's code), ``largest_answer`` (the longest answer to
            one, in characters) and ``grader_memory_mb`` (the most memory the grader's process
            for the student held).
    """

    student: str
    cells: Dict[Tuple[str, str], Tuple[float, float]] = field(default_factory=dict)
    problems: List[str] = field(default_factory=list)
    messages: Dict[Tuple[str, str], str] = field(default_factory=dict)
    missions: Dict[str, Driving] = field(default_factory=dict)
    seconds: float = 0.0
    complete: bool = True
    to_grade: List[Tuple[str, str]] = field(default_factory=list)
    comments: Dict[Tuple[str, str], str] = field(default_factory=dict)
    timings: Dict[str, float] = field(default_factory=dict)
    name: str = ""

    @property
    def shown(self) -> str:
        """The student as the instructor named them: the folder's name as written."""
        return self.name or self.student

    @property
    def total(self) -> float:
        """The points scored, all assignments together."""
        return sum(score for score, _ in self.cells.values())

    @property
    def driving_score(self) -> Optional[float]:
        """The mean of the missions' scores, out of 100, or None when none was driven."""
        return driving_score(self.missions) if self.missions else None

    @property
    def max_total(self) -> float:
        """The points there were to score."""
        return sum(most for _, most in self.cells.values())


def _key(pair: Tuple[str, str]) -> str:
    return f"{pair[0]}:{pair[1]}"


#: The pictures of a driving run, bytes kept as base64 text.
_PICTURES = ("figure", "animation")


def _pair(key: str) -> Tuple[str, str]:
    assignment, _, grade_id = key.partition(":")
    return assignment, grade_id


def to_data(result: StudentResult) -> Dict[str, Any]:
    """``result`` as JSON-ready data."""
    missions = {}
    for name, driving in result.missions.items():
        data = dataclasses.asdict(driving)
        for picture in _PICTURES:
            value = data.get(picture)
            data[picture] = None if value is None else base64.b64encode(value).decode("ascii")
        missions[name] = data
    return {
        "student": result.student,
        "cells": {_key(key): list(value) for key, value in result.cells.items()},
        "problems": list(result.problems),
        "messages": {_key(key): value for key, value in result.messages.items()},
        "missions": missions,
        "seconds": result.seconds,
        "complete": result.complete,
        "to_grade": [_key(cell) for cell in result.to_grade],
        "comments": {_key(key): value for key, value in result.comments.items()},
        "timings": dict(result.timings),
        "name": result.name,
    }


def from_data(data: Dict[str, Any]) -> StudentResult:
    """The result that :func:`to_data` gave ``data`` for."""
    known = {item.name for item in dataclasses.fields(Driving)}
    missions = {}
    for name, driving in (data.get("missions") or {}).items():
        kept = {key: value for key, value in driving.items() if key in known}
        for picture in _PICTURES:
            if kept.get(picture) is not None:
                kept[picture] = base64.b64decode(kept[picture])
        missions[str(name)] = Driving(**kept)
    return StudentResult(
        student=str(data["student"]),
        cells={_pair(key): (float(v[0]), float(v[1])) for key, v in data["cells"].items()},
        problems=[str(problem) for problem in data.get("problems", [])],
        messages={_pair(key): str(value) for key, value in data.get("messages", {}).items()},
        missions=missions,
        seconds=float(data.get("seconds", 0.0)),
        complete=bool(data.get("complete", True)),
        to_grade=[_pair(str(key)) for key in data.get("to_grade", [])],
        comments={_pair(key): str(value) for key, value in data.get("comments", {}).items()},
        timings={str(key): float(value) for key, value in data.get("timings", {}).items()},
        name=str(data.get("name", "")),
    )


def write_atomic(path: Union[str, Path], data: Union[str, bytes]) -> None:
    """Write ``path`` whole or not at all: a temporary file beside it, then renamed over it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    raw = data.encode("utf-8") if isinstance(data, str) else data
    with tempfile.NamedTemporaryFile(dir=path.parent, delete=False, suffix=".tmp") as handle:
        handle.write(raw)
        handle.flush()
        os.fsync(handle.fileno())
    Path(handle.name).replace(path)
