"""Run one notebook's cells inside the sandbox, as nbgrader's executor runs it.

The grader sends the notebook (instructor's cells restored, hidden tests included) on standard
input and reads the executed notebook on standard output; the notebook never lies in the
sandbox's folder, so the student's code cannot open the file to read the hidden tests.
Usage (inside the sandbox): ``python execute.py CELL_SECONDS``; or, to run all of one
student's notebooks in one sandbox, one after the other (each in a new kernel),
``python execute.py --serve CELL_SECONDS [--sandboxed]``, with requests and answers as frames
on standard input and output (:func:`serve`).

A cell that never got to run (the kernel died before it: ``os._exit``, a crash, the memory
limit) gets an error output, so nbgrader scores its tests as failed rather than passed.

The kernel is forked from a pre-warmed process (:class:`Zygote`) that has already imported
ipykernel and the course's libraries while this script read the notebook, rather than started
as a new Python: that saves the start of a second interpreter and lets the imports overlap the
reading. ``DUCKIE_KERNEL_ZYGOTE=0`` turns it off; if the zygote cannot start, the kernel is
launched the usual way.

Test cells come here empty and run in the grader (:mod:`autograder.calls`); the kernel only
answers their calls. Before the first cell, a guard keeps the originals of what tests once
relied on in the kernel (``np.allclose``, a fake ``np``, IPython's error display); before each
test cell it puts back whatever the student's code replaced, and the grader reports it.
"""

from __future__ import annotations

import ast
import contextlib
import json
import os
import select
import signal
import sys
import time
from pathlib import Path
from typing import Any, Dict, Iterator, List, Mapping, NoReturn, Optional, Sequence, Tuple

NOT_RUN = "NotRun"
#: Where the grader's findings travel back, in the notebook's metadata.
METADATA_KEY = "duckie_grading"
#: The module of the calls' kernel side, in a kernel (as ``autograder.calls`` names it).
KERNEL_MODULE = "__duckie_calls__"
#: The most output one cell keeps, in characters (a picture's data counts too).
OUTPUT_LIMIT = 2_000_000
#: The error a cell that ran out of time is given (as nbgrader gives it).
TIMEOUT_ERROR = {
    "ename": "CellTimeoutError",
    "evalue": "",
    "traceback": ["CellTimeoutError: No reply from kernel before timeout"],
}

#: Run before the first cell: keeps the originals of what tests rely on.
GUARD_SETUP = r"""
def _setup():
    import builtins, os, sys, types
    # Writes outside the student's folders are noted for the grader (the sandbox refuses them;
    # an audit hook cannot be removed, so the note survives the student's code).
    home = os.path.dirname(os.getcwd()) + os.sep
    allowed = (home, "/tmp/", "/dev/", "/proc/")
    writing = os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_TRUNC
    changes = {"os.remove", "os.rename", "os.mkdir", "os.rmdir", "os.symlink", "os.link",
               "os.chmod", "os.truncate", "shutil.rmtree"}
    busy = []

    def audit(event, args):
        if busy or (event != "open" and event not in changes):
            return
        if event == "open":
            path, mode, flags = args
            if not ((flags or 0) & writing or (isinstance(mode, str) and set(mode) & set("wax+"))):
                return
        else:
            path = args[0]
        if not isinstance(path, (str, bytes, os.PathLike)):
            return
        busy.append(True)
        try:
            full = os.path.abspath(os.fsdecode(path))
            if not (full + os.sep).startswith(allowed):
                with open(WRITES_FILE, "a", encoding="utf-8") as noted:
                    noted.write(full + "\n")
        except Exception:
            pass
        finally:
            busy.pop()

    sys.addaudithook(audit)
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

#: Where the guard notes the paths a notebook tried to write outside the student's folders.
WRITES_FILE = "/tmp/.grader-writes"
GUARD_SETUP = GUARD_SETUP.replace("WRITES_FILE", repr(WRITES_FILE))

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


def _guarded_client_class():
    """The NotebookClient of nbclient, run as nbgrader's Execute runs it, with the guard.

    The settings are those of nbgrader's ``Execute`` preprocessor (errors allowed, a cell that
    runs out of time interrupted and given a ``CellTimeoutError``, the kernel's history kept in
    memory); nbclient is used directly because importing nbgrader in the sandbox costs about
    0.8 s of CPU per notebook, more than many notebooks' own cells.
    """
    import nbformat
    from nbclient import NotebookClient

    class GuardedClient(NotebookClient):
        async def async_execute_cell(self, cell, cell_index, execution_count=None, **kwargs):
            if not getattr(self, "guarded", False):
                self.guarded = True
                await self._run_hidden(GUARD_SETUP, cell_index)
            meta = cell.get("metadata", {}).get("nbgrader", {})
            if cell.cell_type == "code" and meta.get("grade"):
                changed = await self._run_hidden(GUARD_CHECK, cell_index)
                if changed:
                    self.replaced[meta.get("grade_id", f"cell {cell_index + 1}")] = changed
            if cell.get("metadata", {}).get(METADATA_KEY, {}).get("remote"):
                await self._serve_test(cell, cell_index, meta.get("grade_id", ""))
                return cell
            try:
                return await super().async_execute_cell(cell, cell_index, execution_count, **kwargs)
            finally:
                if getattr(self, "sandboxed", False):
                    _kill_kernel_copies(getattr(self.km.provisioner, "pid", None))

        async def _serve_test(self, cell, index, grade_id):
            """A test the grader runs on its side: relay its calls until it says it is done.

            The cell's code never comes here (its source is empty). While the test runs, the
            kernel serves the calls (``serve`` of ``autograder/calls.py``, one hidden
            execution for the whole test, with the cell's time limit) over a socket of its
            own; :class:`_Relay` passes each call from the grader to it and each answer, a
            text, back.
            """
            import asyncio

            if not getattr(self, "calls_ready", False):
                self.calls_ready = True
                await self._run_hidden(_calls_setup(), index)
            relay = _Relay(self.channel, self.timeout or 60)
            try:
                self.channel.say({"test": grade_id})
                talk = asyncio.ensure_future(asyncio.to_thread(relay.run))
                try:
                    code = f"__import__('sys').modules[{KERNEL_MODULE!r}].serve({relay.path!r})"
                    await self._run_hidden(code, index)
                finally:
                    relay.kernel_done(_no_answer(self.last_probe))
                    await talk
            finally:
                relay.close()
            cell.outputs = []
            self.code_cells_executed += 1
            cell.execution_count = self.code_cells_executed

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


def _calls_setup() -> str:
    """The code that makes the calls module (``calls.py``, next to this file) in a kernel."""
    source = (Path(__file__).resolve().parent / "calls.py").read_text(encoding="utf-8")
    return (
        "def _duckie_calls(source):\n"
        "    import sys, types\n"
        f"    module = types.ModuleType({KERNEL_MODULE!r})\n"
        f"    module.__file__ = {KERNEL_MODULE!r}\n"
        f"    sys.modules[{KERNEL_MODULE!r}] = module\n"
        f"    exec(compile(source, {KERNEL_MODULE!r}, 'exec'), module.__dict__)\n"
        f"_duckie_calls({source!r})\n"
        "del _duckie_calls\n"
    )


def _no_answer(cell: Any) -> str:
    """Why the kernel gave no answer to a call: the error its probe cell ended with."""
    for output in getattr(cell, "outputs", []) or []:
        if output.get("output_type") == "error":
            if output.get("ename") == "CellTimeoutError":
                return "the student's code ran out of time"
            return f"the kernel gave no answer ({output.get('ename')})"
    return "the kernel gave no answer"


class _Relay:
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
                data = read_frame(stream)
        except OSError:
            data = None
        if data is None:
            self.connection = None
            connection.close()
            return None
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


class Channel:
    """The server's end of the conversation with the grader during remote tests."""

    def __init__(self, given: Any, answer: Any) -> None:
        self.given, self.answer = given, answer

    def say(self, message: Dict[str, Any]) -> None:
        """Send ``message`` to the grader."""
        self.answer.write(frame(json.dumps(message).encode("utf-8")))
        self.answer.flush()

    def hear(self) -> Optional[Dict[str, Any]]:
        """The grader's next message, or None when it has closed the pipe."""
        data = read_frame(self.given)
        return None if data is None else json.loads(data)


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


#: Set to ``0`` to launch every kernel the usual way (a new Python) instead of forking it.
ZYGOTE_VARIABLE = "DUCKIE_KERNEL_ZYGOTE"
#: What the zygote imports before it forks a kernel: the kernel itself, and what the first cell
#: of every course notebook imports. None of them selects matplotlib's backend on import.
ZYGOTE_IMPORTS = (
    "ipykernel.kernelapp",
    "ipykernel.ipkernel",
    "numpy",
    "matplotlib",
    "matplotlib.pyplot",
    "PIL.Image",
    "IPython.display",
    "duckielib.bags",
    "duckielib.sim",
    "duckielib.ros",
    "duckielib.plots",
    "duckielib.nodes",
)
#: How long a kernel's launch waits for the zygote (its imports included), in seconds.
ZYGOTE_SECONDS = 60.0
#: The matplotlib backend ipykernel chooses when ``MPLBACKEND`` is not set.
_INLINE_BACKEND = "module://matplotlib_inline.backend_inline"
#: How often the provisioner looks whether a kernel it killed has ended, in seconds.
_POLL_SECONDS = 0.005


class Zygote:
    """A process that has imported the kernel and the course's libraries, and forks kernels.

    Starting a kernel the usual way runs a new Python, which imports ipykernel and then, in
    the notebook's first cell, numpy, matplotlib and duckielib. The zygote is forked from this
    script before the script reads the notebook or imports nbclient, zmq or asyncio (so it holds
    neither the notebook nor a thread); it imports all that while the script reads the notebook,
    then forks each kernel the kernel manager asks for: the child starts a session of its own,
    changes to the notebook's folder and runs ipykernel's ``IPKernelApp`` on the connection
    file, as ``python -m ipykernel_launcher`` would. The zygote reaps its children and reports
    their exit status over a pipe; :meth:`exit_code` is how the kernel's provisioner learns that
    the kernel died.

    A forked kernel starts as a new one: the environment and arguments the kernel manager gives
    it, ``sys.path`` of a new kernel, an empty namespace whose ``__name__`` is ``"__main__"``,
    numpy's global random state seeded anew. The modules already imported are the difference
    (a student's ``numpy.py`` next to the notebook cannot stand in for one of them). The zygote
    serves only kernels whose environment is its own (the imports may have read it), and only
    while it runs a single thread (``OPENBLAS_NUM_THREADS=1``, as in the sandbox).

    Messages are JSON lines: to the zygote ``{"command", "cwd", "env"}``; back ``{"started":
    pid}``, ``{"failed": reason}``, ``{"exited": pid, "code": code}``.
    """

    def __init__(self, pid: int, requests: int, replies: int) -> None:
        self.pid = pid
        self._requests: Optional[int] = requests
        self._replies = replies
        self._pending = b""
        self._exits: Dict[int, int] = {}
        self._gone = False

    @classmethod
    def start(cls) -> Optional[Zygote]:
        """Fork the zygote; None if it cannot be (the process limit)."""
        to_zygote, requests = os.pipe()
        replies, from_zygote = os.pipe()
        try:
            pid = os.fork()
        except OSError:  # the process limit
            for fd in (to_zygote, requests, replies, from_zygote):
                os.close(fd)
            return None
        if pid == 0:
            code = 1
            try:
                os.close(requests)
                os.close(replies)
                code = _serve(to_zygote, from_zygote)
            finally:
                os._exit(code)
        os.close(to_zygote)
        os.close(from_zygote)
        os.set_blocking(replies, False)
        return cls(pid, requests, replies)

    def launch(
        self, command: Sequence[str], cwd: Optional[str], env: Dict[str, str]
    ) -> Optional[int]:
        """Fork a kernel that runs ``command`` (``python -m ipykernel_launcher ARGS``).

        Args:
            command: the kernel's command line, as the kernel manager built it.
            cwd: the folder the kernel starts in (None: this process's).
            env: the kernel's environment variables.

        Returns:
            The kernel's process id, or None if the zygote could not start it (it is then to be
            launched the usual way).
        """
        if self._requests is None or self._gone:
            return None
        data = json.dumps({"command": list(command), "cwd": cwd, "env": env}).encode() + b"\n"
        try:
            while data:
                data = data[os.write(self._requests, data) :]
        except OSError:  # the zygote has ended (it could not import, or runs threads)
            self._gone = True
            return None
        deadline = time.monotonic() + ZYGOTE_SECONDS
        while True:
            for message in self._read():
                if "started" in message:
                    return int(message["started"])
                if "failed" in message:
                    return None
            left = deadline - time.monotonic()
            if self._gone or left <= 0:
                self.close(kill=True)
                return None
            select.select([self._replies], [], [], left)

    def exit_code(self, pid: int) -> Optional[int]:
        """The exit code of a kernel the zygote started, None while it runs.

        As :attr:`subprocess.Popen.returncode`: ``-N`` if signal ``N`` ended it. Should the
        zygote be gone before it reported the exit, a kernel that no longer exists counts as
        killed.
        """
        self._read()
        if pid in self._exits:
            return self._exits[pid]
        if self._gone:
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                return -signal.SIGKILL
            except PermissionError:
                pass
        return None

    def _read(self) -> List[Dict[str, Any]]:
        """The messages the zygote sent since the last read; exits are recorded on the way."""
        while not self._gone:
            try:
                data = os.read(self._replies, 65536)
            except BlockingIOError:
                break
            except OSError:
                data = b""
            if not data:
                self._gone = True
            self._pending += data
        *lines, self._pending = self._pending.split(b"\n")
        messages = [json.loads(line) for line in lines if line]
        for message in messages:
            if "exited" in message:
                self._exits[int(message["exited"])] = int(message["code"])
        return messages

    def close(self, kill: bool = False) -> None:
        """End the zygote (it kills the kernels it started) and wait for it.

        Waiting counts the zygote's and its kernels' CPU time in this process's, as a kernel
        launched the usual way is counted.

        Args:
            kill: kill it at once rather than let it finish its work first.
        """
        if self._requests is not None:
            os.close(self._requests)
            self._requests = None
        deadline = time.monotonic() + (0 if kill else 5)
        while True:
            try:
                if os.waitpid(self.pid, os.WNOHANG)[0]:
                    break
            except ChildProcessError:
                break
            if time.monotonic() >= deadline:
                os.kill(self.pid, signal.SIGKILL)
                os.waitpid(self.pid, 0)
                break
            time.sleep(_POLL_SECONDS)
        self._gone = True


def _serve(requests: int, replies: int) -> int:
    """The zygote's life: import, then fork a kernel for each request until the pipe closes.

    Args:
        requests: the pipe the requests come on.
        replies: the pipe the answers and exit statuses go on.

    Returns:
        The zygote's exit code.
    """
    warm = _warm_up(requests, replies)
    if warm is None:
        return 0  # the pipe closes: each kernel is launched the usual way
    path, env, launcher = warm
    _Forks(requests, replies, path, env, launcher).serve()
    return 0


def _warm_up(*keep: int) -> Optional[Tuple[List[str], Dict[str, str], str]]:
    """Make the zygote what a new kernel is before its first cell, with the imports done.

    Args:
        keep: the zygote's pipes, left open (every other descriptor past the standard three
            is closed, as a kernel launched the usual way inherits none).

    Returns:
        A new kernel's ``sys.path`` (before ipykernel adds the working folder), the environment
        the imports saw (see :func:`_kernel_env`) and the file of ``ipykernel_launcher``; None
        if kernels cannot be forked from here (no ipykernel, or a library started a thread).
    """
    import importlib.util

    quiet = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):  # neither the notebook on the input nor the answer on the output
        os.dup2(quiet, fd)
    os.close(quiet)
    low = 3
    for fd in sorted(keep):
        os.closerange(low, fd)
        low = fd + 1
    os.closerange(low, os.sysconf("SC_OPEN_MAX"))
    # A new kernel's sys.path: without the folder Python put first for this script, as
    # ipykernel_launcher takes out the one Python put first for it.
    if not sys.flags.safe_path:
        del sys.path[0]
    if not os.environ.get("MPLBACKEND"):  # the kernel sets it so before matplotlib's import
        os.environ["MPLBACKEND"] = _INLINE_BACKEND
    env = _kernel_env(os.environ)
    for name in ZYGOTE_IMPORTS:
        with contextlib.suppress(Exception):  # the notebook's own import says why
            __import__(name)
    launcher = importlib.util.find_spec("ipykernel_launcher")
    if _threads() != 1 or launcher is None or launcher.origin is None:
        return None
    if _kernel_env(os.environ) != env:  # an import set a variable the kernel would not have
        return None
    return list(sys.path), env, launcher.origin


class _Forks:
    """The zygote's loop: fork a kernel for each request, report each kernel's exit.

    Single-threaded: a SIGCHLD wakes the loop through a pipe (``signal.set_wakeup_fd``).
    """

    def __init__(
        self, requests: int, replies: int, path: List[str], env: Dict[str, str], launcher: str
    ) -> None:
        self.requests, self.replies = requests, replies
        self.path, self.env, self.launcher = path, env, launcher
        self.children: List[int] = []
        self.wake, woken = os.pipe()
        os.set_blocking(self.wake, False)
        os.set_blocking(woken, False)
        self.own = (requests, replies, self.wake, woken)
        signal.signal(signal.SIGCHLD, lambda *_: None)
        signal.set_wakeup_fd(woken, warn_on_full_buffer=False)

    def serve(self) -> None:
        """Answer requests until the pipe closes; then kill what is left and reap it."""
        pending = b""
        try:
            while True:
                ready = select.select([self.requests, self.wake], [], [])[0]
                if self.wake in ready:
                    self.reap()
                if self.requests not in ready:
                    continue
                data = os.read(self.requests, 65536)
                if not data:
                    return
                *lines, pending = (pending + data).split(b"\n")
                for line in lines:
                    self.answer(json.loads(line))
        finally:
            for pid in self.children:  # left only if this script ended without stopping them
                try:
                    os.killpg(pid, signal.SIGKILL)
                except OSError:  # not yet in a session of its own
                    with contextlib.suppress(OSError):
                        os.kill(pid, signal.SIGKILL)
            for pid in self.children:
                with contextlib.suppress(ChildProcessError):
                    os.waitpid(pid, 0)

    def answer(self, request: Dict[str, Any]) -> None:
        """Fork the kernel ``request`` asks for, if it can be forked here; say which it is."""
        if _kernel_env(request["env"]) != self.env:
            self.say({"failed": "the kernel's environment differs from the zygote's"})
        elif _threads() != 1:
            self.say({"failed": "the zygote runs more than one thread"})
        else:
            pid = os.fork()
            if pid == 0:
                _run_kernel(request, self.launcher, self.path, self.own)
            self.children.append(pid)
            self.say({"started": pid})

    def reap(self) -> None:
        """Reap the kernels that ended and report their exit codes."""
        with contextlib.suppress(BlockingIOError):
            while os.read(self.wake, 512):
                pass
        while self.children:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                return
            if pid == 0:
                return
            if pid in self.children:
                self.children.remove(pid)
                self.say({"exited": pid, "code": os.waitstatus_to_exitcode(status)})

    def say(self, message: Dict[str, Any]) -> None:

        data = json.dumps(message).encode() + b"\n"
        while data:
            data = data[os.write(self.replies, data) :]


def _kernel_env(env: Mapping[str, str]) -> Dict[str, str]:
    """The environment variables that matter to the zygote's imports, from a kernel's.

    ``JPY_PARENT_PID`` names the kernel's parent, set for each kernel, and ``IPYTHONDIR`` its
    IPython folder, new for each notebook (read when the kernel starts, not at import); an unset
    ``MPLBACKEND`` is the inline backend ipykernel sets.
    """
    kept = {key: value for key, value in env.items() if key not in ("JPY_PARENT_PID", "IPYTHONDIR")}
    if not kept.get("MPLBACKEND"):
        kept["MPLBACKEND"] = _INLINE_BACKEND
    return kept


def _threads() -> int:
    """How many threads this process runs; 0 if that cannot be known."""
    try:
        return sum(1 for _ in Path("/proc/self/task").iterdir())
    except OSError:
        return 0


def _run_kernel(
    request: Dict[str, Any], launcher: str, path: List[str], inherited: Sequence[int]
) -> NoReturn:
    """In a child of the zygote: become the kernel ``request`` asks for, and end with it.

    What ``python -m ipykernel_launcher ARGS`` would be, started as jupyter_client starts it:
    a session of its own, standard input an empty pipe, output and error the zygote's (the
    null device), the working folder and environment of the request, ``JPY_PARENT_PID`` the
    parent (here the zygote, which ends with this script).

    Args:
        request: the command line, working folder and environment of the kernel.
        launcher: the file of ``ipykernel_launcher`` (``sys.argv[0]`` of a new kernel).
        path: ``sys.path`` of a new kernel, before ipykernel adds the working folder.
        inherited: the zygote's own file descriptors, closed here.
    """
    import atexit

    code = 1
    try:
        os.setsid()
        signal.set_wakeup_fd(-1)
        signal.signal(signal.SIGCHLD, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        for fd in inherited:
            os.close(fd)
        empty, closed = os.pipe()
        os.close(closed)
        os.dup2(empty, 0)
        os.close(empty)
        if request["cwd"]:
            os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        os.environ["JPY_PARENT_PID"] = str(os.getppid())
        command = request["command"]
        sys.argv = [launcher, *command[3:]]
        sys.orig_argv = list(command)
        sys.path[:] = path
        if "numpy" in sys.modules:  # a new process seeds numpy's global generator anew
            sys.modules["numpy"].random.seed()
        from ipykernel.kernelapp import IPKernelApp

        app = IPKernelApp.instance()
        app.parent_handle = os.getppid()  # its default was read at import, in the zygote
        app.initialize()
        app.start()
        code = 0
    except SystemExit as stop:
        code = stop.code if isinstance(stop.code, int) else int(stop.code is not None)
    except BaseException:
        import traceback

        traceback.print_exc()
    finally:
        try:
            atexit._run_exitfuncs()
            sys.stdout.flush()
            sys.stderr.flush()
        finally:
            os._exit(code)


def _forking_manager_class(zygote: Zygote) -> type:
    """An AsyncKernelManager whose kernels the zygote forks, when it can.

    Its provisioner is jupyter_client's ``LocalProvisioner`` (connection file, ports, the
    usual launch as the fallback) with the launch and the process handling of a forked kernel:
    poll and wait read the exit status the zygote reports, signals go to the kernel's process
    group (an interrupt is SIGINT, as for a kernel launched the usual way).
    """
    import asyncio
    import uuid
    from queue import Empty

    from jupyter_client.asynchronous import AsyncKernelClient
    from jupyter_client.manager import AsyncKernelManager
    from jupyter_client.provisioning import LocalProvisioner

    class ForkedProvisioner(LocalProvisioner):
        forked: Optional[int] = None

        @property
        def has_process(self) -> bool:
            return self.forked is not None or super().has_process

        async def launch_kernel(self, cmd: List[str], **kwargs: Any) -> Any:
            usual = set(kwargs) <= {"env", "cwd", "kernel_id"}  # nothing only Popen can do
            if usual and _is_ipykernel(cmd):
                pid = zygote.launch(cmd, kwargs.get("cwd"), kwargs.get("env", dict(os.environ)))
                if pid is not None:
                    self.forked = self.pid = self.pgid = pid
                    self.cwd = kwargs.get("cwd") or Path.cwd()
                    return self.connection_info
            return await super().launch_kernel(cmd, **kwargs)

        async def poll(self) -> Optional[int]:
            if self.forked is None:
                return await super().poll()
            return zygote.exit_code(self.forked)

        async def wait(self) -> Optional[int]:
            if self.forked is None:
                return await super().wait()
            while zygote.exit_code(self.forked) is None:
                await asyncio.sleep(_POLL_SECONDS)
            code = zygote.exit_code(self.forked)
            self.forked = None
            return code

        async def send_signal(self, signum: int) -> None:
            if self.forked is None:
                await super().send_signal(signum)
            elif zygote.exit_code(self.forked) is None:
                try:
                    os.killpg(self.forked, signum)
                except OSError:
                    with contextlib.suppress(ProcessLookupError):
                        os.kill(self.forked, signum)

        async def kill(self, restart: bool = False) -> None:
            if self.forked is None:
                await super().kill(restart)
            else:
                await self.send_signal(signal.SIGKILL)

        async def terminate(self, restart: bool = False) -> None:
            if self.forked is None:
                await super().terminate(restart)
            else:
                await self.send_signal(signal.SIGTERM)

    class PromptClient(AsyncKernelClient):
        """jupyter_client's client, with the wait for a new kernel cut to what it needs.

        Once the kernel has answered ``kernel_info`` and its first IOPub message arrived, the
        usual wait still listens 0.2 s for more IOPub messages before it returns: a fifth of a
        second per notebook, idle. Here it stops after 20 ms of silence; later messages of the
        start are told apart by their parent anyway, as nbclient reads only its own.
        """

        async def wait_for_ready(self, timeout: Optional[float] = None) -> None:
            deadline = time.monotonic() + (60.0 if timeout is None else timeout)
            while True:
                self.kernel_info()
                try:
                    reply = await self.shell_channel.get_msg(timeout=0.5)
                except Empty:
                    reply = None
                if reply is not None and reply["msg_type"] == "kernel_info_reply":
                    try:
                        await self.iopub_channel.get_msg(timeout=0.2)
                    except Empty:
                        pass
                    else:
                        self._handle_kernel_info_reply(reply)
                        break
                if not await self._async_is_alive():
                    raise RuntimeError("Kernel died before replying to kernel_info")
                if time.monotonic() > deadline:
                    raise RuntimeError(f"Kernel didn't respond in {timeout} seconds")
            while True:
                try:
                    await self.iopub_channel.get_msg(timeout=0.02)
                except Empty:
                    break

    class ForkingKernelManager(AsyncKernelManager):
        client_factory = PromptClient

        async def _async_wait(self, pollinterval: float = 0.1) -> None:
            # A killed kernel is gone in milliseconds: look every 5 ms, not every 100.
            await super()._async_wait(pollinterval=min(pollinterval, _POLL_SECONDS))

        async def _async_pre_start_kernel(self, **kw: Any) -> Any:
            if self.provisioner is None:
                self.kernel_id = self.kernel_id or kw.pop("kernel_id", str(uuid.uuid4()))
                self.provisioner = ForkedProvisioner(
                    kernel_id=self.kernel_id, kernel_spec=self.kernel_spec, parent=self
                )
            return await super()._async_pre_start_kernel(**kw)

    return ForkingKernelManager


def _is_ipykernel(command: Sequence[str]) -> bool:
    """Whether ``command`` runs ipykernel with this Python, as the zygote would."""
    return (
        len(command) >= 3
        and list(command[1:3]) == ["-m", "ipykernel_launcher"]
        and Path(command[0]).absolute() == Path(sys.executable).absolute()
    )


def _execute(
    notebook: Any,
    folder: str,
    cell_seconds: int,
    zygote: Optional[Zygote],
    sandboxed: bool = False,
    channel: Optional[Channel] = None,
) -> None:
    """Run every cell of ``notebook`` in a new kernel working in ``folder``; note the problems.

    In a sandbox of its own (``sandboxed``), the copies of the kernel a cell forked are killed
    after the cell (:func:`_kill_kernel_copies`).

    The problems (a kernel that died, helpers the tests rely on that had been replaced, outputs
    cut) go into the notebook's metadata under :data:`METADATA_KEY`.
    """
    from nbclient.exceptions import DeadKernelError

    options = {"kernel_manager_class": _forking_manager_class(zygote)} if zygote else {}
    executor = _guarded_client_class()(
        notebook,
        timeout=cell_seconds,
        kernel_name=notebook.metadata.get("kernelspec", {}).get("name", "python3"),
        allow_errors=True,
        interrupt_on_timeout=True,
        raise_on_iopub_timeout=True,
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
    problems = []
    try:
        executor.execute()
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
    for grade_id, changed in executor.replaced.items():
        problems.append(
            f"before {grade_id}, the student's code had replaced {', '.join(changed)}; "
            "the originals were put back for the test"
        )
    problems += limit_outputs(notebook)
    problems += _writes_outside()
    notebook.metadata[METADATA_KEY] = {"problems": problems}


def _writes_outside() -> List[str]:
    """What the guard noted the notebook tried to write outside the student's folders.

    The note is then removed, for the next notebook. It lies in the sandbox's ``/tmp``, where
    the student's code may put anything: it is read only if it is a regular file.
    """
    import stat

    path = Path(WRITES_FILE)
    try:
        handle = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return []
    with os.fdopen(handle, "rb") as noted:
        text = noted.read(100_000) if stat.S_ISREG(os.fstat(handle).st_mode) else b""
    with contextlib.suppress(OSError):
        path.unlink()
    lines = text.decode("utf-8", errors="replace").splitlines()
    paths = [line for line in dict.fromkeys(line.strip() for line in lines) if line]
    if not paths:
        return []
    shown = ", ".join(paths[:5]) + (f" and {len(paths) - 5} more" if len(paths) > 5 else "")
    return [f"the notebook tried to write outside the student's folders: {shown}"]


def _private_streams() -> Tuple[Any, Any]:
    """This script's own input and output; fds 0, 1 and 2 then point at the null device.

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


def read_frame(stream: Any) -> Optional[bytes]:
    """One message of the serving protocol: an 8-byte big-endian length, then that many bytes.

    Returns:
        The message, or None at the end of the stream.
    """
    head = stream.read(8)
    if len(head) < 8:
        return None
    size = int.from_bytes(head, "big")
    data = stream.read(size)
    return data if len(data) == size else None


def frame(data: bytes) -> bytes:
    """``data`` as one message of the serving protocol (see :func:`read_frame`)."""
    return len(data).to_bytes(8, "big") + data


def _kill_kernel_copies(kernel: Optional[int]) -> None:
    """Kill the copies of the kernel a cell forked and left running (after each cell).

    A process forked by the kernel without running another program (``os.fork()`` in a loop,
    a ``multiprocessing`` worker) is a second kernel sharing the first one's connections: it
    may answer the next cell's request in its place. Programs a cell started
    (``subprocess.Popen``) are left alone until the notebook ends (:func:`_kill_strays`).
    """
    if kernel is None:
        return
    try:
        command = Path(f"/proc/{kernel}/cmdline").read_bytes()
    except OSError:
        return
    for pid, entry in _processes(keep=[kernel]):
        try:
            if os.getpgid(pid) == kernel and (entry / "cmdline").read_bytes() == command:
                os.kill(pid, signal.SIGKILL)
        except OSError:
            continue


def _processes(keep: Sequence[int]) -> Iterator[Tuple[int, Path]]:
    """The processes in sight (in a sandbox: its own) but ``keep``: each pid and /proc entry."""
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and int(entry.name) not in keep:
            yield int(entry.name), entry


def _kill_strays(keep: Sequence[int]) -> int:
    """Kill every process of this user left in the sandbox but ``keep`` (between notebooks).

    A notebook may start processes that outlive its kernel (``subprocess.Popen`` of a
    server); the next notebook starts among none of them, as in a sandbox of its own.

    Returns:
        How many were killed (processes that had already ended are not counted).
    """
    me = str(os.getuid())
    killed = 0
    for pid, entry in _processes(keep):
        try:
            # /proc/PID/status, not the folder's owner: the folder of a process that is not
            # dumpable (as the kernels here, see _not_dumpable) belongs to root.
            fields = dict(
                line.split(":", 1)
                for line in (entry / "status").read_text().splitlines()
                if ":" in line
            )
            if fields.get("Uid", "").split()[:1] == [me] and not fields.get(
                "State", ""
            ).strip().startswith(("Z", "X")):
                os.kill(pid, signal.SIGKILL)
                killed += 1
        except OSError:
            continue
    return killed


def _not_dumpable() -> None:
    """Keep this process's memory and files out of the kernels' reach (Linux).

    The kernels run as the same user. A process that is not dumpable cannot be traced, and
    its ``/proc/PID/mem`` and ``/proc/PID/fd`` cannot be opened, by a process of that user
    without privileges, so a kernel can neither read this script's memory nor write on its
    answer pipe. The zygote and the kernels forked from it inherit the setting.
    """
    import ctypes

    with contextlib.suppress(Exception):
        ctypes.CDLL(None, use_errno=True).prctl(4, 0, 0, 0, 0)  # PR_SET_DUMPABLE, 0


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
    _not_dumpable()
    zygote = _start()
    import shutil
    import tempfile

    import nbformat

    given, answer = _private_streams()
    keep = [1, os.getpid()] + ([zygote.pid] if zygote is not None else [])
    channel = Channel(given, answer)
    while True:
        request = read_frame(given)
        if request is None:
            break
        try:
            message = json.loads(request)
            if "notebook" not in message:  # a late word of a test the grader gave up on
                continue
            notebook = nbformat.reads(message["notebook"], as_version=4)
            folder = str(Path(message["folder"]).absolute())
            # A new IPython folder for each notebook's kernel: nothing a notebook writes there
            # (a startup file, a configuration) reaches the next one.
            ipython = tempfile.mkdtemp(prefix="ipython-")
            os.environ["IPYTHONDIR"] = ipython
            try:
                _execute(notebook, folder, cell_seconds, zygote, sandboxed, channel)
            finally:
                shutil.rmtree(ipython, ignore_errors=True)
            if sandboxed:
                left = _kill_strays(keep)
                if left:
                    notebook.metadata[METADATA_KEY]["problems"].append(
                        f"the notebook left {left} process{'es' if left > 1 else ''} running "
                        "after its last cell; the grader stopped them"
                    )
            reply = {"notebook": nbformat.writes(notebook)}
        except Exception as error:  # the grader reports it for this notebook
            reply = {"problem": f"could not be run: {type(error).__name__}: {error}"}
            if sandboxed:
                _kill_strays(keep)
        answer.write(frame(json.dumps(reply).encode("utf-8")))
        answer.flush()
    _end(zygote)


def _start() -> Optional[Zygote]:
    """The zygote, unless turned off: forked first, before nbclient, zmq or asyncio is imported.

    See :class:`Zygote`.
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
    _, answer = _private_streams()
    _execute(notebook, ".", int(sys.argv[1]), zygote)
    answer.write(nbformat.writes(notebook).encode("utf-8"))
    answer.flush()
    _end(zygote)


if __name__ == "__main__":
    main()
