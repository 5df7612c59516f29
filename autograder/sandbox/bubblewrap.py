"""The sandbox a student's code runs in while it is graded: bubblewrap, as an unprivileged user.

nbgrader runs student code with the rights of whoever grades. Here every submission's code
runs instead inside a bubblewrap container (Debian's ``bwrap``) built from scratch:

- it sees only the Python environment and the system's libraries (read-only) and its own
  folder (``/sandbox``, writable); not the repository (so not ``solutions/``), not the
  gradebook, not other students' folders, not the instructor's home;
- it has no network (its own network namespace, with only its own loopback: the kernel's
  ports cannot collide with another sandbox's, the race plain nbgrader has in parallel);
- it runs as the unprivileged user ``nobody``, in its own PID namespace, with limits on
  memory (address space), processes (so a fork bomb stops at the limit) and CPU time, and it
  dies with the grader.

Wall time is bounded by the caller (per cell by nbgrader's executor, per submission by the
subprocess timeout here).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, Iterator, List, Optional, Sequence, Tuple

from duckielib.errors import DuckielibError

__all__ = [
    "Limits",
    "end_student_groups",
    "student_groups",
    "SandboxError",
    "SandboxUnavailable",
    "check_sandbox",
    "run",
    "sandboxed_command",
]

#: The unprivileged user and group the code runs as.
NOBODY = 65534
#: The first of the user ids given to students' gradings (:func:`unit_user`).
FIRST_UNIT_USER = 1_000_000
#: Where the submission's own folder appears inside the sandbox.
INSIDE = "/sandbox"
#: Where the student's notebooks appear (read-only) when a notebook needs its neighbours.
COURSE = "/course"


class SandboxError(DuckielibError):
    """Running code in the sandbox failed for a reason of the grader's, not the student's."""


class SandboxUnavailable(SandboxError):
    """bubblewrap is missing or cannot create a sandbox on this machine."""


@dataclass(frozen=True)
class Limits:
    """What one submission may use.

    Attributes:
        cell_seconds: wall time of one notebook cell.
        submission_seconds: wall time of one notebook, all cells and the kernel's start.
        memory_bytes: address space of each process (a 20 GB allocation fails at once).
        processes: processes and threads of the sandbox user (a fork bomb stops there).
        cpu_seconds: CPU time of each process.
        mission_seconds: wall time of the driving run (the mission on the virtual Duckiebot).
        stall_seconds: wall time a node of the driving run may compute without calling rospy
            (simulated time stands still meanwhile) before the run stops it, saying why.
        file_bytes: the largest file a process may write (its standard output too).
        output_bytes: the most the grader reads of a run's standard output and error.
        uid: the unprivileged user (and group) the code runs as. The process limit counts
            every process of that user, so each student's grading uses a user of its own
            (:func:`unit_user`): a fork bomb cannot starve another student's sandbox.
        cpus: how many CPUs all of one student's sandboxed processes may use together, where
            the machine lets the grader make control groups (:func:`student_groups`): busy
            loops a student leaves running slow only that student's grading.
        total_memory_bytes: the memory all of one student's sandboxed processes may use
            together (a control group, as ``cpus``).
    """

    cell_seconds: int = 60
    submission_seconds: int = 600
    memory_bytes: int = 4 * 1024**3
    processes: int = 256
    cpu_seconds: int = 900
    mission_seconds: int = 180
    stall_seconds: int = 10
    file_bytes: int = 1024**3
    output_bytes: int = 256 * 1024**2
    uid: int = NOBODY
    cpus: float = 1.0
    total_memory_bytes: int = 6 * 1024**3


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


def _remove_when_empty(groups: Sequence[Path]) -> None:
    """Remove the groups once the processes just killed in them are gone (0.1 s at most).

    A group another sandbox of the same student still uses stays (its unit removes it).
    """
    for group in groups:
        _remove(group, tries=10)


def end_student_groups(uid: int) -> None:
    """Kill what is left in user ``uid``'s control groups, and remove them."""
    name = f"duckie-{uid}"
    owners = [_own_group(controller) for controller in ("cpu", "memory", "pids")]
    candidates = [owner / name for owner in owners if owner is not None]
    candidates += [root / name for root in CGROUP_V2]
    for group in candidates:
        if group.is_dir():
            _remove(group, tries=100, kill=True)


def unit_user() -> int:
    """A user id of its own for one student's grading, among 2**24 that no account uses."""
    import secrets

    return FIRST_UNIT_USER + secrets.randbelow(2**24)


def _readonly_paths() -> List[str]:
    """What the sandbox sees read-only: the system, Python, the library, the robot project.

    Notebook 11 reads the course's robot project (``robot_nodes/``) and prepares a copy of it
    with the library's robot modules, as students do.
    """
    import duckielib
    from duckielib.tools.deploy import PROJECT

    paths = ["/usr", "/etc", sys.prefix, sys.base_prefix]
    library = Path(duckielib.__file__).resolve().parent
    # Of the grader, only what runs in the sandbox: its server (`inside/`) and the calls' kernel
    # side (not the scoring code, the tests' data or the gradebook's handling).
    wing = Path(__file__).resolve().parent
    paths += [str(library), str(wing / "inside"), str(wing.parent / "calls.py"), str(PROJECT)]
    real_python = Path(sys.executable).resolve().parent.parent
    paths.append(str(real_python))
    unique: List[str] = []
    for path in paths:
        if path not in unique and Path(path).exists():
            unique.append(path)
    return unique


def _generated_robot_folders() -> List[str]:
    """The folders of the robot project that ``duckie robot prepare`` writes, where they exist."""
    from duckielib.tools.deploy import GENERATED, PROJECT

    return [str(PROJECT / name) for name in GENERATED if (PROJECT / name).is_dir()]


def _parents(path: str) -> List[str]:
    parts = Path(path).parts[1:-1]
    return ["/" + "/".join(parts[: index + 1]) for index in range(len(parts))]


def sandboxed_command(
    command: Sequence[str],
    folder: Path,
    limits: Limits,
    env: Optional[Dict[str, str]] = None,
    course: Optional[Path] = None,
    shared: Optional[Tuple[Path, str]] = None,
) -> List[str]:
    """The command line that runs ``command`` in a sandbox whose only writable folder is ``folder``.

    Args:
        command: what to run, inside the sandbox.
        folder: the writable folder, the command's working directory (``/sandbox``); it must
            be writable by the user ``nobody`` (the caller owns it over).
        limits: what the sandbox may use.
        env: environment variables besides the sandbox's own.
        course: the folder of the student's assignment folders (``NAME/NAME.ipynb``), shown
            read-only at ``/course`` with ``folder`` writable at ``/course/NAME`` (``NAME`` is
            ``folder``'s name), so a notebook can load the student's other notebooks from
            ``..`` as it does in JupyterLab. When it is ``folder`` itself, all of it is
            writable at ``/course``, the working folder (to run every notebook in turn).
        shared: a folder of the grader's and where the sandbox sees it, read-only: files the
            grader's tests hand to the student's code (:mod:`autograder.calls`).
    """
    bwrap = shutil.which("bwrap")
    if bwrap is None:
        raise SandboxUnavailable(
            "bubblewrap (bwrap) is not installed; install it with `make ros` (Debian: "
            "apt-get install bubblewrap), or grade without a sandbox with --no-sandbox "
            "(student code then runs with your rights)."
        )
    args = [bwrap, *_system_view()]
    if course is None:
        inside = INSIDE
    elif Path(course) == Path(folder):  # all the student's folders, writable
        inside, course = COURSE, None
    else:
        inside = f"{COURSE}/{Path(folder).name}"
    if course is not None:
        args += ["--ro-bind", str(course), COURSE]
    if shared is not None:
        args += ["--ro-bind", str(shared[0]), shared[1]]
    args += ["--bind", str(folder), inside, "--chdir", inside, *_as_student(limits)]
    return args + _environment(env) + list(command)


def _system_view() -> List[str]:
    """Bubblewrap's options for what the sandbox sees of the system: read-only, its own /tmp."""
    args = [
        "--unshare-net",
        "--unshare-pid",
        "--unshare-ipc",
        "--unshare-uts",
        "--unshare-cgroup-try",
        "--die-with-parent",
        "--new-session",
        "--symlink", "usr/lib", "/lib",
        "--symlink", "usr/lib64", "/lib64",
        "--symlink", "usr/bin", "/bin",
        "--symlink", "usr/sbin", "/sbin",
    ]  # fmt: skip
    # /tmp first: a Python environment that lives under /tmp is bound on top of it below.
    args += ["--perms", "1777", "--tmpfs", "/tmp"]
    made = {"/usr", "/etc", "/lib", "/lib64", "/bin", "/sbin", "/tmp"}
    for path in _readonly_paths():
        for parent in _parents(path):
            if parent not in made:
                args += ["--perms", "0755", "--dir", parent]
                made.add(parent)
        args += ["--ro-bind", path, path]
        made.add(path)
    # `duckie robot prepare` writes a solution into the robot project (the reference one, on an
    # instructor's machine): those folders stay out of sight.
    for path in _generated_robot_folders():
        args += ["--tmpfs", path]
    args += [
        "--dev", "/dev",
        "--proc", "/proc",
    ]  # fmt: skip
    return args


def _as_student(limits: Limits) -> List[str]:
    """The command line's middle: become the unprivileged user, with ``limits``, no environment."""
    return [
        # Only to become nobody just below; setpriv then drops every capability.
        "--cap-add", "CAP_SETUID",
        "--cap-add", "CAP_SETGID",
        "setpriv",
        f"--reuid={limits.uid}",
        f"--regid={limits.uid}",
        "--clear-groups",
        "--no-new-privs",
        "--inh-caps=-all",
        "--bounding-set=-all",
        "prlimit",
        f"--as={limits.memory_bytes}",
        f"--nproc={limits.processes}",
        f"--cpu={limits.cpu_seconds}",
        f"--fsize={limits.file_bytes}",
        "--core=0",
        "--",
        "env",
        "-i",
    ]  # fmt: skip


def _environment(env: Optional[Dict[str, str]]) -> List[str]:
    """The sandbox's environment variables, as ``env -i`` takes them: its own, then ``env``."""
    base = {
        "HOME": "/tmp",
        "USER": "student",  # the user may have no name on this machine
        "LOGNAME": "student",
        "PATH": f"{Path(sys.executable).parent}:/usr/bin:/bin",
        "LANG": "C.UTF-8",
        "MPLBACKEND": "Agg",
        "MPLCONFIGDIR": "/tmp/matplotlib",
        "JUPYTER_RUNTIME_DIR": "/tmp/jupyter",
        "IPYTHONDIR": "/tmp/ipython",
        "PYTHONDONTWRITEBYTECODE": "1",
        # One thread per numerical library: the grader runs several sandboxes at once.
        "OPENBLAS_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1",
    }
    base.update(env or {})
    return [f"{key}={value}" for key, value in base.items()]


class Started:
    """A command started by :func:`started`: its process and where its output goes.

    Attributes:
        process: the running process.
        stdout: the captured standard output, read once it has ended (:meth:`outputs`).
        stderr: the captured standard error, likewise.
    """

    def __init__(self, process: subprocess.Popen, out, err, limit: int) -> None:
        self.process = process
        self._files = (out, err)
        self._limit = limit

    def outputs(self) -> Tuple[str, str]:
        """What it printed, as text, each cut at the sandbox's output limit."""
        out, err = (_bounded_text(handle, self._limit) for handle in self._files)
        return out, err


@contextlib.contextmanager
def started(
    command: Sequence[str],
    folder: Path,
    limits: Limits,
    use_sandbox: bool = True,
    stdin: Optional[str] = None,
    env: Optional[Dict[str, str]] = None,
    course: Optional[Path] = None,
    pass_fds: Sequence[int] = (),
    shared: Optional[Tuple[Path, str]] = None,
) -> Iterator[Started]:
    """Start ``command`` in ``folder``, in the sandbox unless told, and end it on leaving.

    On leaving the block, everything it started is killed (it is meant to have ended by
    then: wait for :attr:`Started.process` inside the block) and its control groups removed.
    ``pass_fds`` are file descriptors the command inherits (the sandbox keeps them open);
    ``shared`` a folder shown read-only (see :func:`sandboxed_command`). Other arguments as
    :func:`run`.
    """
    import signal
    import tempfile

    environment = None
    if use_sandbox:
        command = sandboxed_command(command, folder, limits, env=env, course=course, shared=shared)
    elif env:
        environment = {**os.environ, **env}
    with tempfile.TemporaryFile() as given, tempfile.TemporaryFile() as out, (
        tempfile.TemporaryFile()
    ) as err:
        given.write((stdin or "").encode("utf-8"))
        given.seek(0)
        groups = student_groups(limits) if use_sandbox else []
        command = joined(groups, command)
        process = subprocess.Popen(
            list(command),
            stdin=given,
            stdout=out,
            stderr=err,
            cwd=folder,
            env=environment,
            start_new_session=True,
            pass_fds=tuple(pass_fds),
        )
        try:
            yield Started(process, out, err, limits.output_bytes)
        finally:
            # What it left behind in its session (without the sandbox), or itself if it runs.
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(process.pid, signal.SIGKILL)
            process.wait()
            _remove_when_empty(groups)


def run(
    command: Sequence[str],
    folder: Path,
    limits: Limits,
    timeout: float,
    use_sandbox: bool = True,
    stdin: Optional[str] = None,
    env: Optional[Dict[str, str]] = None,
    course: Optional[Path] = None,
) -> subprocess.CompletedProcess:
    """Run ``command`` in ``folder``, in the sandbox (see :func:`sandboxed_command`) unless told.

    What the command prints goes to files of the grader's, not to pipes, and is read back only
    up to ``limits.output_bytes``: a run that prints without end cannot fill the grader's memory.

    Args:
        command: what to run.
        folder: the writable working folder.
        limits: what the sandbox may use.
        timeout: wall-clock seconds before the command is killed.
        use_sandbox: whether to use the sandbox (off: the command runs with your rights).
        stdin: text sent on the command's standard input.
        env: environment variables besides the sandbox's own (or the grader's, without it).
        course: the student's assignment folders, shown at ``/course`` (sandbox only).

    Returns:
        The finished process, its output captured as text (cut at ``limits.output_bytes``,
        with a last line saying so).

    Raises:
        subprocess.TimeoutExpired: if it ran longer than ``timeout`` (it is killed, with
            every process it started).
    """
    with started(command, folder, limits, use_sandbox, stdin, env, course) as running:
        process = running.process
        try:
            process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise subprocess.TimeoutExpired(process.args, timeout) from None
        texts = running.outputs()
    return subprocess.CompletedProcess(process.args, process.returncode, texts[0], texts[1])


def _bounded_text(handle, limit: int) -> str:
    """At most ``limit`` bytes of an output file, as text, with a line saying if it was cut."""
    size = handle.seek(0, os.SEEK_END)
    handle.seek(0)
    text = handle.read(limit).decode("utf-8", errors="replace")
    if size > limit:
        text += f"\n[output cut: {size} bytes printed, {limit} read]\n"
    return text


def check_sandbox() -> None:
    """Make sure a sandbox can be created here.

    Raises:
        SandboxUnavailable: saying what is missing and how to install it.
    """
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        os.chown(folder, NOBODY, NOBODY)
        command = sandboxed_command(
            [sys.executable, "-c", "import os; print(os.getuid())"], Path(folder), Limits()
        )
        try:
            result = subprocess.run(
                command, check=False, capture_output=True, text=True, timeout=60
            )
        except (OSError, subprocess.TimeoutExpired) as error:
            raise SandboxUnavailable(f"bubblewrap could not start a sandbox: {error}.") from None
    if result.returncode != 0 or result.stdout.strip() != str(NOBODY):
        raise SandboxUnavailable(
            "bubblewrap could not start a sandbox here: "
            + (result.stderr.strip().splitlines() or ["no message"])[-1]
            + " (grading needs root, or unprivileged user namespaces, and the `setpriv` and "
            "`prlimit` tools of util-linux)."
        )
