"""The visible tests of a student's earlier notebooks, run against the solution they make.

A later notebook builds on functions the student wrote earlier: it loads them with
``load_solution("..", required=[...])``. When one of them is wrong, the later notebook fails far
from the mistake (an odometry metres off, a ``KeyError`` in a plot). So the load first runs the
visible tests of the required parts, and of the parts they build on, from the student's own
earlier notebooks, and names the first function whose test fails (:func:`first_failing_test`).

What runs: for each function, in course order, its own test cells (read by
:class:`~duckielib.solution.cascade.Dependencies`), with whatever they need from the cells
before them in its notebook: the imports, the ``def`` and ``class`` statements and the UPPER_CASE
constants that bind a name the tests use, nothing else (no simulation, no figure). The solution's
parts stand in for the notebook's own definitions, so the tests check what the later notebook
will call. The tests are the student's own (hidden tests are left out even where a notebook
still holds them): they hold no answer. A test that needs something else of its notebook (a
variable a simulation filled) cannot be run alone and is passed over, as is one that runs
out of time.

This module imports only the standard library: it ships with the robot's copy of the package,
but only the laptop's notebooks run it.
"""

from __future__ import annotations

import ast
import builtins
import contextlib
import io
import json
import linecache
import os
import re
import signal
import threading
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Iterator, List, Mapping, Optional, Sequence, Set, Tuple, Union

from duckielib.solution.cascade import (
    Dependencies,
    Function,
    TestId,
    _parse,
    _uses,
    notebook_stamps,
)
from duckielib.solution.contract import CONTRACT

__all__ = ["FailedTest", "TEST_SECONDS", "checking", "first_failing_test"]

#: The longest one visible test may run before it is passed over, in seconds.
TEST_SECONDS = 10.0

_HIDDEN_TESTS = re.compile(
    r"^[ \t]*### BEGIN HIDDEN TESTS[^\n]*\n.*?^[ \t]*### END HIDDEN TESTS[^\n]*$", re.M | re.S
)
#: The longest test message quoted, in characters.
_MESSAGE = 400
_STATEMENTS = (ast.Import, ast.ImportFrom, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)
_RUNNING = threading.local()
#: The checks that passed, by what they read (the notebooks' stamps and the parts): a notebook
#: that loads the same unchanged solution again (09 does three times) does not test it again.
_PASSED: Set[Tuple[Any, ...]] = set()


@dataclass(frozen=True)
class FailedTest:
    """A visible test of an earlier notebook that fails with the student's solution.

    Attributes:
        function: the graded function whose own test it is.
        grade_id: the test cell's nbgrader name (``"test_delta_phi"``).
        message: what the test says, on one line: its ``assert`` message, or the error it
            raised (``"TypeError: ..."``).
        unwritten: whether it failed because a function still raises ``NotImplementedError``.
    """

    function: Function
    grade_id: str
    message: str
    unwritten: bool = False

    def sentence(self) -> str:
        """The sentence for the student: which notebook to fix first, and why."""
        notebook, name = self.function.assignment, self.function.name
        if self.unwritten:
            return (
                f"Finish notebook {notebook} first: {name} is not written yet (its visible test "
                "stops at NotImplementedError). Write it, save the notebook, and run this cell "
                "again."
            )
        message = self.message.rstrip(".")
        if len(message) > _MESSAGE:
            message = message[: _MESSAGE - 1].rstrip() + "…"
        return (
            f"Fix notebook {notebook} first: {name} fails its visible test: {message}. "
            "Then save it and run this cell again."
        )


def checking() -> bool:
    """Whether this thread is running earlier notebooks' tests (a load inside them: no check)."""
    return bool(getattr(_RUNNING, "active", False))


def first_failing_test(
    folder: Union[str, Path],
    solution: Any,
    parts: Mapping[str, str],
    before: Optional[str] = None,
) -> Optional[FailedTest]:
    """Run the visible tests of ``parts`` and of what they build on; the first that fails.

    Args:
        folder: the student's folder of notebooks, one folder per assignment (``course/``).
        solution: the solution loaded from it (a module): its parts are what the tests call.
        parts: the parts to check, each with the assignment its code was exported from
            (``{"delta_phi": "05_odometry"}``).
        before: only notebooks whose assignment comes before this one (the notebook loading
            the solution, which tests its own parts itself); None: every notebook.

    Returns:
        The first failing test, functions taken in course order (one a later function builds
        on comes first); None if every test that could run passed.
    """
    if not parts:
        return None
    course = Path(folder).resolve()
    key = (str(course), notebook_stamps(course, before), before, tuple(sorted(parts.items())))
    if key in _PASSED:
        return None
    dependencies = Dependencies.from_source(course, through=before)
    wanted = [
        function
        for function in _functions(dependencies, parts)
        if before is None or function.assignment < before
    ]
    failed = _run(course, solution, dependencies, wanted) if wanted else None
    if failed is None:
        _PASSED.add(key)
    return failed


def _functions(dependencies: Dependencies, parts: Mapping[str, str]) -> List[Function]:
    """The functions to test, in course order: the parts and what they build on."""
    found: Set[Function] = set()
    for name, assignment in parts.items():
        function = Function(assignment, name)
        if function in dependencies.functions:
            found.add(function)
            found |= dependencies.functions[function]
    order = list(dependencies.functions)
    return sorted(
        (function for function in found if dependencies.own_tests.get(function)),
        key=order.index,
    )


def _run(
    folder: Path, solution: Any, dependencies: Dependencies, functions: Sequence[Function]
) -> Optional[FailedTest]:
    """Run the functions' own tests, notebook by notebook, until one fails."""
    by_notebook: Dict[str, List[Tuple[TestId, Function]]] = {}
    for function in functions:
        for test in dependencies.own_tests[function]:
            by_notebook.setdefault(test[0], []).append((test, function))
    provided = {name: getattr(solution, name) for name in CONTRACT if hasattr(solution, name)}
    with _isolated():
        # Notebooks in course order, so the deepest mistake is found first.
        for assignment in sorted(by_notebook):
            tests = dict(by_notebook[assignment])
            failed = _run_notebook(folder / assignment / f"{assignment}.ipynb", tests, provided)
            if failed is not None:
                return failed
    return None


@dataclass
class _Step:
    """A statement to run for the tests (a definition, an import), or a whole test cell."""

    code: Any  # a compiled code object
    binds: Set[str]
    needs: Set[str]
    test: Optional[TestId] = None


def _run_notebook(
    path: Path, tests: Mapping[TestId, Function], provided: Mapping[str, Any]
) -> Optional[FailedTest]:
    """Run one notebook's tests of ``tests`` with what they need; the first that fails."""
    if not path.is_file():  # not a FIFO, which would block the reader
        return None
    try:
        cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    steps = _steps(cells, path.parent.name, {test[1] for test in tests}, set(provided))
    namespace: Dict[str, Any] = {"__name__": "__main__", "__builtins__": builtins}
    for step in _needed(steps, set(provided)):
        namespace.update(provided)
        if step.test is None:
            with contextlib.suppress(Exception):
                exec(step.code, namespace)
            continue
        failed = _run_test(step, namespace, tests[step.test])
        if failed is not None:
            return failed
    return None


def _steps(
    cells: Sequence[Any], assignment: str, wanted: Set[str], provided: Set[str]
) -> List[_Step]:
    """The test cells called ``wanted``, and before each the statements that may serve it."""
    steps: List[_Step] = []
    for number, cell in enumerate(cells, start=1):
        if not wanted:
            break
        if not isinstance(cell, dict) or cell.get("cell_type") != "code":
            continue
        marks = (cell.get("metadata") or {}).get("nbgrader") or {}
        source = cell.get("source", "")
        text = _HIDDEN_TESTS.sub("", "".join(source) if isinstance(source, list) else str(source))
        tree = _parse(text)
        if tree is None:
            continue
        label = f"<{assignment}, cell {number}>"
        linecache.cache[label] = (len(text), None, text.splitlines(True), label)
        grade_id = marks.get("grade_id")
        if marks.get("grade") and not marks.get("solution") and grade_id in wanted:
            wanted = wanted - {grade_id}
            code = _compiled(tree, label)
            if code is not None:
                steps.append(_Step(code, set(), _uses(tree, {}).names, (assignment, grade_id)))
            continue
        for statement in tree.body:
            binds = _binds(statement)
            if binds and not binds <= provided:
                code = _compiled(ast.Module(body=[statement], type_ignores=[]), label)
                if code is not None:
                    steps.append(_Step(code, binds, _uses(statement, {}).names))
    return steps


def _binds(statement: ast.stmt) -> Set[str]:
    """The names a statement worth running for a test binds: imports, definitions, CONSTANTS."""
    if isinstance(statement, (ast.Import, ast.ImportFrom)):
        return {(alias.asname or alias.name).split(".")[0] for alias in statement.names}
    if isinstance(statement, _STATEMENTS):
        return {statement.name}  # type: ignore[union-attr]
    targets: List[ast.expr] = []
    if isinstance(statement, ast.Assign):
        targets = statement.targets
    elif isinstance(statement, ast.AnnAssign) and statement.value is not None:
        targets = [statement.target]
    names = {target.id for target in targets if isinstance(target, ast.Name)}
    if targets and len(names) == len(targets) and all(name.isupper() for name in names):
        return names
    return set()


def _compiled(tree: ast.Module, label: str) -> Any:
    try:
        return compile(tree, label, "exec")
    except (SyntaxError, ValueError, TypeError):
        return None


def _needed(steps: Sequence[_Step], provided: Set[str]) -> List[_Step]:
    """The tests, and of the other steps those that bind a name a later needed step uses."""
    needed: Set[str] = set()
    kept: List[_Step] = []
    for step in reversed(steps):
        if step.test is None:
            if not step.binds & needed:
                continue
            needed -= step.binds
        kept.append(step)
        needed |= step.needs - provided
    return kept[::-1]


def _run_test(step: _Step, namespace: Dict[str, Any], function: Function) -> Optional[FailedTest]:
    """Run one test cell; what it says if it fails (None: passed, or could not judge)."""
    try:
        with _time_limit(TEST_SECONDS):
            exec(step.code, namespace)
    except _OutOfTime:
        return None
    except NameError as error:
        # A name the cell's own code misses: it needs something of its notebook that cannot
        # run alone. A name the solution misses is the student's mistake.
        return None if _raised_in_cells(error) else _failed(step, function, error)
    except (Exception, SystemExit) as error:  # exit() in the student's code fails too
        return _failed(step, function, error, isinstance(error, NotImplementedError))
    return None


def _raised_in_cells(error: BaseException) -> bool:
    """Whether an error came from a notebook cell's own code, not from the solution's."""
    frames = traceback.extract_tb(error.__traceback__)
    return bool(frames) and frames[-1].filename.startswith("<") and ", cell " in frames[-1].filename


def _failed(
    step: _Step, function: Function, error: BaseException, unwritten: bool = False
) -> FailedTest:
    assert step.test is not None
    text = " ".join(str(error).split())
    if isinstance(error, AssertionError) and text:
        message = text
    elif isinstance(error, AssertionError):
        message = f"an assert failed{_line_of(error)}"
    else:
        message = f"{type(error).__name__}{_line_of(error)}" + (f": {text}" if text else "")
    return FailedTest(function, step.test[1], message, unwritten)


def _line_of(error: BaseException) -> str:
    """`` (line 3: assert x == 1)``: where in the test cell an error was raised, if there."""
    frames = [
        frame
        for frame in traceback.extract_tb(error.__traceback__)
        if frame.filename.startswith("<") and ", cell " in frame.filename
    ]
    if not frames:
        return ""
    line = (frames[-1].line or "").strip()
    return f" (line {frames[-1].lineno}{': ' + line if line else ''})"


class _OutOfTime(Exception):
    """A test ran longer than :data:`TEST_SECONDS`."""


@contextlib.contextmanager
def _time_limit(seconds: float) -> Iterator[None]:
    """Interrupt the block after ``seconds`` where a timer signal can (the main thread)."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(
        signal, "setitimer"
    ):
        yield
        return

    def interrupt(signum: int, frame: Any) -> None:
        raise _OutOfTime()

    previous = signal.signal(signal.SIGALRM, interrupt)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


@contextlib.contextmanager
def _isolated() -> Iterator[None]:
    """Run tests quietly, leaving the working folder, the environment and ROS imports as found.

    What the tests print is not shown (the notebook that loads says what failed); in a test
    cell that loads the solution, output on stderr would even fail the cell under nbgrader.
    """
    from duckielib.ros.modules import modules_installed

    folder, environment = Path.cwd(), dict(os.environ)
    _RUNNING.active = True
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(
            io.StringIO()
        ), modules_installed():
            yield
    finally:
        _RUNNING.active = False
        os.chdir(folder)
        if dict(os.environ) != environment:
            os.environ.clear()
            os.environ.update(environment)
