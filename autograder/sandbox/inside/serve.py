"""The sandbox's server: runs the notebooks the grader sends, one after the other.

The grader (:mod:`autograder.sandbox.server`) starts it in the sandbox, as
``python autograder/sandbox/inside --serve CELL_SECONDS [--sandboxed]``, and sends it
notebooks (their instructor's cells restored, hidden tests left empty) over the wire
(:mod:`.wire`); each runs in a new kernel forked from the zygote (:mod:`.zygote`), as nbgrader's
executor would run it (:mod:`.notebook`), and goes back executed. The notebook never lies in the
sandbox's folder, so the student's code cannot open the file. ``python autograder/sandbox/inside
CELL_SECONDS`` runs one notebook instead, from standard input to standard output.

Runs inside the sandbox: the standard library only at load time.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any, Callable, List, NoReturn, Optional, Tuple

from . import seam
from .notebook import METADATA_KEY, execute_notebook
from .processes import kill_strays, not_dumpable
from .wire import Channel, decode, encode, read_frame
from .zygote import ZYGOTE_VARIABLE, Zygote

__all__ = ["main", "serve"]


def _private_streams() -> Tuple[Any, Any]:
    """The server's own input and output; fds 0, 1 and 2 then point at the null device.

    Kernels inherit file descriptors 0 to 2: the student's ``os.write(1, ...)`` must not reach
    the grader, nor ``os.read(0, ...)`` the next request.
    """
    given = os.fdopen(os.dup(0), "rb")
    answer = os.fdopen(os.dup(1), "wb")
    quiet = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):
        os.dup2(quiet, fd)
    os.close(quiet)
    return given, answer


def serve(cell_seconds: int, sandboxed: bool) -> None:
    """Run the notebooks the grader sends, one after the other, each in a new kernel.

    Each request is a JSON message ``{"folder", "notebook"}`` (the folder relative to the
    working one), each answer ``{"notebook"}`` with the executed notebook, or ``{"problem"}``.
    One zygote serves every kernel, so the libraries are imported once for all the notebooks.

    Args:
        cell_seconds: the time limit of a cell.
        sandboxed: whether this runs in a sandbox of its own (its own user and process
            namespace): only then are processes a notebook left behind killed before the next.
    """
    not_dumpable()
    zygote = _start()
    import shutil
    import tempfile

    import nbformat

    given, answer = _private_streams()
    keep = [1, os.getpid()] + ([zygote.pid] if zygote is not None else [])
    channel = Channel(given, answer)
    broken = _seam_broken()
    while True:
        request = read_frame(given)
        if request is None:
            break
        try:
            message = decode(request)
            if "notebook" not in message:  # a late word of a test the grader gave up on
                continue
            if broken:
                raise seam.SeamError(broken)
            notebook = nbformat.reads(message["notebook"], as_version=4)
            folder = str(Path(message["folder"]).absolute())
            # A new IPython folder for each notebook's kernel: nothing a notebook writes there
            # (a startup file, a configuration) reaches the next one.
            ipython = tempfile.mkdtemp(prefix="ipython-")
            os.environ["IPYTHONDIR"] = ipython
            strays = _strays(keep) if sandboxed else None
            try:
                execute_notebook(notebook, folder, cell_seconds, zygote, sandboxed, channel, strays)
            finally:
                shutil.rmtree(ipython, ignore_errors=True)
            if sandboxed:
                # Counted after the last cell (before the hidden tests), when it got that far;
                # what the hidden tests' calls started is stopped without a word.
                left = kill_strays(keep)
                if left and not notebook.metadata[METADATA_KEY].get("strays"):
                    notebook.metadata[METADATA_KEY]["problems"].append(
                        f"the notebook left {left} process{'es' if left > 1 else ''} running "
                        "after its last cell; the grader stopped them"
                    )
            reply = {"notebook": nbformat.writes(notebook)}
        except Exception as error:  # the grader reports it for this notebook
            reply = {"problem": f"could not be run: {type(error).__name__}: {error}"}
            if sandboxed:
                kill_strays(keep)
        answer.write(encode(reply))
        answer.flush()
    _end(zygote)


def _strays(keep: List[int]) -> Callable[[], int]:
    """Kills what a notebook left running, but its kernel; how many (see :func:`kill_strays`)."""

    def strays() -> int:
        # The kernels are the zygote's children, or this server's without a zygote.
        return kill_strays([*keep, *_children(keep[-1])])

    return strays


def _children(parent: int) -> List[int]:
    """The processes whose parent is ``parent`` (the zygote's: the kernels)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == parent:
            found.append(int(entry.name))
    return found


def _seam_broken() -> str:
    """Why the installed Jupyter packages cannot run a notebook here (:mod:`.seam`), or nothing."""
    try:
        seam.check()
    except seam.SeamError as error:
        return str(error)
    return ""


def _start() -> Optional[Zygote]:
    """The zygote, unless turned off: forked first, before nbclient, zmq or asyncio is imported.

    See :class:`.zygote.Zygote`.
    """
    zygote = Zygote.start() if os.environ.get(ZYGOTE_VARIABLE, "1") != "0" else None
    # nbformat validates with jsonschema, whose optional "iri" format checker builds a grammar
    # at import (about 1.2 s, for a format no notebook uses): leave that package out.
    sys.modules.setdefault("rfc3987_syntax", None)  # type: ignore[arg-type]
    return zygote


def _end(zygote: Optional[Zygote]) -> NoReturn:
    """End the zygote (and the kernels it started), then this process."""
    if zygote is not None:
        zygote.close()
    os._exit(0)  # nothing left to clean up: the sandbox and all in it end with this process


def main() -> None:
    """Read a notebook on stdin, run it, write it on stdout (``--serve``: many, as frames)."""
    if sys.argv[1] == "--serve":
        serve(int(sys.argv[2]), sandboxed="--sandboxed" in sys.argv[3:])
    zygote = _start()
    import nbformat

    notebook = nbformat.read(sys.stdin, as_version=4)
    seam.check()
    _, answer = _private_streams()
    execute_notebook(notebook, ".", int(sys.argv[1]), zygote)
    answer.write(nbformat.writes(notebook).encode("utf-8"))
    answer.flush()
    _end(zygote)
