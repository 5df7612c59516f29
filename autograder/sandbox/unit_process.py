"""The grader's process for one student: unprivileged, in a view and on a disk of its own.

Each student is graded in a process of its own (:mod:`autograder.unit`). It runs no line of the
student's (their code runs in its sandboxes), but it reads their files and talks to their code,
so it is built as if it could be taken over. Where the grader runs as root (which it needs to
give each student a user of their own), the process for a student does not keep root:

- it runs as the student's own unprivileged user (:func:`autograder.sandbox.unit_user`), with
  no capability and no way to gain one (``no_new_privs``), its address space bounded
  (``Limits.grader_memory_bytes``), no network, and in the student's control groups, so the
  CPU, memory and process limits it shares with that student's sandboxes hold for it too;
- it sees a view of the machine of its own (a mount namespace made by bubblewrap): the system,
  the Python environment and the course's code read-only, the course for this grading (with
  its hidden tests) read-only at ``/unit/course``, the student's files read-only at
  ``/unit/submission``, and ``/unit/out``, the one folder of the machine it writes to (its
  result). Nothing else: not the repository's ``solutions/``, not the class's results or
  gradebook, not another student's files;
- everything it writes (nbgrader's trees, the notebooks, the missions' bags) lies on a file
  system of its own (``/unit``, :data:`GRADER_DISK_BYTES`, in memory), and everything the
  student's sandboxes write (their folders, their ``/tmp``) on another, of
  ``Limits.disk_bytes`` (``/unit/student``): a student who fills theirs fills neither the disk
  the class is graded on nor the grader's files for them, which are graded as usual.

The student's sandboxes then run inside it, as bubblewrap sandboxes without root: a user
namespace of the same user, in which no further one can be made
(:func:`autograder.sandbox.bubblewrap.sandboxed_command`).
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Dict, List

from autograder.sandbox.bubblewrap import (
    GRADER_TASKS,
    Limits,
    SandboxUnavailable,
    _readonly_paths,
    fonts_view,
    joined,
    namespaces,
    read_only_view,
    student_groups,
    unit_user,
)
from autograder.sandbox.bubblewrap import check_sandbox as _check_the_sandbox
from autograder.sandbox.groups import end_student_groups
from autograder.sandbox.limits import STUDENT_DISK_VARIABLE

__all__ = [
    "STUDENT_DISK",
    "UNIT_INSIDE",
    "apart",
    "check_sandbox",
    "grader_paths",
    "unit_command",
]

#: Where the grader's process for a student sees its own folder.
UNIT_INSIDE = "/unit"
#: The file system the student's sandboxes write in (``Limits.disk_bytes``).
STUDENT_DISK = f"{UNIT_INSIDE}/student"
#: matplotlib's cache folder there (``MPLCONFIGDIR``), where its font list is.
_MATPLOTLIB_CACHE = f"{UNIT_INSIDE}/tmp/matplotlib"
#: The size of the file system of the grader's own files for a student (nbgrader's trees, the
#: gradebook's copy, the missions' bags): the reference course needs about 60 MB.
GRADER_DISK_BYTES = 1024**3
#: The variables of the grader's environment the process for a student keeps (the course's
#: own switches); every other one is left behind.
KEPT_PREFIX = "DUCKIE_"


def apart(use_sandbox: bool) -> bool:
    """Whether the process for a student runs apart from the grader (as root, with a sandbox)."""
    return use_sandbox and os.geteuid() == 0


def unit_limits(limits: Limits) -> Limits:
    """The limits of the student's control groups when the grader's process for them is in too."""
    return dataclasses.replace(limits, processes=limits.processes + GRADER_TASKS)


def grader_paths() -> List[str]:
    """What the process for a student sees read-only: the sandbox's view, and the grader."""
    grader = str(Path(__file__).resolve().parents[1])
    paths = [*_readonly_paths(), grader]
    # A path inside another one is shown with it.
    return [
        path
        for path in paths
        if not any(path != other and path.startswith(other.rstrip("/") + "/") for other in paths)
    ]


def unit_command(
    command: List[str], folder: Path, course: Path, limits: Limits, uid: int
) -> List[str]:
    """The command line that runs ``command`` as the grader's process for one student.

    Args:
        command: what to run (``python -I -m autograder.unit /unit``).
        folder: the grader's folder for this student: ``task.json`` and ``submission/``, shown
            read-only, and ``out/`` (owned by ``uid``), shown writable; its own mode keeps
            everyone else out.
        course: the course's folder for this grading (``source/``, ``release/``,
            ``gradebook.db``), readable by ``uid``, shown read-only.
        limits: what the student may use (``disk_bytes``, ``grader_memory_bytes``, the
            control groups).
        uid: the student's user, which the process becomes.
    """
    bwrap = shutil.which("bwrap") or "bwrap"
    # The machine's process ids and control groups, as the machine's /proc below shows them.
    args = [bwrap, *namespaces(processes=False, control_groups=False)]
    tmp = ["--perms", "1777", "--size", str(64 * 1024**2), "--tmpfs", "/tmp"]
    args += read_only_view(grader_paths(), tmp)[0]
    args += [
        "--dev", "/dev",
        # The machine's own /proc: the sandboxes made inside mount a /proc of their own, which
        # the kernel allows only where one is already shown whole. Its processes are not this
        # user's to touch.
        "--bind", "/proc", "/proc",
        "--perms", "1777", "--size", str(GRADER_DISK_BYTES), "--tmpfs", UNIT_INSIDE,
        "--perms", "1777", "--dir", f"{UNIT_INSIDE}/tmp",
        *fonts_view(_MATPLOTLIB_CACHE),
        "--perms", "1777", "--size", str(limits.disk_bytes), "--tmpfs", STUDENT_DISK,
        "--ro-bind", str(folder / "task.json"), f"{UNIT_INSIDE}/task.json",
        "--ro-bind", str(folder / "submission"), f"{UNIT_INSIDE}/submission",
        "--ro-bind", str(course), f"{UNIT_INSIDE}/course",
        "--bind", str(folder / "out"), f"{UNIT_INSIDE}/out",
        "--chdir", UNIT_INSIDE,
        # Only to become the student's user just below; setpriv then drops every capability.
        "--cap-add", "CAP_SETUID",
        "--cap-add", "CAP_SETGID",
        "setpriv",
        f"--reuid={uid}",
        f"--regid={uid}",
        "--clear-groups",
        "--no-new-privs",
        "--inh-caps=-all",
        "--bounding-set=-all",
        "prlimit",
        f"--as={limits.grader_memory_bytes}",
        f"--nproc={limits.processes + GRADER_TASKS}",
        f"--fsize={limits.file_bytes}",
        "--core=0",
        "--",
        "env",
        "-i",
        *[f"{key}={value}" for key, value in _environment().items()],
        *command,
    ]  # fmt: skip
    return joined(student_groups(unit_limits(limits)), args)


#: Run as the grader's process for a student: a sandbox inside it, which prints its user.
_CHAIN_PROBE = """
import sys
from pathlib import Path
from autograder.sandbox.bubblewrap import sandboxed_command
from autograder.sandbox.limits import Limits
import subprocess
probe = [sys.executable, "-c", "import os; print(os.getuid())"]
command = sandboxed_command(probe, Path("/unit/student"), Limits())
done = subprocess.run(command, capture_output=True, text=True, timeout=60)
print(done.stdout.strip() or (done.stderr.strip().splitlines() or ["no message"])[-1])
"""


def check_sandbox() -> None:
    """Make sure the sandbox, and the grader's process for a student around it, can run here.

    Raises:
        SandboxUnavailable: saying what is missing and what to do.
    """
    _check_the_sandbox()
    if os.geteuid() != 0:
        return
    uid = unit_user()
    with tempfile.TemporaryDirectory(prefix="duckie-check-") as scratch:
        base = Path(scratch)
        for name in ("submission", "out", "course"):
            (base / name).mkdir()
        (base / "task.json").write_text("{}", encoding="utf-8")
        os.chown(base / "out", uid, uid)
        limits = dataclasses.replace(Limits(), uid=uid)
        command = unit_command(
            [sys.executable, "-I", "-c", _CHAIN_PROBE], base, base / "course", limits, uid
        )
        try:
            done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)
        except (OSError, subprocess.TimeoutExpired) as error:
            done = subprocess.CompletedProcess(command, 1, "", str(error))
        finally:
            end_student_groups(uid)
    if done.stdout.strip() != str(uid):
        said = (done.stdout.strip() or done.stderr.strip() or "no message").splitlines()[-1]
        raise SandboxUnavailable(
            "The grader's process for a student could not start its sandbox here: "
            f"{said[:300]} (it runs as an unprivileged user and needs unprivileged user "
            "namespaces: sysctl user.max_user_namespaces above 0, and on Ubuntu "
            "kernel.apparmor_restrict_unprivileged_userns=0 or an AppArmor profile that "
            "lets bwrap make them)."
        )


def _environment() -> Dict[str, str]:
    """The environment of the process for a student: its own, and the course's switches."""
    base = {
        "HOME": f"{UNIT_INSIDE}/tmp",
        "TMPDIR": f"{UNIT_INSIDE}/tmp",
        "USER": "grader",
        "LOGNAME": "grader",
        # nbgrader runs alembic by name: the environment's programs first.
        "PATH": f"{Path(sys.executable).parent}:/usr/bin:/bin",
        "LANG": "C.UTF-8",
        "MPLBACKEND": "Agg",
        "MPLCONFIGDIR": _MATPLOTLIB_CACHE,
        "PYTHONDONTWRITEBYTECODE": "1",
        "OPENBLAS_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1",
    }
    base.update({key: value for key, value in os.environ.items() if key.startswith(KEPT_PREFIX)})
    base[STUDENT_DISK_VARIABLE] = STUDENT_DISK
    return base
