"""The kernel zygote: a process that has imported the kernel and the libraries, and forks kernels.

Each notebook's kernel is forked from it (:class:`Zygote`) rather than started as a new Python.
Runs inside the sandbox: the standard library only at load time (the zygote imports the rest
itself, see :data:`ZYGOTE_IMPORTS`).
"""

from __future__ import annotations

import contextlib
import json
import os
import select
import signal
import sys
import time
from pathlib import Path
from typing import Any, Dict, List, Mapping, NoReturn, Optional, Sequence, Tuple

__all__ = [
    "INLINE_BACKEND",
    "POLL_SECONDS",
    "ZYGOTE_IMPORTS",
    "ZYGOTE_SECONDS",
    "ZYGOTE_VARIABLE",
    "Zygote",
    "kernel_env",
    "threads",
]

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
INLINE_BACKEND = "module://matplotlib_inline.backend_inline"
#: How often the provisioner looks whether a kernel it killed has ended, in seconds.
POLL_SECONDS = 0.005


class Zygote:
    """A process that has imported the kernel and the course's libraries, and forks kernels.

    Starting a kernel the usual way runs a new Python, which imports ipykernel and then, in
    the notebook's first cell, numpy, matplotlib and duckielib. The zygote is forked from the
    server before the server reads the notebook or imports nbclient, zmq or asyncio (so it holds
    neither the notebook nor a thread); it imports all that while the server reads the notebook,
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
            time.sleep(POLL_SECONDS)
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
        the imports saw (see :func:`kernel_env`) and the file of ``ipykernel_launcher``; None
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
    # A new kernel's sys.path: without the folder the server's launcher put first, as
    # ipykernel_launcher takes out the one Python put first for it.
    if not sys.flags.safe_path:
        del sys.path[0]
    if not os.environ.get("MPLBACKEND"):  # the kernel sets it so before matplotlib's import
        os.environ["MPLBACKEND"] = INLINE_BACKEND
    env = kernel_env(os.environ)
    for name in ZYGOTE_IMPORTS:
        with contextlib.suppress(Exception):  # the notebook's own import says why
            __import__(name)
    launcher = importlib.util.find_spec("ipykernel_launcher")
    if threads() != 1 or launcher is None or launcher.origin is None:
        return None
    if kernel_env(os.environ) != env:  # an import set a variable the kernel would not have
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
            for pid in self.children:  # left only if the server ended without stopping them
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
        if kernel_env(request["env"]) != self.env:
            self.say({"failed": "the kernel's environment differs from the zygote's"})
        elif threads() != 1:
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


def kernel_env(env: Mapping[str, str]) -> Dict[str, str]:
    """The environment variables that matter to the zygote's imports, from a kernel's.

    ``JPY_PARENT_PID`` names the kernel's parent, set for each kernel, and ``IPYTHONDIR`` its
    IPython folder, new for each notebook (read when the kernel starts, not at import); an unset
    ``MPLBACKEND`` is the inline backend ipykernel sets.
    """
    kept = {key: value for key, value in env.items() if key not in ("JPY_PARENT_PID", "IPYTHONDIR")}
    if not kept.get("MPLBACKEND"):
        kept["MPLBACKEND"] = INLINE_BACKEND
    return kept


def threads() -> int:
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
    parent (here the zygote, which ends with the server).

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
