"""The project's own import graph: rooms, arrows between them, circles, the largest modules.

Run it from the repository's root to see the structure::

    .venv/bin/python tests/import_graph.py

A module's imports are read from its source with :mod:`ast`, never by importing it. An import
at a module's top level is an arrow that holds as soon as the module loads; one inside a
function (a lazy import) is listed apart, since it only holds when that function runs; so is a
module named in a string for ``importlib.import_module`` or ``__import__``. A circle is a set
of modules that reach each other through top-level arrows. The tests (``tests/test_purity.py``)
use :func:`graph` to keep the arrows the way they should point. The report also names the
modules and functions over the house's limits (:data:`MODULE_LINES`, :data:`FUNCTION_LINES`),
and apart those that do not say why they are so long.

A module or function over its limit says why at its top, in one comment: ``# Over 600
lines:`` (``# Over 80 lines:`` for a function) and the reason, a sentence that ends with a
full stop and may go on over the comment lines below. It stands where only comments can:

- a module's, between its docstring and its first statement (usually the ``__future__``
  import)::

      # Over 600 lines: one state machine, whose states read best side by side.

      from __future__ import annotations

- a function's or method's, first in its body, after its docstring::

      def replay(bag):
          (the docstring)
          # Over 80 lines: the message path is one loop, for speed.
          ...

Anything else is no reason (:func:`reason`).
"""

from __future__ import annotations

import ast
import sys
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Set, Tuple

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("duckielib", "autograder")
#: The house's limits: longer modules and functions say at their top why they are so long.
MODULE_LINES, FUNCTION_LINES = 600, 80
#: The calls that import a module named in a string.
_BY_NAME = {"import_module", "__import__"}


@dataclass
class Graph:
    """Each module's lines and the project's modules it imports, at its top level or lazily."""

    lines: Dict[str, int] = field(default_factory=dict)
    top: Dict[str, Set[str]] = field(default_factory=lambda: defaultdict(set))
    lazy: Dict[str, Set[str]] = field(default_factory=lambda: defaultdict(set))
    typing: Dict[str, Set[str]] = field(default_factory=lambda: defaultdict(set))
    named: Dict[str, Set[str]] = field(default_factory=lambda: defaultdict(set))
    #: ``module:Class.function`` -> its lines.
    functions: Dict[str, int] = field(default_factory=dict)
    #: A module's or ``module:Class.function``'s reason for its length, where it gives one.
    reasons: Dict[str, str] = field(default_factory=dict)

    def circles(self, every: bool = False) -> List[List[str]]:
        """The sets of modules that import each other, largest first.

        Args:
            every: count lazy imports, those for type hints only and modules named for
                importlib too, not just the top level.
        """
        edges: Dict[str, Set[str]] = defaultdict(set)
        for kinds in (self.top, self.lazy, self.typing, self.named) if every else (self.top,):
            for module, imported in kinds.items():
                edges[module] |= imported
        index: Dict[str, int] = {}
        low: Dict[str, int] = {}
        stack: List[str] = []
        found: List[List[str]] = []

        def visit(module: str) -> None:  # Tarjan's strongly connected components
            index[module] = low[module] = len(index)
            stack.append(module)
            for other in sorted(edges.get(module, ())):
                if other not in index:
                    visit(other)
                    low[module] = min(low[module], low[other])
                elif other in stack:
                    low[module] = min(low[module], index[other])
            if low[module] == index[module]:
                group = []
                while True:
                    member = stack.pop()
                    group.append(member)
                    if member == module:
                        break
                if len(group) > 1:
                    found.append(sorted(group))

        for module in sorted(self.lines):
            if module not in index:
                visit(module)
        return sorted(found, key=len, reverse=True)

    def arrows(self, source: str, target: str) -> List[str]:
        """Every import from a module under ``source`` to one under ``target``, of any kind."""
        said = []
        kinds = ("top", self.top), ("lazy", self.lazy), ("typing", self.typing)
        for kind, edges in (*kinds, ("by name", self.named)):
            for module, imported in sorted(edges.items()):
                if _under(module, source):
                    said += [f"{module} -> {other} ({kind})" for other in sorted(imported)
                             if _under(other, target)]  # fmt: skip
        return said


def _under(module: str, prefix: str) -> bool:
    return module == prefix or module.startswith(prefix + ".")


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _resolve(name: str, known: Set[str]) -> str | None:
    """The project module ``name`` refers to (a name imported from a module is that module)."""
    while name:
        if name in known:
            return name
        name = name.rpartition(".")[0]
    return None


def graph() -> Graph:
    """The import graph of ``duckielib`` and ``autograder``."""
    paths = sorted(path for package in PACKAGES for path in (ROOT / package).rglob("*.py"))
    known = {_module_name(path) for path in paths}
    result = Graph()
    for path in paths:
        module = _module_name(path)
        text = path.read_text(encoding="utf-8")
        lines = text.splitlines()
        result.lines[module] = len(lines)
        tree = ast.parse(text, str(path))
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        top_level = set(map(id, tree.body))
        said = reason(lines, tree, MODULE_LINES)
        if said is not None:
            result.reasons[module] = said
        _count_functions(tree, module, lines, result)
        for node in ast.walk(tree):
            named = _named_module(node)
            if named is not None:
                target = _resolve(named, known)
                if target is not None and target != module:
                    result.named[module].add(target)
                continue
            names = _imported_names(node, package, known)
            guarded = isinstance(node, ast.ImportFrom) and node.module == "__future__"
            for name in names:
                target = _resolve(name, known)
                if target is None or target == module or guarded:
                    continue
                if _in_type_checking(tree, node):
                    result.typing[module].add(target)
                elif id(node) in top_level:
                    result.top[module].add(target)
                else:
                    result.lazy[module].add(target)
    return result


def _imported_names(node: ast.AST, package: str, known: Set[str]) -> List[str]:
    """The modules an import statement names (none for any other node)."""
    if isinstance(node, ast.Import):
        return [alias.name for alias in node.names]
    if not isinstance(node, ast.ImportFrom):
        return []
    base = node.module or ""
    if node.level:
        parent = package.split(".")[: len(package.split(".")) - node.level + 1]
        base = ".".join(parent + ([base] if base else []))
    # A name that is a module is an arrow to it; any other name, to its module.
    return [
        f"{base}.{alias.name}" if f"{base}.{alias.name}" in known else base for alias in node.names
    ]


def _named_module(node: ast.AST) -> str | None:
    """The module a call ``import_module("x")`` or ``__import__("x")`` names, if a constant."""
    if not isinstance(node, ast.Call) or not node.args:
        return None
    function = node.func
    name = function.attr if isinstance(function, ast.Attribute) else getattr(function, "id", "")
    argument = node.args[0]
    if name in _BY_NAME and isinstance(argument, ast.Constant) and isinstance(argument.value, str):
        return argument.value
    return None


def _count_functions(
    tree: ast.AST, module: str, lines: List[str], result: Graph, prefix: str = ""
) -> None:
    """Each function's and method's lines (decorators left out), by ``module:Class.name``."""
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            name = f"{module}:{prefix}{node.name}"
            result.functions[name] = node.end_lineno - node.lineno + 1
            said = reason(lines, node, FUNCTION_LINES)
            if said is not None:
                result.reasons[name] = said
            _count_functions(node, module, lines, result, f"{prefix}{node.name}.")
        elif isinstance(node, ast.ClassDef):
            _count_functions(node, module, lines, result, f"{prefix}{node.name}.")
        else:
            _count_functions(node, module, lines, result, prefix)


def reason(lines: List[str], node: ast.AST, limit: int) -> str | None:
    """The reason a module or function gives for being over ``limit`` lines (module doc).

    Args:
        lines: the module's source, line by line.
        node: the module (:class:`ast.Module`) or the function.
        limit: :data:`MODULE_LINES` or :data:`FUNCTION_LINES`, the number the comment names.

    Returns:
        The sentence after ``# Over LIMIT lines:``, its comment lines joined; None if the
        comment is not at the top or its sentence has no full stop.
    """
    body = getattr(node, "body", [])
    docstring = ast.get_docstring(node, clean=False) is not None  # type: ignore[arg-type]
    # Only comments stand after the docstring (or the def line) and before the first statement.
    first = body[0].end_lineno if docstring else getattr(node, "lineno", 1) - 1
    statements = body[1:] if docstring else body
    last = statements[0].lineno - 1 if statements else getattr(node, "end_lineno", len(lines))
    marker = f"# Over {limit} lines:"
    top = [line.strip() for line in lines[first:last]]
    for index, line in enumerate(top):
        if not line.startswith(marker):
            continue
        words = [line[len(marker) :].strip()]
        for more in top[index + 1 :]:
            if words[-1].endswith(".") or not more.startswith("#"):
                break
            words.append(more.lstrip("#").strip())
        said = " ".join(word for word in words if word)
        return said if said.endswith(".") and len(said) > 1 else None
    return None


def _in_type_checking(tree: ast.Module, node: ast.AST) -> bool:
    """Whether ``node`` sits in a top-level ``if TYPE_CHECKING:`` block (no arrow at run time)."""
    return any(
        isinstance(statement, ast.If)
        and "TYPE_CHECKING" in ast.unparse(statement.test)
        and any(node is inner for inner in ast.walk(statement))
        for statement in tree.body
    )


def robot_to_laptop(found: Graph) -> List[str]:
    """Every import, of any kind, from a module deployed to the robot to a laptop package."""
    from duckielib.tools.deploy import LAPTOP_PACKAGES

    laptop = [f"duckielib.{package}" for package in LAPTOP_PACKAGES]
    said = []
    for package in laptop:
        said += [
            arrow
            for arrow in found.arrows("duckielib", package)
            if not any(_under(arrow.split(" -> ")[0], other) for other in laptop)
        ]
    return sorted(said)


def _over(sizes: Dict[str, int], limit: int) -> List[str]:
    """The names whose size is over ``limit``, largest first."""
    return sorted(
        (name for name, size in sizes.items() if size > limit), key=lambda name: -sizes[name]
    )


def without_reason(found: Graph) -> Tuple[List[str], List[str]]:
    """The long modules and functions that do not say why they are so long, largest first.

    Returns:
        The modules over :data:`MODULE_LINES` lines and the functions over
        :data:`FUNCTION_LINES` with no reason at their top (module doc).
    """
    return (
        [module for module in _over(found.lines, MODULE_LINES) if module not in found.reasons],
        [name for name in _over(found.functions, FUNCTION_LINES) if name not in found.reasons],
    )


def report(found: Graph) -> str:
    """The structure in a few lines, for people."""
    rooms: Dict[str, int] = defaultdict(int)
    for module, count in found.lines.items():
        rooms[".".join(module.split(".")[:2])] += count
    lines = ["rooms (lines):"]
    lines += [f"  {room:32s} {count:6d}" for room, count in sorted(rooms.items())]
    lines.append("largest modules (lines):")
    largest = sorted(found.lines.items(), key=lambda item: -item[1])[:8]
    lines += [f"  {module:40s} {count:6d}" for module, count in largest]
    for every, what in ((False, "top-level imports"), (True, "any import, lazy or for types")):
        circles = found.circles(every)
        lines.append(f"circles ({what}): {len(circles)}")
        lines += [f"  {' <-> '.join(group)}" for group in circles]
    upward = found.arrows("duckielib", "autograder")
    lines.append(f"arrows from duckielib to autograder: {len(upward)}")
    lines += [f"  {arrow}" for arrow in upward]
    robot = robot_to_laptop(found)
    lines.append(f"arrows from the robot's modules to the laptop's packages: {len(robot)}")
    lines += [f"  {arrow}" for arrow in robot]
    long_modules, long_functions = (
        _over(found.lines, MODULE_LINES),
        _over(found.functions, FUNCTION_LINES),
    )
    lines.append(f"modules over {MODULE_LINES} lines: {len(long_modules)}")
    lines += [f"  {module:40s} {found.lines[module]:6d}" for module in long_modules]
    lines.append(f"functions over {FUNCTION_LINES} lines: {len(long_functions)}")
    lines += [f"  {name:64s} {found.functions[name]:4d}" for name in long_functions]
    modules, functions = without_reason(found)
    lines.append(f"modules over {MODULE_LINES} lines with no reason: {len(modules)}")
    lines += [f"  {module:40s} {found.lines[module]:6d}" for module in modules]
    lines.append(f"functions over {FUNCTION_LINES} lines with no reason: {len(functions)}")
    lines += [f"  {name:64s} {found.functions[name]:4d}" for name in functions]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.stdout.write(report(graph()) + "\n")
