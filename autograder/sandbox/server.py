"""The grader's end of a sandbox that runs one student's notebooks (:class:`NotebookServer`).

The other end is the server in the sandbox (:mod:`autograder.sandbox.inside.serve`); both speak
the messages of :mod:`autograder.sandbox.inside.wire`. Here every read and write has a
deadline and every message a size limit: whatever the sandbox does, the grader waits no longer
than the notebook's time and reads no more than the limits allow.
"""

from __future__ import annotations

import contextlib
import os
import select
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

from autograder.sandbox.inside import wire

__all__ = ["RUNNER", "SHARED_INSIDE", "NotebookServer"]

#: The sandbox's server, started as ``python RUNNER --serve CELL_SECONDS``.
RUNNER = Path(__file__).resolve().parent / "inside"
#: Where the folder of files the grader's tests hand to the student's code appears (read-only)
#: in the sandbox.
SHARED_INSIDE = "/grader"


class NotebookServer:
    """The sandbox that runs one student's notebooks, one after the other (``inside --serve``).

    One sandbox and one pre-warmed kernel launcher serve all of the student's notebooks, each
    in a new kernel, so the libraries are imported once per student rather than once per
    notebook. A notebook that runs out of time, or a sandbox that dies, costs that notebook
    only: the sandbox is killed and a new one serves the next notebook.
    """

    def __init__(self, folder: Path, limits: Any, use_sandbox: bool, shared: Path) -> None:
        self.folder = folder
        self.shared = shared
        self.limits = limits
        self.use_sandbox = use_sandbox
        self.process: Optional[subprocess.Popen] = None
        self.errors: Any = None
        self.scratch: Any = None

    def _start(self) -> subprocess.Popen:
        from autograder.sandbox import sandboxed_command
        from autograder.sandbox.bubblewrap import scratch

        command = [sys.executable, str(RUNNER), "--serve", str(self.limits.cell_seconds)]
        if self.use_sandbox:
            self.scratch = scratch()
            command = sandboxed_command(
                [*command, "--sandboxed"],
                self.folder,
                self.limits,
                course=self.folder,
                shared=(self.shared, SHARED_INSIDE),
                tmp=self.scratch.__enter__(),
            )
        from autograder.sandbox import joined, student_groups

        self.errors = tempfile.TemporaryFile()  # noqa: SIM115 - open for the sandbox's life
        if self.use_sandbox:
            command = joined(student_groups(self.limits), command)
        return subprocess.Popen(
            command,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self.errors,
            cwd=self.folder,
            start_new_session=True,
        )

    def run(
        self, name: str, text: str, tests: Any = None, seconds: Optional[float] = None
    ) -> Tuple[Optional[str], str]:
        """Run notebook ``name`` (its folder's name); its executed text, or None and why.

        Args:
            name: the notebook's folder.
            text: the notebook to run.
            tests: called as ``tests(kind, grade_id, ask)`` when the run reaches a test the
                grader runs on its side (``kind``: ``"test"``, its visible part where the
                notebook reaches it; ``"hidden"``, its hidden part after the last cell;
                ``"rerun"``, all of it again, in a new kernel after one died);
                ``ask(request, until, seconds)`` sends a call to the kernel and returns its
                answer (a text).
            seconds: the notebook's wall time (all cells and the kernel's start); its own
                limit unless told.
        """
        from autograder.calls import Abandon, CallsBroken

        seconds = self.limits.submission_seconds if seconds is None else seconds
        deadline = time.monotonic() + seconds
        if self.process is None:
            self.process = self._start()
        request = wire.encode({"folder": name, "notebook": text})
        final: List[Dict[str, Any]] = []
        process = self.process

        def ask(call: str, until: float, cell_seconds: int) -> str:
            if final:
                raise CallsBroken("the notebook's kernel had stopped")
            try:
                _write_all(process.stdin, wire.encode({"call": call}), deadline)
                while True:
                    got = self._reply(min(until, deadline), deadline)
                    if "answer" in got:
                        return str(got["answer"])
                    if "notebook" in got or "problem" in got:
                        final.append(got)
                        raise CallsBroken("the notebook's kernel stopped during the test")
            except TimeoutError as error:
                if time.monotonic() < deadline:
                    raise CallsBroken(
                        f"the test ran out of the {cell_seconds} s a cell may take"
                    ) from None
                raise Abandon from error
            except (OSError, EOFError, ValueError, _TooMuch) as error:
                raise Abandon from error

        try:
            _write_all(self.process.stdin, request, deadline)
            while True:
                reply = self._reply(deadline)
                kind = next((kind for kind in wire.TEST_KINDS if kind in reply), None)
                if kind is not None and tests is not None:
                    tests(kind, str(reply[kind]), ask)
                    if final:
                        reply = final[0]
                        break
                    _write_all(self.process.stdin, wire.encode({"end": True}), deadline)
                elif "answer" not in reply and kind is None:
                    break
        except (TimeoutError, OSError, EOFError, ValueError, _TooMuch, Abandon) as error:
            # A test's call that could not go on ended the run the same ways.
            cause = error.__cause__ if isinstance(error, Abandon) else error
            return None, self._ended(cause, seconds)
        if "notebook" not in reply:
            return None, str(reply.get("problem", "gave no notebook"))[:500]
        return str(reply["notebook"]), ""

    def _ended(self, error: Optional[BaseException], seconds: float) -> str:
        """End the sandbox after its run stopped with ``error``; why, in a sentence."""
        if isinstance(error, _TooMuch):
            why = f"answered with {error} bytes, more than the grader reads"
        elif isinstance(error, TimeoutError):
            why = (
                f"ran out of its {seconds} s (all cells and the kernel's start); the cells "
                "after that never ran"
            )
        else:
            why = self._last_words() or "stopped with no output"
        self.stop()
        return why

    def _reply(self, deadline: float, whole: Optional[float] = None) -> Dict[str, Any]:
        """The sandbox's next message; TimeoutError, EOFError, ValueError or _TooMuch.

        A message that has begun by ``deadline`` is read whole by ``whole`` (the notebook's
        own deadline): a message left half read would make the next one unreadable.
        """
        assert self.process is not None
        assert self.process.stdout is not None
        whole = deadline if whole is None else max(deadline, whole)
        size = wire.size(_read_exact(self.process.stdout, wire.HEADER, deadline, whole))
        if size > self.limits.output_bytes:
            raise _TooMuch(size)
        return wire.decode(_read_exact(self.process.stdout, size, whole))

    def _last_words(self) -> str:
        if self.errors is None:
            return ""
        self.errors.seek(0)
        return self.errors.read(1_000_000).decode("utf-8", errors="replace").strip()[-500:]

    def stop(self) -> None:
        """End the sandbox and everything in it."""
        if self.process is None:
            return
        # _start always opens both pipes; Popen only types them as optional.
        if self.process.stdin is not None:
            with contextlib.suppress(OSError):
                self.process.stdin.close()
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.process.pid, signal.SIGKILL)
        self.process.wait()
        if self.process.stdout is not None:
            self.process.stdout.close()
        self.errors.close()
        if self.scratch is not None:
            self.scratch.__exit__(None, None, None)
        self.process = self.errors = self.scratch = None


class _TooMuch(Exception):
    """The sandbox sent a message larger than the grader reads."""


def _write_all(stream: Any, data: bytes, deadline: float) -> None:
    """Write ``data`` to a pipe before ``deadline`` (monotonic), or raise TimeoutError."""
    fd = stream.fileno()
    os.set_blocking(fd, False)
    view = memoryview(data)
    while view:
        left = deadline - time.monotonic()
        if left <= 0 or not select.select([], [fd], [], left)[1]:
            raise TimeoutError
        try:
            view = view[os.write(fd, view) :]
        except BlockingIOError:
            continue


def _read_exact(stream: Any, size: int, deadline: float, then: Optional[float] = None) -> bytes:
    """Read ``size`` bytes from a pipe before ``deadline``; EOFError if it closes first.

    Once the first byte is in, the rest may come until ``then`` (``deadline`` unless told).
    """
    fd = stream.fileno()
    chunks, got = [], 0
    while got < size:
        left = (deadline if not got or then is None else then) - time.monotonic()
        if left <= 0 or not select.select([fd], [], [], left)[0]:
            raise TimeoutError
        chunk = os.read(fd, min(size - got, 1 << 20))
        if not chunk:
            raise EOFError
        chunks.append(chunk)
        got += len(chunk)
    return b"".join(chunks)
