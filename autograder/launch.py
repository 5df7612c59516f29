"""Starting one student's unit on a worker, and reading back what it wrote.

:func:`run_unit` writes what a worker is given (the student's files, the task) into a folder
of its own, starts ``python -I -m autograder.unit`` with a time limit (where the grader runs
as root, apart: unprivileged, in a view of its own, :mod:`autograder.sandbox.unit_process`),
and reads back the result it wrote as it reads any file a student's grading wrote: regular
files only, bounded. A unit that stopped, for any reason, is a student not graded this time.
"""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any, Dict, Optional

from autograder.sandbox import Limits, end_student_groups, unit_user
from autograder.sandbox.unit_process import UNIT_INSIDE, apart, unit_command

__all__ = ["RESULT_LIMIT", "UNIT_MARGIN_S", "run_unit", "unit_seconds"]


#: Seconds a unit may take besides its notebooks' and mission's limits (nbgrader's own work).
UNIT_MARGIN_S = 300


def unit_seconds(task: Dict[str, Any]) -> float:
    """The wall time a student's unit may take: each notebook's limit, the missions', a margin."""
    from autograder.driving import MISSIONS

    limits = Limits(**task["limits"])
    driving = len(MISSIONS) * limits.mission_seconds if task.get("driving") else 0
    notebooks = min(len(task["names"]) * limits.submission_seconds, limits.student_seconds)
    return notebooks + driving + UNIT_MARGIN_S


def _pdeathsig() -> None:  # pragma: no cover - runs in the child before exec
    """Die with the worker that started this unit (Linux), so none outlives a killed worker."""
    import ctypes

    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG


def run_unit(
    task: Dict[str, Any], files: Dict[str, bytes], course: Path, scratch: Optional[str] = None
) -> Dict[str, Any]:
    """Grade one student in a process of its own; what it found, as plain data.

    Args:
        task: the student, the assignments, the limits (see :mod:`autograder.grade`).
        files: the student's files, ``"NAME/relative/path" -> bytes``, already read safely.
        course: a folder with the class's ``source/``, ``release/`` and ``gradebook.db``.
        scratch: the folder the unit's own temporary folder goes in (the system's by default).

    Returns:
        ``{"result": ..., "autograded": {NAME: notebook text}}``, the result as
        :func:`autograder.results.to_data` writes it; when the unit itself stopped (its time
        limit, a crash), a result with ``complete`` false and a sentence saying why.
    """
    seconds = unit_seconds(task)
    # The student's user id, chosen here: whatever ends the unit, its control groups go with it.
    uid = unit_user()
    with tempfile.TemporaryDirectory(prefix="duckie-unit-", dir=scratch) as folder:
        try:
            return _run_unit(task, files, course, Path(folder), seconds, uid)
        finally:
            end_student_groups(uid)


def _run_unit(
    task: Dict[str, Any],
    files: Dict[str, bytes],
    course: Path,
    base: Path,
    seconds: float,
    uid: int,
) -> Dict[str, Any]:
    """:func:`run_unit` in folder ``base``, the student running as user ``uid``.

    As root with the sandbox, the unit's process runs apart (see this module's docstring): as
    user ``uid``, seeing ``base``'s ``task.json`` and ``submission/`` and the course
    read-only, writing only ``base/out``, on a file system of the student's own. Otherwise it
    runs as the grader does. Either way it is started isolated (``python -I``): neither the
    folder ``duckie grade`` was started from nor a variable such as ``PYTHONPATH`` puts a
    module of anyone's on its path.
    """
    from autograder.files import write_files

    separate = apart(bool(task["use_sandbox"]))
    folder = Path(UNIT_INSIDE) if separate else base
    write_files(base / "submission", files)
    (base / "submission").mkdir(exist_ok=True)  # an empty submission is graded too
    (base / "out").mkdir()
    if separate:
        course = _readable_course(course, base)
    (base / "task.json").write_text(
        json.dumps(
            {**task, "course_dir": str(folder / "course" if separate else course), "uid": uid}
        ),
        encoding="utf-8",
    )
    command = [sys.executable, "-I", "-m", "autograder.unit", str(folder)]
    if separate:
        for path in [base / "out", base / "task.json", *(base / "submission").rglob("*")]:
            os.chown(path, uid, uid, follow_symlinks=False)
        limits = dataclasses.replace(Limits(**task["limits"]), uid=uid)
        command = unit_command(command, base, course, limits, uid)
    stopped = None
    try:
        finished = subprocess.run(
            command,
            capture_output=True,
            text=True,
            timeout=seconds,
            check=False,
            preexec_fn=_pdeathsig,
            cwd=base,
        )
        if finished.returncode != 0 or not (base / "out" / "result.json").is_file():
            lines = [line for line in finished.stderr.splitlines() if line.strip()]
            stopped = (
                f"the grader's process for this student stopped ({lines[-1][:300]})"
                if lines
                else f"the grader's process for this student ended with {finished.returncode}"
            )
    except subprocess.TimeoutExpired:
        stopped = f"the grading of this student took more than {seconds:.0f} s and was stopped"
    if stopped is not None:
        return _stopped_unit(task, stopped)
    # Read as any file a student's grading wrote: regular files only, bounded.
    from autograder.files import UnsafeFile, read_regular

    limit = int(task["limits"].get("output_bytes", RESULT_LIMIT))
    try:
        answer = json.loads(read_regular(base / "out", "result.json", RESULT_LIMIT))
    except (UnsafeFile, ValueError) as error:
        return _stopped_unit(task, f"its result could not be read ({error})")
    autograded = {}
    for name in task["names"]:
        try:
            text = read_regular(base / "out" / "autograded", f"{name}.ipynb", limit)
        except (UnsafeFile, OSError):
            continue
        autograded[name] = text.decode("utf-8", errors="replace")
    return {"result": answer, "autograded": autograded}


#: The largest result a unit may write, in bytes.
RESULT_LIMIT = 64 * 1024**2


def _stopped_unit(task: Dict[str, Any], stopped: str) -> Dict[str, Any]:
    """A unit's answer when it stopped before its result: not graded, graded again next run."""
    from autograder.results import not_graded

    return {
        "result": {
            "student": task["student"],
            "cells": {},
            "problems": [not_graded(stopped)],
            "messages": {},
            "missions": {},
            "complete": False,
        },
        "autograded": {},
    }


def _readable_course(course: Path, base: Path) -> Path:
    """A copy of the course in ``base`` that the student's user may read, and no one else.

    The course holds the hidden tests: the copy lies in ``base``, whose mode lets no one else
    in, and the unit's process sees only the copy (read-only).
    """
    copy = base / "course"
    shutil.copytree(course, copy)
    for path in [copy, *copy.rglob("*")]:
        if not path.is_symlink():
            path.chmod(0o755 if path.is_dir() else 0o644)
    base.chmod(0o700)
    return copy
