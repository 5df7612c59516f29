"""Grading a class: real ``nbgrader autograde`` per student, each student a task on Dask.

Each student's grading is a unit of its own (:mod:`autograder.unit`): a process that repairs
their notebooks, autogrades them with nbgrader on a private copy of the gradebook, runs their
cells in the sandbox and drives the mission with their exported code. Units are tasks of Dask
distributed: on a local cluster of ``jobs`` worker processes by default, or on an existing
cluster (``scheduler``: one started by dask-jobqueue on Slurm, by dask-kubernetes...), whose
workers need only the course's Python environment and bubblewrap. A worker that dies takes
no student with it: Dask runs its tasks again elsewhere.

This process is the one writer of the class's results. It reads each student's files itself,
safely (:mod:`autograder.files`: regular files only, no links, sizes bounded) and hands the
bytes to the task; when a student's result comes back it is written at once, each file whole
or not at all: the gradebook (``work/gradebook.db``, the scores nbgrader's formgrader shows),
the autograded notebooks, ``feedback/STUDENT.html``, ``results/STUDENT.json`` and
``grades.csv``. A crash or Ctrl-C loses only the students in flight; running again grades only
the students whose files changed, who are new, or whose grading stopped.

Input: a folder with one folder (or ``.zip``) per student, holding their assignment folders
(a copy of ``course/``), or nbgrader's own ``submitted/STUDENT/ASSIGNMENT`` layout.
"""

# Over 600 lines: grading a class is one pipeline with one writer of its results (reading the
# submissions, fingerprints that skip unchanged students, the Dask tasks and `_Writer`), whose steps
# share the out folder's layout; `_Writer` is the seam should it grow.

from __future__ import annotations

import csv
import dataclasses
import functools
import hashlib
import io
import json
import logging
import os
import re
import shutil
import signal
import socket
import stat
import tarfile
import tempfile
import threading
import time
from concurrent.futures import CancelledError
from contextlib import contextmanager
from pathlib import Path, PurePosixPath
from typing import Any, Callable, Dict, Iterator, List, Optional, Set, Tuple

from autograder.course import (
    ROOT,
    CourseError,
    assignments,
    log_tail,
    nbgrader_api,
    nbgrader_config,
)
from autograder.driving import MAX_SCORE, MISSIONS
from autograder.feedback import write_feedback
from autograder.files import Collected, UnsafeFile, collect_folder, unpack_zip
from autograder.formgrade import for_formgrader, rubrics
from autograder.launch import run_unit
from autograder.notebook_problems import raised_outside_tests
from autograder.results import StudentResult, from_data, not_graded, to_data, write_atomic
from autograder.sandbox import Limits
from duckielib.solution.cascade import Dependencies

__all__ = [
    "StudentResult",
    "find_submissions",
    "grade_class",
    "raised_outside_tests",
    "read_submission",
    "write_grades",
]

#: What of a student's folder is never read: hidden files and folders, Python's caches.
_SKIPPED = (".*", "__pycache__", "*.pyc")
#: Bumped when what a unit computes changes, so results kept from before are graded again.
GRADER_VERSION = 3


def find_submissions(folder: Path) -> Tuple[Dict[str, Path], List[str]]:
    """The students' folders and ``.zip`` files in ``folder``, and what was skipped (sentences).

    A student's entry that is a link, a FIFO or anything but a folder or a regular ``.zip``
    file is skipped and said, as is a hidden folder or zip (its name starts with a dot).
    """
    folder = Path(folder)
    if (folder / "submitted").is_dir():
        folder = folder / "submitted"
    found: Dict[str, Path] = {}
    skipped: List[str] = []
    for entry in sorted(os.scandir(folder), key=lambda item: item.name):
        path = Path(entry.path)
        name = path.stem if path.suffix == ".zip" else entry.name
        mode = entry.stat(follow_symlinks=False).st_mode
        if name.startswith("."):
            # A hidden file (.DS_Store) is no submission; a hidden folder or zip may be one.
            if stat.S_ISDIR(mode) or path.suffix == ".zip":
                skipped.append(
                    f"{entry.name}: hidden (its name starts with a dot), so not graded; rename "
                    "it without the dot to grade it"
                )
            continue
        if stat.S_ISDIR(mode) or (stat.S_ISREG(mode) and path.suffix == ".zip"):
            if name in found:
                skipped.append(f"{entry.name}: {name} has a folder too; the folder is graded")
                continue
            found[name] = path
        elif stat.S_ISLNK(mode):
            skipped.append(f"{entry.name}: a symbolic link, not a student's folder")
        else:
            skipped.append(f"{entry.name}: neither a folder nor a .zip")
    return found, skipped


def read_submission(path: Path, course: List[str]) -> Collected:
    """A student's files of the assignments ``course``, read safely from a folder or a zip.

    The files are keyed ``"NAME/relative/path"``. A zip (or folder) holding one folder that
    holds the assignments is read from that folder. Everything else is left out silently;
    what is left out of the assignments' folders is said.

    Raises:
        UnsafeFile: if a zip cannot be read or holds paths outside itself.
    """
    wanted = set(course)
    if path.is_dir() and not path.is_symlink():
        if not any((path / name).is_dir() for name in wanted):
            inner = [
                entry
                for entry in os.scandir(path)
                if entry.is_dir(follow_symlinks=False) and not entry.name.startswith(".")
            ]
            if len(inner) == 1:
                path = Path(inner[0].path)
        collected = Collected()
        for name in course:
            folder = path / name
            if folder.is_symlink():
                collected.left_out.append(f"{name}/ is a symbolic link; it was left out.")
                continue
            if not folder.is_dir():
                continue
            part = collect_folder(folder, skip=_SKIPPED)
            collected.files.update({f"{name}/{key}": data for key, data in part.files.items()})
            collected.left_out += [f"{name}/{said}" for said in part.left_out]
        return collected
    unpacked = unpack_zip(path, skip=_SKIPPED)
    tops = {PurePosixPath(key).parts[0] for key in unpacked.files}
    if not tops & wanted and len(tops) == 1:
        (top,) = tops
        unpacked.files = {key[len(top) + 1 :]: value for key, value in unpacked.files.items()}
    unpacked.files = {
        key: value for key, value in unpacked.files.items() if PurePosixPath(key).parts[0] in wanted
    }
    return unpacked


def _left_out(lines: List[str], names: List[str]) -> List[str]:
    """What was left out, as ``NAME: sentence`` for a graded assignment's folder.

    What was left out of an assignment that is not graded is not said; a sentence about the
    whole submission (a refused zip, whose path may hold a ``/``) is said as it is.
    """
    said = []
    for line in lines:
        name, _, rest = line.partition("/")
        if name in names and rest:
            said.append(f"{name}: {rest}")
        elif not (rest and _ASSIGNMENT.match(name)):
            said.append(line[:1].upper() + line[1:])
    return said


#: An assignment's folder name (``05_odometry``).
_ASSIGNMENT = re.compile(r"[0-9]{2}_[A-Za-z0-9_]+\Z")
#: A student's folder name nbgrader and every file system take as it is.
_PLAIN_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}\Z")


def student_id(name: str) -> str:
    """The id a student is graded under: their folder's name, or a plain form of it and a hash.

    nbgrader cannot grade a student whose id has spaces at its ends, brackets or a new line,
    and a file system refuses a file name of more than 255 bytes; such a name becomes its
    letters, digits, ``_`` and ``-`` (at most 40) and 8 digits of its SHA-256 (``alice `` ->
    ``alice-3f6c...``). The name as written stays in ``grades.csv`` and the feedback page.
    """
    if _PLAIN_ID.match(name) and not name.endswith("."):
        return name
    raw = name.encode("utf-8", "surrogateescape")
    stem = re.sub(r"[^A-Za-z0-9_-]+", "-", name).strip("-")[:40] or "student"
    return f"{stem}-{hashlib.sha256(raw).hexdigest()[:8]}"


def _as_written(name: str) -> str:
    """A folder's name as text (bytes that are not UTF-8 shown as the replacement character)."""
    return name.encode("utf-8", "surrogateescape").decode("utf-8", "replace")


def _fingerprint(*parts: Any) -> str:
    """One hash of bytes and JSON-able values, in order."""
    digest = hashlib.sha256()
    for part in parts:
        raw = part if isinstance(part, bytes) else json.dumps(part, sort_keys=True).encode()
        digest.update(hashlib.sha256(raw).digest())
    return digest.hexdigest()


def _files_fingerprint(files: Dict[str, bytes]) -> str:
    return _fingerprint(*[name.encode() + b"\0" + files[name] for name in sorted(files)])


@dataclasses.dataclass
class _Course:
    """What every unit of the class needs: the source, the release, the gradebook's copy."""

    blob: bytes
    key: str
    cells: Dict[Tuple[str, str], float]


def _set_up(work: Path, source: Path, course: List[str], names: List[str]) -> _Course:
    """Generate the assignments into the class's gradebook, and pack what the units need."""
    config = nbgrader_config(root=work, release="release", db=work / "gradebook.db", source=source)
    key = _fingerprint(
        GRADER_VERSION,
        course,
        *[
            path.relative_to(source).as_posix().encode() + path.read_bytes()
            for path in sorted(source.rglob("*"))
            if path.is_file()
        ],
    )
    stamp = work / "course.json"
    if not (stamp.is_file() and json.loads(stamp.read_text()).get("key") == key):
        api = nbgrader_api(config)
        for name in course:
            result = api.generate_assignment(name, force=True)
            if not result["success"]:
                raise CourseError(f"nbgrader could not set up {name}:\n{log_tail(result)}")
        write_atomic(stamp, json.dumps({"key": key}))
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as archive:
        archive.add(source, "source")
        for name in course:
            archive.add(work / "release" / name, f"release/{name}")
        archive.add(work / "gradebook.db", "gradebook.db")
    from nbgrader.api import Gradebook

    cells: Dict[Tuple[str, str], float] = {}
    with Gradebook(config.CourseDirectory.db_url) as gradebook:
        for name in names:
            for notebook in gradebook.find_assignment(name).notebooks:
                for cell in notebook.grade_cells:
                    cells[(name, cell.name)] = float(cell.max_score)
    return _Course(buffer.getvalue(), key, cells)


_UNPACKED: Dict[str, Path] = {}


def _scratch() -> Optional[str]:
    """The Dask worker's own folder, removed with the worker: the unpacked course goes there."""
    from distributed import get_worker

    try:
        return get_worker().local_directory
    except ValueError:  # not on a worker
        return None


def _grade_on_worker(
    task: Dict[str, Any], files: Dict[str, bytes], key: str, blob: bytes
) -> Dict[str, Any]:
    """The Dask task: one student's unit, on whichever worker runs it."""
    course = _UNPACKED.get(key)
    if course is None or not course.is_dir():
        # A worker that outlives a class run (a cluster's) keeps only the latest course.
        for old in [old for old in _UNPACKED if old != key]:
            shutil.rmtree(_UNPACKED.pop(old), ignore_errors=True)
        course = Path(tempfile.mkdtemp(prefix="duckie-course-", dir=_scratch()))
        with tarfile.open(fileobj=io.BytesIO(blob), mode="r:gz") as archive:
            archive.extractall(course, filter="data")
        _UNPACKED[key] = course
    # In the worker's own folder: Dask removes it with the worker, even one that was killed.
    return run_unit(task, files, course, scratch=_scratch())


@contextmanager
def _whole_on_ctrl_c() -> Iterator[None]:
    """Finish the block before a Ctrl-C stops the run: a student is recorded whole or not at all.

    A Ctrl-C that arrives inside the block is kept and raised as ``KeyboardInterrupt`` at its
    end. Outside the main thread, where Python cannot catch signals, the block simply runs.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: List[int] = []
    before = signal.signal(signal.SIGINT, lambda number, frame: caught.append(number))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)
    if caught:
        raise KeyboardInterrupt


@dataclasses.dataclass
class _Writer:
    """The one writer of the class's results."""

    out: Path
    names: List[str]
    cells: Dict[Tuple[str, str], float]
    db_url: str
    dependencies: Optional[Dependencies] = None
    results: Dict[str, StudentResult] = dataclasses.field(default_factory=dict)
    #: The rubric of each answer in words, shown under it in the notebooks Formgrader shows.
    rubrics: Dict[Tuple[str, str], str] = dataclasses.field(default_factory=dict)
    #: The folder's name as written, by student id, where the two differ (:func:`student_id`).
    shown: Dict[str, str] = dataclasses.field(default_factory=dict)

    def record(self, result: StudentResult, autograded: Dict[str, str], key: str) -> None:
        """Keep one student's result: gradebook, notebooks, feedback, JSON, the class's CSV.

        A Ctrl-C waits until all of them are written, so the CSV and ``results/`` always agree.
        """
        with _whole_on_ctrl_c():
            self._record(result, autograded, key)

    def _record(self, result: StudentResult, autograded: Dict[str, str], key: str) -> None:
        result.name = self.shown.get(result.student, result.name)
        for cell, most in self.cells.items():
            result.cells.setdefault(cell, (0.0, most))
        result.cells = {cell: result.cells[cell] for cell in sorted(result.cells)}
        self._explain(result)
        if result.complete:  # a grading that stopped is no grade: the gradebook keeps its own
            self._save_grades(result, sorted(autograded))
        for name, text in autograded.items():
            path = self.out / "work" / "autograded" / result.student / name / f"{name}.ipynb"
            write_atomic(path, for_formgrader(text, name, self.rubrics))
        self.write_feedback(result)
        data = {"key": key, **to_data(result)}
        write_atomic(self.out / "results" / f"{result.student}.json", json.dumps(data, indent=1))
        self.results[result.student] = result
        self.write_csv()

    def write_feedback(self, result: StudentResult) -> None:
        """The student's feedback page, whole or not at all."""
        page = self.out / "feedback" / f"{result.student}.html"
        page.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=page.parent) as staging:
            write_feedback(Path(staging) / page.name, result, self.names, self.answers)
            (Path(staging) / page.name).replace(page)

    @functools.cached_property
    def answers(self) -> Set[Tuple[str, str]]:
        """The answers in words of the graded assignments: the grade cells that are markdown."""
        from nbgrader.api import Gradebook, MissingEntry

        found = set()
        with Gradebook(self.db_url) as gradebook:
            for name in self.names:
                try:
                    notebooks = gradebook.find_assignment(name).notebooks
                except MissingEntry:
                    continue
                for notebook in notebooks:
                    found |= {
                        (name, cell.name)
                        for cell in notebook.grade_cells
                        if cell.cell_type == "markdown"
                    }
        return found

    def _explain(self, result: StudentResult) -> None:
        """Name first the function a failure builds on, when that function fails its own test."""
        if self.dependencies is None:
            return
        failed = {cell for cell, (score, most) in result.cells.items() if score < most}
        explained = self.dependencies.explain(
            {cell: result.messages.get(cell, "") for cell in failed}
        )
        for cell, message in explained.items():
            if message.strip() != result.messages.get(cell, "").strip():
                result.messages[cell] = message.strip()
        note = self.dependencies.driving_note(failed)
        for driving in result.missions.values():
            if note is not None and driving.score < MAX_SCORE:
                driving.reasons.insert(0, note)

    def _save_grades(self, result: StudentResult, graded: List[str]) -> None:
        """The student's scores into the class's gradebook, where nbgrader's tools read them.

        Only the assignments that were autograded get a submission, as ``nbgrader autograde``
        gives them. The grades people gave are then read back into ``result``.
        """
        from nbgrader.api import Gradebook, MissingEntry

        scores = dict(result.cells)
        waiting = set(result.to_grade)
        with Gradebook(self.db_url) as gradebook:
            gradebook.update_or_create_student(result.student)
            for name in graded:
                try:
                    submission = gradebook.find_submission(name, result.student)
                except MissingEntry:
                    submission = gradebook.add_submission(name, result.student)
                for notebook in submission.notebooks:
                    for grade in notebook.grades:
                        key = (name, grade.name)
                        if key not in scores:
                            continue
                        # As nbgrader's SaveAutoGrades: a person's grade is never touched, and
                        # a cell with a person's grade or none automatic is to be reviewed.
                        grade.auto_score = None if key in waiting else scores[key][0]
                        grade.needs_manual_grade = (
                            grade.manual_score is not None or grade.auto_score is None
                        )
            gradebook.db.commit()
            _people_grades(gradebook, result)

    def read_people_grades(self, results: List[StudentResult]) -> None:
        """Put the grades people gave in Formgrader over the automatic ones, in ``results``.

        A cell a person graded scores what they gave; an answer in words nobody graded yet
        stays in ``to_grade``. Read at every run, so grades given since the last one show.
        """
        from nbgrader.api import Gradebook

        with Gradebook(self.db_url) as gradebook:
            for result in results:
                _people_grades(gradebook, result)

    def write_csv(self) -> None:
        results = [self.results[name] for name in sorted(self.results)]
        columns = sorted({key for result in results for key in result.cells})
        driven = [name for name in MISSIONS if any(name in item.missions for item in results)]
        buffer = io.StringIO()
        writer = csv.writer(buffer)
        writer.writerow(
            ["student", "total", "max_total", "to_grade", "driving_score"]
            + [f"driving:{name}" for name in driven]
            + ["problems", "driving_problems"]
            + [f"{assignment}:{grade_id}" for assignment, grade_id in columns]
        )
        for result in results:
            # A student whose grading stopped has no grade: empty cells, not zeros.
            score = result.driving_score if result.complete else None
            writer.writerow(
                [
                    _text_cell(result.shown),
                    f"{result.total:g}" if result.complete else "",
                    f"{result.max_total:g}",
                    str(len(result.to_grade)),
                    "" if score is None else f"{score:g}",
                ]
                + [
                    f"{result.missions[name].score:g}"
                    if name in result.missions and result.complete
                    else ""
                    for name in driven
                ]
                + [
                    _text_cell(" | ".join(result.problems)),
                    _text_cell(
                        " | ".join(
                            f"{name}: {reason}"
                            for name, driving in result.missions.items()
                            for reason in driving.reasons
                        )
                    ),
                ]
                + [
                    f"{result.cells[key][0]:g}"
                    if key in result.cells and key not in result.to_grade and result.complete
                    else ""
                    for key in columns
                ]
            )
        write_atomic(self.out / "grades.csv", buffer.getvalue())


#: How a spreadsheet's formula starts: a text cell that starts so is read as one (a student
#: named ``=HYPERLINK(...)`` would be a link in the instructor's grade book).
_FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def _text_cell(text: str) -> str:
    """A text of grades.csv as written, as plain text if a spreadsheet would take a formula.

    A terminal's control sequences (colours, titles) and other control characters in a
    student's error text are left out. A leading apostrophe makes it plain text: spreadsheets
    read it as "text follows" and do not show it.
    """
    from duckielib.tools.handin import without_controls

    text = without_controls(text)
    return f"'{text}" if text.startswith(_FORMULA_STARTS) else text


#: Said of an answer in words left as it was released.
_UNANSWERED = "No answer was written here, so it scores 0."


def _people_grades(gradebook: Any, result: StudentResult) -> None:
    """The grades and comments people gave ``result``'s student, from an open gradebook."""
    from nbgrader.api import MissingEntry

    waiting = []
    comments = {}
    for name in sorted({name for name, _ in result.cells}):
        try:
            submission = gradebook.find_submission(name, result.student)
        except MissingEntry:
            continue
        for notebook in submission.notebooks:
            for grade in notebook.grades:
                key = (name, grade.name)
                if key not in result.cells:
                    continue
                in_words = grade.cell.cell_type == "markdown"
                if in_words:
                    result.messages.pop(key, None)
                if grade.manual_score is not None:
                    result.cells[key] = (float(grade.manual_score), result.cells[key][1])
                elif grade.auto_score is None:
                    waiting.append(key)
                elif in_words:  # nbgrader scores an answer left as released 0 by itself
                    result.messages[key] = _UNANSWERED
            for comment in notebook.comments:
                if (comment.manual_comment or "").strip():
                    comments[(name, comment.name)] = comment.manual_comment.strip()
    result.to_grade = waiting
    result.comments = comments


def _keep_submitted(work: Path, student: str, files: Dict[str, bytes], names: List[str]) -> None:
    """The student's handed-in notebooks, as bytes, in nbgrader's ``submitted/`` tree.

    Formgrader counts a class's submissions there; the grader itself never reads them back.
    """
    for name in names:
        data = files.get(f"{name}/{name}.ipynb")
        if data is not None:
            write_atomic(work / "submitted" / student / name / f"{name}.ipynb", data)


def _kept(out: Path, student: str, key: str) -> Optional[StudentResult]:
    """The result kept from an earlier run for the same files and course, if whole."""
    path = out / "results" / f"{student}.json"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if data.get("key") != key or not data.get("complete", True):
        return None
    try:
        return from_data(data)
    except (KeyError, TypeError, ValueError):
        return None


def _reachable(scheduler: str) -> None:
    """Fail at once when nothing listens at a TCP scheduler's address.

    Dask's client retries a refused connection until its timeout (30 s); a wrong address or a
    scheduler that is not running is known within milliseconds, so it is said at once.

    Raises:
        OSError: if the address is refused, unknown or does not answer within 5 s.
    """
    from distributed.comm import parse_address, parse_host_port

    protocol, location = parse_address(scheduler)
    if protocol not in ("tcp", "tls"):
        return
    host, port = parse_host_port(location)
    with socket.create_connection((host, port), timeout=5):
        pass


def _no_scheduler(scheduler: str, error: OSError) -> CourseError:
    return CourseError(
        f"No Dask scheduler answered at {scheduler} ({error}); start one with "
        "`dask scheduler`, or leave out --scheduler to grade on this machine."
    )


def _client(jobs: int, scheduler: Optional[str]) -> Tuple[Any, Any]:
    """A Dask client: of the cluster at ``scheduler``, or of a local one with ``jobs`` workers."""
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            _reachable(scheduler)
            return Client(scheduler, timeout="30s"), None
        except OSError as error:
            raise _no_scheduler(scheduler, error) from None
    cluster = LocalCluster(
        n_workers=jobs,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        # No dashboard; the scheduler's small HTTP server (health, metrics) on any free port,
        # so that two gradings at once never compete for Dask's usual 8787.
        scheduler_kwargs={"dashboard_address": ":0"},
        # Dask's own log says nothing an instructor acts on (what fails is said for the student
        # it failed on), and at a Ctrl-C its workers print tracebacks as the scheduler goes.
        silence_logs=logging.CRITICAL,
        # A worker's memory is its units' business (each is a process of its own).
        memory_limit=0,
    )
    return Client(cluster), cluster


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
    scheduler: Optional[str] = None,
) -> List[StudentResult]:
    """Autograde every student of ``submissions`` into ``out``, each student a Dask task.

    Writes, as each student finishes: ``out/grades.csv`` (one row per student graded so far),
    ``out/feedback/STUDENT.html``, ``out/results/STUDENT.json`` and the gradebook
    ``out/work/gradebook.db``; and ``out/skipped.json`` (what in ``submissions`` was not a
    student's folder). Students whose files and course are unchanged since a finished earlier
    run into the same ``out`` are not graded again.

    Args:
        submissions: one folder (or ``.zip``) per student, or nbgrader's ``submitted/`` layout.
        out: the results' folder; its ``work/`` holds the gradebook and nbgrader's trees.
        jobs: the local cluster's workers: how many students are graded at once.
        limits: what each submission may use (default :class:`Limits`).
        use_sandbox: whether student code runs in the sandbox (off: with your rights).
        names: the assignments to grade (default: all of ``source``).
        source: the course source, whose hidden tests are run.
        progress: called with one line after each student.
        driving: whether each student's export drives the mission (the driving score).
        scheduler: the address of a running Dask scheduler (``tcp://host:8786``); None: a
            local cluster.

    Returns:
        One result per student, in name order.

    Raises:
        CourseError: if nbgrader cannot set the assignments up, or the scheduler is not there.
    """
    limits = limits or Limits()
    if scheduler:
        try:  # before the course is set up: a wrong address is said at once
            _reachable(scheduler)
        except OSError as error:
            raise _no_scheduler(scheduler, error) from None
    out = Path(out).resolve()
    work = out / "work"
    work.mkdir(parents=True, exist_ok=True)
    (out / "feedback").mkdir(exist_ok=True)
    source = Path(source).resolve()
    names = list(names) if names is not None else assignments(source)
    # The driving score exports the whole course: every notebook is then repaired and laid out.
    course = sorted(set(assignments(source)) | set(names)) if driving else list(names)
    students, skipped = find_submissions(Path(submissions))
    write_atomic(out / "skipped.json", json.dumps(skipped, indent=2) + "\n")
    setup = _set_up(work, source, course, names)
    writer = _Writer(
        out,
        names,
        setup.cells,
        f"sqlite:///{work / 'gradebook.db'}",
        Dependencies.from_source(source),
        rubrics=rubrics(source, names),
    )
    options = {
        "names": names,
        "course": course,
        "limits": dataclasses.asdict(limits),
        "use_sandbox": use_sandbox,
        "driving": driving,
    }
    started = time.monotonic()
    pending = _to_grade(students, out, setup, writer, options)
    writer.read_people_grades(list(writer.results.values()))  # given since the last run
    writer.write_csv()
    if pending:
        _run(pending, setup, writer, jobs, scheduler, progress, started, len(students))
    return [writer.results[name] for name in sorted(writer.results)]


def _to_grade(
    students: Dict[str, Path], out: Path, setup: _Course, writer: _Writer, options: Dict[str, Any]
) -> List[Tuple[str, Dict[str, Any], Dict[str, bytes], str, List[str]]]:
    """Read each student's submission; what is left to grade, by student.

    A student whose files, course and options are those of a finished earlier run into
    ``out`` keeps that run's result (into ``writer``); the others are kept in ``out/work``
    and come back as ``(student, options, files, key, what was left out)``.
    """
    course, names = options["course"], options["names"]
    pending: List[Tuple[str, Dict[str, Any], Dict[str, bytes], str, List[str]]] = []
    for folder_name in sorted(students):
        student = student_id(folder_name)
        if student != folder_name:
            writer.shown[student] = _as_written(folder_name)
        try:
            collected = read_submission(students[folder_name], course)
        except UnsafeFile as error:
            collected, refused = Collected(), f"the submission was not graded: {error}"
            collected.left_out.append(refused)
        files = _files_fingerprint(collected.files)
        key = _fingerprint(setup.key, options, files, collected.left_out)
        kept = _kept(out, student, key)
        if kept is not None:
            kept.name = writer.shown.get(student, kept.name)
            writer.results[student] = kept
            continue
        said = _left_out(collected.left_out, names)
        _keep_submitted(out / "work", student, collected.files, names)
        pending.append((student, {**options, "student": student}, collected.files, key, said))
    return pending


def write_grades(out: Path, source: Path = ROOT / "solutions") -> List[StudentResult]:
    """Write ``grades.csv`` and the feedback pages again, with what people gave in Formgrader.

    Nothing is graded or run: the results kept in ``out/results/`` are read back, the grades
    and comments given in the gradebook since (nbgrader's Formgrader, ``duckie formgrade``) are
    put over them, and every student's feedback page and the class's CSV are written again.

    Args:
        out: the folder ``duckie grade --out`` wrote.
        source: the course source (the assignments' order).

    Returns:
        One result per student, in name order.

    Raises:
        CourseError: if ``out`` holds no graded class.
    """
    out = Path(out).resolve()
    database = out / "work" / "gradebook.db"
    kept = sorted((out / "results").glob("*.json")) if (out / "results").is_dir() else []
    if not database.is_file() or not kept:
        raise CourseError(
            f"{out} holds no graded class: grade it first with "
            f"`duckie grade SUBMISSIONS --out {out}`."
        )
    results = []
    for path in kept:
        try:
            results.append(from_data(json.loads(path.read_text(encoding="utf-8"))))
        except (OSError, ValueError, KeyError, TypeError):
            raise CourseError(
                f"{path} cannot be read; run `duckie grade` again to grade that student anew."
            ) from None
    graded = {name for result in results for name, _ in result.cells}
    order = assignments(source)
    names = [name for name in order if name in graded] + sorted(graded - set(order))
    writer = _Writer(out, names, {}, f"sqlite:///{database}")
    writer.read_people_grades(results)
    for result in results:
        writer.results[result.student] = result
        writer.write_feedback(result)
    writer.write_csv()
    return results


def _progress(writer: _Writer, total: int, per_student: float) -> str:
    """The line that says how far the class's grading is, and how long is left."""
    count = len(writer.results)
    failed = sum(1 for item in writer.results.values() if item.problems)
    return (
        f"{count}/{total} graded ({failed} with problems), "
        f"about {(total - count) * per_student:.0f} s left"
    )


def _stopped(student: str, why: str) -> StudentResult:
    """A student whose grading stopped for ``why``, to be graded again by the next run."""
    return StudentResult(
        student,
        problems=[not_graded(why)],
        complete=False,
    )


#: A student's work waiting to be graded: name, task, files, key, what was said of the files.
_Item = Tuple[str, Dict[str, Any], Dict[str, bytes], str, List[str]]

#: How many times a student's task is sent when the cluster drops it (a worker lost with the
#: course's files): the second try finds them sent again.
_ATTEMPTS = 3


def _run(
    pending: List[_Item],
    setup: _Course,
    writer: _Writer,
    jobs: int,
    scheduler: Optional[str],
    progress: Optional[Callable[[str], None]],
    started: float,
    total: int,
) -> None:
    """Run the units on the cluster and record each result as it arrives."""
    from distributed import as_completed

    client, cluster = _client(max(1, jobs), scheduler)
    try:
        course = [client.scatter(setup.blob, broadcast=True)]
        workers = max(1, len(client.scheduler_info().get("workers", {})) or jobs)
        queue = iter(pending)
        futures: Dict[Any, Tuple[str, str, List[str], float]] = {}
        items = {item[0]: item for item in pending}
        attempts: Dict[str, int] = {}

        def submit(item: Optional[_Item]) -> bool:
            if item is None:
                return False
            student, task, files, key, said = item
            attempts[student] = attempts.get(student, 0) + 1
            future = client.submit(
                _grade_on_worker, task, files, setup.key, course[0],
                key=f"grade-{student}-{key[:12]}-{attempts[student]}", pure=False,
            )  # fmt: skip
            futures[future] = (student, key, said, time.monotonic())
            return True

        # A few students per worker in flight: their files are in memory until they are sent.
        for _ in range(2 * workers):
            if not submit(next(queue, None)):
                break
        flow = as_completed(list(futures))
        done = 0
        for future in flow:
            student, key, said, began = futures.pop(future)
            try:
                answer = future.result()
                result = from_data(answer["result"])
                autograded = answer.get("autograded", {})
            except CancelledError:
                # The scheduler dropped the task: the course's files it needs were lost with a
                # worker (scattered data cannot be made again). Send them again, and the student.
                if attempts[student] < _ATTEMPTS:
                    course[0] = client.scatter(setup.blob, broadcast=True)
                    submit(items[student])
                    flow.add(list(futures)[-1])
                    continue
                result, autograded = _stopped(student, "the cluster dropped its task"), {}
            except Exception as error:  # a worker lost for good, a task that raised
                why = f"{type(error).__name__}: {str(error)[:300]}"
                result, autograded = _stopped(student, why), {}
            result.problems = said + result.problems
            result.seconds = time.monotonic() - began
            writer.record(result, autograded, key)
            done += 1
            if submit(next(queue, None)):
                flow.add(list(futures)[-1])
            if progress is not None:
                progress(_progress(writer, total, (time.monotonic() - started) / done))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
