"""Run one notebook's cells inside the sandbox, with nbgrader's own executor.

The grader sends the notebook (instructor's cells restored, hidden tests included) on standard
input and reads the executed notebook on standard output; the notebook never lies in the
sandbox's folder, so the student's code cannot open the file to read the hidden tests.
Usage (inside the sandbox): ``python execute.py CELL_SECONDS``.

A cell that never got to run (the kernel died before it: ``os._exit``, a crash, the memory
limit) gets an error output, so nbgrader scores its tests as failed rather than passed.
"""

from __future__ import annotations

import sys

NOT_RUN = "NotRun"


def mark_not_run(notebook: object, reason: str) -> None:
    """Give every code cell without outputs an error saying why it did not run."""
    import nbformat

    for cell in notebook.cells:  # type: ignore[attr-defined]
        if cell.cell_type == "code" and not cell.get("outputs"):
            cell.outputs = [
                nbformat.v4.new_output("error", ename=NOT_RUN, evalue=reason, traceback=[reason])
            ]


def main() -> None:
    """Read a notebook on stdin, run it, write it on stdout."""
    import os

    import nbformat
    from nbclient.exceptions import DeadKernelError
    from nbgrader.preprocessors import Execute

    cell_seconds = int(sys.argv[1])
    notebook = nbformat.read(sys.stdin, as_version=4)
    # The kernel inherits file descriptors 1 and 2: keep the student's os.write(1, ...) out of
    # the notebook this script answers with.
    answer = os.fdopen(os.dup(1), "w", encoding="utf-8")
    quiet = os.open(os.devnull, os.O_WRONLY)
    os.dup2(quiet, 1)
    os.dup2(quiet, 2)
    executor = Execute(timeout=cell_seconds)
    try:
        executor.preprocess(notebook, {"metadata": {"path": "."}})
    except DeadKernelError:
        mark_not_run(
            notebook,
            "This cell did not run: the notebook's kernel died in an earlier cell "
            "(os._exit, a crash, or more memory than the limit).",
        )
    except Exception as error:  # the grader reports it with the notebook
        mark_not_run(notebook, f"This cell did not run: {type(error).__name__}: {error}")
    answer.write(nbformat.writes(notebook))
    answer.flush()


if __name__ == "__main__":
    main()
