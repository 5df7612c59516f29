"""Exporting a solution: the cells tagged ``export`` of a folder of notebooks, as one module.

A student writes the graded functions and classes in the notebooks; the cells that define them
carry the tag ``export``. :func:`export_solution` collects those cells into the text of one
Python module, a *solution*, and checks each part against the contract
(:data:`~duckielib.solution.contract.CONTRACT`).
The reference solution is the export of the instructors' ``solutions/``; a student's is the
export of their copy of ``course/``.

This module imports only the standard library: it runs on the robot (Python 3.8).
"""

from __future__ import annotations

import ast
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Tuple, Union

from duckielib.solution.contract import (
    CONTRACT,
    EXPORT_TAG,
    PRELUDE,
    Part,
    SolutionError,
)

__all__ = ["Export", "check_definition", "export_solution"]


@dataclass
class Export:
    """The result of :func:`export_solution`.

    Attributes:
        source: the text of the solution module.
        found: the notebook each contract part was exported from, by part name.
        missing: the contract parts no exported cell defines, by name.
        unfinished: the parts defined but not written yet (their body still raises
            ``NotImplementedError``).
        problems: sentences about parts whose parameters differ from the contract.
        notebooks: the notebooks read, relative to the exported folder.
        broken: sentences about exported cells that are not valid Python (left out), by
            notebook.
    """

    source: str
    found: Dict[str, str] = field(default_factory=dict)
    missing: List[str] = field(default_factory=list)
    unfinished: List[str] = field(default_factory=list)
    problems: List[str] = field(default_factory=list)
    notebooks: List[str] = field(default_factory=list)
    broken: Dict[str, str] = field(default_factory=dict)

    @property
    def complete(self) -> bool:
        """Whether every part of the contract is present, written and well-formed."""
        return not (self.missing or self.unfinished or self.problems)

    def report(self) -> str:
        """What is done and what is left, by notebook, in a few lines."""
        done = len(CONTRACT) - len(self.missing) - len(self.unfinished)
        lines = [f"{done} of {len(CONTRACT)} graded parts exported."]
        todo: Dict[str, Dict[str, List[str]]] = {}
        for name in self.unfinished:
            todo.setdefault(CONTRACT[name].notebook, {}).setdefault("write", []).append(name)
        for name in self.missing:
            todo.setdefault(CONTRACT[name].notebook, {}).setdefault("define", []).append(name)
        for notebook in sorted(todo):
            steps = []
            if "write" in todo[notebook]:
                steps.append(f"write {', '.join(todo[notebook]['write'])}")
            if "define" in todo[notebook]:
                steps.append(
                    f"define {', '.join(todo[notebook]['define'])} in a cell tagged {EXPORT_TAG!r}"
                )
            lines.append(f"Finish notebook {notebook}: {'; '.join(steps)}.")
        lines.extend(self.problems)
        return "\n".join(lines)


def _notebooks(folder: Path) -> List[Path]:
    found = sorted(
        path
        for path in folder.rglob("*.ipynb")
        if ".ipynb_checkpoints" not in path.parts
        and not path.name.startswith(".")
        and path.is_file()  # not a FIFO or a device, which would block or never end
    )
    if not found:
        raise SolutionError(
            f"{folder} holds no notebook (.ipynb): export the folder with your course notebooks."
        )
    return found


def _exported_cells(path: Path) -> List[str]:
    try:
        notebook = json.loads(path.read_text(encoding="utf-8"))
        cells = notebook["cells"]
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise SolutionError(f"{path} is not a readable notebook ({error}).") from None
    sources = []
    for cell in cells:
        if cell.get("cell_type") != "code":
            continue
        if EXPORT_TAG not in cell.get("metadata", {}).get("tags", []):
            continue
        source = cell.get("source", "")
        sources.append("".join(source) if isinstance(source, list) else source)
    return sources


def _kept(node: ast.stmt) -> bool:
    """Whether a top-level statement of an exported cell belongs in the solution."""
    if isinstance(node, (ast.Import, ast.ImportFrom, ast.FunctionDef, ast.ClassDef)):
        return True
    targets: List[ast.expr] = []
    if isinstance(node, ast.Assign):
        targets = node.targets
    elif isinstance(node, ast.AnnAssign):
        targets = [node.target]
    return bool(targets) and all(
        isinstance(target, ast.Name) and target.id.isupper() for target in targets
    )


def _unwritten(body: List[ast.stmt]) -> bool:
    """Whether a body is only a docstring, comments and ``raise NotImplementedError``."""
    statements = [
        node
        for node in body
        if not (isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant))
        and not isinstance(node, ast.Pass)
    ]
    if len(statements) != 1 or not isinstance(statements[0], ast.Raise):
        return False
    raised = statements[0].exc
    if isinstance(raised, ast.Call):
        raised = raised.func
    return isinstance(raised, ast.Name) and raised.id == "NotImplementedError"


def _parameters(function: ast.FunctionDef, drop_self: bool) -> Tuple[str, ...]:
    names = [argument.arg for argument in function.args.posonlyargs + function.args.args]
    return tuple(names[1:] if drop_self and names else names)


def check_definition(part: Part, node: ast.stmt, notebook: str) -> Tuple[bool, List[str]]:
    """Whether a definition is unwritten, and what differs from the contract."""
    problems = []
    if part.is_class:
        if not isinstance(node, ast.ClassDef):
            return False, [f"In notebook {notebook}, {part.name} must be a class."]
        if _unwritten(node.body):
            return True, []
        methods = {item.name: item for item in node.body if isinstance(item, ast.FunctionDef)}
        init = methods.get("__init__")
        found = _parameters(init, True) if init is not None else ()
        if init is not None and found != part.parameters:
            problems.append(
                f"In notebook {notebook}, {part.name}.__init__ takes ({', '.join(found)}); "
                f"the course's version takes ({', '.join(part.parameters)})."
            )
        unwritten = False
        for name, parameters in part.methods:
            method = methods.get(name)
            if method is None:
                problems.append(f"In notebook {notebook}, {part.name} has no method {name}.")
                continue
            unwritten = unwritten or _unwritten(method.body)
            found = _parameters(method, True)
            if found != parameters:
                problems.append(
                    f"In notebook {notebook}, {part.name}.{name} takes ({', '.join(found)}); "
                    f"the course's version takes ({', '.join(parameters)})."
                )
        return unwritten or (init is not None and _unwritten(init.body)), problems
    if not isinstance(node, ast.FunctionDef):
        return False, [f"In notebook {notebook}, {part.name} must be a function (def)."]
    found = _parameters(node, False)
    if found != part.parameters:
        problems.append(
            f"In notebook {notebook}, {part.name} takes ({', '.join(found)}); "
            f"the course's version takes ({', '.join(part.parameters)})."
        )
    return _unwritten(node.body), problems


def _label(path: Path, folder: Path) -> str:
    return path.relative_to(folder).as_posix()


def export_solution(folder: Union[str, Path], strict: bool = True) -> Export:
    """Collect the cells tagged ``export`` of a folder's notebooks into one solution module.

    Notebooks are read in path order (``01_...`` first), so a later notebook can use what an
    earlier one defined. Of each exported cell only imports, ``def``, ``class`` and UPPER_CASE
    constants are kept: calls and prints made while exploring stay in the notebook.

    Args:
        folder: a folder of notebooks, at any depth: a student's ``course/``, one assignment
            folder, or the instructors' ``solutions/``.
        strict: whether an exported cell that is not valid Python stops the export; if not,
            the cell is left out and named in ``broken`` (a half-typed cell in a later
            notebook then does not keep an earlier notebook from loading its parts).

    Returns:
        The module's text and what is missing, unfinished or malformed, by notebook.

    Raises:
        SolutionError: if the folder has no notebook, a notebook cannot be read, or an
            exported cell is not valid Python (the message names the notebook and line).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise SolutionError(f"There is no folder {folder}; give the folder of your notebooks.")
    export = Export(
        source=(
            f'"""A Duckiebot course solution, exported from {folder.name}/ by duckie export.\n\n'
            'Do not edit this file: change the notebooks and export again.\n"""\n\n' + PRELUDE
        )
    )
    definitions: Dict[str, Tuple[str, ast.stmt]] = {}
    for path in _notebooks(folder):
        label = _label(path, folder)
        export.notebooks.append(label)
        for index, cell in enumerate(_exported_cells(path), start=1):
            try:
                tree = ast.parse(cell)
            except SyntaxError as error:
                sentence = (
                    f"In notebook {label}, exported cell {index} is not valid Python "
                    f"(line {error.lineno}: {error.msg}); fix it and export again."
                )
                if strict:
                    raise SolutionError(sentence) from None
                export.broken.setdefault(path.stem, sentence)
                continue
            lines = cell.splitlines()
            kept = []
            for node in tree.body:
                if not _kept(node):
                    continue
                first = min([node.lineno] + [d.lineno for d in _decorators(node)])
                kept.append("\n".join(lines[first - 1 : node.end_lineno]))
                if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and node.name in CONTRACT:
                    definitions[node.name] = (label, node)
            if kept:
                export.source += f"\n\n# From {label}, exported cell {index}.\n"
                export.source += "\n\n".join(kept) + "\n"
    for name, part in CONTRACT.items():
        if name not in definitions:
            export.missing.append(name)
            continue
        label, node = definitions[name]
        export.found[name] = label
        unwritten, problems = check_definition(part, node, label)
        if unwritten:
            export.unfinished.append(name)
        export.problems.extend(problems)
    return export


def _decorators(node: ast.stmt) -> List[ast.expr]:
    return list(getattr(node, "decorator_list", []))
