"""The guard: what runs in a notebook's kernel before its first cell, and its notes.

The server runs this file's source in the kernel as a module of its own
(:data:`MODULE`, see :func:`autograder.sandbox.inside.notebook.module_code`) and calls
:func:`install`. The guard then:

- notes every path the notebook opens for writing, or removes, renames or changes, outside the
  student's folders, in :data:`WRITES_FILE` (the sandbox refuses the write; an audit hook
  cannot be removed, so the note survives the student's code), which the server reads after
  the notebook (:func:`writes_outside`);
- keeps the originals of what tests once relied on in the kernel (``np.allclose``, ``math``,
  IPython's error display, ...). Before each test cell the server runs :data:`CHECK`, which puts
  back whatever the student's code replaced and names it, for the grader's report.

Runs in the kernel and in the server: the standard library only at load time.
"""

from __future__ import annotations

import builtins
import contextlib
import os
import sys
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, List, Sequence, Set, Tuple

__all__ = ["CHECK", "MODULE", "WRITES_FILE", "install", "writes_outside"]

#: The guard's module, in a kernel.
MODULE = "__grader_guard__"
#: Where the guard notes the paths a notebook tried to write outside the student's folders.
WRITES_FILE = "/tmp/.grader-writes"
#: Run before each test cell: puts the originals back; its value lists what had been replaced.
CHECK = f'__import__("sys").modules[{MODULE!r}].check()'

#: The places a notebook may write: its own folders' parent is added at install.
_ALLOWED = ("/tmp/", "/dev/", "/proc/")
_WRITING = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_TRUNC
_CHANGES = {
    "os.remove",
    "os.rename",
    "os.mkdir",
    "os.rmdir",
    "os.symlink",
    "os.link",
    "os.chmod",
    "os.truncate",
    "shutil.rmtree",
}
_BUILTINS = (
    "abs", "all", "any", "isinstance", "len", "max", "min", "round", "sum", "type", "float",
    "int", "tuple", "list", "print", "AssertionError",
)  # fmt: skip
_MATH = ("isclose", "isfinite", "isnan", "pi", "tau", "sqrt", "hypot", "atan2")
_NUMPY = (
    "allclose", "isclose", "array_equal", "array", "asarray", "all", "any", "abs", "shape",
    "ndarray", "pi",
)  # fmt: skip
_SHELL_METHODS = (
    "run_cell",
    "run_ast_nodes",
    "run_code",
    "showtraceback",
    "_showtraceback",
    "showsyntaxerror",
)
_KERNEL_METHODS = ("do_execute", "execute_request")


def install(writes_file: str = WRITES_FILE) -> Callable[[], List[str]]:
    """Start noting writes and keep the originals; the check to run before each test cell.

    Args:
        writes_file: where the writes outside the student's folders are noted.

    Returns:
        The check: it puts back every original the student's code replaced and returns their
        names, sorted.
    """
    _note_writes(writes_file)
    numpy, testing, math = _real_modules()
    from IPython import get_ipython

    shell = get_ipython()
    kernel = getattr(shell, "kernel", None)
    watched: List[Tuple[Any, str, Any]] = []
    for module, names in (
        (builtins, _BUILTINS),
        (math, _MATH),
        (numpy, _NUMPY),
        (testing, tuple(name for name in dir(testing) if name.startswith("assert"))),
    ):
        watched += [
            (module, name, getattr(module, name)) for name in names if hasattr(module, name)
        ]
    classes = [(type(shell), name) for name in _SHELL_METHODS]
    if kernel is not None:
        classes += [(type(kernel), name) for name in _KERNEL_METHODS]
    own = [
        (owner, name, vars(owner).get(name))
        for owner in (shell, kernel)
        if owner is not None
        for _, name in classes
    ]
    methods = [(cls, name, cls.__dict__.get(name)) for cls, name in classes]
    bound = {"np": numpy, "numpy": numpy, "math": math}
    modules = {"numpy": numpy, "numpy.testing": testing, "math": math}

    def put_back_attributes() -> Set[str]:
        changed: Set[str] = set()
        for module, name, original in watched:
            if getattr(module, name, None) is not original:
                setattr(module, name, original)
                changed.add(f"{module.__name__}.{name}")
        for cls, name, original in methods:
            if original is not None and cls.__dict__.get(name) is not original:
                setattr(cls, name, original)
                changed.add(f"IPython {name}")
        for owner, name, original in own:
            if vars(owner).get(name) is not original:
                if original is None:
                    vars(owner).pop(name, None)
                else:
                    vars(owner)[name] = original
                changed.add(f"IPython {name}")
        return changed

    def put_back_names() -> Set[str]:
        changed: Set[str] = set()
        if shell.custom_exceptions:
            shell.set_custom_exc((), None)
            changed.add("IPython custom exception handler")
        for name, module in bound.items():
            if name in shell.user_ns and shell.user_ns[name] is not module:
                shell.user_ns[name] = module
                changed.add(f"the name {name}")
        for name, module in modules.items():
            if sys.modules.get(name) is not module:
                sys.modules[name] = module
                changed.add(f"sys.modules[{name!r}]")
        return changed

    def check() -> List[str]:
        return sorted(put_back_attributes() | put_back_names())

    return check


def _note_writes(writes_file: str) -> None:
    """Note in ``writes_file`` each write outside the student's folders (an audit hook)."""
    allowed = (str(Path.cwd().parent) + os.sep, *_ALLOWED)
    busy: List[bool] = []

    def audit(event: str, args: Tuple[Any, ...]) -> None:
        if busy or (event != "open" and event not in _CHANGES):
            return
        if event == "open":
            path, mode, flags = args
            if not ((flags or 0) & _WRITING or (isinstance(mode, str) and set(mode) & set("wax+"))):
                return
        else:
            path = args[0]
        if not isinstance(path, (str, bytes, os.PathLike)):
            return
        busy.append(True)
        try:
            full = os.path.abspath(os.fsdecode(path))  # noqa: PTH100 - as written, links kept
            if not (full + os.sep).startswith(allowed):
                with Path(writes_file).open("a", encoding="utf-8") as noted:
                    noted.write(full + "\n")
        except Exception:  # a note that fails must not stop the student's code
            pass
        finally:
            busy.pop()

    sys.addaudithook(audit)


def _real_modules() -> Tuple[ModuleType, ModuleType, ModuleType]:
    """numpy, numpy.testing and math: the real ones, not a student's ``numpy.py`` in the folder."""
    path = list(sys.path)
    sys.path[:] = [entry for entry in path if entry not in ("", ".", str(Path.cwd()))]
    try:
        import math

        import numpy
        import numpy.testing
    finally:
        sys.path[:] = path
    return numpy, numpy.testing, math


def writes_outside(writes_file: str = WRITES_FILE) -> List[str]:
    """What the guard noted the notebook tried to write outside the student's folders.

    Read by the server after each notebook; the note is then removed, for the next one. It lies
    in the sandbox's ``/tmp``, where the student's code may put anything: it is read only if it
    is a regular file.

    Returns:
        A sentence for the grader's report, or nothing.
    """
    import stat

    path = Path(writes_file)
    try:
        handle = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return []
    try:
        text = os.read(handle, 100_000) if stat.S_ISREG(os.fstat(handle).st_mode) else b""
    finally:
        os.close(handle)
    with contextlib.suppress(OSError):
        path.unlink()
    lines = text.decode("utf-8", errors="replace").splitlines()
    paths = [line for line in dict.fromkeys(line.strip() for line in lines) if line]
    if not paths:
        return []
    shown = _first(paths, 5)
    return [f"the notebook tried to write outside the student's folders: {shown}"]


def _first(items: Sequence[str], count: int) -> str:
    """The first ``count`` items, and how many more."""
    more = f" and {len(items) - count} more" if len(items) > count else ""
    return ", ".join(items[:count]) + more
