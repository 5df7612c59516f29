"""Cascades: a test that fails because a function it builds on fails its own test.

One small mistake travels: a wrong ``delta_phi`` (05_odometry) also fails ``WheelPairing``'s
test, which calls it, and both tests of 09_mission, whose mission runs the student's odometry.
Each of those messages then describes a symptom far from the cause. This module says first
which function to fix.

Where the dependencies come from (worked out from the course source, never listed by hand):

- **Graded functions** are the functions and classes defined at the top level of the answer
  cells (nbgrader ``solution: true``), one per ``(assignment, name)``.
- **Answer code** builds on the graded functions its reference solution uses by name: a name of
  its own notebook first, else the exported one (cells tagged ``export``, the last in course
  order, as in the exported solution the robot runs).
- **A test cell** (nbgrader ``grade: true``, hidden tests included) builds on what its free
  names are bound to in its notebook at that point (answer cells' definitions, and the graded
  functions that ordinary cells' helpers and variables use), on the exported function behind
  each attribute named like one (``mine.light_service_node``), and on every part each
  ``load_solution(..., required=PARTS)`` call in it or in those helpers loads. ``PARTS`` is a
  literal list of names or a constant of :mod:`duckielib.solution` such as ``MISSION_PARTS``;
  without it, ``load_solution``'s default. So the mission tests of 09_mission, which load the
  student's solution and run a whole mission, build on every part the mission needs. PARTS
  that cannot be worked out stand for every exported function.
- Everything is transitive: a test builds on what its functions build on.
- **Its own tests**: a graded function's own tests are the test cells of its notebook that name
  it directly. When a test names several of its notebook's functions, the ones an earlier test
  already named are set-up, not what it tests.
- **A cascade**: a failed test builds on a function (not its own) one of whose own tests, not
  this one, failed too. Only the deepest such functions are named: one is left out when each
  of its failed tests builds on another failing function itself (a wrong ``delta_phi`` fails
  ``WheelPairing``'s test and the mission's: only ``delta_phi`` is named).

Cells are Python with IPython's magics (``%matplotlib``, ``!ls``, ``x = !ls``, ``name?``)
left out; a cell that is still not Python is read for names only, and a notebook that cannot
be read is skipped (see :attr:`Dependencies.problems`).

The same reading works on a student's own notebooks (``course/``, where the answer code is
theirs and only the visible tests are left): ``duckie handin`` says which failed tests wait on
another function, and a later notebook's ``load_solution`` runs the own tests of the parts it
loads (:mod:`duckielib.solution.visible_tests`). It holds no answer, and it reads a statement's
names only when a test needs them.

Typical use, once per class::

    dependencies = Dependencies.from_source(Path("solutions"))
    messages = dependencies.explain(messages)   # {(assignment, grade_id): message}
    note = dependencies.driving_note(messages)  # or None

This module imports only the standard library (it ships with the robot's copy of the package).
"""

# Over 600 lines: one analysis of the course's notebooks (their cells' names, load_solution's parts,
# the transitive dependencies and the cascades they explain) whose steps feed each other through
# `_Builder`.

from __future__ import annotations

import ast
import builtins
import json
import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import (
    Dict,
    FrozenSet,
    Iterable,
    List,
    Mapping,
    Optional,
    Sequence,
    Set,
    Tuple,
    Union,
)

__all__ = ["Dependencies", "Function", "TestId"]

#: A test cell: ``(assignment, grade_id)``.
TestId = Tuple[str, str]

#: The cell tag of the cells whose code goes into a student's exported solution.
_EXPORT_TAG = "export"

_LOAD_SOLUTION = "load_solution"
_BUILTINS = frozenset(dir(builtins))
_WORD = re.compile(r"[A-Za-z_]\w*")
_TOP_LEVEL_DEFINITION = re.compile(r"^(?:async\s+)?(?:def|class)\s+([A-Za-z_]\w*)", re.MULTILINE)
_MAGIC_ASSIGNMENT = re.compile(r"^([^=#'\"]*[^=!<>:+\-*/%&|^@])=\s*[!%]")
_DEFINITIONS = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)
_SCOPES = (*_DEFINITIONS, ast.Lambda)
_COMPREHENSIONS = (ast.ListComp, ast.SetComp, ast.DictComp, ast.GeneratorExp)


@dataclass(frozen=True, order=True)
class Function:
    """A graded function or class, written by the student in an answer cell.

    Attributes:
        assignment: the notebook's assignment folder, for example ``"05_odometry"``.
        name: its name, for example ``"delta_phi"``.
    """

    assignment: str
    name: str

    def __str__(self) -> str:
        return f"{self.name} ({self.assignment})"


# --- Reading cells ------------------------------------------------------------------------


def _text(cell: Mapping[str, object]) -> str:
    source = cell.get("source", "")
    if isinstance(source, list):
        return "".join(str(line) for line in source)
    return source if isinstance(source, str) else ""


def _without_magics(source: str) -> str:
    """The source with IPython's magics, shell escapes and help queries made into ``pass``."""
    lines = source.splitlines()
    if lines and lines[0].lstrip().startswith("%%"):
        lines[0] = ""  # a cell magic; its body is often Python (%%time, %%capture)
    kept = []
    for line in lines:
        stripped = line.lstrip()
        indent = line[: len(line) - len(stripped)]
        magic = _MAGIC_ASSIGNMENT.match(stripped)
        if stripped.startswith(("%", "!")):
            kept.append(f"{indent}pass")
        elif magic:
            kept.append(f"{indent}{magic.group(1)}= None")
        elif stripped.endswith("?") and not stripped.startswith("#"):
            kept.append(f"{indent}pass")
        else:
            kept.append(line)
    return "\n".join(kept)


@lru_cache(maxsize=4096)
def _parse(source: str) -> Optional[ast.Module]:
    """The cell as Python, or None if it is not Python even without its magics.

    Kept per text (do not change the tree): a notebook saved again parses only its new cells.
    """
    # Plain Python first: a line that starts with % may continue an expression (a modulo).
    for text in (source, _without_magics(source)):
        try:
            return ast.parse(text)
        except (SyntaxError, ValueError, RecursionError):
            continue
    return None


@dataclass
class _Uses:
    """What a piece of code uses: free names, attribute names, solutions it loads."""

    names: Set[str] = field(default_factory=set)
    attributes: Set[str] = field(default_factory=set)
    #: The parts of each ``load_solution`` call; None where they cannot be worked out.
    loads: List[Optional[Tuple[str, ...]]] = field(default_factory=list)

    def add(self, other: _Uses) -> None:
        self.names |= other.names
        self.attributes |= other.attributes
        self.loads.extend(other.loads)


def _bound(node: ast.AST) -> Set[str]:
    """Every name a piece of code binds anywhere in it (variables, parameters, imports, defs)."""
    names: Set[str] = set()
    for child in ast.walk(node):
        if isinstance(child, ast.Name) and isinstance(child.ctx, (ast.Store, ast.Del)):
            names.add(child.id)
        elif isinstance(child, _DEFINITIONS):
            names.add(child.name)
        elif isinstance(child, ast.arg):
            names.add(child.arg)
        elif isinstance(child, (ast.Import, ast.ImportFrom)):
            names.update((alias.asname or alias.name).split(".")[0] for alias in child.names)
        elif isinstance(child, ast.ExceptHandler) and child.name:
            names.add(child.name)
    return names


def _uses(node: ast.AST, constants: Mapping[str, Tuple[str, ...]]) -> _Uses:
    """The names ``node`` reads but does not bind, the attributes it reads, what it loads.

    Args:
        node: a statement, a definition or a whole cell.
        constants: lists of part names the code may pass as ``required``, by name.
    """
    uses = _Uses()
    bound = _bound(node)
    if isinstance(node, _DEFINITIONS):
        bound.discard(node.name)  # a definition that names itself (recursion) is not a use
    for child in ast.walk(node):
        if isinstance(child, ast.Name) and isinstance(child.ctx, ast.Load):
            if child.id not in bound and child.id not in _BUILTINS:
                uses.names.add(child.id)
        elif isinstance(child, ast.Attribute) and isinstance(child.ctx, ast.Load):
            uses.attributes.add(child.attr)
        elif isinstance(child, ast.Call) and _called(child) == _LOAD_SOLUTION:
            uses.loads.append(_required(child, constants))
    return uses


def _called(call: ast.Call) -> Optional[str]:
    if isinstance(call.func, ast.Name):
        return call.func.id
    if isinstance(call.func, ast.Attribute):
        return call.func.attr
    return None


def _required(
    call: ast.Call, constants: Mapping[str, Tuple[str, ...]]
) -> Optional[Tuple[str, ...]]:
    """The parts a ``load_solution`` call asks for, or None if they cannot be worked out."""
    argument: Optional[ast.expr] = call.args[1] if len(call.args) > 1 else None
    for keyword in call.keywords:
        if keyword.arg == "required":
            argument = keyword.value
        elif keyword.arg is None:
            return None  # **options: anything may be in there
    if argument is None:
        return constants.get("", None)
    return _names_in(argument, constants)


def _names_in(
    node: ast.expr, constants: Mapping[str, Tuple[str, ...]]
) -> Optional[Tuple[str, ...]]:
    """The strings of a literal list of names, built from constants, ``*`` and ``+``."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return (node.value,)
    if isinstance(node, ast.Name):
        return constants.get(node.id)
    if isinstance(node, ast.Starred):
        return _names_in(node.value, constants)
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add):
        parts = [_names_in(node.left, constants), _names_in(node.right, constants)]
    elif isinstance(node, (ast.List, ast.Tuple, ast.Set)):
        parts = [_names_in(element, constants) for element in node.elts]
    elif isinstance(node, ast.Call) and _called(node) in ("list", "tuple") and len(node.args) == 1:
        parts = [_names_in(node.args[0], constants)]
    else:
        return None
    if any(part is None for part in parts):
        return None
    return tuple(name for part in parts for name in part or ())


def _uses_of_text(source: str) -> _Uses:
    """For a cell that is not Python: every word in it may be a name it uses."""
    uses = _Uses(names=set(_WORD.findall(source)))
    if _LOAD_SOLUTION in uses.names:
        uses.loads.append(None)
    return uses


def _library_constants() -> Dict[str, Tuple[str, ...]]:
    """The lists of part names :mod:`duckielib.solution` offers; ``""`` is the default."""
    from duckielib.solution import contract

    constants = {
        name: tuple(value)
        for name, value in vars(contract).items()
        if name.isupper()
        and isinstance(value, (tuple, list))
        and value
        and all(isinstance(item, str) for item in value)
    }
    # load_solution's default (its module runs this one's users: it is not imported here).
    constants[""] = tuple(contract.ODOMETRY_PARTS)
    return constants


# --- The course's notebooks ---------------------------------------------------------------


@dataclass
class _Cell:
    kind: str  # "answer", "test" or "other"
    grade_id: Optional[str]
    exported: bool
    source: str
    tree: Optional[ast.Module]


@dataclass
class _Notebook:
    assignment: str
    cells: List[_Cell]


def _read_notebook(path: Path) -> _Notebook:
    notebook = json.loads(path.read_text(encoding="utf-8"))
    cells = []
    for cell in notebook["cells"]:
        if cell.get("cell_type") != "code":
            continue
        metadata = cell.get("metadata") or {}
        marks = metadata.get("nbgrader") or {}
        if marks.get("solution"):
            kind = "answer"
        elif marks.get("grade") and marks.get("grade_id"):
            kind = "test"
        else:
            kind = "other"
        source = _text(cell)
        cells.append(
            _Cell(
                kind=kind,
                grade_id=marks.get("grade_id"),
                exported=_EXPORT_TAG in (metadata.get("tags") or []),
                source=source,
                tree=_parse(source),
            )
        )
    return _Notebook(path.parent.name, cells)


def _definitions(cell: _Cell) -> List[Tuple[str, Optional[ast.stmt]]]:
    """The functions and classes defined at the top level of a cell, with their code."""
    if cell.tree is None:
        return [(name, None) for name in _TOP_LEVEL_DEFINITION.findall(cell.source)]
    return [(node.name, node) for node in cell.tree.body if isinstance(node, _DEFINITIONS)]


def _statement_bindings(statement: ast.AST) -> List[str]:
    """The names a top-level statement binds for the cells after it.

    Names bound inside a function, class, lambda or comprehension stay there.
    """
    if isinstance(statement, _DEFINITIONS):
        return [statement.name]
    if isinstance(statement, (ast.Import, ast.ImportFrom)):
        return [(alias.asname or alias.name).split(".")[0] for alias in statement.names]
    if isinstance(statement, ast.Name):
        return [statement.id] if isinstance(statement.ctx, ast.Store) else []
    if isinstance(statement, (*_SCOPES, *_COMPREHENSIONS)):
        return []
    names: List[str] = []
    for child in ast.iter_child_nodes(statement):
        names.extend(_statement_bindings(child))
    return names


def _join(words: Sequence[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    if len(words) <= 1:
        return "".join(words)
    return f"{', '.join(words[:-1])} and {words[-1]}"


# --- The dependencies ---------------------------------------------------------------------


@dataclass(frozen=True)
class Dependencies:
    """Which graded functions each test of a course builds on, and the cascades that follow.

    Build it with :meth:`from_source`. Every mapping is in course order.

    Attributes:
        functions: every graded function, each with the graded functions its reference
            code builds on, directly or through others (itself not included).
        tests: every test cell, each with every graded function it builds on (its own
            included).
        own_tests: each graded function's own tests, in its notebook.
        mission: the graded functions a mission builds on: the parts a mission loads
            (:data:`duckielib.solution.MISSION_PARTS`) and what they build on.
        problems: sentences about notebooks that could not be read (left out).
    """

    functions: Mapping[Function, FrozenSet[Function]]
    tests: Mapping[TestId, FrozenSet[Function]]
    own_tests: Mapping[Function, Tuple[TestId, ...]]
    mission: FrozenSet[Function]
    problems: Tuple[str, ...] = ()

    @classmethod
    def from_source(cls, source: Union[str, Path], through: Optional[str] = None) -> Dependencies:
        """Work out the dependencies from a course source, once per folder and version.

        Args:
            source: the course: one folder per assignment, each with its notebook (the
                nbgrader source ``solutions/``, or a student's ``course/``).
            through: only the assignments up to this one, included (what a notebook builds
                on); None: all.

        Returns:
            The dependencies; the same object again for the same folder while none of its
            notebooks changed.
        """
        folder = Path(source).resolve()
        return _build(folder, through, notebook_stamps(folder, through))

    def own_functions(self, test: TestId) -> FrozenSet[Function]:
        """The graded functions a test is the own test of."""
        return frozenset(function for function, own in self.own_tests.items() if test in own)

    def builds_on(self, test: TestId) -> FrozenSet[Function]:
        """The graded functions a test builds on, other than its own."""
        return self.tests.get(test, frozenset()) - self.own_functions(test)

    def causes(self, test: TestId, failed: Iterable[TestId]) -> List[Function]:
        """The functions a failed test builds on that fail their own tests, deepest only.

        A function counts if one of its own tests, other than ``test``, failed. Of those, a
        function is left out when each of its failed tests builds on another failing function
        itself: its failure may come from there too.

        Args:
            test: the failed test.
            failed: every failed test of the student.

        Returns:
            The functions to fix first, in course order (empty: no cascade).
        """
        failed = set(failed)
        return self._deepest(self.builds_on(test), failed, test)

    def explain(self, failed: Mapping[TestId, str]) -> Dict[TestId, str]:
        """The failed tests' messages, each cascade's first sentence naming what to fix first.

        Args:
            failed: every failed test of one student, with its message.

        Returns:
            The same tests and messages, a sentence such as "This test builds on delta_phi
            (05_odometry), which fails its own test test_delta_phi: fix that first." put
            before the message of each test whose failure may come from another function's.
        """
        keys = set(failed)
        explained = {}
        for test, message in failed.items():
            sentence = self._sentence("This test builds on", keys, test)
            explained[test] = f"{sentence} {message}" if sentence else message
        return explained

    def driving_note(self, failed: Iterable[TestId]) -> Optional[str]:
        """The sentence to put before the driving score's reasons, or None.

        Args:
            failed: every failed test of one student (a mapping's keys are used).

        Returns:
            For example "The mission uses delta_phi (05_odometry), which fails its own test
            test_delta_phi: fix that first.", naming the deepest of the functions the mission
            builds on that fail their own tests; None if none does.
        """
        return self._sentence("The mission uses", set(failed), None)

    def _failed_own(
        self, function: Function, failed: Set[TestId], test: Optional[TestId]
    ) -> List[TestId]:
        """A function's own tests that failed, ``test`` left out."""
        return [key for key in self.own_tests.get(function, ()) if key in failed and key != test]

    def _deepest(
        self, functions: Iterable[Function], failed: Set[TestId], test: Optional[TestId]
    ) -> List[Function]:
        """Those of ``functions`` that fail an own test other than ``test``, deepest only."""
        failing = [function for function in functions if self._failed_own(function, failed, test)]

        def explained(own_test: TestId) -> bool:
            return any(
                self._failed_own(other, failed, own_test) for other in self.builds_on(own_test)
            )

        deepest = [
            function
            for function in failing
            if not all(explained(key) for key in self._failed_own(function, failed, test))
        ]
        order = list(self.functions)
        return sorted(deepest or failing, key=order.index)

    def _sentence(self, start: str, failed: Set[TestId], test: Optional[TestId]) -> Optional[str]:
        """The cascade's sentence for one test, or for the mission (``test`` None)."""
        functions = self.mission if test is None else self.builds_on(test)
        causes = self._deepest(functions, failed, test)
        if not causes:
            return None
        tests = {
            function: [key[1] for key in self._failed_own(function, failed, test)]
            for function in causes
        }
        if len(causes) == 1:
            (function,) = causes
            plural = "s" if len(tests[function]) > 1 else ""
            return (
                f"{start} {function}, which fails its own test{plural} "
                f"{_join(tests[function])}: fix that first."
            )
        listed = [
            f"{function.name} ({function.assignment}, {_join(tests[function])})"
            for function in causes
        ]
        return f"{start} functions that fail their own tests: {_join(listed)}; fix those first."


# --- Working the dependencies out ---------------------------------------------------------


@lru_cache(maxsize=8)
def _build(
    folder: Path, through: Optional[str], stamps: Tuple[Tuple[str, int, int], ...]
) -> Dependencies:
    """The dependencies of the course source ``folder`` (``stamps`` only keys the cache)."""
    del stamps
    return _Builder(folder, through).build()


def notebook_stamps(
    folder: Path, through: Optional[str] = None
) -> Tuple[Tuple[str, int, int], ...]:
    """The version of a course folder's notebooks (up to ``through``): path, time and size.

    Equal stamps mean unchanged notebooks: what is worked out from them can be kept.
    """
    stamps = []
    for path in _notebook_paths(folder, through):
        try:
            stat = path.stat()
        except OSError:
            continue
        stamps.append((path.relative_to(folder).as_posix(), stat.st_mtime_ns, stat.st_size))
    return tuple(stamps)


def _notebook_paths(folder: Path, through: Optional[str]) -> List[Path]:
    """The notebooks of a course folder in course order, up to ``through`` if given.

    Only each assignment's own notebook (``05_odometry/05_odometry.ipynb``), and only a regular
    file: anything else a student's folder holds is not read (a FIFO would block the reader).
    """
    return [
        path
        for path in sorted(folder.glob("*/*.ipynb"))
        if path.stem == path.parent.name
        and (through is None or path.parent.name <= through)
        and path.is_file()
    ]


class _Builder:
    """Works the dependencies of one course source out, notebook by notebook."""

    def __init__(self, folder: Path, through: Optional[str] = None) -> None:
        self.constants = _library_constants()
        self.notebooks: List[_Notebook] = []
        self.problems: List[str] = []
        for path in _notebook_paths(folder, through):
            try:
                self.notebooks.append(_read_notebook(path))
            except (OSError, ValueError, KeyError, TypeError, AttributeError) as error:
                self.problems.append(
                    f"The source notebook {path.parent.name}/{path.name} cannot be read "
                    f"({error}); its tests are left out of the cascades."
                )
        if not self.notebooks and not self.problems:
            self.problems.append(
                f"{folder} holds no source notebook (one folder per assignment, each with its "
                "notebook): no test is explained by another."
            )
        # The graded functions, their code, and the exported one of each name (last one wins).
        self.code: Dict[Function, List[Tuple[Optional[ast.stmt], str]]] = {}
        self.exported: Dict[str, Function] = {}
        for notebook in self.notebooks:
            for cell in notebook.cells:
                if cell.kind != "answer":
                    continue
                for name, node in _definitions(cell):
                    function = Function(notebook.assignment, name)
                    self.code.setdefault(function, []).append((node, cell.source))
                    if cell.exported:
                        self.exported[name] = function
        self.functions: Dict[Function, FrozenSet[Function]] = {}

    def build(self) -> Dependencies:
        direct = {function: self._direct(function) for function in self.code}
        for function in self.code:
            seen: Set[Function] = set()
            todo = list(direct[function])
            while todo:
                item = todo.pop()
                if item not in seen:
                    seen.add(item)
                    todo.extend(direct.get(item, ()))
            self.functions[function] = frozenset(seen - {function})
        tests: Dict[TestId, FrozenSet[Function]] = {}
        own_tests: Dict[Function, List[TestId]] = {}
        for notebook in self.notebooks:
            self._read_tests(notebook, tests, own_tests)
        mission = self._closure(
            self.exported[name]
            for name in self.constants.get("MISSION_PARTS", ())
            if name in self.exported
        )
        return Dependencies(
            functions=self.functions,
            tests=tests,
            own_tests={
                function: tuple(own_tests[function])
                for function in self.functions
                if function in own_tests
            },
            mission=mission,
            problems=tuple(self.problems),
        )

    def _loaded(self, uses: _Uses) -> Set[Function]:
        """The exported functions code reaches through a loaded solution."""
        found: Set[Function] = set()
        for parts in uses.loads:
            if parts is None:
                found.update(self.exported.values())
            else:
                found.update(self.exported[name] for name in parts if name in self.exported)
        found.update(self.exported[name] for name in uses.attributes if name in self.exported)
        return found

    def _direct(self, function: Function) -> Set[Function]:
        """The graded functions a graded function's reference code uses directly."""
        uses = _Uses()
        for node, source in self.code[function]:
            uses.add(_uses(node, self.constants) if node is not None else _uses_of_text(source))
        found = self._loaded(uses)
        for name in uses.names:
            same = Function(function.assignment, name)
            if same in self.code:
                found.add(same)
            elif name in self.exported:
                found.add(self.exported[name])
            else:
                found.update(other for other in self.code if other.name == name)
        return found - {function}

    def _closure(self, start: Iterable[Function]) -> FrozenSet[Function]:
        found = set(start)
        for function in list(found):
            found |= self.functions.get(function, frozenset())
        return frozenset(found)

    def _resolve(self, uses: _Uses, scope: Mapping[str, _Bound]) -> Set[Function]:
        found = self._loaded(uses)
        for name in uses.names:
            found |= self._value(scope.get(name))
        return found

    def _value(self, bound: Optional[_Bound]) -> FrozenSet[Function]:
        """The graded functions a name is bound to (a statement's worked out once, if asked)."""
        if bound is None:
            return frozenset()
        if isinstance(bound, _Pending):
            if bound.value is None:
                bound.value = frozenset(
                    self._resolve(_uses(bound.statement, self.constants), bound.scope)
                )
            return bound.value
        return bound

    def _read_tests(
        self,
        notebook: _Notebook,
        tests: Dict[TestId, FrozenSet[Function]],
        own_tests: Dict[Function, List[TestId]],
    ) -> None:
        """Add a notebook's tests: what each builds on, and whose own test it is."""
        scope: Dict[str, _Bound] = {}
        named_before: Set[Function] = set()
        for cell in notebook.cells:
            if cell.kind == "test":
                if cell.tree is not None:
                    uses = _uses(cell.tree, self.constants)
                else:
                    uses = _uses_of_text(cell.source)
                test = (notebook.assignment, str(cell.grade_id))
                tests[test] = self._closure(self._resolve(uses, scope))
                named = {
                    Function(notebook.assignment, name)
                    for name in uses.names
                    if Function(notebook.assignment, name) in self._value(scope.get(name))
                }
                for function in sorted((named - named_before) or named):
                    own_tests.setdefault(function, []).append(test)
                named_before |= named
            for name, bound in _bindings(cell, notebook.assignment):
                if isinstance(bound, ast.AST):
                    # Worked out only if a test needs it: most statements are no test's concern.
                    scope[name] = _Pending(bound, dict(scope))
                else:
                    scope[name] = bound


@dataclass
class _Pending:
    """A name bound by a statement, to resolve against the names bound before it."""

    statement: ast.AST
    scope: Dict[str, _Bound]
    value: Optional[FrozenSet[Function]] = None


#: What a name of a notebook is bound to: graded functions, or a statement to work out.
_Bound = Union[FrozenSet[Function], _Pending]


def _bindings(
    cell: _Cell, assignment: str
) -> List[Tuple[str, Union[FrozenSet[Function], ast.stmt]]]:
    """What a cell binds for the cells after it, in order.

    Each name comes with the graded function it is (an answer cell's definition), nothing (an
    import: the library's), or the statement that binds it (a helper or a variable), whose
    uses resolve against the names bound before it.
    """
    if cell.tree is None:
        if cell.kind != "answer":
            return []
        return [(name, frozenset({Function(assignment, name)})) for name, _ in _definitions(cell)]
    bindings: List[Tuple[str, Union[FrozenSet[Function], ast.stmt]]] = []
    for statement in cell.tree.body:
        value: Union[FrozenSet[Function], ast.stmt]
        if cell.kind == "answer" and isinstance(statement, _DEFINITIONS):
            value = frozenset({Function(assignment, statement.name)})
        elif isinstance(statement, (ast.Import, ast.ImportFrom)):
            value = frozenset()
        else:
            value = statement
        bindings.extend((name, value) for name in _statement_bindings(statement))
    return bindings
