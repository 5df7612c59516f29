"""The processes a notebook leaves behind in the sandbox, and the server kept out of their reach.

Runs inside the sandbox: the standard library only.
"""

from __future__ import annotations

import contextlib
import os
import signal
from pathlib import Path
from typing import Iterator, Optional, Sequence, Tuple

__all__ = ["kill_kernel_copies", "kill_strays", "not_dumpable"]


def kill_kernel_copies(kernel: Optional[int]) -> None:
    """Kill the copies of the kernel a cell forked and left running (after each cell).

    A process forked by the kernel without running another program (``os.fork()`` in a loop,
    a ``multiprocessing`` worker) is a second kernel sharing the first one's connections: it
    may answer the next cell's request in its place. Programs a cell started
    (``subprocess.Popen``) are left alone until the notebook ends (:func:`kill_strays`).
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


def kill_strays(keep: Sequence[int]) -> int:
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
            # dumpable (as the kernels here, see not_dumpable) belongs to root.
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


def not_dumpable() -> None:
    """Keep this process's memory and files out of the kernels' reach (Linux).

    The kernels run as the same user. A process that is not dumpable cannot be traced, and
    its ``/proc/PID/mem`` and ``/proc/PID/fd`` cannot be opened, by a process of that user
    without privileges, so a kernel can neither read the server's memory nor write on its
    answer pipe. The zygote and the kernels forked from it inherit the setting.
    """
    import ctypes

    with contextlib.suppress(Exception):
        ctypes.CDLL(None, use_errno=True).prctl(4, 0, 0, 0, 0)  # PR_SET_DUMPABLE, 0
