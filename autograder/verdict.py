"""A test's verdict, reached in the grader: the test cell's code runs here, never in the kernel.

A test cell of a graded notebook runs in the unit's process (:mod:`autograder.unit`), in a
namespace of its own: the imports of the course's own notebook (:func:`prelude`, never a
submission's), what earlier tests defined, and the names the course's answer cells define
(:func:`answer_names`), each asked of the student's kernel through
:class:`~autograder.calls.Link`. Any other name a test reads is the grader's.

A test with hidden tests runs in two parts (:class:`TestRun`): where the notebook reaches it,
its visible part, which fetches every student name the whole test needs; after the notebook's
last cell, its hidden part, in the same namespace, so it calls the very functions the test
fetched at its place. No cell of the student's runs after a hidden input reached their code:
nothing their code learned in a hidden test can come back in a later cell's output or error.
"""

from __future__ import annotations

import builtins
from typing import Any, Dict, List, Optional, Sequence, Tuple

from autograder.calls import (
    KERNEL_MODULE,
    Abandon,
    AnswerRefused,
    CallsBroken,
    Link,
    RaisedInKernel,
    Remote,
    StudentError,
)

__all__ = [
    "HIDDEN_NOT_RUN",
    "TestRun",
    "answer_names",
    "free_names",
    "prelude",
    "run_test",
    "split_hidden",
]

#: Said for a test whose hidden part never ran.
HIDDEN_NOT_RUN = (
    "This test's hidden part did not run: the notebook's kernel stopped before its last cell."
)
_BEGIN, _END = "### BEGIN HIDDEN TESTS", "### END HIDDEN TESTS"


def _defined_names(source: str, imports: bool = True) -> List[str]:
    """The names ``source`` binds at its top level (its imports too, unless told)."""
    import symtable

    try:
        table = symtable.symtable(source, "<test>", "exec")
    except SyntaxError:
        return []
    return [
        s.get_name()
        for s in table.get_symbols()
        if s.is_assigned() or (imports and s.is_imported())
    ]


def free_names(source: str) -> List[str]:
    """The names ``source`` reads but neither defines nor finds among Python's builtins."""
    import symtable

    table = symtable.symtable(source, "<test>", "exec")
    defined = {s.get_name() for s in table.get_symbols() if s.is_assigned() or s.is_imported()}
    found: List[str] = []

    def walk(scope: Any) -> None:
        for symbol in scope.get_symbols():
            name = symbol.get_name()
            module_level = scope.get_type() == "module"
            if (symbol.is_global() or (module_level and symbol.is_referenced())) and (
                name not in defined and not hasattr(builtins, name) and name not in found
            ):
                found.append(name)
        for child in scope.get_children():
            walk(child)

    walk(table)
    return found


def answer_names(cells: List[Any]) -> List[str]:
    """The names the course's answer cells define: the only names a test asks of the kernel.

    Args:
        cells: the cells of the course's own notebook (its source), never a submission's.
    """
    found: List[str] = []
    for cell in cells:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        if cell.get("cell_type") != "code" or not meta.get("solution"):
            continue
        lines = str(cell.get("source", "")).splitlines()
        text = "\n".join("" if line.lstrip().startswith(("%", "!")) else line for line in lines)
        found += [name for name in _defined_names(text, imports=False) if name not in found]
    return found


def prelude(cells: List[Any]) -> Dict[str, Any]:
    """The grader's namespace for a notebook's tests: the imports of its instructor's cells.

    Only ``import`` statements of the cells that are neither answers nor tests are run, here in
    the grader. ``cells`` must be the course's own notebook (its source or its release), never
    a submission: a cell a student added would run its imports in the grader, and an import
    may run any code (a module beside the notebook) or rebind a name the tests read
    (``from unittest.mock import call as math``).
    """
    import ast
    import contextlib
    import io
    import warnings

    space: Dict[str, Any] = {"__name__": "__grader_tests__"}
    for cell in cells:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        if cell.get("cell_type") != "code" or meta.get("grade") or meta.get("solution"):
            continue
        lines = str(cell.get("source", "")).splitlines()
        text = "\n".join("" if line.lstrip().startswith(("%", "!")) else line for line in lines)
        try:
            tree = ast.parse(text)
        except SyntaxError:
            continue
        for node in tree.body:
            if isinstance(node, (ast.Import, ast.ImportFrom)) and not getattr(node, "level", 0):
                code = compile(ast.Module(body=[node], type_ignores=[]), "<imports>", "exec")
                with contextlib.suppress(Exception), warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    with contextlib.redirect_stdout(io.StringIO()):
                        exec(code, space)
    return space


def split_hidden(source: str) -> Tuple[str, str]:
    """A test's code as its visible part and its hidden part (``### BEGIN HIDDEN TESTS``).

    The hidden part is what follows the region's first line, to the end of the test. A test
    whose region does not start at the top level (inside a ``try``, say), or whose parts do not
    each parse, runs whole as its hidden part: ``("", source)``. A test without hidden tests
    is all visible: ``(source, "")``.
    """
    import ast

    lines = source.splitlines(keepends=True)
    starts = [i for i, line in enumerate(lines) if line.strip().startswith(_BEGIN)]
    if not starts:
        return source, ""
    first = starts[0]
    visible, hidden = "".join(lines[:first]), "".join(lines[first:])
    if lines[first] != lines[first].lstrip():
        return "", source
    try:
        ast.parse(visible)
        ast.parse(hidden)
    except SyntaxError:
        return "", source
    return visible, hidden


class TestRun:
    """One test cell's run in the grader: its visible part at its place, its hidden part later.

    Args:
        source: the test's code (hidden tests included).
        grade_id: the test's name, in its tracebacks.
        space: the notebook's namespace for its tests (:func:`prelude`); what the test defines
            at its top level stays there for the next tests, as in a kernel.
        answers: the names the test may ask of the kernel (:func:`answer_names`); any other
            name the test reads is the grader's or undefined. None: any name (the student's
            own notebook, where every name is the student's anyway).

    Attributes:
        outputs: the cell's outputs so far, as notebook data: what the test printed and, if it
            failed, an error whose traceback holds only the error's line (never the test's
            code) and, for an error the student's code raised, the student's own traceback.
        failed: whether a part failed (the hidden part is then not run).
    """

    def __init__(
        self,
        source: str,
        grade_id: str,
        space: Dict[str, Any],
        answers: Optional[Sequence[str]] = None,
    ) -> None:
        self.source = source
        self.grade_id = grade_id
        self.space = space
        self.answers = answers
        self.visible, self.hidden = split_hidden(source)
        self.cell: Optional[Dict[str, Any]] = None
        self.outputs: List[Dict[str, Any]] = []
        self.failed = False
        self.finished = False

    @property
    def waiting(self) -> bool:
        """Whether the hidden part is still to run."""
        return bool(self.hidden) and not (self.failed or self.finished) and self.cell is not None

    def asked(self) -> List[str]:
        """The names the test asks of the kernel: the student's it reads."""
        return [
            name
            for name in free_names(self.source)
            if name not in self.space and (self.answers is None or name in self.answers)
        ]

    def refuse(self, why: str) -> None:
        """Fail the test without running it: the student's answer breaks a rule (said)."""
        self.cell = dict(self.space)
        self.failed = True
        self.outputs.append(
            {"output_type": "error", "ename": "RuleBroken", "evalue": why, "traceback": [why]}
        )

    def run_visible(self, link: Link) -> None:
        """Fetch the student's names the whole test needs, then run the visible part."""
        import contextlib

        self.cell = dict(self.space)
        names = self.asked()
        try:
            for name in names:
                # Without it, the test raises NameError where it uses the name, as in a kernel.
                with contextlib.suppress(NameError):
                    self.cell[name] = link.get(name)
        except BaseException as raised:
            self._failed(raised)
            return
        self._run(self.visible)

    def run_hidden(self) -> None:
        """Run the hidden part, in the namespace the visible part left."""
        if self.waiting:
            self.finished = True
            self._run(self.hidden)

    def not_run(self, why: str = HIDDEN_NOT_RUN) -> None:
        """Fail the test: its hidden part could not run (said with ``why``)."""
        if self.waiting or (self.hidden and self.cell is None):
            self.failed = True
            self.outputs.append(
                {"output_type": "error", "ename": "NotRun", "evalue": why, "traceback": [why]}
            )

    def _run(self, code: str) -> None:
        import contextlib
        import io

        assert self.cell is not None
        printed = io.StringIO()
        try:
            compiled = compile(code, f"<{self.grade_id}>", "exec")
            with contextlib.redirect_stdout(printed):
                exec(compiled, self.cell)
            error = None
        except BaseException as raised:  # the test's verdict
            error = raised
        finally:
            for name in _defined_names(code):
                if name in self.cell and not isinstance(self.cell[name], Remote):
                    self.space[name] = self.cell[name]
        if printed.getvalue():
            self.outputs.append(
                {"output_type": "stream", "name": "stdout", "text": printed.getvalue()}
            )
        if error is not None:
            self._failed(error)

    def _failed(self, error: BaseException) -> None:
        if isinstance(error, (Abandon, KeyboardInterrupt)) and not isinstance(
            error.__cause__, RaisedInKernel
        ):
            raise error
        self.failed = True
        self.outputs.append(_error_output(error))


def run_test(
    source: str,
    grade_id: str,
    space: Dict[str, Any],
    link: Link,
    answers: Optional[Sequence[str]] = None,
) -> List[Dict[str, Any]]:
    """Run one whole test cell here, the student's names asked of the kernel; its outputs.

    Both parts at once (:class:`TestRun` has the arguments and the outputs).
    """
    run = TestRun(source, grade_id, space, answers)
    run.run_visible(link)
    run.run_hidden()
    return run.outputs


def _error_output(error: BaseException) -> Dict[str, Any]:
    if isinstance(error, AnswerRefused):
        name, value = "AnswerTooLong", str(error)
    elif isinstance(error, CallsBroken):
        name, value = "CellTimeoutError" if "time" in str(error) else "KernelError", str(error)
    else:
        name, value = type(error).__name__, str(error)
        if isinstance(error, StudentError):
            name, _, value = value.partition(": ")
    line = f"{name}: {value}" if value else name
    lines = []
    if isinstance(error.__cause__, RaisedInKernel):
        lines = [
            line
            for line in str(error.__cause__).splitlines()
            if KERNEL_MODULE not in line and line.strip() != "Traceback (most recent call last):"
        ]
        lines = ["Traceback of your code (most recent call last):", *lines[:-1]] if lines else []
    return {"output_type": "error", "ename": name, "evalue": value, "traceback": [*lines, line]}
