"""Run one notebook's cells inside the sandbox, with nbgrader's own executor.

The grader sends the notebook (instructor's cells restored, hidden tests included) on standard
input and reads the executed notebook on standard output; the notebook never lies in the
sandbox's folder, so the student's code cannot open the file to read the hidden tests.
Usage (inside the sandbox): ``python execute.py CELL_SECONDS``.

A cell that never got to run (the kernel died before it: ``os._exit``, a crash, the memory
limit) gets an error output, so nbgrader scores its tests as failed rather than passed.

Tests run in the same kernel as the student's code, so that code could replace what the tests
rely on (``np.allclose = lambda *a, **k: True``, a fake ``np``, IPython's error display). Before
the first cell, a guard keeps the originals; before each test cell it puts back whatever was
replaced, and the grader reports it. This stops the easy ways of making tests pass; code that
sets out to defeat the guard itself is a matter for the instructor, like any cheating.
"""

from __future__ import annotations

import ast
import sys

NOT_RUN = "NotRun"
#: Where the grader's findings travel back, in the notebook's metadata.
METADATA_KEY = "duckie_grading"

#: Run before the first cell: keeps the originals of what tests rely on.
GUARD_SETUP = r"""
def _setup():
    import builtins, os, sys, types
    # The real modules, not a student's numpy.py next to the notebook.
    path = list(sys.path)
    sys.path[:] = [p for p in path if p not in ("", ".", os.getcwd())]
    import math
    import numpy
    import numpy.testing
    sys.path[:] = path
    from IPython import get_ipython

    shell = get_ipython()
    kernel = getattr(shell, "kernel", None)
    watched = []
    for module, names in (
        (builtins, ("abs", "all", "any", "isinstance", "len", "max", "min", "round", "sum",
                    "type", "float", "int", "tuple", "list", "print", "AssertionError")),
        (math, ("isclose", "isfinite", "isnan", "pi", "tau", "sqrt", "hypot", "atan2")),
        (numpy, ("allclose", "isclose", "array_equal", "array", "asarray", "all", "any",
                 "abs", "shape", "ndarray", "pi")),
        (numpy.testing, tuple(name for name in dir(numpy.testing) if name.startswith("assert"))),
    ):
        watched += [(module, name, getattr(module, name)) for name in names
                    if hasattr(module, name)]
    methods = [(type(shell), name) for name in ("run_cell", "run_ast_nodes", "run_code",
               "showtraceback", "_showtraceback", "showsyntaxerror")]
    if kernel is not None:
        methods += [(type(kernel), name) for name in ("do_execute", "execute_request")]
    own = [(owner, name, vars(owner).get(name)) for owner in (shell, kernel)
           if owner is not None for _, name in methods]
    methods = [(cls, name, cls.__dict__.get(name)) for cls, name in methods]
    names = {"np": numpy, "numpy": numpy, "math": math}
    modules = {"numpy": numpy, "numpy.testing": numpy.testing, "math": math}

    def check():
        changed = []
        for module, name, original in watched:
            if getattr(module, name, None) is not original:
                setattr(module, name, original)
                changed.append(f"{module.__name__}.{name}")
        for cls, name, original in methods:
            if original is not None and cls.__dict__.get(name) is not original:
                setattr(cls, name, original)
                changed.append(f"IPython {name}")
        for owner, name, original in own:
            if vars(owner).get(name) is not original:
                if original is None:
                    vars(owner).pop(name, None)
                else:
                    vars(owner)[name] = original
                changed.append(f"IPython {name}")
        if shell.custom_exceptions:
            shell.set_custom_exc((), None)
            changed.append("IPython custom exception handler")
        for name, module in names.items():
            if name in shell.user_ns and shell.user_ns[name] is not module:
                shell.user_ns[name] = module
                changed.append(f"the name {name}")
        for name, module in modules.items():
            if sys.modules.get(name) is not module:
                sys.modules[name] = module
                changed.append(f"sys.modules[{name!r}]")
        return sorted(set(changed))

    sys.modules["__grader_guard__"] = types.SimpleNamespace(check=check)

_setup()
del _setup
"""

#: Run before each test cell: puts the originals back, returns what had been replaced.
GUARD_CHECK = '__import__("sys").modules["__grader_guard__"].check()'


def mark_not_run(notebook: object, reason: str) -> None:
    """Give every code cell that did not run an error saying why.

    A cell that ran has an execution count (nbgrader clears the student's own before the run).
    """
    import nbformat

    for cell in notebook.cells:  # type: ignore[attr-defined]
        if cell.cell_type == "code" and cell.get("execution_count") is None:
            cell.outputs = [
                nbformat.v4.new_output("error", ename=NOT_RUN, evalue=reason, traceback=[reason])
            ]


def _guarded_execute_class():
    """The Execute of nbgrader, with the guard run before the first cell and before each test."""
    import nbformat
    from nbgrader.preprocessors import Execute

    class GuardedExecute(Execute):
        def preprocess(self, nb, resources=None, km=None):
            self.replaced = {}
            self.guarded = False
            return super().preprocess(nb, resources, km)

        def preprocess_cell(self, cell, resources, index):
            if not self.guarded:
                self.guarded = True
                self._run_hidden(GUARD_SETUP, index)
            meta = cell.get("metadata", {}).get("nbgrader", {})
            if cell.cell_type == "code" and meta.get("grade"):
                changed = self._run_hidden(GUARD_CHECK, index)
                if changed:
                    self.replaced[meta.get("grade_id", f"cell {index + 1}")] = changed
            return super().preprocess_cell(cell, resources, index)

        def _run_hidden(self, source, index):
            """Run ``source`` in the kernel without a cell of its own; its value, if a list."""
            real = self.nb.cells[index]
            probe = nbformat.v4.new_code_cell(source)
            try:
                self.execute_cell(probe, index, store_history=False)
            finally:
                self.nb.cells[index] = real  # nbclient puts the executed cell at the index
            for output in probe.get("outputs", []):
                if output.get("output_type") == "execute_result":
                    try:
                        value = ast.literal_eval(output["data"].get("text/plain", ""))
                    except (ValueError, SyntaxError):
                        return []
                    return [str(item) for item in value] if isinstance(value, list) else []
            return []

    return GuardedExecute


def main() -> None:
    """Read a notebook on stdin, run it, write it on stdout."""
    import os

    cell_seconds = int(sys.argv[1])
    # nbformat validates with jsonschema, whose optional "iri" format checker builds a grammar
    # at import (about 1.2 s, for a format no notebook uses): leave that package out.
    sys.modules.setdefault("rfc3987_syntax", None)  # type: ignore[arg-type]
    import nbformat
    from nbclient.exceptions import DeadKernelError

    notebook = nbformat.read(sys.stdin, as_version=4)
    # The kernel inherits file descriptors 1 and 2: keep the student's os.write(1, ...) out of
    # the notebook this script answers with.
    answer = os.fdopen(os.dup(1), "w", encoding="utf-8")
    quiet = os.open(os.devnull, os.O_WRONLY)
    os.dup2(quiet, 1)
    os.dup2(quiet, 2)
    # The kernel is killed rather than asked to stop: the sandbox ends with this script.
    executor = _guarded_execute_class()(timeout=cell_seconds, shutdown_kernel="immediate")
    problems = []
    try:
        executor.preprocess(notebook, {"metadata": {"path": "."}})
    except DeadKernelError:
        problems.append(
            "the kernel died (os._exit, a crash, or more memory than the limit); the cells "
            "after it did not run"
        )
        mark_not_run(
            notebook,
            "This cell did not run: the notebook's kernel died in an earlier cell "
            "(os._exit, a crash, or more memory than the limit).",
        )
    except Exception as error:  # the grader reports it with the notebook
        problems.append(f"the notebook stopped running: {type(error).__name__}: {error}")
        mark_not_run(notebook, f"This cell did not run: {type(error).__name__}: {error}")
    for grade_id, changed in getattr(executor, "replaced", {}).items():
        problems.append(
            f"before {grade_id}, the student's code had replaced {', '.join(changed)}; "
            "the originals were put back for the test"
        )
    notebook.metadata[METADATA_KEY] = {"problems": problems}
    answer.write(nbformat.writes(notebook))
    answer.flush()
    os._exit(0)  # nothing left to clean up: the sandbox and all in it end with this process


if __name__ == "__main__":
    main()
