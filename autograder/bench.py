"""Benchmark: grading a class, plain sequential nbgrader against the sandboxed parallel grader.

Every submission is a realistic one of the whole course: the released ``course/`` with every
graded answer cell filled with the reference code of ``solutions/``, as a student who solved
everything would hand it in (see :func:`filled_course`). ``N`` copies of it (environment
variable ``DUCKIE_BENCH_GRADE_N``, default 4) are graded four times, each run in a tmp folder
of its own:

- ``nbgrader_sequential_s_per_submission``: :func:`autograder.course.autograde`, plain
  ``NbGraderAPI.autograde`` one submission after the other, no sandbox;
- ``grade_jobs1_s_per_submission``: :func:`autograder.grade.grade_class` with the sandbox, one
  student at a time;
- ``grade_jobs2_s_per_submission``: the same with two students at a time (a local Dask
  cluster of two workers);
- ``grade_cluster2_s_per_submission``: the same through a Dask cluster started as an instructor
  starts one (``dask scheduler`` and two ``dask worker`` processes), its start not counted.

Where one student's grading spends its time, from the one-job run (``jobs1_*``): the whole
unit, the sandboxed notebook runs (kernels' starts included), the cells themselves, and
nbgrader's own converters and gradebook.

The grader's driving score is left out (``driving=False``): plain nbgrader has no such step,
and the figures compare the grading of the same notebooks.

Each figure is wall-clock seconds per submission. Every copy must score full marks in every
graded cell in all three runs (``all_full_marks``), since timing a broken grading means
nothing. The headline, last, is the grader's throughput with two jobs against plain
sequential nbgrader (``grade_speedup_vs_nbgrader``).
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
import time
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Dict, Iterable, List, Mapping, Optional, Set, Tuple

import nbformat
from nbformat import NotebookNode

from autograder.course import ROOT, CourseError, assignments

if TYPE_CHECKING:
    from autograder.results import StudentResult

#: What ``duckie bench`` lists for this benchmark.
DESCRIPTION = (
    "grading filled courses: plain nbgrader against the sandboxed grader with 1 and 2 jobs"
)

__all__ = [
    "DESCRIPTION",
    "N",
    "check_full_marks",
    "filled_course",
    "filled_notebook",
    "reference_answers",
    "run",
]

#: How many copies of the filled course each run grades.
N = int(os.environ.get("DUCKIE_BENCH_GRADE_N", "4"))

_MARKERS = ("### BEGIN SOLUTION", "### END SOLUTION")

Cells = Mapping[Tuple[str, str], Tuple[float, float]]


def _notebook(folder: Path, name: str) -> Path:
    return folder / name / f"{name}.ipynb"


def _text(cell: dict) -> str:
    text = cell.get("source", "")
    return "".join(text) if isinstance(text, list) else text


def _grade_id(cell: dict) -> Optional[str]:
    return cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")


def reference_answers(
    source: Path = ROOT / "solutions", names: Optional[Iterable[str]] = None
) -> Dict[Tuple[str, str], str]:
    """The reference code of every graded answer cell, as a student would type it.

    Args:
        source: the course source (nbgrader source notebooks, one folder per assignment).
        names: the assignments to read (default: all of ``source``).

    Returns:
        ``(assignment, grade_id) -> cell source``, without the solution region's markers.
    """
    answers = {}
    for name in assignments(source) if names is None else names:
        notebook = json.loads(_notebook(Path(source), name).read_text(encoding="utf-8"))
        for cell in notebook["cells"]:
            marks = cell.get("metadata", {}).get("nbgrader", {})
            if marks.get("solution") and not marks.get("grade"):
                lines = _text(cell).splitlines()
                kept = [line for line in lines if line.strip() not in _MARKERS]
                answers[(name, marks["grade_id"])] = "\n".join(kept) + "\n"
    return answers


def filled_notebook(
    name: str, release: Path = ROOT / "course", source: Path = ROOT / "solutions"
) -> NotebookNode:
    """The released notebook of assignment ``name`` with every graded answer cell solved."""
    notebook = nbformat.read(_notebook(Path(release), name), as_version=4)
    _fill(notebook, name, reference_answers(source, [name]))
    return notebook


def _fill(notebook: NotebookNode, name: str, answers: Mapping[Tuple[str, str], str]) -> None:
    for cell in notebook.cells:
        gid = _grade_id(cell)
        answer = answers.get((name, gid)) if gid is not None else None
        if answer is not None:
            cell.source = answer


def filled_course(
    folder: Path, release: Path = ROOT / "course", source: Path = ROOT / "solutions"
) -> Path:
    """Write a copy of the release into ``folder`` with every graded answer cell solved.

    Args:
        folder: where the copy goes (must not exist yet).
        release: the released student notebooks.
        source: the course source whose reference code fills the answer cells.

    Returns:
        ``folder``, which then holds one folder per assignment, as a student hands it in.
    """
    folder = Path(folder)
    shutil.copytree(release, folder)
    answers = reference_answers(source)
    for name in assignments(release):
        path = _notebook(folder, name)
        notebook = nbformat.read(path, as_version=4)
        _fill(notebook, name, answers)
        nbformat.write(notebook, path)
    return folder


def check_full_marks(
    run_name: str,
    student: str,
    cells: Cells,
    expected: Set[Tuple[str, str]],
    problems: Iterable[str] = (),
) -> None:
    """Make sure a filled course scored every point of every graded cell.

    Args:
        run_name: the grading run, for the message (``"nbgrader"``, ...).
        student: the copy's student id.
        cells: ``(assignment, grade_id) -> (score, max_score)`` as the run gave them.
        expected: every ``(assignment, grade_id)`` that must have a score.
        problems: what went wrong while grading, one sentence each (none expected).

    Raises:
        CourseError: naming the student and the first cell that is missing or short of marks.
    """
    problems = list(problems)
    if problems:
        raise CourseError(f"{run_name} had problems grading {student}: {'; '.join(problems)}.")
    missing = sorted(set(expected) - set(cells))
    if missing:
        assignment, grade_id = missing[0]
        raise CourseError(
            f"{run_name} gave {student} no score for {assignment} {grade_id}"
            f"{_and_more(len(missing) - 1)}, where every graded cell should have one."
        )
    short = [
        (key, value)
        for key, value in sorted(cells.items())
        if value[0] != value[1] and key in expected
    ]
    if short:
        (assignment, grade_id), (score, most) = short[0]
        raise CourseError(
            f"{run_name} gave {student} {score:g} of {most:g} in {assignment} {grade_id}"
            f"{_and_more(len(short) - 1)}, where the reference code scores full marks."
        )


def _and_more(count: int) -> str:
    """`` (and 3 more cells)``, or nothing when there are none."""
    if count == 0:
        return ""
    return f" (and {count} more {'cell' if count == 1 else 'cells'})"


def _expected_cells(source: Path, names: List[str]) -> Set[Tuple[str, str]]:
    """Every autograded test cell of ``names``: ``(assignment, grade_id)``."""
    expected = set()
    for name in names:
        notebook = json.loads(_notebook(source, name).read_text(encoding="utf-8"))
        for cell in notebook["cells"]:
            marks = cell.get("metadata", {}).get("nbgrader", {})
            if marks.get("grade") and not marks.get("solution"):  # not answers in words
                expected.add((name, marks["grade_id"]))
    return expected


def run(
    names: Optional[List[str]] = None,
    copies: Optional[int] = None,
    source: Path = ROOT / "solutions",
) -> List[Tuple[str, str]]:
    """Grade ``copies`` filled courses four ways; return the figures, headline last.

    Args:
        names: the assignments to grade (default: all of the course). Later notebooks load
            the student's earlier ones from the folder above their own (``load_solution("..")``),
            so a subset must hold the assignments its notebooks build on.
        copies: how many submissions (default: :data:`N`).
        source: the course source.

    Returns:
        ``(name, value)`` pairs: seconds per submission of each run, the full-marks check and
        the speed-up of the two-job grader over plain sequential nbgrader.

    Raises:
        CourseError: if a copy does not get full marks in a run, naming the student and cell.
    """
    import autograder.grade  # noqa: F401 - loaded before any run is timed
    from autograder.course import autograde

    source = Path(source).resolve()
    names = list(names) if names is not None else assignments(source)
    copies = N if copies is None else copies
    if copies < 1:
        raise CourseError(f"The benchmark needs at least one submission, not {copies}.")
    expected = _expected_cells(source, names)
    import nbgrader.apps  # noqa: F401 - imported once here, so no run pays for it
    from sqlalchemy.exc import SAWarning

    with warnings.catch_warnings(), tempfile.TemporaryDirectory(
        prefix="duckie-bench-grade-"
    ) as tmp:
        # nbgrader's own gradebook code warns about its session on every autograde.
        warnings.filterwarnings("ignore", category=SAWarning)
        tmp_path = Path(tmp)
        submissions = tmp_path / "submissions"
        filled_course(submissions / "student_1", source=source)
        students = [f"student_{index}" for index in range(1, copies + 1)]
        for student in students[1:]:
            shutil.copytree(submissions / students[0], submissions / student)

        started = time.perf_counter()
        plain = autograde(
            {student: submissions / student for student in students},
            tmp_path / "nbgrader",
            names=names,
            source=source,
        )
        nbgrader_s = time.perf_counter() - started
        for student, scores in plain.items():
            check_full_marks("nbgrader", student, scores.cells, expected)

        grader_s: Dict[str, float] = {}
        timings: Dict[str, float] = {}
        for run_name, jobs in (("jobs1", 1), ("jobs2", 2), ("cluster2", 2)):
            results, grader_s[run_name] = _grade_timed(
                run_name, jobs, submissions, tmp_path, names, source
            )
            for result in results:
                check_full_marks(
                    f"grade_class ({run_name})",
                    result.student,
                    result.cells,
                    expected,
                    result.problems,
                )
            if {result.student for result in results} != set(students):
                raise CourseError(f"grade_class ({run_name}) did not grade every copy.")
            if run_name == "jobs1":  # one student at a time: the times are not shared
                for result in results:
                    for part, seconds in result.timings.items():
                        timings[part] = timings.get(part, 0.0) + seconds / copies

    return _figures(copies, len(names), nbgrader_s, grader_s, timings)


def _grade_timed(
    run_name: str, jobs: int, submissions: Path, tmp_path: Path, names: List[str], source: Path
) -> Tuple[List[StudentResult], float]:
    """Grade ``submissions`` with ``jobs`` workers; the results and the seconds it took.

    A run whose name starts with ``cluster`` grades on a Dask cluster started as an instructor
    starts one; its start is not counted.
    """
    from autograder.cluster import dask_cluster
    from autograder.grade import grade_class

    started = time.perf_counter()
    with contextlib.ExitStack() as stack:
        scheduler = None
        if run_name.startswith("cluster"):
            scheduler = stack.enter_context(dask_cluster(jobs)).address
            started = time.perf_counter()  # the cluster's start is not grading
        results = grade_class(
            submissions,
            tmp_path / f"grade_{run_name}",
            jobs=jobs,
            names=names,
            source=source,
            driving=False,
            scheduler=scheduler,
        )
    return results, time.perf_counter() - started


def _figures(
    copies: int,
    notebooks: int,
    nbgrader_s: float,
    grader_s: Dict[str, float],
    timings: Dict[str, float],
) -> List[Tuple[str, str]]:
    """The benchmark's figures (module doc) from its runs' seconds, headline last."""
    return [
        ("submissions", str(copies)),
        ("notebooks_per_submission", str(notebooks)),
        ("nbgrader_sequential_s_per_submission", f"{nbgrader_s / copies:.1f}"),
        ("grade_jobs1_s_per_submission", f"{grader_s['jobs1'] / copies:.1f}"),
        *[
            (f"jobs1_{part}_s_per_submission", f"{timings.get(part, 0.0):.1f}")
            for part in ("unit", "notebooks", "cells", "nbgrader")
        ],
        ("grade_jobs2_s_per_submission", f"{grader_s['jobs2'] / copies:.1f}"),
        ("grade_cluster2_s_per_submission", f"{grader_s['cluster2'] / copies:.1f}"),
        ("all_full_marks", "yes"),
        ("grade_cluster2_speedup_vs_nbgrader", f"{nbgrader_s / grader_s['cluster2']:.2f}"),
        ("grade_speedup_vs_nbgrader", f"{nbgrader_s / grader_s['jobs2']:.2f}"),
    ]
