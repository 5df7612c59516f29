"""Grading a class: real ``nbgrader autograde`` per student, student code in a sandbox, in parallel.

nbgrader's autograde does two kinds of work: the instructor's (restore the instructor's cells
and hidden tests from the gradebook, save the scores into it) and the student's (run the
notebook). Here the first stays with nbgrader, in this process, as the gradebook's one writer;
the second is handed, by a preprocessor that takes the place of nbgrader's ``Execute``, to
:mod:`autograder.execute` running inside the sandbox of :mod:`autograder.sandbox`. Several
students are graded at once by threads: while one student's notebook runs in its sandbox, the
others' bookkeeping goes on; every gradebook access holds one lock, so grades are written one
at a time and none is lost. Each sandbox has its own network namespace, so the kernels' ports
never collide (the race plain nbgrader has when run in parallel). What comes back from the
sandbox is read as data: the executed notebook's error outputs name the cells outside the tests
that raised (:func:`raised_outside_tests`), judged on the notebook this process sent.

Input: a folder with one folder (or ``.zip``) per student, holding their assignment folders
(a copy of ``course/``), or nbgrader's own ``submitted/STUDENT/ASSIGNMENT`` layout.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import zipfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple

import nbformat

from autograder import sandbox
from autograder.course import ROOT, CourseError, _api, _log_tail, assignments, nbgrader_config
from autograder.driving import Driving, drive
from autograder.execute import METADATA_KEY, NOT_RUN, mark_not_run
from autograder.feedback import failure_messages, write_feedback
from autograder.sandbox import NOBODY, Limits
from autograder.tamper import repair
from duckielib.handin import raised_cells

__all__ = ["StudentResult", "grade_class", "find_submissions", "raised_outside_tests"]

_EXECUTE = Path(__file__).resolve().parent / "execute.py"
_GRADEBOOK = threading.RLock()


@dataclass
class StudentResult:
    """What grading one student gave.

    Attributes:
        student: the student's id (their folder's name).
        cells: ``(assignment, grade_id) -> (score, max_score)``.
        problems: one sentence each: what went wrong while grading (not failed tests).
        messages: ``(assignment, grade_id) -> message`` of each failed test.
        driving: the driving score, or None when the mission was not driven.
        seconds: wall-clock seconds spent on this student.
    """

    student: str
    cells: Dict[Tuple[str, str], Tuple[float, float]] = field(default_factory=dict)
    problems: List[str] = field(default_factory=list)
    messages: Dict[Tuple[str, str], str] = field(default_factory=dict)
    driving: Optional[Driving] = None
    seconds: float = 0.0

    @property
    def total(self) -> float:
        """The points scored, all assignments together."""
        return sum(score for score, _ in self.cells.values())

    @property
    def max_total(self) -> float:
        """The points there were to score."""
        return sum(most for _, most in self.cells.values())


def find_submissions(folder: Path, work: Path) -> Tuple[Dict[str, Path], List[str]]:
    """The students' folders in ``folder`` (zips unpacked into ``work``), and what was skipped."""
    folder = Path(folder)
    if (folder / "submitted").is_dir():
        folder = folder / "submitted"
    found: Dict[str, Path] = {}
    skipped: List[str] = []
    for entry in sorted(folder.iterdir()):
        name = entry.stem if entry.suffix == ".zip" else entry.name
        if name.startswith("."):
            continue
        if entry.is_dir():
            found[name] = entry
        elif entry.suffix == ".zip":
            target = work / "unzipped" / name
            try:
                with zipfile.ZipFile(entry) as archive:
                    for member in archive.namelist():
                        if member.startswith("/") or ".." in Path(member).parts:
                            raise zipfile.BadZipFile(f"unsafe path {member!r}")
                    archive.extractall(target)
            except zipfile.BadZipFile as error:
                skipped.append(f"{entry.name}: not a readable zip ({error})")
                continue
            inner = [path for path in target.iterdir() if path.is_dir()]
            found[name] = inner[0] if len(inner) == 1 and not _has_assignment(target) else target
        else:
            skipped.append(f"{entry.name}: neither a folder nor a .zip")
    return found, skipped


def _has_assignment(folder: Path) -> bool:
    return any(folder.glob("*/*.ipynb"))


def _sandboxed_execute_class(
    limits: Limits,
    use_sandbox: bool,
    folders: Dict[str, Tuple[Path, Path]],
    notes: Dict[str, List[str]],
):
    """The class that takes the place of nbgrader's Execute: the notebook runs in the sandbox."""
    from nbgrader.preprocessors import Execute

    class SandboxedExecute(Execute):
        def preprocess(self, nb, resources):
            key = f"{resources['nbgrader']['student']}/{resources['nbgrader']['assignment']}"
            folder, view = folders[key]
            command = [sys.executable, str(_EXECUTE), str(limits.cell_seconds)]
            text = nbformat.writes(nb)
            _GRADEBOOK.release()  # others may use the gradebook while this notebook runs
            try:
                result = sandbox.run(
                    command,
                    folder,
                    limits,
                    limits.submission_seconds,
                    use_sandbox=use_sandbox,
                    stdin=text,
                    course=view,
                )
                output = result.stdout
                problem = None if output.strip() else (result.stderr.strip()[-500:] or "no output")
            except subprocess.TimeoutExpired:
                output, problem = "", f"stopped after {limits.submission_seconds} s"
            finally:
                _GRADEBOOK.acquire()
            if problem is not None:
                mark_not_run(nb, f"This cell did not run: the notebook {problem}.")
                notes.setdefault(key, []).append(
                    f"{resources['nbgrader']['assignment']}: the notebook {problem}"
                )
                return nb, resources
            executed = nbformat.reads(output, as_version=4)
            found = executed.metadata.pop(METADATA_KEY, {}).get("problems", [])
            assignment = resources["nbgrader"]["assignment"]
            notes.setdefault(key, []).extend(f"{assignment}: {problem}" for problem in found)
            raised = raised_outside_tests(assignment, nb, executed, limits.cell_seconds)
            if raised is not None:
                notes[key].append(raised)
            return executed, resources

    return SandboxedExecute


def raised_outside_tests(
    assignment: str, sent: Any, executed: Any, cell_seconds: Optional[int] = None
) -> Optional[str]:
    """One sentence naming every cell outside the test cells that raised, or None if none did.

    Which cells are tests, where each cell is and what it says come from ``sent``: the notebook
    this process handed to the run, rebuilt on the release's instructor cells
    (:func:`autograder.tamper.repair`, then nbgrader's own restoring from the gradebook), so a
    student cannot turn a cell into a test or out of one. Only the error outputs are read from
    ``executed``, what came back from the run, and only as text. Cells that never ran because
    the kernel died (the ``NotRun`` error of :func:`autograder.execute.mark_not_run`) are left
    out: the kernel's death is a problem of its own.

    Args:
        assignment: the assignment's name, which starts the sentence.
        sent: the notebook as sent to be run.
        executed: the same notebook as it came back, with its outputs.
        cell_seconds: the time limit of a cell, quoted for a cell that ran out of it.
    """
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


def _links(directory: str, names: List[str]) -> List[str]:
    """The symbolic links among ``names`` (for ``shutil.copytree``'s ``ignore``)."""
    return [name for name in names if (Path(directory) / name).is_symlink()]


def _prepare_folder(work: Path, student: str, assignment: str, source: Path, notebook) -> Path:
    """The writable folder a student's notebook runs in: their assignment's files.

    It holds the student's data files and their (repaired) notebook, which notebooks that load
    their neighbours read from ``..``. Left out: symbolic links (one pointing outside would
    hand the sandbox a file of the grader's) and Python modules (a ``numpy.py`` next to the
    notebook would stand in for numpy in the tests).
    """
    folder = work / "sandboxes" / student / assignment
    if folder.exists():
        shutil.rmtree(folder)
    skipped = shutil.ignore_patterns("*.ipynb", ".*", "*.py", "*.pyc", "*.pth", "*.so")
    shutil.copytree(
        source, folder, ignore=lambda where, names: [*_links(where, names), *skipped(where, names)]
    )
    nbformat.write(notebook, folder / f"{assignment}.ipynb")
    for path in [folder.parent, folder, *folder.rglob("*")]:
        os.chown(path, NOBODY, NOBODY, follow_symlinks=False)
    return folder


def grade_class(
    submissions: Path,
    out: Path,
    jobs: int = 1,
    limits: Optional[Limits] = None,
    use_sandbox: bool = True,
    names: Optional[List[str]] = None,
    source: Path = ROOT / "solutions",
    progress: Optional[Callable[[str], None]] = None,
    driving: bool = True,
) -> List[StudentResult]:
    """Autograde every student of ``submissions`` into ``out``.

    Writes ``out/grades.csv`` (one row per student), ``out/feedback/STUDENT.html`` and
    ``out/skipped.json`` (what in ``submissions`` was not a student's folder).

    Args:
        submissions: one folder (or ``.zip``) per student, or nbgrader's ``submitted/`` layout.
        out: the results' folder; its ``work/`` holds the gradebook and nbgrader's trees.
        jobs: how many students are graded at once.
        limits: what each submission may use (default :class:`Limits`).
        use_sandbox: whether student code runs in the sandbox (off: with your rights).
        names: the assignments to grade (default: all of ``source``).
        source: the course source, whose hidden tests are run.
        progress: called with one line after each student.
        driving: whether each student's export drives the mission (the driving score).

    Returns:
        One result per student, in name order.

    Raises:
        CourseError: if nbgrader cannot set the assignments up.
    """
    limits = limits or Limits()
    out = Path(out).resolve()
    work = out / "work"
    work.mkdir(parents=True, exist_ok=True)
    source = Path(source).resolve()
    names = list(names) if names is not None else assignments(source)
    students, skipped = find_submissions(Path(submissions), work)
    folders: Dict[str, Tuple[Path, Path]] = {}
    notes: Dict[str, List[str]] = {}
    config = nbgrader_config(root=work, release="release", db=work / "gradebook.db", source=source)
    config.CourseDirectory.submitted_directory = "submitted"
    config.CourseDirectory.autograded_directory = "autograded"
    execute = _sandboxed_execute_class(limits, use_sandbox, folders, notes)
    config.Autograde.autograde_preprocessors = [
        execute if getattr(pp, "__name__", "") == "Execute" else pp
        for pp in _default_autograde_preprocessors()
    ]
    api = _api(config)
    # The driving score exports the whole course: every notebook is then repaired and laid out.
    course = sorted(set(assignments(source)) | set(names)) if driving else list(names)
    with _GRADEBOOK:
        for name in course:
            result = api.generate_assignment(name, force=True)
            if not result["success"]:
                raise CourseError(f"nbgrader could not set up {name}:\n{_log_tail(result)}")
    (out / "feedback").mkdir(exist_ok=True)
    run = _Run(api, config, out, names, students, folders, notes, max(1, jobs), progress)
    run.limits, run.use_sandbox, run.driving = limits, use_sandbox, driving
    run.course = course
    cwd = Path.cwd()
    # nbgrader 0.9 sets NBGRADER_EXECUTION around each execution and then restores the value
    # of the variable named by its *value* ("autograde"; a slip in nbgrader.utils.setenv),
    # deleting it when that is unset: two threads would delete it under each other. With
    # both set for the whole run, every restore just writes "autograde" back.
    before = {key: os.environ.get(key) for key in ("NBGRADER_EXECUTION", "autograde")}
    os.environ.update(NBGRADER_EXECUTION="autograde", autograde="autograde")
    try:
        with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
            results = list(pool.map(run.grade, sorted(students)))
    finally:
        os.chdir(cwd)  # nbgrader's converters change directory while they run
        for key, value in before.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
    _write_csv(out / "grades.csv", results)
    (out / "skipped.json").write_text(json.dumps(skipped, indent=2) + "\n")
    return results


@dataclass
class _Run:
    """One class's grading: what each thread needs to grade a student."""

    api: Any
    config: Any
    out: Path
    names: List[str]
    students: Dict[str, Path]
    folders: Dict[str, Tuple[Path, Path]]
    notes: Dict[str, List[str]]
    jobs: int
    progress: Optional[Callable[[str], None]]
    limits: Limits = field(default_factory=Limits)
    use_sandbox: bool = True
    driving: bool = True
    course: List[str] = field(default_factory=list)
    started: float = field(default_factory=time.monotonic)
    done: List[StudentResult] = field(default_factory=list)

    @property
    def work(self) -> Path:
        """The nbgrader course root: the gradebook, ``submitted/`` and ``autograded/``."""
        return self.out / "work"

    def _hand_in(self, student: str, name: str, result: StudentResult) -> bool:
        """Put one assignment, repaired, where nbgrader grades it and where it runs.

        Returns:
            Whether the student handed it in.
        """
        submitted = self.students[student] / name
        handed_in = submitted / f"{name}.ipynb"
        if not (handed_in.is_file() or handed_in.is_symlink()):
            result.problems.append(f"{name}: no {name}.ipynb in the submission")
            return False
        target = self.work / "submitted" / student / name
        if target.exists():
            shutil.rmtree(target)
        # Without links: writing the repaired notebook through one would overwrite its target.
        shutil.copytree(submitted, target, ignore=_links)
        # Graded on the instructor's cells: deleted, duplicated or renamed ones put back,
        # an unreadable notebook replaced by the release (see autograder.tamper).
        release = self.work / "release" / name / f"{name}.ipynb"
        if handed_in.is_symlink():  # never read a file of the grader's in its place
            result.problems.append(f"{name}: the notebook is a link; the release was graded")
            handed_in = release
        notebook, found = repair(handed_in, release)
        result.problems += found
        nbformat.write(notebook, target / f"{name}.ipynb")
        _prepare_folder(self.work, student, name, submitted, notebook)
        return True

    def grade(self, student: str) -> StudentResult:
        """Autograde every assignment of one student (in a worker thread)."""
        began = time.monotonic()
        result = StudentResult(student)
        view = self.work / "sandboxes" / student
        # Every notebook is repaired and laid out (the driving score exports them all), but
        # only those graded are reported on.
        aside = StudentResult(student)
        handed_in = [
            name
            for name in self.course
            if self._hand_in(student, name, result if name in self.names else aside)
            and name in self.names
        ]
        for name in handed_in:
            key = f"{student}/{name}"
            self.folders[key] = (view / name, view)
            with _GRADEBOOK:
                outcome = self.api.autograde(name, student, force=True, create=True)
            result.problems += self.notes.get(key, [])
            if not outcome["success"]:
                result.problems.append(f"{name}: nbgrader could not grade it ({_why(outcome)})")
            graded = self.work / "autograded" / student / name / f"{name}.ipynb"
            for grade_id, message in failure_messages(graded).items():
                result.messages[(name, grade_id)] = message
        with _GRADEBOOK:
            _read_scores(self.config, result, self.names)
        if self.driving:
            # From the repaired copies: a notebook linked to a file of the grader's (the
            # reference solutions) is never exported.
            box = self.work / "driving" / student
            result.driving = drive(view, box, self.limits, self.use_sandbox)
        write_feedback(self.out / "feedback" / f"{student}.html", result, self.names)
        result.seconds = time.monotonic() - began
        self.done.append(result)
        if self.progress is not None:
            count, total = len(self.done), len(self.students)
            per_student = (time.monotonic() - self.started) / count
            failed = sum(1 for item in self.done if item.problems)
            self.progress(
                f"{count}/{total} graded ({failed} with problems), "
                f"about {(total - count) * per_student:.0f} s left"
            )
        return result


def _default_autograde_preprocessors() -> list:
    from nbgrader.converters import Autograde

    return list(Autograde.class_traits()["autograde_preprocessors"].default())


def _why(outcome: Dict[str, object]) -> str:
    lines = [line for line in _log_tail(outcome).splitlines() if line.strip()]
    return lines[-1][:300] if lines else "no log"


def _read_scores(config: object, result: StudentResult, names: List[str]) -> None:
    """The student's scores from the gradebook; a test never graded scores 0 of its points."""
    from nbgrader.api import Gradebook, MissingEntry

    with Gradebook(config.CourseDirectory.db_url) as gradebook:  # type: ignore[attr-defined]
        for name in names:
            for notebook in gradebook.find_assignment(name).notebooks:
                for cell in notebook.grade_cells:
                    result.cells[(name, cell.name)] = (0.0, float(cell.max_score))
            try:
                submission = gradebook.find_submission(name, result.student)
            except MissingEntry:
                continue
            for notebook in submission.notebooks:
                for grade in notebook.grades:
                    result.cells[(name, grade.name)] = (float(grade.score), float(grade.max_score))


def _write_csv(path: Path, results: List[StudentResult]) -> None:
    columns = sorted({key for result in results for key in result.cells})
    with tempfile.NamedTemporaryFile(
        "w", dir=path.parent, delete=False, newline="", suffix=".tmp"
    ) as handle:
        writer = csv.writer(handle)
        writer.writerow(
            ["student", "total", "max_total", "driving_score", "problems", "driving_problems"]
            + [f"{assignment}:{grade_id}" for assignment, grade_id in columns]
        )
        for result in results:
            driving = result.driving
            writer.writerow(
                [
                    result.student,
                    f"{result.total:g}",
                    f"{result.max_total:g}",
                    "" if driving is None else f"{driving.score:g}",
                    " | ".join(result.problems),
                    "" if driving is None else " | ".join(driving.reasons),
                ]
                + [f"{result.cells[key][0]:g}" if key in result.cells else "" for key in columns]
            )
    Path(handle.name).replace(path)
