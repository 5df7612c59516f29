"""The control groups of one student's grading: the CPUs, memory and processes they share.

All of one student's sandboxed processes (and, where the grader runs as root, the grader's own
process for that student, :mod:`.unit_process`) share one set of control groups, made inside
the grader's own: ``Limits.cpus`` CPUs, ``Limits.total_memory_bytes`` of memory and
``Limits.processes`` processes in all. Busy loops a student leaves running then slow only that
student's grading. Only root makes them; where the machine lets the grader make none (no
controller, no right to write it), the per-process limits (``prlimit``) still hold.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
from typing import Dict, List, Optional, Sequence

from autograder.sandbox.limits import Limits

__all__ = ["end_student_groups", "joined", "remove_when_empty", "student_groups"]

#: Where the control groups of one student's sandboxes are made: cgroup v1's controllers (one
#: folder each), or cgroup v2's single tree.
CGROUP_V1 = Path("/sys/fs/cgroup")
CGROUP_V2 = (Path("/sys/fs/cgroup/unified"), Path("/sys/fs/cgroup"))
_PERIOD = 100_000


def _quota(limits: Limits) -> int:
    """The CPU time the student's processes may use per :data:`_PERIOD`, in microseconds."""
    return max(1000, int(limits.cpus * _PERIOD))


def _v1_settings(limits: Limits) -> Dict[str, Dict[str, str]]:
    return {
        "cpu": {"cpu.cfs_period_us": str(_PERIOD), "cpu.cfs_quota_us": str(_quota(limits))},
        "memory": {"memory.limit_in_bytes": str(limits.total_memory_bytes)},
        "pids": {"pids.max": str(limits.processes)},
    }


def student_groups(limits: Limits) -> List[Path]:
    """The control groups of user ``limits.uid``'s sandboxes, made on first use.

    All of one student's sandboxed processes together may use at most ``limits.cpus`` CPUs,
    ``limits.total_memory_bytes`` of memory and ``limits.processes`` processes. Where the
    machine lets the grader make no control group (no controller, no right to write it), the
    list is empty and the per-process limits (``prlimit``) and the per-user process limit
    still hold.
    """
    if os.geteuid() != 0:  # only root makes them (the grader's process for a student is in them)
        return []
    name = f"duckie-{limits.uid}"
    made: List[Path] = []
    for controller, settings in _v1_settings(limits).items():
        root = _own_group(controller)
        if root is not None and _make(root / name, settings):
            made.append(root / name)
    if made:
        return made
    for root in CGROUP_V2:
        enabled = _text(root / "cgroup.subtree_control").split()
        if not {"cpu", "memory", "pids"} <= set(enabled):
            continue
        settings = {
            "cpu.max": f"{_quota(limits)} {_PERIOD}",
            "memory.max": str(limits.total_memory_bytes),
            "pids.max": str(limits.processes),
        }
        if _make(root / name, settings):
            return [root / name]
    return []


def _own_group(controller: str) -> Optional[Path]:
    """The folder of this process's own cgroup v1 group of ``controller``, if it has one.

    A student's group is made inside it, so whatever limits the grader's own group has (a
    container's memory) hold for the students' too.
    """
    for line in _text(Path("/proc/self/cgroup")).splitlines():
        _, controllers, path = line.split(":", 2)
        if controller in controllers.split(","):
            folder = CGROUP_V1 / controller / path.lstrip("/")
            return folder if (folder / "cgroup.procs").is_file() else None
    return None


def _make(group: Path, settings: Dict[str, str]) -> bool:
    try:
        group.mkdir(exist_ok=True)
        for file, value in settings.items():
            (group / file).write_text(value)
    except OSError:
        with contextlib.suppress(OSError):
            group.rmdir()
        return False
    return True


def _text(path: Path) -> str:
    try:
        return path.read_text()
    except OSError:
        return ""


def joined(groups: Sequence[Path], command: Sequence[str]) -> List[str]:
    """``command``, started from within ``groups`` (so are all the processes it starts)."""
    if not groups:
        return list(command)
    # The shell moves itself into each group, then becomes the command.
    script = 'for group in "$@"; do [ "$group" = -- ] && break; echo $$ > "$group"; shift; done'
    script += '; shift; exec "$@"'
    procs = [str(group / "cgroup.procs") for group in groups]
    return ["/bin/sh", "-c", script, "sh", *procs, "--", *command]


def _remove(group: Path, tries: int, kill: bool = False) -> None:
    """Remove ``group`` once no process is left in it, trying ``tries`` times 10 ms apart.

    With ``kill``, every process still in it is killed first at each try.
    """
    import signal
    import time

    for _ in range(tries):
        if kill:
            for pid in _text(group / "cgroup.procs").split():
                with contextlib.suppress(OSError, ValueError):
                    os.kill(int(pid), signal.SIGKILL)
        try:
            group.rmdir()
            return
        except FileNotFoundError:
            return
        except OSError:
            time.sleep(0.01)


def remove_when_empty(groups: Sequence[Path]) -> None:
    """Remove the groups once the processes just killed in them are gone (0.1 s at most).

    A group another sandbox of the same student still uses stays (its unit removes it).
    """
    for group in groups:
        _remove(group, tries=10)


def end_student_groups(uid: int) -> None:
    """Kill what is left in user ``uid``'s control groups, and remove them (root only).

    The grader's process for a student runs in that student's groups: it never ends them.
    """
    if os.geteuid() != 0:
        return
    name = f"duckie-{uid}"
    owners = [_own_group(controller) for controller in ("cpu", "memory", "pids")]
    candidates = [owner / name for owner in owners if owner is not None]
    candidates += [root / name for root in CGROUP_V2]
    for group in candidates:
        if group.is_dir():
            _remove(group, tries=100, kill=True)
