"""Expensive runs made once per ``make test``, whichever of its workers asks first.

A graded class, the course's Run All, the reference's drives: several test modules read the
same run, and pytest-xdist hands modules to different worker processes, so a module's fixture
alone would make it once per worker. :func:`shared` makes it once per test session, in a folder
every worker of the session sees, under a file lock: the first worker to ask makes it while
the others wait, then each reads what it made. The folder's name holds a key of everything the
run is made from (the course, the instructors' notebooks, the library, the grader, the robot's
project and the tests) as they were when the session began, so a run made from other files is
never read.

A run that raised is not made again by the next worker: each reader fails with its error.
A run whose worker died half-way (no value and no error) is made again from an empty folder.
What a run returns is pickled beside it, so it must be made of plain values and paths; its
folder is read, never written, by the tests that share it.
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import pickle
import shutil
import traceback
from pathlib import Path
from typing import Any, Callable

__all__ = ["SharedRunError", "content_key", "shared"]

ROOT = Path(__file__).resolve().parent.parent
#: What a shared run is made from: its key changes when any of their files does.
SOURCES = ("course", "solutions", "duckielib", "autograder", "robot_nodes", "tests")
SUFFIXES = {".py", ".ipynb", ".launch", ".msg", ".srv", ".yaml", ".json", ".txt", ".toml"}


class SharedRunError(RuntimeError):
    """The shared run failed where it was made, in this worker or another."""


#: The environment variable that hands the key on: the first process of a session computes it,
#: before its workers start, so that every worker names a run alike even if a file changes
#: during the session.
VARIABLE = "DUCKIE_TEST_CONTENT_KEY"


def content_key() -> str:
    """A key of the files the shared runs are made from, as they were when the session began."""
    if VARIABLE not in os.environ:
        os.environ[VARIABLE] = _files_key()
    return os.environ[VARIABLE]


def _files_key() -> str:
    """A key of the files the shared runs are made from (their paths and their bytes)."""
    digest = hashlib.sha256()
    for top in SOURCES:
        for path in sorted((ROOT / top).rglob("*")):
            if (
                path.suffix in SUFFIXES
                and path.is_file()
                and "__pycache__" not in path.parts
                and "deploy" not in path.relative_to(ROOT).parts[:3]
            ):
                digest.update(str(path.relative_to(ROOT)).encode() + b"\0")
                digest.update(path.read_bytes() + b"\0")
    digest.update((ROOT / "pyproject.toml").read_bytes())
    return digest.hexdigest()[:16]


def _session_folder(tmp_path_factory: Any) -> Path:
    """The folder every worker of this session sees: pytest-xdist's workers' common parent."""
    base = Path(tmp_path_factory.getbasetemp())
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


def shared(tmp_path_factory: Any, name: str, make: Callable[[Path], Any]) -> Any:
    """What ``make(folder)`` returns, made once per session in ``folder`` for every worker.

    Args:
        tmp_path_factory: pytest's fixture of the same name.
        name: the run's name, unique among the shared runs.
        make: makes the run in the empty folder it is given and returns what the tests read.

    Raises:
        SharedRunError: if ``make`` raised, here or in the worker that made the run.
    """
    top = _session_folder(tmp_path_factory) / "shared"
    top.mkdir(exist_ok=True)
    folder = top / f"{name}-{content_key()}"
    value, failed = folder / "value.pickle", folder / "failed.txt"
    with (top / f"{name}.lock").open("a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            if not value.exists() and not failed.exists():
                shutil.rmtree(folder, ignore_errors=True)
                (folder / "run").mkdir(parents=True)
                try:
                    made = make(folder / "run")
                except BaseException as error:
                    if isinstance(error, (KeyboardInterrupt, SystemExit)):
                        raise
                    failed.write_text(traceback.format_exc(), encoding="utf-8")
                else:
                    partial = folder / "value.partial"
                    partial.write_bytes(pickle.dumps(made))
                    partial.replace(value)
            if failed.exists():
                raise SharedRunError(
                    f"The shared run {name!r} failed where it was made:\n"
                    + failed.read_text(encoding="utf-8")
                )
            return pickle.loads(value.read_bytes())
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def graded_course(folder: Path) -> Any:
    """The course graded as ``duckie grade`` grades a class: real nbgrader, every notebook in
    the sandbox, the driving score. Three students hand in the whole course: ``reference``
    (the release with every graded cell filled with the reference code), ``untouched`` (the
    release as students receive it) and ``mistaken`` (the first deliberately wrong solution
    of every graded cell, ``tests/course/wrong_*.py``).

    Returns:
        ``folder``, each student's result by name, and the mistakes by (notebook, grade id).
    """
    import sys

    course_helpers = str(ROOT / "tests" / "course")
    if course_helpers not in sys.path:
        sys.path.append(course_helpers)
    from coursetools import reference_answers, student_copy, wrong_solutions
    from pace import seconds

    from autograder.grade import grade_class
    from autograder.sandbox import Limits

    first_mistakes: dict = {}
    for (name, grade_id, _), text in wrong_solutions().items():
        first_mistakes.setdefault((name, grade_id), text)
    submissions = folder / "submissions"
    student_copy(submissions / "reference", reference_answers())
    student_copy(submissions / "untouched", {})
    student_copy(submissions / "mistaken", first_mistakes)
    # The time limits are twice the defaults, grown with the pace: the course's slowest cell
    # (notebook 11 runs the robot project, about 6 s alone) took 31 s here beside the suite's
    # other workers on two cores, past the default 30 s after which a cell is named as slow.
    # A busy machine is not a problem of the reference.
    default = Limits()
    limits = Limits(
        **{
            name: seconds(2 * getattr(default, name))
            for name in (
                "cell_seconds",
                "submission_seconds",
                "mission_seconds",
                "student_seconds",
                "slow_cell_seconds",
            )
        }
    )
    results = grade_class(submissions, folder / "out", jobs=2, limits=limits)
    return folder, {result.student: result for result in results}, first_mistakes
