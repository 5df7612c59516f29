"""The static reading of a notebook's code that the rules are judged on, with :mod:`ast`.

A notebook's cells, their IPython syntax made Python (:class:`_Magics`); what each statement
binds, in Python's scopes (:func:`_bound`, :class:`_Scope`); what some code references and the
dynamic constructs it uses (:class:`_Reader`); the notebook's module-level bindings across its
cells (:class:`_Notebook`); and what a graded answer reaches through them (:func:`_reach`), or
what the student's top-level code could rebind unseen (:func:`_rebinding`). It reads, never runs.
"""

from __future__ import annotations

import ast
import builtins
import re
from dataclasses import dataclass, field
from typing import Any, Dict, Iterator, List, Mapping, Optional, Sequence, Set, Tuple

# What static analysis cannot follow, and what to write instead.
_NAMES = "use the names themselves"
_IMPORT = "import the module with an import statement"
_WRITE = "write the code itself in the notebook"
_CODE = "write the code itself, not a string that holds it"
_ATTRIBUTE = "write the attribute itself (module.name, not getattr(module, name))"
_BUILTINS = {
    "eval": _CODE,
    "exec": _CODE,
    "compile": _CODE,
    "__import__": _IMPORT,
    "globals": _NAMES,
    "vars": _NAMES,
    "get_ipython": _WRITE,
    "__builtins__": _NAMES,
}
_MODULES = {
    "importlib": _IMPORT,
    "builtins": _NAMES,
    "__main__": _NAMES,
    "sys.modules": _IMPORT,
    "sys._getframe": _NAMES,
    "sys.meta_path": _IMPORT,
    "runpy": _WRITE,
    "pkgutil": _IMPORT,
    "inspect": _NAMES,
    "gc": _NAMES,
    "pickle": _WRITE,
    "marshal": _WRITE,
    "ctypes": _NAMES,
    "operator.attrgetter": _ATTRIBUTE,
    "operator.methodcaller": "call the method itself",
}
_ATTRIBUTES = {
    "__dict__", "__globals__", "__builtins__", "__getattribute__", "__subclasses__", "__code__",
    "__closure__", "__mro__", "__bases__", "__base__", "__loader__", "__spec__", "__import__",
    "__reduce__", "__reduce_ex__", "f_globals", "f_locals", "f_back", "tb_frame", "gi_frame",
    "cr_frame",
}  # fmt: skip
#: What can bind a name of the notebook where a reader does not see it.
_REBINDING = {
    "eval", "exec", "globals", "vars", "locals", "get_ipython", "__builtins__", "builtins",
    "__main__", "sys.modules",
}  # fmt: skip

_PYTHON_MAGICS = {"time", "timeit", "prun", "capture"}
_NESTED = "code nested too deeply to read"
_READS = {"keys", "values", "items", "get", "copy", "__contains__"}
_QUIET_MAGICS = {
    "matplotlib", "pinfo", "pinfo2", "psearch", "pdoc", "pdef", "psource", "pfile", "env", "pip",
    "conda", "config", "precision", "who", "whos", "who_ls", "ls", "pwd", "history", "lsmagic",
    "magic", "xmode", "colors", "page", "autoreload", "system", "sx", "bash", "sh", "script",
    "html", "HTML", "javascript", "js", "latex", "markdown", "svg", "SVG", "writefile", "file",
    "perl", "ruby", "python", "python2", "python3", "pypy",
}  # fmt: skip
_HIDDEN = re.compile(
    r"^[ \t]*### BEGIN HIDDEN TESTS.*?^[ \t]*### END HIDDEN TESTS[^\n]*$", re.M | re.S
)


# Reading cells.


def _source(cell: Mapping[str, Any]) -> str:
    text = cell.get("source", "")
    return "".join(text) if isinstance(text, list) else str(text)


def _is_answer(cell: Mapping[str, Any]) -> bool:
    marks = (cell.get("metadata") or {}).get("nbgrader") or {}
    return cell.get("cell_type") == "code" and bool(marks.get("solution"))


def _normal(source: str) -> str:
    """The code without trailing spaces and blank lines, which change nothing it does."""
    return "\n".join(line.rstrip() for line in source.splitlines() if line.strip())


def _course_sources(cells: Sequence[Mapping[str, Any]]) -> Set[str]:
    """The course's own code cells, as the source and the release hold them."""
    sources = set()
    for cell in cells:
        if cell.get("cell_type") == "code" and not _is_answer(cell):
            sources.add(_normal(_source(cell)))
            sources.add(_normal(_HIDDEN.sub("", _source(cell))))  # a test cell as released
    return sources


def _parse(source: str) -> Optional[ast.Module]:
    """A cell's code, its IPython syntax made Python (None where IPython cannot run it)."""
    try:
        return ast.parse(source)
    except (SyntaxError, ValueError, RecursionError, MemoryError):
        pass
    try:
        from IPython.core.inputtransformer2 import TransformerManager

        tree = ast.parse(TransformerManager().transform_cell(source))
    except Exception:  # not even IPython's: the cell raises when run, and defines nothing
        return None
    return ast.fix_missing_locations(_Magics().visit(tree))


class _Magics(ast.NodeTransformer):
    """IPython's magics as what they run, as far as the rules go.

    ``%time`` and ``%%capture`` become their Python, ``%matplotlib`` and shell commands nothing,
    and a magic that runs code unseen (``%run``) a name starting with ``%``.
    """

    def visit_Expr(self, node: ast.Expr) -> Any:
        body = self._python(node.value, "exec")
        return body.body if isinstance(body, ast.Module) else self.generic_visit(node)

    def visit_Call(self, node: ast.Call) -> Any:
        func = node.func
        if not (
            isinstance(func, ast.Attribute)
            and isinstance(func.value, ast.Call)
            and isinstance(func.value.func, ast.Name)
            and func.value.func.id == "get_ipython"
        ):
            return self.generic_visit(node)
        expression = self._python(node, "eval")
        if isinstance(expression, ast.Expression):
            return expression.body
        magic, line = ([_literal(arg) for arg in node.args] + [None, None])[:2]
        autoreload = magic == "load_ext" and (line or "").strip() == "autoreload"
        if func.attr in ("system", "getoutput") or magic in _QUIET_MAGICS or autoreload:
            return ast.Constant(None)
        return ast.Call(ast.Name(f"%{magic or func.attr}", ast.Load()), [], [])

    @staticmethod
    def _python(node: ast.expr, mode: str) -> Optional[ast.AST]:
        """The Python a magic such as ``%time`` runs, or None."""
        if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)):
            return None
        args = [_literal(arg) for arg in node.args]
        if len(args) < 2 or args[0] not in _PYTHON_MAGICS:
            return None
        code = args[2] if node.func.attr == "run_cell_magic" and len(args) > 2 else args[1]
        try:
            return ast.parse(code or "", mode=mode)
        except SyntaxError:
            return None


def _literal(node: ast.AST) -> Optional[str]:
    return node.value if isinstance(node, ast.Constant) and isinstance(node.value, str) else None


# What a statement binds, and in which scope.

_COMPREHENSIONS = (ast.ListComp, ast.SetComp, ast.DictComp, ast.GeneratorExp)


def _outside(node: ast.AST, bodies: bool = False) -> List[ast.AST]:
    """The children of ``node`` that run in the scope around it (a def's defaults, not body).

    With ``bodies``, a class's body too: it runs when the class is defined.
    """
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
        defaults = [*node.args.defaults, *[d for d in node.args.kw_defaults if d is not None]]
        return [*getattr(node, "decorator_list", ()), *defaults]
    if isinstance(node, ast.ClassDef):
        body = [part for item in node.body for part in _outside(item, True)] if bodies else []
        return [*node.decorator_list, *node.bases, *node.keywords, *body]
    return list(ast.iter_child_nodes(node)) if not bodies else [node]


def _same_scope(node: ast.AST) -> Iterator[ast.AST]:
    """The nodes inside a statement that belong to its scope (not to a def, class or lambda)."""
    for child in _outside(node):
        yield child
        if isinstance(child, _COMPREHENSIONS):
            for part in ast.walk(child):  # only a := inside binds outside a comprehension
                if isinstance(part, ast.NamedExpr):
                    yield part.target
        else:
            yield from _same_scope(child)


def _bound(statement: ast.AST, declared: bool = True) -> Dict[str, Optional[str]]:
    """The names ``statement`` binds in its scope: name -> the module an import binds, or None.

    With ``declared``, also the names a function inside declares ``global`` (module names).
    """
    names: Dict[str, Optional[str]] = {}
    for node in [statement, *_same_scope(statement)]:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names[node.name] = None
        elif isinstance(node, ast.Name) and not isinstance(node.ctx, ast.Load):
            names[node.id] = None
        elif isinstance(node, (ast.ExceptHandler, ast.MatchAs, ast.MatchStar)) and node.name:
            names[node.name] = None
        elif isinstance(node, ast.Import):
            for alias in node.names:
                top = alias.name if alias.asname else alias.name.split(".")[0]
                names[alias.asname or top] = top
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            for alias in node.names:
                names[alias.asname or alias.name] = f"{node.module}.{alias.name}"
    names.pop("*", None)
    for node in ast.walk(statement) if declared else ():
        if isinstance(node, ast.Global):
            names.update(dict.fromkeys(node.names))
    return names


def _chain(node: ast.AST) -> Optional[Tuple[ast.Name, Tuple[str, ...]]]:
    """``a.b.c`` (or ``getattr(a.b, "c")``) as the name ``a`` and ``("b", "c")``."""
    attrs: List[str] = []
    while not isinstance(node, ast.Name):
        if isinstance(node, ast.Attribute):
            attrs.append(node.attr)
            node = node.value
        elif _getattr_literal(node):
            attrs.append(str(_literal(node.args[1])))  # type: ignore[attr-defined]
            node = node.args[0]  # type: ignore[attr-defined]
        else:
            return None
    return node, tuple(reversed(attrs))


def _getattr_literal(node: ast.AST) -> bool:
    return (
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Name)
        and node.func.id == "getattr"
        and len(node.args) >= 2
        and _literal(node.args[1]) is not None
    )


@dataclass
class _Scope:
    kind: str  # "module", "function" or "class"
    parent: Optional[_Scope] = None
    names: Set[str] = field(default_factory=set)
    #: local name -> what it stands for: ("module", dotted path, attrs) or ("global", name, attrs)
    aliases: Dict[str, List[Tuple[str, str, Tuple[str, ...]]]] = field(default_factory=dict)

    def owner(self, name: str) -> Optional[_Scope]:
        """The function or class scope where ``name`` is local; None for a module name."""
        scope: Optional[_Scope] = self
        while scope is not None and scope.kind != "module":
            if name in scope.names and (scope is self or scope.kind != "class"):
                return scope
            scope = scope.parent
        return None


@dataclass(frozen=True)
class _Ref:
    """A reference to a module-level name (``"global"``) or a module (``"module"``).

    And three uses of the notebook's names: ``"namespace"`` (``globals()``), ``"reads"``
    (``globals()["x"]``), ``"passes"`` (a module-level name called with them: ``f(globals())``).
    """

    kind: str
    root: str
    attrs: Tuple[str, ...]


class _Reader(ast.NodeVisitor):
    """The references and the dynamic constructs of some code, read with Python's scopes."""

    def __init__(self) -> None:
        self.scope = _Scope("module")
        self.refs: List[_Ref] = []
        self.dynamic: List[Tuple[str, str]] = []  # (construct, what to write instead)

    def visit_Name(self, node: ast.Name) -> None:
        if isinstance(node.ctx, ast.Load):
            self._reference(node, ())

    def visit_Attribute(self, node: ast.Attribute) -> None:
        if self._namespace(node.value) and node.attr in _READS:  # globals().keys()
            self.refs.append(_Ref("reads", node.value.func.id, ()))  # type: ignore[attr-defined]
            return
        found = _chain(node)
        if found is not None and isinstance(found[0].ctx, ast.Load):
            self._reference(*found)
            return
        if node.attr in _ATTRIBUTES:
            self.dynamic.append((f".{node.attr}", _NAMES))
        self.generic_visit(node)

    def visit_Call(self, node: ast.Call) -> None:
        func = node.func
        if self._namespace(node):  # the notebook's names, to read or to change
            self.refs.append(_Ref("namespace", func.id, ()))  # type: ignore[attr-defined]
            return
        if isinstance(func, ast.Name) and func.id == "getattr" and not self.scope.owner("getattr"):
            found = _chain(node) if _getattr_literal(node) else None
            if found is not None:
                self._reference(*found)
                for part in [*node.args[2:], *node.keywords]:
                    self.visit(part)
                return
            if not _getattr_literal(node):
                self.dynamic.append(("getattr with a computed name", _ATTRIBUTE))
        values = [*node.args, *[keyword.value for keyword in node.keywords]]
        namespaces = [value for value in values if self._namespace(value)]
        found = _chain(func) if namespaces else None
        if found is None or self.scope.owner(found[0].id):
            self.generic_visit(node)
            return
        # ``f(globals())``: harmless if f is a library's; judged where the name is resolved.
        self.refs.append(_Ref("passes", found[0].id, found[1]))
        for value in values:
            if value not in namespaces:
                self.visit(value)

    def visit_Subscript(self, node: ast.Subscript) -> None:
        if self._namespace(node.value) and isinstance(node.ctx, ast.Load):  # globals()["x"]
            self.refs.append(_Ref("reads", node.value.func.id, ()))  # type: ignore[attr-defined]
            self.visit(node.slice)
        else:
            self.generic_visit(node)

    def visit_Compare(self, node: ast.Compare) -> None:
        for part in [node.left, *node.comparators]:
            if self._namespace(part):  # "x" in globals()
                self.refs.append(_Ref("reads", part.func.id, ()))  # type: ignore[attr-defined]
            else:
                self.visit(part)

    def _namespace(self, node: ast.AST) -> bool:
        """Whether ``node`` is ``globals()``, ``vars()`` or ``locals()``: the notebook's names."""
        return (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in ("globals", "vars", "locals")
            and (node.func.id != "locals" or self.scope.kind == "module")
            and not node.args
            and not self.scope.owner(node.func.id)
        )

    def _reference(self, node: ast.Name, attrs: Tuple[str, ...]) -> None:
        if node.id.startswith("%"):  # a magic that runs code unseen
            self.dynamic.append((node.id, _WRITE))
            return
        dunder = next((attr for attr in attrs if attr in _ATTRIBUTES), None)
        if dunder is not None:
            self.dynamic.append((f".{dunder}", _NAMES))
        owner = self.scope.owner(node.id)
        if owner is None:
            self.refs.append(_Ref("global", node.id, attrs))
            return
        for kind, root, more in owner.aliases.get(node.id, ()):
            self.refs.append(_Ref(kind, root, more + attrs))

    def _enter(self, kind: str, names: Set[str], body: Sequence[ast.AST]) -> None:
        outer = self.scope
        self.scope = _Scope(kind, outer, set(names))
        for statement in body:
            for node in [statement, *_same_scope(statement)]:
                self._note_alias(node)
        for node in body:
            self.visit(node)
        self.scope = outer

    def _note_alias(self, node: ast.AST) -> None:
        """``import numpy as m`` or ``m = np`` inside a function: m stands for numpy."""
        scope = self.scope
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            for name, module in _bound(node).items():
                if module is not None:
                    scope.aliases.setdefault(name, []).append(("module", module, ()))
            return
        found = _chain(node.value) if isinstance(node, ast.Assign) else None
        if found is None:
            return
        base, attrs = found
        owner = scope.owner(base.id)
        for target in node.targets:  # type: ignore[attr-defined]
            if not isinstance(target, ast.Name) or target.id == base.id:
                continue
            aliases = scope.aliases.setdefault(target.id, [])
            if owner is None:
                aliases.append(("global", base.id, attrs))
            else:
                known = owner.aliases.get(base.id, ())
                aliases += [(kind, root, more + attrs) for kind, root, more in known]

    def _function(self, node: Any, body: Sequence[ast.AST]) -> None:
        for part in _outside(node):
            self.visit(part)
        args = node.args
        params = [*args.posonlyargs, *args.args, *args.kwonlyargs, args.vararg, args.kwarg]
        names = {param.arg for param in params if param is not None}
        declared: Set[str] = set()
        for statement in body:
            for part in [statement, *_same_scope(statement)]:
                if isinstance(part, (ast.Global, ast.Nonlocal)):
                    declared.update(part.names)
            names.update(_bound(statement, declared=False))
        self._enter("function", names - declared, body)

    def visit_FunctionDef(self, node: ast.FunctionDef) -> None:
        self._function(node, node.body)

    def visit_AsyncFunctionDef(self, node: ast.AsyncFunctionDef) -> None:
        self._function(node, node.body)

    def visit_Lambda(self, node: ast.Lambda) -> None:
        self._function(node, [ast.Expr(node.body)])

    def visit_ClassDef(self, node: ast.ClassDef) -> None:
        for part in _outside(node):
            self.visit(part)
        names = {name for item in node.body for name in _bound(item, declared=False)}
        self._enter("class", names, node.body)

    def generic_visit(self, node: ast.AST) -> None:
        if isinstance(node, _COMPREHENSIONS):  # its loop variables are its own
            targets = [part for generator in node.generators for part in ast.walk(generator.target)]
            names = {target.id for target in targets if isinstance(target, ast.Name)}
            parts = [node.key, node.value] if isinstance(node, ast.DictComp) else [node.elt]
            self._enter("function", names, [*node.generators, *parts])
        else:
            super().generic_visit(node)


# The notebook, and what an answer reaches in it.


@dataclass(frozen=True)
class _Statement:
    cell: int  # 1-based, as a student counts the cells
    node: ast.stmt
    trusted: bool  # in one of the course's own cells, unchanged
    first_line: str


@dataclass(frozen=True)
class _Found:
    """What an answer reaches: a dotted path (``"path"``) or a construct (``"dynamic"``)."""

    kind: str
    what: str
    instead: str  # for a construct: what to write instead
    via: Tuple[str, ...]  # the names followed on the way, first to last
    trusted: bool  # found in the course's own cells
    binds: bool = True  # a construct that could bind a name (globals() read is not)


class _Notebook:
    """A notebook's top-level statements, and the module-level names each one binds."""

    def __init__(self, cells: Sequence[Mapping[str, Any]], trusted: Set[str]) -> None:
        self.statements: List[_Statement] = []
        self.bindings: Dict[str, List[Tuple[_Statement, Optional[str]]]] = {}
        self.stars: List[str] = []  # the modules of ``from module import *``
        self.readers: Dict[Tuple[int, bool], _Reader] = {}
        self.unreadable: List[_Statement] = []  # nested too deeply to read: could bind anything
        for index, cell in enumerate(cells, start=1):
            source = _source(cell)
            tree = _parse(source) if cell.get("cell_type") == "code" else None
            own = _normal(source) in trusted and not _is_answer(cell)
            first = next((line.strip() for line in source.splitlines() if line.strip()), "")
            for node in tree.body if tree is not None else ():
                statement = _Statement(index, node, own, first[:60])
                self.statements.append(statement)
                try:
                    bound, parts = _bound(node), [node, *_same_scope(node)]
                except RecursionError:
                    bound, parts = {}, []
                    self.unreadable.append(statement)
                for name, module in bound.items():
                    self.bindings.setdefault(name, []).append((statement, module))
                for part in parts:
                    if isinstance(part, ast.ImportFrom) and part.level == 0 and part.module:
                        self.stars += [part.module] * any(a.name == "*" for a in part.names)

    def reader(self, statement: _Statement, running: bool) -> _Reader:
        """What the statement reads (with ``running``, only what runs when its cell runs)."""
        key = (id(statement.node), running)
        if key not in self.readers:
            reader = _Reader()
            try:
                for node in _outside(statement.node, True) if running else [statement.node]:
                    reader.visit(node)
            except RecursionError:
                reader.dynamic.append((_NESTED, "write it more plainly"))
            self.readers[key] = reader
        return self.readers[key]

    def paths(self, name: str, attrs: Tuple[str, ...], seen: Set[str]) -> List[str]:
        """The dotted paths the module-level ``name.attrs`` stands for (imports and aliases)."""
        found = []
        for statement, module in self.bindings.get(name, ()):
            chain = _chain(statement.node.value) if isinstance(statement.node, ast.Assign) else None
            if module is not None:
                found.append(".".join((module, *attrs)))
            elif chain is not None and name not in seen:
                found += self.paths(chain[0].id, chain[1] + attrs, seen | {name})
        if name not in self.bindings and not hasattr(builtins, name):
            found += [".".join((module, name, *attrs)) for module in self.stars]
        return found


def _reach(notebook: _Notebook, name: str, start: Optional[_Statement] = None) -> Iterator[_Found]:
    """What the code of ``name`` reaches in ``notebook``; or, from ``start``, what runs there.

    The student's code is followed through every name it uses; the course's cells one step.
    """
    todo: List[Tuple[_Statement, Tuple[str, ...], bool]] = []
    if start is not None:
        todo.append((start, (), True))
    for statement, module in notebook.bindings.get(name, ()) if start is None else ():
        todo.append((statement, (), False))
        if module is not None:
            yield _Found("path", module, "", (), statement.trusted)
    done: Set[Tuple[int, bool]] = set()
    while todo:
        statement, via, running = todo.pop(0)
        if (id(statement.node), running) in done:
            continue
        done.add((id(statement.node), running))
        reader = notebook.reader(statement, running)
        for construct, instead in reader.dynamic:
            yield _Found("dynamic", construct, instead, via, statement.trusted)
        for ref in reader.refs:
            yield from _resolve(notebook, ref, via, statement.trusted)
            for bound, module in notebook.bindings.get(ref.root, ()):
                follow = ref.kind != "module" and ref.root != name and module is None
                if follow and not statement.trusted:  # the course's cells: one step only
                    todo.append((bound, (*via, ref.root), False))


def _resolve(
    notebook: _Notebook, ref: _Ref, via: Tuple[str, ...], trusted: bool
) -> Iterator[_Found]:
    """The paths and builtins one reference stands for."""
    if ref.kind == "module":
        yield _Found("path", ".".join((ref.root, *ref.attrs)), "", via, trusted)
        return
    if ref.kind in ("namespace", "reads"):  # globals(), vars() or locals() itself
        if ref.root not in notebook.bindings:
            binds = ref.kind == "namespace"
            yield _Found("dynamic", f"{ref.root}()", _NAMES, via, trusted, binds)
        return
    if ref.root in _BUILTINS and ref.root not in notebook.bindings:
        shown = ref.root if ref.root == "__builtins__" else f"{ref.root}()"
        binds = ref.root != "vars"  # vars(something) reads that thing's names
        yield _Found("dynamic", shown, _BUILTINS[ref.root], via, trusted, binds)
    bindings = notebook.bindings.get(ref.root, ())
    if ref.kind == "passes" and any(module is None and not b.trusted for b, module in bindings):
        yield _Found("dynamic", "globals()", _NAMES, via, trusted)  # to the student's own code
    for path in notebook.paths(ref.root, ref.attrs, set()):
        yield _Found("path", path, "", via, trusted)


def _rebinding(notebook: _Notebook, graded: Set[str]) -> Optional[Tuple[str, str]]:
    """Where the student's top-level code could rebind a graded name unseen: (cell, construct)."""
    for statement in notebook.statements:
        if statement.trusted:
            continue
        if statement in notebook.unreadable:
            return f"cell {statement.cell} ({statement.first_line})", _NESTED
        for found in _reach(notebook, "", statement):
            if set(found.via) & graded or not found.binds:
                continue  # a graded function's own code is judged on its own
            what = found.what.replace("()", "")
            key = next((key for key in _REBINDING if _matches(what, key)), None)
            if key is not None or what[:1] == "%":
                construct = found.what if key is None or found.kind == "dynamic" else key
                return f"cell {statement.cell} ({statement.first_line})", construct
    return None


def _matches(path: str, pattern: str) -> bool:
    """Whether ``path`` is ``pattern`` or inside it (``"numpy:unwrap"``: numpy's unwrap)."""
    prefix, _, name = pattern.partition(":")
    inside = path == prefix or path.startswith(prefix + ".")
    return inside and (not name or name in path.split(".")[1:])
