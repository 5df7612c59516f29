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
import functools
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Dict, Iterator, List, Optional, Sequence, Set, Tuple

from autograder.sandbox.groups import (
    end_student_groups,
    joined,
    remove_when_empty,
    student_groups,
)
from autograder.sandbox.limits import NOBODY, STUDENT_DISK_VARIABLE, Limits
from duckielib.errors import DuckielibError

__all__ = [
    "Limits",
    "namespaces",
    "end_student_groups",
    "student_groups",
    "SandboxError",
    "SandboxUnavailable",
    "check_sandbox",
    "folders_above",
    "font_list",
    "fonts_view",
    "generated_robot_folders",
    "read_only_view",
    "run",
    "sandboxed_command",
]

#: The first of the user ids given to students' gradings (:func:`unit_user`).
FIRST_UNIT_USER = 1_000_000
#: matplotlib's cache folder inside the sandbox (``MPLCONFIGDIR``), where its font list is.
MATPLOTLIB_CACHE = "/tmp/matplotlib"
#: Where the submission's own folder appears inside the sandbox.
INSIDE = "/sandbox"
#: Where the student's notebooks appear (read-only) when a notebook needs its neighbours.
COURSE = "/course"


class SandboxError(DuckielibError):
    """Running code in the sandbox failed for a reason of the grader's, not the student's."""


class SandboxUnavailable(SandboxError):
    """bubblewrap is missing or cannot create a sandbox on this machine."""


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


def generated_robot_folders() -> List[str]:
    """The folders of the robot project that ``duckie robot prepare`` writes, where they exist."""
    from duckielib.tools.deploy import GENERATED, PROJECT

    return [str(PROJECT / name) for name in GENERATED if (PROJECT / name).is_dir()]


def read_only_view(paths: Sequence[str], tmp: Sequence[str]) -> Tuple[List[str], Set[str]]:
    """Bubblewrap's options for a view of the machine that shows ``paths`` read-only.

    Each path appears at its own place, the folders above it made empty (``0755``), with the
    system's usual links (``/bin`` to ``usr/bin``...). ``tmp`` are the options that make
    ``/tmp``: they come first, so that a path that lives under ``/tmp`` (a Python environment
    there) is shown on top of it.

    Returns:
        The options, and the folders they show or make (a caller adding its own folders to
        the view makes each only once).
    """
    args = [
        "--symlink", "usr/lib", "/lib",
        "--symlink", "usr/lib64", "/lib64",
        "--symlink", "usr/bin", "/bin",
        "--symlink", "usr/sbin", "/sbin",
        *tmp,
    ]  # fmt: skip
    made = {"/usr", "/etc", "/lib", "/lib64", "/bin", "/sbin", "/tmp"}
    for path in paths:
        for parent in folders_above(path):
            if parent not in made:
                args += ["--perms", "0755", "--dir", parent]
                made.add(parent)
        args += ["--ro-bind", path, path]
        made.add(path)
    return args, made


def folders_above(path: str) -> List[str]:
    """The folders above ``path``, from the top (``/a/b/c`` gives ``/a``, ``/a/b``)."""
    parts = Path(path).parts[1:-1]
    return ["/" + "/".join(parts[: index + 1]) for index in range(len(parts))]


def sandboxed_command(
    command: Sequence[str],
    folder: Path,
    limits: Limits,
    env: Optional[Dict[str, str]] = None,
    course: Optional[Path] = None,
    shared: Optional[Tuple[Path, str]] = None,
    tmp: Optional[Path] = None,
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
        tmp: the folder the sandbox sees as ``/tmp`` (see :func:`scratch`); None: a new file
            system of ``limits.disk_bytes``.
    """
    bwrap = shutil.which("bwrap")
    if bwrap is None:
        raise SandboxUnavailable(
            "bubblewrap (bwrap) is not installed; install it with `make ros` (Debian: "
            "apt-get install bubblewrap), or grade without a sandbox with --no-sandbox "
            "(student code then runs with your rights)."
        )
    args = [bwrap, *_system_view(limits, tmp)]
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


def namespaces(
    network: bool = True, processes: bool = True, control_groups: bool = True
) -> List[str]:
    """Bubblewrap's options that set a process apart from the machine.

    Its own IPC and host name (and, as asked, its own network, process ids and control-group
    names); it ends with its parent and runs in a session of its own (no terminal to write to).

    Args:
        network: no network (its own, empty one).
        processes: its own process ids (it sees and signals only its own processes).
        control_groups: its own view of the control groups, where the kernel allows it.
    """
    return [
        *(["--unshare-net"] if network else []),
        *(["--unshare-pid"] if processes else []),
        "--unshare-ipc",
        "--unshare-uts",
        *(["--unshare-cgroup-try"] if control_groups else []),
        "--die-with-parent",
        "--new-session",
    ]


def _system_view(limits: Limits, tmp: Optional[Path] = None) -> List[str]:
    """Bubblewrap's options for what the sandbox sees of the system: read-only, its own /tmp.

    ``/tmp`` is the folder ``tmp`` when given (the grader's own process for a student gives one
    on that student's file system, :mod:`.unit_process`), a file system of ``limits.disk_bytes``
    otherwise.
    """
    args = namespaces()
    if tmp is not None:
        shown = ["--bind", str(tmp), "/tmp"]
    else:
        shown = ["--perms", "1777", "--size", str(limits.disk_bytes), "--tmpfs", "/tmp"]
    args += read_only_view(_readonly_paths(), shown)[0]
    args += fonts_view(MATPLOTLIB_CACHE)
    # `duckie robot prepare` writes a solution into the robot project (the reference one, on an
    # instructor's machine): those folders stay out of sight.
    for path in generated_robot_folders():
        args += ["--tmpfs", path]
    args += [
        "--dev", "/dev",
        "--proc", "/proc",
    ]  # fmt: skip
    return args


def fonts_view(folder: str) -> List[str]:
    """Bubblewrap's options that give matplotlib's cache ``folder`` the list of the fonts.

    matplotlib makes that list when it is first imported with an empty cache folder, about
    0.2 s of CPU: in every sandbox (whose cache folder starts empty), several times for each
    notebook graded. A sandbox sees the machine's fonts as this process does: the list this
    process made or read is shown to it, read-only, in a folder it may write. Nothing without
    matplotlib.
    """
    fonts = font_list()
    if fonts is None or not fonts.is_file():
        return []
    return [
        "--perms", "1777", "--dir", folder,
        "--ro-bind", str(fonts), f"{folder}/{fonts.name}",
    ]  # fmt: skip


@functools.lru_cache(maxsize=None)
def font_list() -> Optional[Path]:
    """Matplotlib's list of the machine's fonts, as this process keeps it, or None.

    Importing matplotlib's font manager makes the list if it is not there yet.
    """
    try:
        import matplotlib
        from matplotlib import font_manager

        name = f"fontlist-v{font_manager.FontManager.__version__}.json"
        return Path(matplotlib.get_cachedir()) / name
    except Exception:  # the list only saves time: without it, each sandbox makes its own
        return None


def _as_student(limits: Limits) -> List[str]:
    """The command line's middle: become the unprivileged user, with ``limits``, no environment.

    As root, the sandbox's processes become user ``limits.uid``. Without root (the grader's
    own process for a student, :mod:`.unit_process`, already runs as that user), the sandbox
    is a user namespace of that user's, in which no further one can be made.
    """
    if os.geteuid() == 0:
        become = [
            # Only to become the student's user just below; setpriv then drops every capability.
            "--cap-add", "CAP_SETUID",
            "--cap-add", "CAP_SETGID",
            "setpriv",
            f"--reuid={limits.uid}",
            f"--regid={limits.uid}",
            "--clear-groups",
            "--no-new-privs",
            "--inh-caps=-all",
            "--bounding-set=-all",
        ]  # fmt: skip
    else:
        become = ["--unshare-user", "--disable-userns", "--"]
    return [
        *become,
        "prlimit",
        f"--as={limits.memory_bytes}",
        f"--nproc={sandbox_tasks(limits)}",
        f"--cpu={limits.cpu_seconds}",
        f"--fsize={limits.file_bytes}",
        "--core=0",
        "--",
        "env",
        "-i",
    ]  # fmt: skip


#: The most processes and threads the grader's own process for a student may have besides the
#: student's (a mission's robot runs a thread per subscription): they run as the same user.
GRADER_TASKS = 256


def sandbox_tasks(limits: Limits) -> int:
    """The process limit (``RLIMIT_NPROC``) of a sandbox's processes.

    It counts every process and thread of the sandbox's user. As root, that user is the
    student's alone. Without root, the grader's own process for the student
    (:mod:`.unit_process`) is that user too: the sandbox may then have ``limits.processes``
    more than that user has when it starts, so a fork bomb stops where it stops as root.
    """
    if os.geteuid() == 0:
        return limits.processes
    return limits.processes + min(_tasks_of(os.getuid()), GRADER_TASKS)


def _tasks_of(uid: int) -> int:
    """How many processes and threads user ``uid`` has (what ``RLIMIT_NPROC`` counts)."""
    count = 0
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = dict(
                line.split(":", 1) for line in (entry / "status").read_text().splitlines()
            )
            if fields["Uid"].split()[0] == str(uid):
                count += int(fields["Threads"])
        except (OSError, KeyError, ValueError, IndexError):
            continue
    return count


@contextlib.contextmanager
def scratch() -> Iterator[Optional[Path]]:
    """A folder for a sandbox's ``/tmp`` where the grader runs unprivileged, removed afterwards.

    The grader's own process for a student runs without root, on a file system of that
    student's own (:mod:`.unit_process`): a sandbox's ``/tmp`` lies there too, so everything the
    student writes counts against one size (the folder :data:`STUDENT_DISK_VARIABLE` names).
    As root, None: the sandbox makes its own.
    """
    import tempfile

    if os.geteuid() == 0:
        yield None
        return
    folder = Path(
        tempfile.mkdtemp(prefix="sandbox-tmp-", dir=os.environ.get(STUDENT_DISK_VARIABLE))
    )
    try:
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _environment(env: Optional[Dict[str, str]]) -> List[str]:
    """The sandbox's environment variables, as ``env -i`` takes them: its own, then ``env``."""
    base = {
        "HOME": "/tmp",
        "USER": "student",  # the user may have no name on this machine
        "LOGNAME": "student",
        "PATH": f"{Path(sys.executable).parent}:/usr/bin:/bin",
        "LANG": "C.UTF-8",
        "MPLBACKEND": "Agg",
        "MPLCONFIGDIR": MATPLOTLIB_CACHE,
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
    with scratch() as tmp, tempfile.TemporaryFile() as given, tempfile.TemporaryFile() as out, (
        tempfile.TemporaryFile()
    ) as err:
        if use_sandbox:
            command = sandboxed_command(
                command, folder, limits, env=env, course=course, shared=shared, tmp=tmp
            )
        elif env:
            environment = {**os.environ, **env}
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
            remove_when_empty(groups)


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
