"""One notebook run in the sandbox, as nbgrader's executor runs it, with the guard and the tests.

:func:`execute_notebook` runs every cell in a new kernel with nbclient, set as nbgrader's
``Execute`` preprocessor sets it. Before the first cell the guard goes into the kernel
(:mod:`.guard`); before each test cell it puts back what the student's code replaced. A test
cell comes here empty: it runs in the grader (:mod:`autograder.calls`), and the kernel only
answers its calls, which :class:`Relay` passes on. A cell that never got to run (the kernel died
before it: ``os._exit``, a crash, the memory limit) gets an error output, so nbgrader scores its
tests as failed rather than passed. The problems found go into the notebook's metadata
(:data:`METADATA_KEY`).

Runs inside the sandbox: the standard library only at load time.
"""

from __future__ import annotations

import ast
import contextlib
import json
import select
import time
from pathlib import Path
from typing import Any, Callable, List, Optional

from . import guard
from .processes import kill_kernel_copies
from .seam import forking_manager_class
from .wire import ANSWER_LIMIT, Channel, frame, read_frame_within
from .zygote import Zygote

__all__ = [
    "KERNEL_MODULE",
    "METADATA_KEY",
    "NOT_RUN",
    "OUTPUT_LIMIT",
    "execute_notebook",
    "limit_outputs",
    "mark_not_run",
    "module_code",
]

NOT_RUN = "NotRun"
#: Where the grader's findings travel back, in the notebook's metadata.
METADATA_KEY = "duckie_grading"
#: The module of the calls' kernel side, in a kernel (as ``autograder.calls`` names it).
KERNEL_MODULE = "__duckie_calls__"
#: The file of the calls: the grader's side and the kernel's (seen in the sandbox too).
CALLS_FILE = Path(__file__).resolve().parents[2] / "calls.py"
#: The most output one cell keeps, in characters (a picture's data counts too).
OUTPUT_LIMIT = 2_000_000
#: How long a cell's outputs may keep arriving after the kernel said the cell ended, in
#: seconds (nbclient's default is 4: a cell that shows thousands of pictures needs longer).
IOPUB_SECONDS = 30
#: The error a cell that ran out of time is given (as nbgrader gives it).
TIMEOUT_ERROR = {
    "ename": "CellTimeoutError",
    "evalue": "",
    "traceback": ["CellTimeoutError: No reply from kernel before timeout"],
}


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


def _guarded_client_class():
    """The NotebookClient of nbclient, run as nbgrader's Execute runs it, with the guard.

    The settings are those of nbgrader's ``Execute`` preprocessor (errors allowed, a cell that
    runs out of time interrupted and given a ``CellTimeoutError``, the kernel's history kept in
    memory); nbclient is used directly because importing nbgrader in the sandbox costs about
    0.8 s of CPU per notebook, more than many notebooks' own cells.
    """
    # Over 80 lines: the class is made here so that nbclient is imported only when a notebook
    # runs (this module loads with the standard library only); each of its methods is short.
    import nbformat
    from nbclient import NotebookClient

    class GuardedClient(NotebookClient):
        async def async_execute_cell(self, cell, cell_index, execution_count=None, **kwargs):
            self.current = cell_index
            if not getattr(self, "guarded", False):
                self.guarded = True
                await self._run_hidden(_guard_code(), cell_index)
            meta = cell.get("metadata", {}).get("nbgrader", {})
            if cell.cell_type == "code" and meta.get("grade"):
                await self._check(cell_index, meta.get("grade_id", f"cell {cell_index + 1}"))
            if cell.get("metadata", {}).get(METADATA_KEY, {}).get("remote"):
                await self._serve(cell_index, {"test": meta.get("grade_id", "")})
                cell.outputs = []
                self.code_cells_executed += 1
                cell.execution_count = self.code_cells_executed
            else:
                try:
                    await super().async_execute_cell(cell, cell_index, execution_count, **kwargs)
                finally:
                    if getattr(self, "sandboxed", False):
                        kill_kernel_copies(getattr(self.km.provisioner, "pid", None))
            if cell_index == len(self.nb.cells) - 1:
                await self._after_last_cell(cell_index)
            return cell

        async def _check(self, index, label):
            """Put back what the student's code replaced that tests rely on; note what it was."""
            changed = await self._run_hidden(guard.CHECK, index)
            if changed:
                self.replaced[label] = changed

        async def _after_last_cell(self, index):
            """What the notebook left is noted; then the tests' hidden parts run (or run again).

            What is said of the notebook (files written outside the student's folders,
            processes left running) is read now, before any hidden input reaches the student's
            code: nothing after this point is read back but the tests' own verdicts.
            """
            self.writes = guard.writes_outside()
            if self.strays is not None:
                self.left = self.strays()
            kind = "rerun" if self.rerun is not None else "hidden"
            for grade_id in self.rerun if self.rerun is not None else self.hidden:
                await self._check(index, f"the hidden part of {grade_id}")
                await self._serve(index, {kind: grade_id})

        async def _serve(self, index, message):
            """A test (or part) the grader runs on its side: relay its calls until it is done.

            The cell's code never comes here (its source is empty). While the test runs, the
            kernel serves the calls (``serve`` of ``autograder/calls.py``, one hidden
            execution for the whole test, with the cell's time limit) over a socket of its
            own; :class:`Relay` passes each call from the grader to it and each answer, a
            text, back.
            """
            import asyncio

            if not getattr(self, "calls_ready", False):
                self.calls_ready = True
                await self._run_hidden(_calls_code(), index)
            relay = Relay(self.channel, self.timeout or 60)
            try:
                self.channel.say(message)
                talk = asyncio.ensure_future(asyncio.to_thread(relay.run))
                try:
                    code = f"__import__('sys').modules[{KERNEL_MODULE!r}].serve({relay.path!r})"
                    await self._run_hidden(code, index)
                finally:
                    relay.kernel_done(_no_answer(self.last_probe))
                    await talk
            finally:
                relay.close()

        async def _run_hidden(self, source, index):
            """Run ``source`` in the kernel without a cell of its own; its value, if a list."""
            real = self.nb.cells[index]
            probe = nbformat.v4.new_code_cell(source)
            try:
                await super().async_execute_cell(probe, index, store_history=False)
            finally:
                self.nb.cells[index] = real  # nbclient puts the executed cell at the index
            self.last_probe = probe
            for output in probe.get("outputs", []):
                if output.get("output_type") == "execute_result":
                    try:
                        value = ast.literal_eval(output["data"].get("text/plain", ""))
                    except (ValueError, SyntaxError):
                        return []
                    return [str(item) for item in value] if isinstance(value, list) else []
            return []

    return GuardedClient


def module_code(name: str, source: str, then: str = "") -> str:
    """Code that makes ``source`` a module ``name`` in a kernel, then runs ``then`` there.

    The module's names stay out of the student's namespace; ``then`` may use the module as
    ``module``.
    """
    return (
        "def _duckie_module(source):\n"
        "    import sys, types\n"
        f"    module = types.ModuleType({name!r})\n"
        f"    module.__file__ = {name!r}\n"
        f"    sys.modules[{name!r}] = module\n"
        f"    exec(compile(source, {name!r}, 'exec'), module.__dict__)\n"
        + "".join(f"    {line}\n" for line in then.splitlines())
        + f"_duckie_module({source!r})\n"
        "del _duckie_module\n"
    )


def _guard_code() -> str:
    """The code that puts the guard (:mod:`.guard`) in a kernel."""
    source = Path(guard.__file__).read_text(encoding="utf-8")
    install = f"module.check = module.install({guard.WRITES_FILE!r})"
    return module_code(guard.MODULE, source, install)


def _calls_code() -> str:
    """The code that makes the calls' module (``autograder/calls.py``) in a kernel."""
    return module_code(KERNEL_MODULE, CALLS_FILE.read_text(encoding="utf-8"))


def _no_answer(cell: Any) -> str:
    """Why the kernel gave no answer to a call: the error its probe cell ended with."""
    for output in getattr(cell, "outputs", []) or []:
        if output.get("output_type") == "error":
            if output.get("ename") == "CellTimeoutError":
                return "the student's code ran out of time"
            return f"the kernel gave no answer ({output.get('ename')})"
    return "the kernel gave no answer"


class Relay:
    """Passes one test's calls from the grader to the kernel's socket, and the answers back.

    Runs in a thread while the kernel serves the test (see ``_serve_test``). The kernel
    connects to a Unix socket in a new folder of the sandbox's ``/tmp``; each call and answer
    is one frame (:func:`frame`). When the kernel stops serving (the test's end, its time
    limit, a crash), every call still to come is answered ``{"broken": why}``.
    """

    def __init__(self, channel: Channel, seconds: float) -> None:
        import socket
        import tempfile

        self.channel = channel
        self.seconds = seconds
        self.folder = tempfile.mkdtemp(prefix="calls-")
        self.path = str(Path(self.folder) / "socket")
        self.listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.listener.bind(self.path)
        self.listener.listen(1)
        self.connection: Any = None
        self.dead: Optional[str] = None

    def kernel_done(self, why: str) -> None:
        """The kernel serves no more (said from the event loop's thread)."""
        self.dead = why or "the kernel stopped answering"

    def _accept(self) -> Any:
        deadline = time.monotonic() + self.seconds
        while self.connection is None and self.dead is None and time.monotonic() < deadline:
            if select.select([self.listener], [], [], 0.05)[0]:
                self.connection, _ = self.listener.accept()
        return self.connection

    def _ask(self, call: str) -> Optional[str]:
        connection = self._accept()
        if connection is None:
            return None
        try:
            connection.sendall(frame(call.encode("utf-8")))
            with connection.makefile("rb") as stream:
                data = read_frame_within(stream, ANSWER_LIMIT)
        except OSError:
            data = None
        if data is None:
            self.connection = None
            connection.close()
            return None
        if isinstance(data, int):  # too long: the grader hears only how long it was
            return json.dumps({"refused": data})
        return data.decode("utf-8", errors="replace")

    def run(self) -> None:
        """Relay calls until the grader says the test is over (or closes its pipe)."""
        while True:
            message = self.channel.hear()
            if message is None or "end" in message:
                connection = self._accept() if self.dead is None else self.connection
                if connection is not None:
                    with contextlib.suppress(OSError):
                        connection.sendall(frame(b"end"))
                return
            answer = self._ask(str(message.get("call", "")))
            if answer is None:
                answer = json.dumps({"broken": self.dead or "the kernel did not answer"})
            self.channel.say({"answer": answer})

    def close(self) -> None:
        """Close the sockets and remove their folder."""
        import shutil

        for end in (self.connection, self.listener):
            if end is not None:
                with contextlib.suppress(OSError):
                    end.close()
        shutil.rmtree(self.folder, ignore_errors=True)


def _record_reply_error(cell, execute_reply, **_):
    """Give a cell the error of its reply when no output shows it (a timeout's, for one)."""
    import nbformat

    content = (execute_reply or {}).get("content", {})
    if content.get("status") != "error":
        return
    shown = [out.get("ename") for out in cell.get("outputs", []) if out.output_type == "error"]
    if content.get("ename") not in shown:
        cell.outputs.append(
            nbformat.v4.new_output(
                "error",
                ename=content.get("ename", "Error"),
                evalue=content.get("evalue", ""),
                traceback=content.get("traceback") or [content.get("ename", "Error")],
            )
        )


def limit_outputs(notebook: object, limit: int = OUTPUT_LIMIT) -> List[str]:
    """Cut every cell's outputs down to ``limit`` characters; say which cells were cut.

    Text keeps its first ``limit`` characters and a note saying how much was left out;
    pictures and other data past the limit are replaced by the note.

    Returns:
        One sentence per cell that was cut.
    """
    import nbformat

    said = []
    for number, cell in enumerate(notebook.cells, start=1):  # type: ignore[attr-defined]
        if cell.cell_type != "code":
            continue
        total = sum(_output_size(output) for output in cell.get("outputs", []))
        if total <= limit:
            continue
        kept, room = [], limit
        for output in cell.outputs:
            size = _output_size(output)
            if size <= room:
                kept.append(output)
                room -= size
            elif output.output_type == "stream" and room > 0:
                output.text = output.text[:room]
                kept.append(output)
                room = 0
        note = (
            f"[The grader kept {_megabytes(limit)} of this cell's {_megabytes(total)} of output; "
            "the rest was left out.]\n"
        )
        kept.append(nbformat.v4.new_output("stream", name="stdout", text=note))
        cell.outputs = kept
        said.append(
            f"cell {number} showed {_megabytes(total)} of output; the stored notebook keeps "
            f"the first {_megabytes(limit)}"
        )
    return said


def _output_size(output) -> int:
    if output.get("output_type") == "stream":
        return len(output.get("text", ""))
    if output.get("output_type") == "error":
        lines = output.get("traceback", [])
        return len(output.get("evalue", "")) + sum(len(line) for line in lines)
    return sum(len(str(value)) for value in output.get("data", {}).values())


def _megabytes(count: int) -> str:
    return f"{count / 1e6:.1f} MB"


def execute_notebook(
    notebook: Any,
    folder: str,
    cell_seconds: int,
    zygote: Optional[Zygote],
    sandboxed: bool = False,
    channel: Optional[Channel] = None,
    strays: Optional[Callable[[], int]] = None,
) -> None:
    """Run every cell of ``notebook`` in a new kernel working in ``folder``; note the problems.

    In a sandbox of its own (``sandboxed``), the copies of the kernel a cell forked are killed
    after the cell (:func:`kill_kernel_copies`). The tests the grader runs on its side
    (``channel``) run where the notebook reaches them, and their hidden parts after its last
    cell (see :mod:`autograder.verdict`). If the kernel dies before the last cell, the cells
    before the one it died in run again in a new kernel, and the tests among them run there
    whole: a kernel's death costs the tests after it only.

    Args:
        notebook: the notebook to run, changed in place (outputs, metadata).
        folder: the kernel's working folder.
        cell_seconds: the time limit of a cell.
        zygote: the process kernels are forked from, or None for the usual launch.
        sandboxed: whether this runs in a sandbox of its own.
        channel: the way to the grader, which runs the tests on its side.
        strays: kills what the notebook left running (not the kernel) and says how many; called
            after the last cell, before any hidden test.

    The problems (a kernel that died, helpers the tests rely on that had been replaced, outputs
    cut, processes left running) go into the notebook's metadata under :data:`METADATA_KEY`.
    """
    from nbclient.exceptions import DeadKernelError

    executor = _client(notebook, folder, cell_seconds, zygote, sandboxed, channel)
    executor.strays = strays
    executor.hidden = [
        cell.metadata.nbgrader.get("grade_id", "")
        for cell in notebook.cells
        if cell.get("metadata", {}).get(METADATA_KEY, {}).get("hidden")
    ]
    problems = []
    try:
        executor.execute()
    except DeadKernelError:
        if executor.writes is None:  # before the last cell: the cells after it never ran
            problems.append(
                "the kernel died (os._exit, a crash, or more memory than the limit); the cells "
                "after it did not run"
            )
            # Said as they are now: what runs again below sees the tests' hidden inputs.
            executor.writes = guard.writes_outside()
            executor.left = strays() if strays is not None else None
            _run_again(notebook, executor, folder, cell_seconds, zygote, sandboxed, channel)
        else:
            problems.append(
                "the kernel died (os._exit, a crash, or more memory than the limit) while the "
                "hidden tests ran; those after it did not run"
            )
        mark_not_run(
            notebook,
            "This cell did not run: the notebook's kernel died in an earlier cell "
            "(os._exit, a crash, or more memory than the limit).",
        )
    except Exception as error:  # the grader reports it with the notebook
        said = _stopped_by(error, notebook, executor.current)
        problems.append(f"the notebook stopped running: {said}")
        mark_not_run(notebook, f"This cell did not run: {said}")
    _note_problems(notebook, executor, problems)


def _stopped_by(error: Exception, notebook: Any, index: int) -> str:
    """Why the run stopped at cell ``index``, in a sentence."""
    from nbclient.exceptions import CellTimeoutError

    if isinstance(error, CellTimeoutError) and "IOPub" in str(error):
        lines = [line.strip() for line in notebook.cells[index].source.splitlines()]
        first = next((line for line in lines if line and not line.startswith("#")), "")
        return (
            f"the outputs of cell {index + 1} ({first[:50]}) were still arriving "
            f"{IOPUB_SECONDS} s after the cell ended (thousands of outputs, or a kernel too "
            "busy to send them); the cells after it did not run"
        )
    return f"{type(error).__name__}: {error}"


def _note_problems(notebook: Any, executor: Any, problems: List[str]) -> None:
    """Add what the run found to ``problems``, into the notebook's metadata."""
    for grade_id, changed in executor.replaced.items():
        problems.append(
            f"before {grade_id}, the student's code had replaced {', '.join(changed)}; "
            "the originals were put back for the test"
        )
    problems += limit_outputs(notebook)
    # Read (and so removed for the next notebook) in any case; said as it was after the last
    # cell when it was read then, before the hidden tests.
    last = guard.writes_outside()
    problems += executor.writes if executor.writes is not None else last
    if executor.left:
        problems.append(
            f"the notebook left {executor.left} process{'es' if executor.left > 1 else ''} "
            "running after its last cell; the grader stopped them"
        )
    notebook.metadata[METADATA_KEY] = {"problems": problems, "strays": executor.left is not None}


def _client(
    notebook: Any,
    folder: str,
    cell_seconds: int,
    zygote: Optional[Zygote],
    sandboxed: bool,
    channel: Optional[Channel],
) -> Any:
    """The client of nbclient for ``notebook``, set as nbgrader's Execute sets it."""
    options = {"kernel_manager_class": forking_manager_class(zygote)} if zygote else {}
    executor = _guarded_client_class()(
        notebook,
        timeout=cell_seconds,
        kernel_name=notebook.metadata.get("kernelspec", {}).get("name", "python3"),
        allow_errors=True,
        interrupt_on_timeout=True,
        raise_on_iopub_timeout=True,
        iopub_timeout=IOPUB_SECONDS,
        error_on_timeout=TIMEOUT_ERROR,
        extra_arguments=["--HistoryManager.hist_file=:memory:"],
        shutdown_kernel="immediate",
        on_cell_executed=_record_reply_error,
        resources={"metadata": {"path": folder}},
        **options,
    )
    executor.replaced = {}
    executor.sandboxed = sandboxed
    executor.channel = channel
    executor.current = 0
    executor.strays = None
    executor.hidden = []
    executor.rerun = None
    executor.writes = None
    executor.left = None
    return executor


def _run_again(
    notebook: Any,
    died: Any,
    folder: str,
    cell_seconds: int,
    zygote: Optional[Zygote],
    sandboxed: bool,
    channel: Optional[Channel],
) -> None:
    """After the kernel died in cell ``died.current``: the tests before it, whole, in a new kernel.

    The cells before the one the kernel died in run again (their outputs are not kept), then
    each test among them with hidden tests runs whole (the grader runs only those whose hidden
    part was still to run). If the new kernel dies too, those tests stay without a verdict.
    """
    import copy

    from nbclient.exceptions import DeadKernelError

    before = [copy.deepcopy(cell) for cell in notebook.cells[: died.current]]
    tests = [
        cell.metadata.nbgrader.get("grade_id", "")
        for cell in before
        if cell.get("metadata", {}).get(METADATA_KEY, {}).get("hidden")
    ]
    if channel is None or not tests:
        return
    for cell in before:
        if cell.get("metadata", {}).get(METADATA_KEY, {}).get("remote"):
            cell.metadata.pop(METADATA_KEY)  # run as an empty cell: the tests run at the end
    again = copy.deepcopy(notebook)
    again.cells = before
    executor = _client(again, folder, cell_seconds, zygote, sandboxed, channel)
    executor.rerun = tests
    with contextlib.suppress(DeadKernelError):
        executor.execute()
