"""Benchmark: how long a student waits between opening a notebook and its first cell's result.

For each notebook of ``course/``, as JupyterLab opens it: a new ``python3`` kernel started in
the notebook's folder (a copy of it, so that nothing is written into ``course/``), waited for
until it answers, then the notebook's first code cell (its imports) run in it. Figures:

- ``kernel_ready_s``: from starting the kernel to its first answer, median over the notebooks.
- ``first_cell_s``: the first cell's run, median.
- ``kernel_to_first_cell_s_NAME``: the two together, for each notebook.
- ``kernel_to_first_cell_max_s`` and, the headline, ``kernel_to_first_cell_s``: the slowest
  notebook and the median.

JupyterLab adds its own front end and messages on top (about 0.5 s more on an idle machine),
and a busy machine stretches everything.
"""

from __future__ import annotations

import shutil
import statistics
import tempfile
import time
from pathlib import Path
from typing import List, Optional, Sequence, Tuple

from duckielib.errors import DuckielibError

#: The notebooks measured; None: every notebook of the course.
NOTEBOOKS: Optional[Sequence[str]] = None
#: Seconds a kernel may take to start, or the first cell to run, before the benchmark gives up.
TIMEOUT_S = 120.0


def _course() -> Path:
    from duckielib.config import PROJECT_ROOT

    return PROJECT_ROOT / "course"


def first_code_cell(path: Path) -> str:
    """The source of a notebook's first code cell."""
    import nbformat

    notebook = nbformat.read(path, as_version=4)
    for cell in notebook.cells:
        if cell.cell_type == "code" and cell.source.strip():
            return str(cell.source)
    raise DuckielibError(f"{path.name} has no code cell to run.")


def time_first_cell(folder: Path, source: str) -> Tuple[float, float]:
    """Start a ``python3`` kernel in ``folder``, run ``source``: seconds to ready, to the result.

    Raises:
        DuckielibError: if the kernel does not start, or the cell raises.
    """
    from jupyter_client.manager import start_new_kernel

    began = time.perf_counter()
    manager, client = start_new_kernel(
        kernel_name="python3", cwd=str(folder), startup_timeout=TIMEOUT_S
    )
    try:
        ready = time.perf_counter() - began
        reply = client.execute_interactive(source, timeout=TIMEOUT_S, output_hook=lambda _: None)
        done = time.perf_counter() - began
    finally:
        client.stop_channels()
        manager.shutdown_kernel(now=True)
    if reply["content"]["status"] != "ok":
        error = f"{reply['content'].get('ename')}: {reply['content'].get('evalue')}"
        raise DuckielibError(f"The first cell of {folder.name} raised {error}.")
    return ready, done - ready


def run() -> List[Tuple[str, str]]:
    """Open each course notebook's kernel and run its first cell; the figures, headline last."""
    course = _course()
    names = (
        list(NOTEBOOKS)
        if NOTEBOOKS is not None
        else sorted(
            path.parent.name for path in course.glob("*/*.ipynb") if path.stem == path.parent.name
        )
    )
    if not names:
        raise DuckielibError(f"{course} holds no notebook to open.")
    figures: List[Tuple[str, str]] = []
    ready_s, cell_s, total_s = [], [], []
    with tempfile.TemporaryDirectory(prefix="duckie-bench-kernel-") as scratch:
        for name in names:
            folder = Path(scratch) / name
            shutil.copytree(course / name, folder)
            ready, cell = time_first_cell(folder, first_code_cell(folder / f"{name}.ipynb"))
            ready_s.append(ready)
            cell_s.append(cell)
            total_s.append(ready + cell)
            figures.append((f"kernel_to_first_cell_s_{name}", f"{ready + cell:.2f}"))
    return [
        ("kernel_ready_s", f"{statistics.median(ready_s):.2f}"),
        ("first_cell_s", f"{statistics.median(cell_s):.2f}"),
        *figures,
        ("kernel_to_first_cell_max_s", f"{max(total_s):.2f}"),
        ("kernel_to_first_cell_s", f"{statistics.median(total_s):.2f}"),
    ]
