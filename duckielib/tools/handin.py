"""Your notebooks as the grader runs them, and the zip you hand in.

Grading runs each notebook from top to bottom in a fresh kernel, exactly like JupyterLab's
Kernel > Restart Kernel and Run All Cells. :func:`run_notebook` does the same here and notes
every cell that raised; Run All itself stops at the first of them. :func:`check_course` runs a
whole course folder that way, in a copy of it (the notebooks load their neighbours from
``..``, and files they write stay out of your folder), and :func:`handin` then writes the zip
that ``duckie grade`` takes, after saying what is unfinished.

Laptop only: it needs Jupyter (nbclient, nbformat and the ``python3`` kernel).
"""

# Over 600 lines: one path behind `duckie handin` and `duckie submit`: running each notebook as the
# grader does, checking the whole course and writing the zip, sharing what a run found.

from __future__ import annotations

import math
import re
import tempfile
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple, Union

from duckielib.errors import DuckielibError

__all__ = [
    "CELL_SECONDS",
    "CourseCheck",
    "HandinError",
    "NOTEBOOK_SECONDS",
    "NotebookRun",
    "RaisedCell",
    "TIMEOUT",
    "UNANSWERED",
    "answers_left",
    "cell_kind",
    "check_course",
    "check_minutes",
    "first_line",
    "one_line",
    "without_controls",
    "course_notebooks",
    "handin",
    "handin_notebooks",
    "raised_cells",
    "run_notebook",
    "submit",
    "waiting_tests",
]

#: How long one cell may run before it is interrupted, in seconds.
CELL_SECONDS = 300

#: About how long checking one notebook takes, in seconds. Measured: the course's 11
#: notebooks took 79 s finished and 34 s untouched on a quiet two-core machine, 144 s and 76 s
#: on a busy one.
NOTEBOOK_SECONDS = 10

#: The longest excerpt of a cell's first line and of an error message kept in a report.
_EXCERPT, _MESSAGE = 50, 120
#: A terminal's control sequences (colours, titles, cursor moves) and other control characters.
_ANSI = re.compile(
    r"\x1b\[[0-?]*[ -/]*[@-~]|\x1b\][^\x07\x1b]*(?:\x07|\x1b\\)?|\x1b[()*+].|\x1b.?"
    r"|[\x00-\x08\x0b-\x1f\x7f-\x9f]"
)

#: The error a cell that ran out of time shows (nbclient's name for it, as nbgrader's).
TIMEOUT = "CellTimeoutError"

#: What an answer in words reads as released, before it is written.
UNANSWERED = "YOUR ANSWER HERE"


class HandinError(DuckielibError):
    """The notebooks cannot be checked or packed (no such folder, no notebook...)."""


@dataclass(frozen=True)
class RaisedCell:
    """A code cell that raised when its notebook ran.

    Attributes:
        number: the cell's position in the notebook, counting every cell from 1.
        kind: ``"exercise"`` (a graded cell you write), ``"test"`` (a graded test cell) or
            ``"code"`` (any other cell).
        grade_id: the nbgrader name of a graded cell (``"test_delta_phi"``), else None.
        first_line: the cell's first line of code, shortened.
        error: the exception, as ``"NameError: name 'x' is not defined"`` (one line).
    """

    number: int
    kind: str
    grade_id: Optional[str]
    first_line: str
    error: str

    def describe(self) -> str:
        """The cell and its error in a few words, for a report."""
        where = f"cell {self.number}"
        if self.grade_id:
            where += f" ({self.grade_id})"
        elif self.first_line:
            where += f" ({self.first_line})"
        return f"{where}: {self.error}"


@dataclass
class NotebookRun:
    """What happened when a notebook ran from top to bottom in a fresh kernel.

    Attributes:
        name: the notebook's name without ``.ipynb`` (``"05_odometry"``).
        seconds: how long the run took, kernel start included.
        raised: every code cell that raised, in order. Run All stops at the first one; the
            run goes on past it so that every test's result is known.
        tests: each test cell's ``grade_id`` and whether it passed.
        exercises: each graded cell you write, by ``grade_id``, with its cell number, in
            order.
        stopped: why the run ended before the last cell (the kernel died), or None.
        figures_as_text: the cells (numbers) that showed a figure as the text
            ``<Figure size ...>`` instead of a picture.
        printed: the text each code cell showed (what it printed, and its result as text), by
            cell number; pictures are left out.
        waits: each failed test that fails only because a function it builds on fails (of
            this notebook, or of an earlier one the notebook loads), by ``grade_id``, with those
            functions: ``"delta_phi"``, or ``"05_odometry: delta_phi"`` for another notebook's
            (:func:`waiting_tests`).
        answers_left: the answers in words still to write (:func:`answers_left`): their
            points by ``grade_id``, in order.
    """

    name: str
    seconds: float
    raised: List[RaisedCell] = field(default_factory=list)
    tests: Dict[str, bool] = field(default_factory=dict)
    exercises: Dict[str, int] = field(default_factory=dict)
    stopped: Optional[str] = None
    figures_as_text: List[int] = field(default_factory=list)
    printed: Dict[int, str] = field(default_factory=dict)
    waits: Dict[str, List[str]] = field(default_factory=dict)
    answers_left: Dict[str, float] = field(default_factory=dict)

    @property
    def stops_at(self) -> Optional[RaisedCell]:
        """The cell where JupyterLab's Run All stops (the first that raised), or None."""
        return self.raised[0] if self.raised else None

    @property
    def clean(self) -> bool:
        """Whether every cell ran without raising."""
        return not self.raised and self.stopped is None

    @property
    def failed_tests(self) -> List[str]:
        """The test cells that raised, by ``grade_id``."""
        return [grade_id for grade_id, passed in self.tests.items() if not passed]

    @property
    def unfinished(self) -> List[str]:
        """The exercises whose visible test fails on its own (a test of no exercise: its name).

        A test that fails only because another function fails is in :attr:`waiting` instead.
        """
        found = []
        for grade_id in self.failed_tests:
            if grade_id not in self.waits:
                found.append(self._exercise(grade_id))
        return found

    @property
    def waiting(self) -> Dict[str, List[str]]:
        """The exercises whose visible tests fail only because of another function, with it."""
        found: Dict[str, List[str]] = {}
        for grade_id, functions in self.waits.items():
            name = self._exercise(grade_id)
            if name not in self.unfinished:
                found.setdefault(name, [])
                found[name] += [function for function in functions if function not in found[name]]
        return found

    def _exercise(self, grade_id: str) -> str:
        name = grade_id.removeprefix("test_")
        return name if name in self.exercises else grade_id

    def _todo(self) -> str:
        """``to do: delta_phi; WheelPairing waits on it``: what to write or fix, and what waits."""
        todo = self.unfinished
        groups: Dict[Tuple[str, ...], List[str]] = {}
        for name, functions in self.waiting.items():
            groups.setdefault(tuple(functions), []).append(name)
        parts = [f"to do: {', '.join(todo)}"] if todo else []
        if not todo and len(groups) == 1:
            parts.append(f"waits on {_listed(next(iter(groups)))}")
        else:
            for causes, names in groups.items():
                verb = "waits" if len(names) == 1 else "wait"
                on = _listed(causes)
                if list(causes) == todo:
                    on = "it" if len(todo) == 1 else "them"
                parts.append(f"{_listed(names)} {verb} on {on}")
        return "; ".join(parts)

    def summary(self) -> str:
        """One line for a person: the tests, and where Run All stops."""
        passed = sum(self.tests.values())
        text = f"{self.name}: "
        if self.tests:
            text += f"{passed} of {len(self.tests)} visible tests pass"
            if self.failed_tests:
                text += f" ({self._todo()})"
        else:
            text += "no graded test"
        if self.stopped:
            return f"{text}; {self.stopped}"
        if self.clean:
            return f"{text}; Run All runs to the end ({self.seconds:.0f} s)"
        return f"{text}; Run All stops at {self.stops_at.describe()}"  # type: ignore[union-attr]


def _listed(words: Sequence[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} and {words[-1]}"


#: The sentences of :func:`~duckielib.solution.load_solution` that send the student to an
#: earlier notebook: its name, then the functions (the first of them at least).
_EARLIER = re.compile(
    r"SolutionError: (?:Fix|Finish) notebook (?P<notebook>\w+)(?: first)?: "
    r"(?:write )?(?P<names>\w+(?:, \w+)*)"
)


def waiting_tests(run: NotebookRun, folder: Union[str, Path]) -> Dict[str, List[str]]:
    """The failed tests of a run that fail only because a function they build on fails.

    A test waits on a function of its own notebook when that function fails its own visible
    test (:class:`~duckielib.solution.cascade.Dependencies`, read from the notebooks as they
    are), and on an earlier notebook's when the load of the student's earlier work stops in it
    saying which function to fix or write first, while the test's own exercise is written.

    Args:
        run: a notebook's run, its tests' results known.
        folder: the course folder the notebook is in (one folder per notebook).

    Returns:
        ``grade_id -> functions``, each ``"delta_phi"`` (this notebook's) or
        ``"05_odometry: delta_phi"``; the tests that fail on their own are left out.
    """
    from duckielib.solution import SolutionError, export_solution
    from duckielib.solution.cascade import Dependencies

    folder = Path(folder)
    failed = run.failed_tests
    if not failed:
        return {}
    dependencies = Dependencies.from_source(folder)
    errors = {cell.grade_id: cell.error for cell in run.raised if cell.grade_id}
    unwritten: Optional[List[str]] = None
    waits: Dict[str, List[str]] = {}
    for grade_id in failed:
        test = (run.name, grade_id)
        earlier = _EARLIER.match(errors.get(grade_id, ""))
        if earlier and earlier["notebook"] < run.name:
            if unwritten is None:
                try:
                    unwritten = export_solution(folder, strict=False).unfinished
                except SolutionError:
                    unwritten = []
            own = {function.name for function in dependencies.own_functions(test)}
            if not own & set(unwritten):
                waits[grade_id] = [f"{earlier['notebook']}: {earlier['names']}"]
            continue
        causes = dependencies.causes(test, [(run.name, other) for other in failed])
        if causes:
            waits[grade_id] = [
                function.name
                if function.assignment == run.name
                else f"{function.assignment}: {function.name}"
                for function in causes
            ]
    return waits


def _source(cell: Any) -> str:
    text = cell.get("source", "")
    return "".join(text) if isinstance(text, list) else str(text)


def answers_left(cells: Iterable[Any]) -> Dict[str, float]:
    """The answers in words still to write, with their points, by ``grade_id``, in order.

    An answer in words is a markdown cell graded by a person (nbgrader's ``grade`` and
    ``solution``); it is still to write while it reads as released, :data:`UNANSWERED`, or
    is empty. Grading scores it 0 then.
    """
    left = {}
    for cell in cells:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        if cell.get("cell_type") != "markdown" or not (meta.get("grade") and meta.get("solution")):
            continue
        if _source(cell).strip() in ("", UNANSWERED):
            left[str(meta.get("grade_id"))] = float(meta.get("points") or 0)
    return left


def cell_kind(cell: Any) -> str:
    """``"test"``, ``"exercise"`` or ``"code"``: what a code cell is, by its nbgrader metadata."""
    meta = cell.get("metadata", {}).get("nbgrader", {})
    if meta.get("grade") and not meta.get("solution"):
        return "test"
    if meta.get("solution") and not meta.get("grade"):
        return "exercise"
    return "code"


def _cut(text: str, limit: int) -> str:
    return text if len(text) <= limit else text[: limit - 1].rstrip() + "…"


def without_controls(text: str) -> str:
    """``text`` without a terminal's control sequences and other control characters."""
    return _ANSI.sub("", text)


def one_line(value: object) -> str:
    """``value`` as text on one line, without terminal colours."""
    return " ".join(_ANSI.sub(" ", str(value or "")).split())


def first_line(text: str) -> str:
    """A cell's first line of code (comment lines skipped), shortened."""
    for raw in text.splitlines():
        line = raw.strip()
        if line and not line.startswith("#"):
            return _cut(line, _EXCERPT)
    return "an empty cell"


def _error(output: Any, cell_seconds: Optional[float]) -> str:
    """``Name: message`` of an error output, on one line, without its traceback."""
    name = _cut(one_line(output.get("ename")) or "Error", 60)
    message = one_line(output.get("evalue"))
    if not message and name == TIMEOUT and cell_seconds:
        message = f"still running after the {cell_seconds:g} s a cell may take"
    return f"{name}: {_cut(message, _MESSAGE)}" if message else name


def raised_cells(
    sent: Sequence[Any],
    ran: Sequence[Any],
    cell_seconds: Optional[float] = None,
    skip: Iterable[str] = (),
) -> List[RaisedCell]:
    """Every code cell that raised when a notebook ran, in order.

    What each cell is (an exercise, a test) and what it says are read from ``sent``, the cells
    as they were given to the run; only the error outputs are read from ``ran``, the same cells
    as they came back. A grader that runs a student's notebook elsewhere keeps its own copy as
    ``sent``, so the run cannot change which cells are tests.

    Args:
        sent: the notebook's cells before the run.
        ran: the same cells after it, with their outputs.
        cell_seconds: a cell's time limit, quoted for a cell that ran out of it.
        skip: exception names that do not count (a grader's mark for cells never run).
    """
    skipped = set(skip)
    found = []
    for number, (mine, theirs) in enumerate(zip(sent, ran), start=1):
        if mine.get("cell_type") != "code":
            continue
        errors = [
            output
            for output in theirs.get("outputs", [])
            if output.get("output_type") == "error" and output.get("ename") not in skipped
        ]
        if errors:
            kind = cell_kind(mine)
            grade_id = mine.get("metadata", {}).get("nbgrader", {}).get("grade_id")
            found.append(
                RaisedCell(
                    number=number,
                    kind=kind,
                    grade_id=grade_id if kind != "code" else None,
                    first_line=first_line(_source(mine)),
                    error=_error(errors[-1], cell_seconds),
                )
            )
    return found


def run_notebook(path: Union[str, Path], cell_seconds: float = CELL_SECONDS) -> NotebookRun:
    """Run a notebook from top to bottom in a fresh ``python3`` kernel, as Run All does.

    The kernel works in the notebook's folder, as in JupyterLab; the notebook's file is not
    changed. Unlike Run All, the run goes on after a cell raises, so that every cell that
    raises and every test's result are known.

    Args:
        path: the ``.ipynb`` file.
        cell_seconds: a cell that runs longer than this is interrupted (and counts as raised).

    Returns:
        What raised, which tests passed, and how long it took.

    Raises:
        HandinError: if the file is not a readable notebook.
    """
    import nbformat
    from nbclient import NotebookClient
    from nbclient.exceptions import DeadKernelError

    path = Path(path)
    try:
        notebook = nbformat.read(path, as_version=4)
    except (OSError, ValueError) as error:
        raise HandinError(f"{path} is not a readable notebook ({error}).") from None
    client = NotebookClient(
        notebook,
        timeout=cell_seconds,
        kernel_name="python3",
        allow_errors=True,
        interrupt_on_timeout=True,
        resources={"metadata": {"path": str(path.parent)}},
        config=_encrypted_kernels(),
    )
    run = NotebookRun(name=path.stem, seconds=0.0)
    started = time.monotonic()
    try:
        client.execute()
    except DeadKernelError:
        run.stopped = "the kernel died (a crash, os._exit, or out of memory); later cells never ran"
    run.seconds = time.monotonic() - started
    for cell in notebook.cells:
        for output in cell.get("outputs", []):
            if output.get("ename") == "KeyboardInterrupt":  # the run interrupted it: too long
                output["ename"], output["evalue"] = TIMEOUT, ""
    run.raised = raised_cells(notebook.cells, notebook.cells, cell_seconds)
    run.answers_left = answers_left(notebook.cells)
    raised = {cell.number for cell in run.raised}
    for number, cell in enumerate(notebook.cells, start=1):
        if cell.cell_type != "code":
            continue
        kind, grade_id = cell_kind(cell), cell.metadata.get("nbgrader", {}).get("grade_id")
        shown = [out.get("data", {}) for out in cell.get("outputs", []) if "data" in out]
        text = [
            _source({"source": out.get("text", "")})
            if out.get("output_type") == "stream"
            else _source({"source": out.get("data", {}).get("text/plain", "")})
            for out in cell.get("outputs", [])
            if out.get("output_type") in ("stream", "execute_result")
        ]
        if text:
            run.printed[number] = _ANSI.sub("", "".join(text))
        if any(
            str(data.get("text/plain", "")).startswith("<Figure size") and len(data) == 1
            for data in shown
        ):
            run.figures_as_text.append(number)
        if kind == "exercise":
            run.exercises[grade_id] = number
        elif kind == "test":
            run.tests[grade_id] = cell.get("execution_count") is not None and number not in raised
    run.waits = waiting_tests(run, path.parent.parent)
    return run


def _encrypted_kernels() -> Any:
    """Configuration that gives each kernel CurveZMQ keys for its connection, where pyzmq can.

    A kernel connected without them prints "Kernel is running over TCP without encryption" on
    the terminal when it starts, once per notebook; with them it has nothing to warn about.
    """
    import zmq
    from traitlets.config import Config

    policy = "auto" if zmq.has("curve") else "disabled"  # auto: if the kernel can (python3 can)
    return Config({"KernelManager": {"transport_encryption": policy}})


def check_minutes(count: int) -> int:
    """About how many minutes checking ``count`` notebooks takes, at least 1."""
    return max(1, math.ceil(count * NOTEBOOK_SECONDS / 60))


def course_notebooks(folder: Union[str, Path]) -> List[Path]:
    """The course notebooks of a folder: ``NN_name/NN_name.ipynb``, in order.

    Raises:
        HandinError: if the folder does not exist or holds no course notebook.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise HandinError(f"There is no folder {folder}; give the folder of your notebooks.")
    found = sorted(
        path / f"{path.name}.ipynb"
        for path in folder.iterdir()
        if path.is_dir() and (path / f"{path.name}.ipynb").is_file()
    )
    if not found:
        raise HandinError(
            f"{folder} holds no course notebook (a folder such as 05_odometry/ with "
            "05_odometry.ipynb in it): give the folder you work in, course/."
        )
    return found


@dataclass
class CourseCheck:
    """The runs of a course folder's notebooks.

    Attributes:
        folder: the folder checked.
        runs: one run per notebook, in order.
    """

    folder: Path
    runs: List[NotebookRun]

    @property
    def clean(self) -> bool:
        """Whether every notebook ran to the end without a cell raising."""
        return all(run.clean for run in self.runs)

    def answers_left(self) -> Optional[str]:
        """One line naming each answer in words still to write, with its points; or None."""
        left = [
            (run.name, grade_id, points)
            for run in self.runs
            for grade_id, points in run.answers_left.items()
        ]
        if not left:
            return None
        named = ", ".join(
            f"{name} {grade_id} ({_points(points)})" for name, grade_id, points in left
        )
        return (
            f"Written answers left ({_points(sum(points for _, _, points in left))}): {named}. "
            f"Write each in its {UNANSWERED} cell (double-click it), save, and hand in again."
        )

    def report(self) -> str:
        """A line per notebook, then what is left to do."""
        lines = [run.summary() for run in self.runs]
        todo = [run.name for run in self.runs if not run.clean]
        if todo:
            lines.append(f"Unfinished or not running cleanly: {', '.join(todo)}.")
        else:
            lines.append("Every notebook runs from top to bottom and passes its visible tests.")
        answers = self.answers_left()
        if answers:
            lines.append(answers)
        return "\n".join(lines)


def _points(points: float) -> str:
    return f"{points:g} point" + ("" if points == 1 else "s")


def check_course(
    folder: Union[str, Path],
    names: Optional[Iterable[str]] = None,
    cell_seconds: float = CELL_SECONDS,
    progress: Optional[Callable[[NotebookRun], None]] = None,
) -> CourseCheck:
    """Run each notebook of a course folder as Run All does, in a copy of the folder.

    Only the notebooks are copied, as only they are handed in: what a notebook needs beyond
    them it must make itself. Your folder is left as it is.

    Args:
        folder: the folder of notebooks (``course/``, or ``solutions/``).
        names: only these notebooks (``["05_odometry"]``); default: all.
        cell_seconds: a cell that runs longer than this is interrupted.
        progress: called with each notebook's run as soon as it is done.

    Raises:
        HandinError: if the folder holds no course notebook, or a name is not among them.
    """
    folder = Path(folder)
    return _check_snapshot(
        folder, _snapshot(course_notebooks(folder)), names, cell_seconds, progress
    )


def _snapshot(notebooks: List[Path]) -> Dict[str, bytes]:
    """The notebooks' files as they are now, by path in the course (``05_x/05_x.ipynb``)."""
    return {f"{path.parent.name}/{path.name}": path.read_bytes() for path in notebooks}


def _check_snapshot(
    folder: Path,
    snapshot: Dict[str, bytes],
    names: Optional[Iterable[str]],
    cell_seconds: float,
    progress: Optional[Callable[[NotebookRun], None]],
) -> CourseCheck:
    """Run the notebooks of ``snapshot`` (all, or those called ``names``) in a scratch copy."""
    available = [Path(name).stem for name in snapshot]
    wanted = available if names is None else list(names)
    unknown = sorted(set(wanted) - set(available))
    if unknown:
        raise HandinError(f"{folder} has no notebook {', '.join(unknown)}.")
    runs = []
    with tempfile.TemporaryDirectory(prefix="duckie-check-") as scratch:
        copy = Path(scratch) / folder.resolve().name
        for name, data in snapshot.items():
            (copy / name).parent.mkdir(parents=True)
            (copy / name).write_bytes(data)
        for name in snapshot:
            if Path(name).stem in wanted:
                run = run_notebook(copy / name, cell_seconds)
                runs.append(run)
                if progress is not None:
                    progress(run)
    return CourseCheck(folder=folder, runs=runs)


def handin_notebooks(folder: Union[str, Path], output: Union[str, Path]) -> List[Path]:
    """The notebooks :func:`handin` would zip into ``output``, after checking it can.

    Raises:
        HandinError: if ``output`` is not a ``.zip`` in an existing folder outside ``folder``,
            or ``folder`` holds no course notebook.
    """
    output = Path(output)
    if output.suffix != ".zip":
        raise HandinError(f"{output} must end in .zip (name it after yourself: NAME.zip).")
    if not output.parent.is_dir():
        raise HandinError(f"There is no folder {output.parent} to write {output.name} into.")
    notebooks = course_notebooks(folder)
    if output.resolve().is_relative_to(Path(folder).resolve()):
        raise HandinError(
            f"Write the zip outside {folder} (for example next to it), not among your notebooks."
        )
    return notebooks


def handin(
    folder: Union[str, Path],
    output: Union[str, Path],
    progress: Optional[Callable[[NotebookRun], None]] = None,
) -> CourseCheck:
    """Check every notebook of ``folder`` as the grader runs it, then zip the notebooks.

    The zip holds one folder per notebook (``05_odometry/05_odometry.ipynb``), the layout
    ``duckie grade`` takes; name it after yourself (``ada_lovelace.zip``). It is written even
    when work is unfinished: the check says what is left.

    Args:
        folder: your folder of notebooks (``course/``).
        output: the ``.zip`` file to write.
        progress: called with each notebook's run as soon as it is done.

    Raises:
        HandinError: if the folder holds no notebook or the zip cannot be written where asked.
    """
    # The notebooks are read once: what is checked is what is handed in, even if they change
    # while the check runs.
    snapshot = _snapshot(handin_notebooks(folder, output))
    check = _check_snapshot(Path(folder), snapshot, None, CELL_SECONDS, progress)
    output = Path(output)
    partial = output.with_name(output.name + ".partial")
    with zipfile.ZipFile(partial, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for name, data in snapshot.items():
            archive.writestr(name, data)
    partial.replace(output)
    return check


#: The course's name in nbgrader's exchange, on a class hub (``duckie hub``).
COURSE_ID = "duckiebot"


def submit(
    folder: Union[str, Path],
    assignment: str,
    progress: Optional[Callable[[NotebookRun], None]] = None,
) -> CourseCheck:
    """On a class hub: check an assignment as the grader runs it, then submit it.

    The assignment's notebooks run as :func:`handin` runs them (the other notebooks of
    ``folder`` beside them, as their neighbours), then nbgrader's ``submit`` hands the
    assignment's folder in through the hub's exchange, as the Assignment List's Submit button
    does. It is submitted even when work is unfinished: the check says what is left, and you
    may submit again (your instructor collects the latest).

    Raises:
        HandinError: if ``folder/assignment`` is not there (fetch it first) or nbgrader cannot
            submit it (its reason, in a sentence).
    """
    folder = Path(folder)
    if not (folder / assignment / f"{assignment}.ipynb").is_file():
        raise HandinError(
            f"There is no {assignment}/{assignment}.ipynb in {folder.resolve()}: fetch the "
            "assignment first (Nbgrader > Assignment List > Fetch), then run this command in "
            "the folder that holds it."
        )
    snapshot = _snapshot(course_notebooks(folder))
    check = _check_snapshot(folder, snapshot, [assignment], CELL_SECONDS, progress)
    import subprocess
    import sys

    done = subprocess.run(
        [sys.executable, "-m", "nbgrader", "submit", assignment, f"--course={COURSE_ID}"],
        cwd=folder,
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0:
        said = [line for line in (done.stdout + done.stderr).splitlines() if line.strip()]
        reason = said[-1] if said else f"nbgrader exited with {done.returncode}"
        raise HandinError(
            f"{assignment} could not be submitted: {reason}. Submitting works on a class hub "
            "(its Assignment List); elsewhere, hand in a zip with duckie handin -o NAME.zip."
        )
    return check
